// The one order of a set of triangles that canonical_order() puts them in,
// so that the output does not depend on heap addresses or insertion order.
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include "edges.hpp"
#include "prefault.hpp"

#include <algorithm>

namespace sc {
namespace {

// canonical_order() sorts in two passes, first to at most this many ranges
// of vertex numbers.
constexpr uint64_t kCanonRanges = 2048;

} // namespace

void canonical_order(std::vector<uint32_t> &tris, bool keep_orientation) {
  struct Tri {
    uint32_t v[3];
  };
  const size_t nt = tris.size() / 3;
  if (nt == 0)
    return;
  auto normalised = [&](size_t i) {
    Tri x;
    const uint32_t *s = &tris[3 * i];
    if (keep_orientation) {
      int k = s[0] < s[1] ? (s[0] < s[2] ? 0 : 2) : (s[1] < s[2] ? 1 : 2);
      for (int j = 0; j < 3; ++j)
        x.v[j] = s[(k + j) % 3];
    } else {
      const uint32_t lo = std::min(s[0], s[1]), hi = std::max(s[0], s[1]);
      x.v[0] = std::min(lo, s[2]);
      x.v[1] = std::min(hi, std::max(lo, s[2]));
      x.v[2] = std::max(hi, s[2]);
    }
    return x;
  };
  // Either way each triangle starts at its smallest vertex: a counting
  // sort on that vertex, then a sort of each vertex's few triangles. The
  // triangles come in any order, and a scatter straight to each vertex's
  // place was a cache miss per triangle; so they go first to a few
  // thousand ranges of vertex numbers, whose ends stay in cache, and then,
  // range by range, to their vertex's place in tris.
  uint32_t top = 0;
  for (uint32_t v : tris)
    top = std::max(top, v);
  int shift = 0;
  while ((uint64_t(top) >> shift) >= kCanonRanges)
    ++shift;
  const size_t ranges = size_t(top >> shift) + 1;
  std::vector<uint32_t> rstart(ranges + 1, 0);
  for (size_t i = 0; i < nt; ++i)
    ++rstart[(normalised(i).v[0] >> shift) + 1];
  for (size_t r = 0; r < ranges; ++r)
    rstart[r + 1] += rstart[r];
  std::vector<Tri> t(nt);
  {
    std::vector<uint32_t> fill(rstart.begin(), rstart.end() - 1);
    for (size_t i = 0; i < nt; ++i) {
      const Tri x = normalised(i);
      t[fill[x.v[0] >> shift]++] = x;
    }
  }
  // A vertex has a few triangles (see sort_bucket()). Any sort gives the
  // same array: triangles that compare equal are the same three numbers.
  auto before = [](const Tri &a, const Tri &b) {
    return a.v[1] != b.v[1] ? a.v[1] < b.v[1] : a.v[2] < b.v[2];
  };
  std::vector<uint32_t> start((size_t(1) << shift) + 1);
  std::vector<Tri> part;
  for (size_t r = 0; r < ranges; ++r) {
    const uint32_t lo = uint32_t(r << shift);
    std::fill(start.begin(), start.end(), 0);
    for (uint32_t i = rstart[r]; i < rstart[r + 1]; ++i)
      ++start[t[i].v[0] - lo + 1];
    for (size_t v = 0; v + 1 < start.size(); ++v)
      start[v + 1] += start[v];
    part.resize(rstart[r + 1] - rstart[r]);
    for (uint32_t i = rstart[r]; i < rstart[r + 1]; ++i)
      part[start[t[i].v[0] - lo]++] = t[i];
    // start[v] is now where vertex lo + v's triangles end in part.
    for (size_t v = 0; v + 1 < start.size(); ++v) {
      Tri *b = part.data() + (v ? start[v - 1] : 0);
      sort_bucket(b, size_t(part.data() + start[v] - b), before);
    }
    for (size_t i = 0; i < part.size(); ++i)
      std::memcpy(&tris[3 * (size_t(rstart[r]) + i)], part[i].v,
                  sizeof part[i].v);
  }
}

void merge_canonical(std::vector<std::vector<uint32_t>> &parts,
                     std::vector<uint32_t> &out) {
  struct Tri {
    uint32_t v[3];
  };
  static_assert(sizeof(Tri) == 3 * sizeof(uint32_t), "packed triangles");
  // Lexicographic on the three numbers, which canonical_order() sorts
  // ascending within each triangle.
  auto before = [](const Tri &a, const Tri &b) {
    return a.v[0] != b.v[0]   ? a.v[0] < b.v[0]
           : a.v[1] != b.v[1] ? a.v[1] < b.v[1]
                              : a.v[2] < b.v[2];
  };
  auto tris = [](std::vector<uint32_t> &x) {
    return reinterpret_cast<Tri *>(x.data());
  };
  auto merge = [&](std::vector<uint32_t> &a, std::vector<uint32_t> &b) {
    std::vector<uint32_t> m;
    reserve_resident(m, a.size() + b.size());
    m.resize(a.size() + b.size());
    std::merge(tris(a), tris(a) + a.size() / 3, tris(b), tris(b) + b.size() / 3,
               tris(m), before);
    a = std::move(m);
    b = std::vector<uint32_t>();
  };
  // In rounds, each part with the one `step` after it.
  for (size_t step = 1; step < parts.size(); step *= 2)
    for (size_t i = 0; i + step < parts.size(); i += 2 * step)
      merge(parts[i], parts[i + step]);
  out = parts.empty() ? std::vector<uint32_t>() : std::move(parts[0]);
  parts.clear();
}

} // namespace sc
