// Handles of an open surface: a region is grown over each component, one
// triangle at a time, and never takes a triangle that would raise its
// genus. What stays out is a thin cut across each handle, where the fronts
// that came round it met. Watertight mode runs it before closing the holes
// (docs/algorithm.md section 11.2).
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include "edges.hpp"
#include "internal.hpp"
#include "parallel.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <queue>

namespace sc {

namespace {

constexpr uint32_t kNone = UINT32_MAX;
// Small handles: surfaces of at least so many vertices are probed on more
// threads, when given them.
constexpr size_t kParallelProbes = 1024;
// A cut is kept only where it runs mostly along holes: at most this many
// edges cut for each edge of a hole on the loops it opens (measured: the
// zippered bunny's handles 0.06 to 2.6, a kitten's tail and a knotted
// tube, true handles, no hole at all and 10.7) ...
constexpr uint64_t kMaxCutPerHoleEdge = 4;
// ... and where the longest of those holes is at least this many times as
// long as the cut: a handle that closed round a hole of the scan is a
// bridge shorter than the hole, while a true handle is cut across sampled
// surface, past the small holes that extraction left (measured, longest
// hole / cut: the real scans' handles 3.1 to 19.5 on the zippered bunny,
// 4 and 7.4 or more on single scans, 3 or more but for 2 of 3960 on the
// merged scans; true handles of genus-2 and torus samples of 2000 to 6000
// points 1.05 or less).
constexpr uint64_t kMinHolePerCutEdge = 2;

// Small handles: a tube (cut_small_handles()) is a tunnel the labelling
// made only where its triangles' normals are, on average, at least this far
// from the poles of their corners (the mean of |cos|; measured, on random
// samples of the anchor's and the fandisk's meshes: an anchor's small true
// holes 0.81 to 0.90 but for 3 of 12, the fandisk's false tunnels 0.36 to
// 0.73 but for 3 of 34).
constexpr double kTunnelAlign = 0.8;

enum : uint8_t { kIn = 1, kSeen = 2 };

// Half-edge h = 3 t + k of triangle t runs from its corner k to corner k + 1.
inline uint32_t next_in_tri(uint32_t h) { return h % 3 == 2 ? h - 2 : h + 1; }

struct Region {
  std::vector<uint32_t> twin; // the other side's half-edge, or kNone
  std::vector<uint8_t> in;    // kIn: triangle is in the region

  Region(size_t n, const std::vector<uint32_t> &t, Progress &progress,
         EdgeTable &table)
      : in(t.size() / 3, 0) {
    pair_half_edges(n, t, progress, twin, table);
  }

  bool in_region(uint32_t h) const {
    return h != kNone && (in[h / 3] & kIn);
  }

  // The boundary half-edge of the region after h (a boundary half-edge of
  // it), found by turning about h's end vertex through region triangles.
  uint32_t next_boundary(uint32_t h) const {
    uint32_t g = next_in_tri(h);
    while (in_region(twin[g]))
      g = next_in_tri(twin[g]);
    return g;
  }

  // The same for the surface's own holes: the half-edge without a twin
  // after h (one without a twin), turning through every triangle.
  uint32_t next_hole_edge(uint32_t h) const {
    uint32_t g = next_in_tri(h);
    while (twin[g] != kNone)
      g = next_in_tri(twin[g]);
    return g;
  }

