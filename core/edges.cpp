// The edge tables' pools, and the edge-table operations that the rest of
// the core calls through internal.hpp.
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include "edges.hpp"

namespace sc {

thread_local Pool<uint32_t> u32_pool;
thread_local Pool<EdgeTable::Entry> EdgeTable::entry_pool;

void EdgeTableFree::operator()(EdgeTable *et) const { delete et; }

EdgeTablePtr new_edge_table() { return EdgeTablePtr(new EdgeTable); }

void pair_half_edges(size_t n, const std::vector<uint32_t> &tris,
                     Progress &progress, std::vector<uint32_t> &twin,
                     EdgeTable &et) {
  et.build(nullptr, n, tris, progress, false);
  twin.assign(tris.size(), UINT32_MAX);
  for (size_t e = 0; e < et.edges(); ++e) {
    if (et.first[e + 1] - et.first[e] != 2)
      continue;
    const EdgeTable::Entry &a = et.entries[et.first[e]],
                           &b = et.entries[et.first[e] + 1];
    const uint32_t ha = 3 * a.tri + a.corner, hb = 3 * b.tri + b.corner;
    twin[ha] = hb;
    twin[hb] = ha;
  }
}

void keep_edges_of(EdgeTable &et, const std::vector<uint8_t> &keep) {
  et.keep_live(keep, false);
}

void append_edges_of(EdgeTable &et, size_t n,
                     const std::vector<uint32_t> &tris, size_t first_new,
                     Progress &progress) {
  et.append(n, tris, first_new, progress);
}

void release_scratch() {
  EdgeTable::entry_pool.spare.clear();
  u32_pool.spare.clear();
}

} // namespace sc
