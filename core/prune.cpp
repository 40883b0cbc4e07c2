// Sharp-edge pruning of the candidate triangles: an edge whose live
// triangles fit in a narrow wedge, or that has a lone one, cannot be on the
// surface, and its triangles go, until no edge is sharp.
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include "edges.hpp"

namespace sc {
namespace {

// An edge is sharp when its live triangles fit in a wedge narrower than
// pi/2 (a gap between consecutive ones exceeds 3 pi/2), or when it has
// exactly one.
bool is_sharp(const EdgeTable &et, uint32_t e,
              const std::vector<uint8_t> &alive, bool erode_single) {
  int k = 0;
  double first = 0, prev = 0, gap = 0;
  for (uint32_t i = et.first[e]; i < et.first[e + 1]; ++i) {
    if (!alive[et.entries[i].tri])
      continue;
    double a = et.angle[i];
    if (k == 0)
      first = a;
    else
      gap = std::max(gap, a - prev);
    prev = a;
    ++k;
  }
  if (k == 0)
    return false;
  if (k == 1)
    return erode_single;
  // In quarter turns: more than three right angles.
  gap = std::max(gap, 4 - (prev - first));
  return gap > 3;
}

} // namespace

void prune(const double *xyz, size_t n, const std::vector<uint32_t> &cand,
           bool erode_single, const std::vector<uint8_t> &keep_vertex,
           std::vector<uint8_t> &alive, EdgeTablePtr &table, Progress &progress,
           sc_diag_t &diag, unsigned threads) {
  table.reset(new EdgeTable);
  EdgeTable &et = *table;
  {
    // (The table takes about three quarters of the stage.)
    Progress::Span span(progress, 0, 0.75);
    et.build(xyz, n, cand, progress, true, threads);
  }
  Progress::Span span(progress, 0.75, 1);
  const size_t ne = et.edges();
  alive.assign(cand.size() / 3, 1);
  std::vector<uint32_t> work(ne);
  std::iota(work.begin(), work.end(), 0u);
  std::vector<uint8_t> queued(ne, 1);
  auto live_on = [&](uint32_t e) {
    uint32_t k = 0;
    for (uint32_t i = et.first[e]; i < et.first[e + 1]; ++i)
      k += alive[et.entries[i].tri];
    return k;
  };
  // Without erosion, a lone triangle on an edge goes only when it hangs by
  // at most one edge: a fin, not the rim of a hole.
  auto dangling = [&](uint32_t e) {
    if (live_on(e) != 1)
      return false;
    for (uint32_t i = et.first[e]; i < et.first[e + 1]; ++i) {
      uint32_t t = et.entries[i].tri;
      if (!alive[t])
        continue;
      int lone = 0;
      for (int k = 0; k < 3; ++k)
        lone += live_on(et.tri_edge[3 * size_t(t) + k]) == 1;
      return lone >= 2;
    }
    return false;
  };
  size_t steps = 0;
  while (!work.empty()) {
    progress.tick(++steps, ne + diag.pruned);
    uint32_t e = work.back();
    work.pop_back();
    queued[e] = 0;
    // Boundary mode: a boundary sample has a lone triangle, or a wedge of
    // them, on its edges by nature; pruning there would eat the surface
    // from its boundary inward.
    if (!keep_vertex.empty()) {
      uint64_t k = et.entries[et.first[e]].key;
      if (keep_vertex[key_lo(k)] || keep_vertex[uint32_t(k)])
        continue;
    }
    if (!is_sharp(et, e, alive, erode_single)) {
      if (erode_single || !dangling(e))
        continue;
    }
    for (uint32_t i = et.first[e]; i < et.first[e + 1]; ++i) {
      uint32_t t = et.entries[i].tri;
      if (!alive[t])
        continue;
      alive[t] = 0;
      ++diag.pruned;
      for (int k = 0; k < 3; ++k) {
        uint32_t f = et.tri_edge[3 * size_t(t) + k];
        if (f != e && !queued[f]) {
          queued[f] = 1;
          work.push_back(f);
        }
      }
    }
  }
}

} // namespace sc