  // Whether the boundary half-edges r[0..k) of the region lie on one loop.
  // One walker per half-edge steps along its loop, in turns: two meet soon
  // when they share a loop, and a walker back at its start has seen its
  // whole loop, which settles the question.
  bool one_loop(const uint32_t *r, int k) const {
    if (k < 2)
      return true;
    uint32_t pos[3] = {r[0], r[1], k > 2 ? r[2] : 0};
    int group[3] = {0, 1, 2};
    auto merge = [&](int a, int b) {
      int ga = group[a], gb = group[b];
      for (int i = 0; i < k; ++i)
        if (group[i] == gb)
          group[i] = ga;
    };
    auto joined = [&] {
      for (int i = 1; i < k; ++i)
        if (group[i] != group[0])
          return false;
      return true;
    };
    for (;;) {
      for (int i = 0; i < k; ++i) {
        pos[i] = next_boundary(pos[i]);
        if (pos[i] == r[i])
          return joined();
        for (int j = 0; j < k; ++j)
          if (j != i && pos[i] == r[j])
            merge(i, j);
        if (joined())
          return true;
      }
    }
  }
};

// Grows the region over each component of tris, nearest first from the
// component's first triangle, so that the fronts meet on the far side of
// each handle from where they came; the region takes every triangle that
// does not join two of its boundary loops (raise its genus).
void grow_region(const double *xyz, const std::vector<uint32_t> &tris,
                 Region &reg, Progress &progress) {
  const size_t nt = tris.size() / 3;
  // What the growth below reads of a triangle when it reaches it, side by
  // side: its centre and the least distance to it so far. (In arrays of
  // their own, each was a cache miss of its own.)
  struct Reach {
    double centre[3];
    double best;
  };
  std::vector<Reach> reach(nt);
  for (size_t t = 0; t < nt; ++t) {
    for (int j = 0; j < 3; ++j)
      reach[t].centre[j] = (xyz[3 * size_t(tris[3 * t]) + j] +
                            xyz[3 * size_t(tris[3 * t + 1]) + j] +
                            xyz[3 * size_t(tris[3 * t + 2]) + j]) /
                           3;
    reach[t].best = HUGE_VAL;
  }
  auto dist = [&](uint32_t a, uint32_t b) {
    double s = 0;
    for (int j = 0; j < 3; ++j) {
      double d = reach[a].centre[j] - reach[b].centre[j];
      s += d * d;
    }
    return std::sqrt(s);
  };

  // A triangle is seen once taken off the queue (kSeen in reg.in, beside
  // kIn, until the growth ends).
  using Item = std::pair<double, uint32_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
  size_t done = 0;
  for (uint32_t seed = 0; seed < nt; ++seed) {
    if (reg.in[seed] & kSeen)
      continue;
    reach[seed].best = 0;
    queue.push({0.0, seed});
    while (!queue.empty()) {
      auto [d, t] = queue.top();
      queue.pop();
      if (reg.in[t] & kSeen)
        continue;
      reg.in[t] |= kSeen;
      progress.tick(++done, nt);
      uint32_t r[3];
      int k = 0;
      for (int j = 0; j < 3; ++j)
        if (reg.in_region(reg.twin[3 * t + j]))
          r[k++] = reg.twin[3 * t + j];
      if (!reg.one_loop(r, k))
        continue; // would join two loops of the region: a handle
      reg.in[t] |= kIn;
      for (int j = 0; j < 3; ++j) {
        uint32_t h = reg.twin[3 * t + j];
        if (h == kNone || (reg.in[h / 3] & kSeen))
          continue;
        double dn = d + dist(t, h / 3);
        if (dn < reach[h / 3].best) {
          reach[h / 3].best = dn;
          queue.push({dn, h / 3});
        }
      }
    }
  }
  reach = std::vector<Reach>();
  for (uint8_t &f : reg.in) // what follows reads in as in or out
    f &= kIn;
}

// The cuts: the triangles the region left out, in groups that share
// vertices, and what each group's cut opens.
struct Cuts {
  std::vector<uint32_t> group; // per vertex: union-find over the cuts
  // Per group (its root vertex): the edges cut and the hole edges on the
  // loops it opens, and the longest hole among them.
  std::vector<uint64_t> cut_edges, hole_edges, longest_hole;

  uint32_t find(uint32_t v) {
    while (group[v] != v)
      v = group[v] = group[group[v]];
    return v;
  }
  Cuts(size_t n, const std::vector<uint32_t> &tris, const Region &reg);
};

Cuts::Cuts(size_t n, const std::vector<uint32_t> &tris, const Region &reg)
    : group(n) {
  const size_t nt = tris.size() / 3;
  for (uint32_t v = 0; v < n; ++v)
    group[v] = v;
  std::vector<uint8_t> cut_vertex(n, 0);
  for (size_t t = 0; t < nt; ++t) {
    if (reg.in[t])
      continue;
    const uint32_t *v = &tris[3 * t];
    for (int j = 0; j < 3; ++j)
      cut_vertex[v[j]] = 1;
    group[find(v[1])] = find(v[0]);
    group[find(v[2])] = find(v[0]);
  }
  // Each cut opens loops that run partly along holes the surface already
  // had and partly along edges it cut. A handle that closes round a hole
  // (where the scan has no samples) is cut mostly along that hole, which
  // is longer than the cut; a true handle, such as a cat's tail, is cut
  // across sampled surface, far from any hole or past holes shorter than
  // the cut. Cuts of the second kind are put back.
  cut_edges.assign(n, 0);
  hole_edges.assign(n, 0);
  longest_hole.assign(n, 0);
  // The length of the hole each boundary half-edge of the surface is on
  // (turning about vertices through every triangle, not just the region's).
  std::vector<uint32_t> hole_len(tris.size(), 0), on_hole;
  for (uint32_t h = 0; h < tris.size(); ++h) {
    if (reg.twin[h] != kNone || hole_len[h])
      continue;
    on_hole.clear();
    uint32_t g = h;
    do {
      on_hole.push_back(g);
      g = reg.next_hole_edge(g);
    } while (g != h);
    for (uint32_t x : on_hole)
      hole_len[x] = uint32_t(on_hole.size());
  }
  std::vector<uint8_t> walked(tris.size(), 0);
  std::vector<uint32_t> touched;
  for (uint32_t h = 0; h < tris.size(); ++h) {
    if (!reg.in[h / 3] || reg.in_region(reg.twin[h]) || walked[h])
      continue;
    uint64_t cut = 0, hole = 0, longest = 0;
    touched.clear();
    uint32_t g = h;
    do {
      walked[g] = 1;
      (reg.twin[g] == kNone ? hole : cut) += 1;
      if (reg.twin[g] == kNone)
        longest = std::max<uint64_t>(longest, hole_len[g]);
      if (cut_vertex[tris[g]])
        touched.push_back(find(tris[g]));
      g = reg.next_boundary(g);
    } while (g != h);
    std::sort(touched.begin(), touched.end());
    touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
    for (uint32_t c : touched) {
      cut_edges[c] += cut;
      hole_edges[c] += hole;
      longest_hole[c] = std::max(longest_hole[c], longest);
    }
  }
}

} // namespace

size_t cut_handles(const double *xyz, size_t n, std::vector<uint32_t> &tris,
                   Progress &progress, EdgeTable &table) {
  const size_t nt = tris.size() / 3;
  if (nt == 0)
    return 0;
  Region reg(n, tris, progress, table);
  grow_region(xyz, tris, reg, progress);
  // The surface is a manifold: only where the region left triangles out
  // can a vertex have several fans in it.
  fix_fans(n, tris, reg.in, true);

  Cuts groups(n, tris, reg);
  std::vector<uint8_t> counted(n, 0);
  size_t cuts = 0;
  std::vector<uint32_t> kept;
  kept.reserve(tris.size());
  std::vector<uint8_t> keep(nt, 1);
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t c = groups.find(tris[3 * t]);
    if (reg.in[t] ||
        groups.cut_edges[c] > kMaxCutPerHoleEdge * groups.hole_edges[c] ||
        groups.longest_hole[c] < kMinHolePerCutEdge * groups.cut_edges[c]) {
      kept.insert(kept.end(), &tris[3 * t], &tris[3 * t] + 3);
      continue;
    }
    keep[t] = 0;
    if (!counted[c]) {
      counted[c] = 1;
      ++cuts;
    }
  }
  tris.swap(kept);
  // The table that pairing the half-edges built, cut down to the result.
  if (tris.size() < 3 * nt)
    keep_edges_of(table, keep);
  return cuts;
}

namespace {

// Twice the genus of the triangles `region` of a closed, oriented manifold
// surface, summed over the pieces they make across edges; twin[h] is the
// other half-edge of half-edge h = 3 t + c (from corner c of triangle t to
// corner c + 1, pair_half_edges()), at[t] the place of triangle t in
// region when in_region(t). Where the region's boundary passes a vertex
// more than once, each fan of the region there counts as a vertex of its
// own, and the loops are followed about their vertices through the
// region's triangles. mark: scratch, a byte per vertex, left all 0; par
// and seen: scratch of any size.
template <class InRegion>
int64_t region_twice_genus(
    const std::vector<uint32_t> &tris, const std::vector<uint32_t> &twin,
    const std::vector<uint32_t> &region, const std::vector<uint32_t> &at,
    InRegion in_region, std::vector<uint8_t> &mark, std::vector<uint32_t> &par,
    std::vector<uint8_t> &seen, int64_t &pieces_out, int64_t &loops_out) {
  const size_t f = region.size();
  auto next_in = [](size_t h) { return h - h % 3 + (h % 3 + 1) % 3; };
  auto inside = [&](size_t h) {
    return twin[h] != UINT32_MAX && in_region(twin[h] / 3);
  };
  // Pieces across edges, by union-find over places in region.
  par.resize(f);
  std::iota(par.begin(), par.end(), 0u);
  auto root = [&](uint32_t x) {
    while (par[x] != x)
      x = par[x] = par[par[x]];
    return x;
  };
  int64_t nb = 0, loops = 0, v = 0;
  for (size_t i = 0; i < f; ++i)
    for (int c = 0; c < 3; ++c) {
      const size_t h = 3 * size_t(region[i]) + c;
      if (!inside(h)) {
        ++nb;
        mark[tris[h]] = 1; // a vertex with a fan ending here
      } else {
        const uint32_t x = root(uint32_t(i)), y = root(at[twin[h] / 3]);
        if (x != y)
          par[x] = y;
      }
    }
  int64_t pieces = 0;
  for (size_t i = 0; i < f; ++i)
    pieces += par[i] == i;
  // Loops: from a boundary half-edge a -> b, the next is the boundary
  // half-edge leaving b met turning about b through the region; seen
  // marks them by place in region and corner.
  seen.assign(3 * f, 0);
  for (size_t i = 0; i < f; ++i)
    for (int c = 0; c < 3; ++c) {
      size_t h = 3 * size_t(region[i]) + c;
      if (inside(h) || seen[3 * i + c])
        continue;
      ++loops;
      for (size_t k = 3 * i + c; !seen[k]; k = 3 * size_t(at[h / 3]) + h % 3) {
        seen[k] = 1;
        h = next_in(h); // leaves the end of the last one
        for (size_t guard = 0; inside(h) && guard < 3 * f; ++guard)
          h = next_in(twin[h]);
      }
    }
  // Vertices: one per fan; a vertex with a boundary half-edge leaving it
  // has one fan per such half-edge (nb in all), the others one.
  for (size_t i = 0; i < f; ++i)
    for (int c = 0; c < 3; ++c) {
      const uint32_t w = tris[3 * size_t(region[i]) + c];
      if (mark[w] == 0) {
        mark[w] = 2;
        ++v;
      }
    }
  v += nb;
  for (size_t i = 0; i < f; ++i)
    for (int c = 0; c < 3; ++c)
      mark[tris[3 * size_t(region[i]) + c]] = 0;
  const int64_t e = (3 * int64_t(f) + nb) / 2;
  const int64_t chi = v - e + int64_t(f);
  pieces_out = pieces;
  loops_out = loops;
  return 2 * pieces - chi - loops;
}

enum : uint8_t { kNothing = 0, kHandle = 1, kTube = 2 };

// The region of the triangles within `rings` rings of a vertex, and
// whether it holds a handle: with its own scratch, so that probes of
// separate vertices run on separate threads.
class RingProbe {
public:
  RingProbe(const std::vector<uint32_t> &tris,
            const std::vector<uint32_t> &twin, const VertexStar &star, size_t n,
            int rings)
      : tris_(tris), twin_(twin), star_(star), rings_(rings),
        place_(tris.size() / 3, 0), tri_stamp_(tris.size() / 3, 0),
        vert_stamp_(n, 0), mark_(n, 0) {}

  // What the region about v holds: kHandle, or kTube where it is one
  // piece with two loops and no genus, an annulus round a thin tube (a
  // tunnel, or a thin part: cut_small_handles() tells them apart), or
  // kNothing; the region's triangles are then in region() and its
  // vertices in verts().
  uint8_t handle_at(uint32_t v) {
    ++stamp_;
    region_.clear();
    verts_.assign(1, v);
    vert_stamp_[v] = stamp_;
    front_.assign(1, v);
    for (int r = 0; r < rings_; ++r) {
      next_.clear();
      for (uint32_t u : front_)
        for (uint32_t k = star_.first[u]; k < star_.first[u + 1]; ++k) {
          const uint32_t t = star_.tris[k];
          if (tri_stamp_[t] == stamp_)
            continue;
          tri_stamp_[t] = stamp_;
          place_[t] = uint32_t(region_.size());
          region_.push_back(t);
          for (int c = 0; c < 3; ++c) {
            const uint32_t w = tris_[3 * t + c];
            if (vert_stamp_[w] != stamp_) {
              vert_stamp_[w] = stamp_;
              verts_.push_back(w);
              next_.push_back(w);
            }
          }
        }
      front_.swap(next_);
    }
    // A disc (Euler characteristic 1) holds no handle, and is what nearly
    // every region is: counted from the edges to triangles outside it
    // before anything is sorted. (Its vertices counted once, the
    // characteristic is at most that of region_twice_genus(), and a
    // handle in one or two pieces needs it at most 0.)
    int64_t outside = 0;
    for (uint32_t t : region_)
      for (int c = 0; c < 3; ++c)
        outside += twin_[3 * t + c] == UINT32_MAX ||
                   tri_stamp_[twin_[3 * t + c] / 3] != stamp_;
    const int64_t f = int64_t(region_.size());
    if (2 * int64_t(verts_.size()) - f - outside > 0)
      return kNothing;
    int64_t pieces = 0, loops = 0;
    const int64_t g = region_twice_genus(
        tris_, twin_, region_, place_,
        [&](uint32_t t) { return tri_stamp_[t] == stamp_; }, mark_, par_, seen_,
        pieces, loops);
    if (g >= 2)
      return kHandle;
    return g == 0 && pieces == 1 && loops == 2 ? kTube : kNothing;
  }
  bool in_region(uint32_t t) const { return tri_stamp_[t] == stamp_; }
  const std::vector<uint32_t> &region() const { return region_; }
  const std::vector<uint32_t> &verts() const { return verts_; }

private:
  const std::vector<uint32_t> &tris_, &twin_;
  const VertexStar &star_;
  const int rings_;
  // Each triangle's place in the region under way.
  std::vector<uint32_t> place_, tri_stamp_, vert_stamp_;
  // Scratch of region_twice_genus(), kept from probe to probe: the
  // regions that are not discs are many on a rough closure.
  std::vector<uint8_t> mark_, seen_;
  std::vector<uint32_t> par_;
  std::vector<uint32_t> region_, verts_, front_, next_;
  uint32_t stamp_ = 0;
};

// The triangles of tris by their corners in increasing order, sorted.
std::vector<std::array<uint32_t, 3>>
sorted_triangles(const std::vector<uint32_t> &tris) {
  std::vector<std::array<uint32_t, 3>> keys(tris.size() / 3);
  for (size_t t = 0; t < keys.size(); ++t) {
    keys[t] = {tris[3 * t], tris[3 * t + 1], tris[3 * t + 2]};
    std::sort(keys[t].begin(), keys[t].end());
  }
  std::sort(keys.begin(), keys.end());
  return keys;
}

// What the probes of the last round found that still holds on tris: a
// probe reads only the stars of the vertices within rings - 1 rings of its
// vertex, so it finds the same where none of those stars changed. The
// vertices of the triangles that differ from the last round's surface, and
// those within `rings` rings of them on tris, are probed again: cache.known
// is left marking the others. The cache then holds tris's triangles.
void keep_probes(size_t n, const std::vector<uint32_t> &tris,
                 const VertexStar &star, int rings, ProbeCache &cache) {
  std::vector<std::array<uint32_t, 3>> keys = sorted_triangles(tris);
  if (cache.rings == rings && cache.known.size() == n) {
    std::vector<uint32_t> front;
    std::vector<uint8_t> stale(n, 0);
    auto mark = [&](const std::array<uint32_t, 3> &k) {
      for (uint32_t w : k)
        if (!stale[w]) {
          stale[w] = 1;
          front.push_back(w);
        }
    };
    size_t i = 0, j = 0;
    while (i < keys.size() || j < cache.keys.size()) {
      if (j == cache.keys.size() ||
          (i < keys.size() && keys[i] < cache.keys[j]))
        mark(keys[i++]);
      else if (i == keys.size() || cache.keys[j] < keys[i])
        mark(cache.keys[j++]);
      else
        ++i, ++j;
    }
    std::vector<uint32_t> next;
    for (int r = 0; r < rings && !front.empty(); ++r) {
      next.clear();
      for (uint32_t u : front)
        for (uint32_t k = star.first[u]; k < star.first[u + 1]; ++k)
          for (int c = 0; c < 3; ++c) {
            const uint32_t w = tris[3 * size_t(star.tris[k]) + c];
            if (!stale[w]) {
              stale[w] = 1;
              next.push_back(w);
            }
          }
      front.swap(next);
    }
    for (size_t v = 0; v < n; ++v)
      cache.known[v] = cache.known[v] && !stale[v];
  } else {
    cache.holds.assign(n, kNothing);
    cache.known.assign(n, 0);
  }
  cache.rings = rings;
  cache.keys.swap(keys);
}

} // namespace

size_t cut_small_handles(const double *xyz, size_t n,
                         std::vector<uint32_t> &tris, int rings,
                         size_t max_sites, const double *poles,
                         const std::vector<uint8_t> *only, unsigned threads,
                         Progress &progress, ProbeCache *cache) {
  const size_t nt = tris.size() / 3;
  VertexStar star;
  star.build(n, tris, [](size_t) { return true; });
  std::vector<uint32_t> twin;
  {
    EdgeTable table;
    pair_half_edges(n, tris, progress, twin, table);
  }
  if (cache)
    keep_probes(n, tris, star, rings, *cache);
  // Every vertex probed first, on the threads, each slice of the vertices
  // with a probe of its own; then, in the order of the vertices, a region
  // that holds a handle is a site unless a site before it covers its
  // vertex. (What a probe finds does not depend on what is covered: the
  // same sites as probing one vertex after another and skipping those
  // covered.)
  // With a cache, the vertices whose probe still holds are not probed
  // again (keep_probes()).
  std::vector<uint8_t> fresh;
  std::vector<uint8_t> &holds = cache ? cache->holds : fresh;
  if (!cache)
    fresh.assign(n, kNothing);
  const size_t slices = threads > 1 && n >= kParallelProbes ? threads : 1;
  run_parallel(slices, threads, progress, [&](size_t i, Progress &mine) {
    RingProbe probe(tris, twin, star, n, rings);
    const size_t from = n * i / slices, to = n * (i + 1) / slices;
    for (size_t v = from; v < to; ++v) {
      mine.tick(v - from, to - from);
      const bool probed = star.first[v] != star.first[v + 1] &&
                          (!poles || (only && (*only)[v]));
      if (cache && probed && cache->known[v])
        continue; // as the last round found
      holds[v] = probed ? probe.handle_at(uint32_t(v)) : uint8_t(kNothing);
      if (cache)
        cache->known[v] = probed;
    }
  });
  RingProbe probe(tris, twin, star, n, rings);
  // A site covers its region's vertices: no site after it starts there.
  std::vector<uint8_t> covered(n, 0), cut(nt, 0);
  // Each place: its triangles' area, where its triangles are listed, and
  // for a tube, the triangles outside it across its two loops.
  struct Site {
    double area;
    size_t from, to, rim_from, rim_to;
  };
  std::vector<Site> sites;
  std::vector<uint32_t> site_tris, rims;
  // Whether the tube `region` (one piece, two loops, probe.in_region())
  // faces its axis: a tunnel through the solid, which the samples do not
  // support, rather than a thin part of it (a true handle, a leg), which
  // faces away. The axis joins the middles of the two loops.
  std::vector<uint32_t> loop_of(n, kNone);
  auto tunnel = [&](const std::vector<uint32_t> &region) {
    if (!poles)
      return false;
    std::vector<uint32_t> ends;
    for (uint32_t t : region)
      for (int c = 0; c < 3; ++c) {
        const uint32_t h = twin[3 * size_t(t) + c];
        if (h == kNone || !probe.in_region(h / 3)) {
          const uint32_t a = tris[3 * size_t(t) + c],
                         b = tris[3 * size_t(t) + (c + 1) % 3];
          ends.push_back(a);
          ends.push_back(b);
          loop_of[a] = a;
          loop_of[b] = b;
        }
      }
    auto root = [&](uint32_t x) {
      while (loop_of[x] != x)
        x = loop_of[x] = loop_of[loop_of[x]];
      return x;
    };
    for (size_t k = 0; k < ends.size(); k += 2)
      loop_of[root(ends[k])] = root(ends[k + 1]);
    if (ends.empty())
      return false;
    double mid[2][3] = {{0, 0, 0}, {0, 0, 0}};
    double count[2] = {0, 0};
    const uint32_t first = root(ends[0]);
    for (uint32_t w : ends) {
      const int side = root(w) == first ? 0 : 1;
      for (int j = 0; j < 3; ++j)
        mid[side][j] += xyz[3 * size_t(w) + j];
      count[side] += 1;
    }
    for (uint32_t w : ends)
      loop_of[w] = kNone;
    if (count[1] == 0)
      return false; // the loops meet at a vertex
    double axis[3], centre[3];
    for (int j = 0; j < 3; ++j) {
      mid[0][j] /= count[0];
      mid[1][j] /= count[1];
      axis[j] = mid[1][j] - mid[0][j];
      centre[j] = (mid[0][j] + mid[1][j]) / 2;
    }
    const double len2 = dot3(axis, axis);
    if (!(len2 > 0))
      return false;
    double facing = 0;
    for (uint32_t t : region) {
      const uint32_t *v = &tris[3 * size_t(t)];
      double nrm[3], r[3];
      triangle_normal(xyz, v[0], v[1], v[2], nrm);
      for (int j = 0; j < 3; ++j)
        r[j] = (xyz[3 * size_t(v[0]) + j] + xyz[3 * size_t(v[1]) + j] +
                xyz[3 * size_t(v[2]) + j]) /
                   3 -
               centre[j];
      const double along = dot3(r, axis) / len2;
      for (int j = 0; j < 3; ++j)
        r[j] -= along * axis[j];
      facing += dot3(nrm, r);
    }
    if (!(facing < 0))
      return false;
    // A true hole through the solid, small as it may be (an anchor's eye),
    // is sampled surface: its triangles lie across the samples' poles, as
    // everywhere on the surface. A tunnel the labelling made runs through
    // the solid, its triangles at an angle to the poles of their corners.
    double align = 0, weight = 0;
    for (uint32_t t : region) {
      const uint32_t *v = &tris[3 * size_t(t)];
      double nrm[3];
      triangle_normal(xyz, v[0], v[1], v[2], nrm);
      const double area = std::sqrt(dot3(nrm, nrm));
      for (int c = 0; c < 3 && area > 0; ++c) {
        const double *p = poles + 3 * size_t(v[c]);
        const double lp = std::sqrt(dot3(p, p));
        if (lp > 0) {
          align += std::fabs(dot3(nrm, p)) / lp;
          weight += area;
        }
      }
    }
    return weight > 0 && align < kTunnelAlign * weight;
  };
  const uint8_t kind = poles ? kTube : kHandle;
  for (size_t v = 0; v < n; ++v) {
    if (holds[v] != kind || covered[v])
      continue;
    (void)probe.handle_at(uint32_t(v)); // its region again
    const std::vector<uint32_t> &region = probe.region();
    if (kind == kTube && !tunnel(region))
      continue;
    double area = 0;
    const size_t rim_from = rims.size();
    for (uint32_t t : region) {
      double nrm[3];
      triangle_normal(xyz, tris[3 * t], tris[3 * t + 1], tris[3 * t + 2], nrm);
      area += std::sqrt(dot3(nrm, nrm));
      if (kind == kTube)
        for (int c = 0; c < 3; ++c) {
          const uint32_t h = twin[3 * size_t(t) + c];
          if (h != kNone && !probe.in_region(h / 3))
            rims.push_back(h / 3);
        }
    }
    sites.push_back({area, site_tris.size(), site_tris.size() + region.size(),
                     rim_from, rims.size()});
    site_tris.insert(site_tris.end(), region.begin(), region.end());
    for (uint32_t w : probe.verts())
      covered[w] = 1;
  }
  if (sites.empty())
    return 0;
  // The smallest first: the tightest handles. A tube is one only where
  // cutting it leaves its two sides joined, with the sites taken before it
  // cut too (a tunnel; across a thin part, a leg or a finger, it would cut
  // the part off).
  std::stable_sort(
      sites.begin(), sites.end(),
      [](const Site &a, const Site &b) { return a.area < b.area; });
  std::vector<uint32_t> stamp(nt, 0), queue;
  uint32_t round = 0;
  auto sides_joined = [&](const Site &st) {
    ++round;
    size_t left = 0;
    for (size_t k = st.rim_from; k < st.rim_to; ++k)
      if (!cut[rims[k]] && stamp[rims[k]] != round) {
        stamp[rims[k]] = round; // round: a rim triangle not yet reached
        ++left;
      }
    if (left == 0)
      return false;
    ++round; // round: reached
    queue.clear();
    for (size_t k = st.rim_from; k < st.rim_to && queue.empty(); ++k)
      if (!cut[rims[k]]) {
        queue.push_back(rims[k]);
        stamp[rims[k]] = round;
        --left;
      }
    for (size_t q = 0; q < queue.size() && left > 0; ++q)
      for (int c = 0; c < 3; ++c) {
        const uint32_t h = twin[3 * size_t(queue[q]) + c];
        if (h == kNone || cut[h / 3] || stamp[h / 3] == round)
          continue;
        if (stamp[h / 3] == round - 1)
          --left;
        stamp[h / 3] = round;
        queue.push_back(h / 3);
      }
    return left == 0;
  };
  size_t taken = 0;
  for (const Site &st : sites) {
    if (taken == max_sites)
      break;
    for (size_t k = st.from; k < st.to; ++k)
      cut[site_tris[k]] = 1;
    if (st.rim_to > st.rim_from && !sides_joined(st)) {
      for (size_t k = st.from; k < st.to; ++k)
        cut[site_tris[k]] = 0;
      continue;
    }
    ++taken;
  }
  if (taken == 0)
    return 0;
  std::vector<uint32_t> kept;
  kept.reserve(tris.size());
  for (size_t t = 0; t < nt; ++t)
    if (!cut[t])
      kept.insert(kept.end(), &tris[3 * t], &tris[3 * t] + 3);
  tris.swap(kept);
  return taken;
}

} // namespace sc
