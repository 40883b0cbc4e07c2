// Hole filling: each boundary loop of a manifold surface is closed by the
// patch of least area that adds no edge the surface has already; long
// loops are first cut into pieces by short chords.
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include "edges.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sc {
namespace {

// Boundary mode leaves open the loops of at least this many edges that run
// mostly through samples whose cells open sideways (see fill_holes()).
constexpr size_t kMinOpenLoop = 8;
// Loops longer than this are cut into pieces before they are patched: the
// least-area patch costs the cube of the length. (Measured on the bunny
// scans against 32: patches half the time, their area a few tenths of a
// percent of the surface's larger, the same loops and genus, as many
// samples kept or more.)
constexpr size_t kMaxPatch = 16;
// A loop narrower than this many of its edges (median length) is a slit:
// see is_slit().
constexpr double kSlitWidth = 1.0;

// Whether the triangle {a, b, c} is in tris, looked up through edge ab.
bool is_triangle_of(const EdgeTable &et, const std::vector<uint32_t> &tris,
                    uint32_t a, uint32_t b, uint32_t c) {
  uint64_t k = edge_key(a, b);
  auto it = std::lower_bound(
      et.entries.begin(), et.entries.end(), k,
      [](const EdgeTable::Entry &x, uint64_t key) { return x.key < key; });
  for (; it != et.entries.end() && it->key == k; ++it) {
    const uint32_t *t = &tris[3 * size_t(it->tri)];
    if (t[0] == c || t[1] == c || t[2] == c)
      return true;
  }
  return false;
}

// Each vertex's neighbours along the surface's edges, and along the chords
// added by earlier fills, which count as existing edges too: two holes that
// share vertices must not both add the same chord. A chord is two links,
// one in the list of each end, so that the chords of a hole that cannot be
// filled come off again in reverse.
class Neighbours {
public:
  Neighbours(size_t n, const EdgeTable &et)
      : adj_first_(n + 1, 0), adj_(2 * et.edges()) {
    for (size_t e = 0; e < et.edges(); ++e) {
      const uint64_t k = et.entries[et.first[e]].key;
      ++adj_first_[key_lo(k) + 1];
      ++adj_first_[uint32_t(k) + 1];
    }
    for (size_t v = 0; v < n; ++v)
      adj_first_[v + 1] += adj_first_[v];
    {
      std::vector<uint32_t> fill(adj_first_.begin(), adj_first_.end() - 1);
      for (size_t e = 0; e < et.edges(); ++e) {
        const uint64_t k = et.entries[et.first[e]].key;
        adj_[fill[key_lo(k)]++] = uint32_t(k);
        adj_[fill[uint32_t(k)]++] = key_lo(k);
      }
    }
    chord_head_.assign(n, UINT32_MAX);
  }

  void add_chord(uint64_t k) {
    const uint32_t a = key_lo(k), b = uint32_t(k);
    links_.push_back({b, chord_head_[a]});
    chord_head_[a] = uint32_t(links_.size() - 1);
    links_.push_back({a, chord_head_[b]});
    chord_head_[b] = uint32_t(links_.size() - 1);
  }
  // Where the chords stand now, for drop_chords_to().
  size_t mark() const { return links_.size(); }
  // Takes off the chords added since mark() gave `mark`.
  void drop_chords_to(size_t mark) {
    for (; links_.size() > mark; links_.resize(links_.size() - 2)) {
      const size_t i = links_.size() - 2;
      chord_head_[links_[i + 1].other] = links_[i].next;
      chord_head_[links_[i].other] = links_[i + 1].next;
    }
  }
  // Calls visit(w) on every vertex w joined to a by an edge or a chord.
  template <class Visit> void for_each(uint32_t a, Visit &&visit) const {
    for (uint32_t i = adj_first_[a]; i < adj_first_[a + 1]; ++i)
      visit(adj_[i]);
    for (uint32_t i = chord_head_[a]; i != UINT32_MAX; i = links_[i].next)
      visit(links_[i].other);
  }
  bool has_edge(uint32_t a, uint32_t b) const {
    bool joined = false;
    for_each(a, [&](uint32_t w) { joined = joined || w == b; });
    return joined;
  }

private:
  struct Link {
    uint32_t other, next;
  };
  std::vector<uint32_t> adj_first_, adj_;
  std::vector<uint32_t> chord_head_;
  std::vector<Link> links_;
};

// Patches the loop (vertex numbers in order; the hole runs along it) with
// the triangulation of least total area whose chords are all new edges, and
// appends its triangles to res and its chords to `chords`. The edge from the
// last vertex back to the first is part of the loop. nb tells the vertices
// joined to each by an edge; pos is scratch, n entries
// of UINT32_MAX, left so. Returns false when no such triangulation exists.
bool patch(const double *xyz, const std::vector<uint32_t> &loop,
           const Neighbours &nb, std::vector<uint32_t> &pos,
           std::vector<uint8_t> &joined, std::vector<double> &cost,
           std::vector<double> &costT, std::vector<uint32_t> &split,
           std::vector<uint32_t> &res, std::vector<uint64_t> &chords) {
  const size_t L = loop.size();
  // Which of the loop's vertices are joined already, from their neighbours
  // (the programme below asks about every pair).
  for (size_t i = 0; i < L; ++i)
    pos[loop[i]] = uint32_t(i);
  joined.assign(L * L, 0);
  for (size_t i = 0; i < L; ++i)
    nb.for_each(loop[i], [&](uint32_t w) {
      if (pos[w] != UINT32_MAX)
        joined[i * L + pos[w]] = 1;
    });
  for (size_t i = 0; i < L; ++i)
    pos[loop[i]] = UINT32_MAX;
  // The loop's points side by side: the triple loop below reads them
  // L^3 / 6 times.
  std::vector<double> p(3 * L);
  for (size_t i = 0; i < L; ++i)
    std::memcpy(&p[3 * i], xyz + 3 * size_t(loop[i]), 3 * sizeof(double));
  auto area = [&](size_t i, size_t k, size_t j) {
    const double *a = &p[3 * i], *b = &p[3 * k], *c = &p[3 * j];
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double x = u[1] * w[2] - u[2] * w[1], y = u[2] * w[0] - u[0] * w[2],
           z = u[0] * w[1] - u[1] * w[0];
    return std::sqrt(x * x + y * y + z * z);
  };
  const double inf = std::numeric_limits<double>::infinity();
  // cost[i L + j]: the least area over the sub-loop i..j; costT holds the
  // same numbers transposed, so that the inner loop reads both of its
  // operands along rows.
  cost.assign(L * L, inf);
  costT.assign(L * L, inf);
  split.assign(L * L, UINT32_MAX);
  for (size_t i = 0; i + 1 < L; ++i)
    cost[i * L + i + 1] = costT[(i + 1) * L + i] = 0;
  for (size_t len = 2; len < L; ++len) {
    for (size_t i = 0; i + len < L; ++i) {
      size_t j = i + len;
      // (0, L-1) is a loop edge; any other chord must be a new edge.
      if (!(i == 0 && j == L - 1) && joined[i * L + j])
        continue;
      const double *left = &cost[i * L], *right = &costT[j * L];
      double best = inf;
      uint32_t best_k = UINT32_MAX;
      for (size_t k = i + 1; k < j; ++k) {
        // An area is never negative: a split that already costs as much as
        // the best one so far (or cannot be done) is not worth the area.
        double c = left[k] + right[k];
        if (!(c < best))
          continue;
        c += area(i, k, j);
        if (c < best) {
          best = c;
          best_k = uint32_t(k);
        }
      }
      cost[i * L + j] = costT[j * L + i] = best;
      split[i * L + j] = best_k;
    }
  }
  if (cost[L - 1] == inf)
    return false;
  std::vector<std::pair<size_t, size_t>> stack{{0, L - 1}};
  while (!stack.empty()) {
    auto [i, j] = stack.back();
    stack.pop_back();
    if (j - i < 2)
      continue;
    size_t k = split[i * L + j];
    res.push_back(loop[i]);
    res.push_back(loop[k]);
    res.push_back(loop[j]);
    if (k - i > 1)
      chords.push_back(edge_key(loop[i], loop[k]));
    if (j - k > 1)
      chords.push_back(edge_key(loop[k], loop[j]));
    stack.push_back({i, k});
    stack.push_back({k, j});
  }
  return true;
}

// Cuts a loop in two by its shortest new chord between vertices about half
// the loop apart: `loop` keeps the part from one end of the chord to the
// other, `rest` gets the other part; both then end with the chord. Returns
// false when every such chord is an edge already.
bool cut_loop(const double *xyz, std::vector<uint32_t> &loop,
              std::vector<uint32_t> &rest, const Neighbours &nb) {
  const size_t L = loop.size(), half = L / 2, window = L / 8;
  double best = std::numeric_limits<double>::infinity();
  size_t bi = 0, bj = 0;
  // The loop's points side by side, one and a half times over, so that the
  // window after any vertex is one run of the array. The chords wanted are
  // those whose ends are at least half - window apart along the loop either
  // way; each is read once, from the end after which the other is at most
  // half along (an even loop's middle chords twice): L^2 / 8 pairs.
  std::vector<double> p(3 * (L + half));
  for (size_t i = 0; i < L + half; ++i)
    std::memcpy(&p[3 * i], xyz + 3 * size_t(loop[i < L ? i : i - L]),
                3 * sizeof(double));
  auto shortest = [&](bool new_only) {
    best = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < L; ++i) {
      const double *a = &p[3 * i];
      for (size_t j = i + half - window; j <= i + half; ++j) {
        const double *b = &p[3 * j];
        double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
        double d2 = dx * dx + dy * dy + dz * dz;
        if (d2 < best) {
          const size_t jj = j < L ? j : j - L;
          if (loop[i] != loop[jj] &&
              (!new_only || !nb.has_edge(loop[i], loop[jj])))
            best = d2, bi = i, bj = jj;
        }
      }
    }
  };
  // The shortest chord of all is nearly always a new edge, and then it is
  // the shortest new one: asking about the neighbours of only that chord,
  // not of every chord that was the shortest so far, saves most of the
  // search's time. Only if it is an edge already is the search run again.
  shortest(false);
  if (best < std::numeric_limits<double>::infinity() &&
      nb.has_edge(loop[bi], loop[bj]))
    shortest(true);
  if (!(best < std::numeric_limits<double>::infinity()))
    return false;
  // Each part, from one end of the chord round to the other.
  auto part = [&](size_t from, size_t to, std::vector<uint32_t> &out) {
    out.resize((to + L - from) % L + 1);
    for (size_t k = 0; k < out.size(); ++k)
      out[k] = loop[(from + k) % L];
  };
  std::vector<uint32_t> a;
  part(bi, bj, a);
  part(bj, bi, rest);
  loop.swap(a);
  return true;
}

// A loop's width (vertex numbers in order), in its edges' median length:
// twice its vector area over its length, the width of a long thin strip,
// the radius of a round hole.
double loop_width(const double *xyz, const std::vector<uint32_t> &loop) {
  const size_t k = loop.size();
  const double *o = xyz + 3 * size_t(loop[0]);
  double area[3] = {0, 0, 0}, length = 0;
  std::vector<double> edge(k);
  for (size_t i = 0; i < k; ++i) {
    const double *p = xyz + 3 * size_t(loop[i]),
                 *q = xyz + 3 * size_t(loop[(i + 1) % k]);
    const double a[3] = {p[0] - o[0], p[1] - o[1], p[2] - o[2]},
                 b[3] = {q[0] - o[0], q[1] - o[1], q[2] - o[2]};
    area[0] += a[1] * b[2] - a[2] * b[1];
    area[1] += a[2] * b[0] - a[0] * b[2];
    area[2] += a[0] * b[1] - a[1] * b[0];
    edge[i] = std::sqrt(dist2(p, q));
    length += edge[i];
  }
  std::nth_element(edge.begin(), edge.begin() + k / 2, edge.end());
  const double unit = length * edge[k / 2];
  return unit > 0 ? std::sqrt(dot3(area, area)) / unit
                  : std::numeric_limits<double>::infinity();
}

// Whether a loop (vertex numbers in order) is a slit: narrower than
// kSlitWidth of its edges (loop_width(); a round hole of 8 edges or more
// is never that narrow). Such a strip of missing triangles is what the
// candidate tests leave along a sharp edge or a crease, where the cells of
// the samples open sideways as at the end of a surface; a hole in the
// surface itself, a scan's edge or the gap between scans, is wide.
// (Measured: the loops that boundary mode left open along the sharp edges
// and thin parts of closed models, 0.3 to 2 of an edge, most under 1; the
// bunny scans' edges and holes, 4 to 38.)
bool is_slit(const double *xyz, const std::vector<uint32_t> &loop) {
  return loop_width(xyz, loop) <= kSlitWidth;
}

// Calls take(loop, ok) for each boundary loop of the surface res (vertex
// numbers in order; the hole runs along it): ok is false for a loop that
// passes a vertex where two boundary edges leave, or does not close.
template <class Take>
void for_each_loop(size_t n, const EdgeTable &et,
                   const std::vector<uint32_t> &res, Take &&take) {
  // The hole runs against the orientation of the triangle on each boundary
  // edge: a triangle with x -> y leaves the hole edge y -> x.
  std::vector<uint32_t> next(n, UINT32_MAX);
  std::vector<uint8_t> bad(n, 0);
  for (size_t e = 0; e < et.edges(); ++e) {
    if (et.first[e + 1] - et.first[e] != 1)
      continue;
    const EdgeTable::Entry &en = et.entries[et.first[e]];
    const uint32_t *t = &res[3 * size_t(en.tri)];
    for (int k = 0; k < 3; ++k) {
      uint32_t x = t[k], y = t[(k + 1) % 3];
      if (edge_key(x, y) != en.key)
        continue;
      if (next[y] != UINT32_MAX)
        bad[y] = 1;
      next[y] = x;
    }
  }
  std::vector<uint32_t> loop;
  std::vector<uint8_t> seen(n, 0);
  for (uint32_t v0 = 0; v0 < n; ++v0) {
    if (next[v0] == UINT32_MAX || seen[v0])
      continue;
    loop.clear();
    bool ok = true;
    uint32_t v = v0;
    while (!seen[v]) {
      seen[v] = 1;
      ok = ok && !bad[v];
      loop.push_back(v);
      v = next[v];
      if (v == UINT32_MAX) {
        ok = false;
        break;
      }
    }
    take(loop, ok && v == v0);
  }
}

// The loops of the surface's holes that are to be filled, shortest first:
// each a loop of at most max_loop edges (vertex numbers in order; the hole
// runs along it) and not where the surface ends (see below), or a slit of
// any length (is_slit()) where max_loop is not 0.
std::vector<std::vector<uint32_t>>
holes_to_fill(const double *xyz, size_t n, const EdgeTable &et,
              const std::vector<uint32_t> &res, size_t max_loop,
              const std::vector<uint8_t> &boundary) {
  std::vector<std::vector<uint32_t>> loops;
  for_each_loop(n, et, res, [&](const std::vector<uint32_t> &loop, bool ok) {
    if (!ok || loop.size() < 3 || max_loop == 0)
      return;
    const bool slit = loop.size() >= kMinOpenLoop && is_slit(xyz, loop);
    if (loop.size() > max_loop && !slit)
      return;
    // A loop of at least kMinOpenLoop edges, most of whose samples failed
    // the ratio test (their Voronoi cells open sideways), is where the
    // surface ends, not a hole left by a missing triangle. Loops through
    // samples that are boundary samples only for disagreeing poles (stray
    // samples, thin parts such as the bunny's ears) are closed like any
    // other hole.
    if (!boundary.empty() && loop.size() >= kMinOpenLoop && !slit) {
      size_t opens = 0;
      for (uint32_t w : loop)
        opens += boundary[w] == kOpenSample;
      if (2 * opens >= loop.size())
        return;
    }
    // A three-edge loop around a lone triangle would be closed by a second
    // copy of that triangle.
    if (loop.size() == 3 &&
        is_triangle_of(et, res, loop[0], loop[1], loop[2]))
      return;
    loops.push_back(loop);
  });
  // Shortest first: when the work runs out, the many small holes are
  // closed and a few long ones stay open, not the other way round.
  std::stable_sort(loops.begin(), loops.end(),
                   [](const std::vector<uint32_t> &a,
                      const std::vector<uint32_t> &b) {
                     return a.size() < b.size();
                   });
  return loops;
}

// The scratch of the patches, kept from one hole to the next; pos holds
// n entries of UINT32_MAX between patches.
struct PatchScratch {
  std::vector<std::vector<uint32_t>> pieces;
  std::vector<double> cost, costT;
  std::vector<uint32_t> split, pos;
  std::vector<uint8_t> joined;
  explicit PatchScratch(size_t n) : pos(n, UINT32_MAX) {}
};

// Fills one hole, within max_work steps of the dynamic programme (less the
// steps taken on return): a long loop is first cut by short chords into
// pieces of at most kMaxPatch edges; the pieces are patched one by one, and
// the hole is filled only if all of them are. Otherwise res and the chords
// are left as they were, and returns false.
bool fill_hole(const double *xyz, const std::vector<uint32_t> &hole,
               Neighbours &nb, PatchScratch &scratch, uint64_t &max_work,
               std::vector<uint32_t> &res) {
  std::vector<std::vector<uint32_t>> &pieces = scratch.pieces;
  pieces.assign(1, hole);
  const size_t mark = nb.mark();
  bool cut_ok = true;
  for (size_t p = 0; p < pieces.size() && cut_ok; ++p) {
    while (pieces[p].size() > kMaxPatch) {
      std::vector<uint32_t> rest;
      if (!cut_loop(xyz, pieces[p], rest, nb)) {
        cut_ok = false;
        break;
      }
      const std::vector<uint32_t> &q = pieces[p];
      nb.add_chord(edge_key(q.front(), q.back()));
      pieces.push_back(std::move(rest));
    }
  }
  uint64_t work = 0;
  for (const auto &q : pieces)
    work += uint64_t(q.size()) * q.size() * q.size() / 6;
  const size_t before = res.size();
  std::vector<uint64_t> added_chords;
  bool ok_all = cut_ok && work <= max_work;
  for (size_t p = 0; p < pieces.size() && ok_all; ++p)
    ok_all = patch(xyz, pieces[p], nb, scratch.pos, scratch.joined,
                   scratch.cost, scratch.costT, scratch.split, res,
                   added_chords);
  if (!ok_all) {
    // Not all pieces could be patched: leave the hole as it was.
    res.resize(before);
    nb.drop_chords_to(mark);
    return false;
  }
  max_work -= work;
  for (uint64_t k : added_chords)
    nb.add_chord(k);
  return true;
}

} // namespace

// Closes the holes of an edge-manifold, consistently oriented, vertex-
// manifold surface whose boundary loops have at most max_loop edges. Each
// hole is triangulated over its own loop by dynamic programming for the
// least total area, never creating an edge the surface already has, so the
// result stays a manifold.
void fill_holes(const double *xyz, size_t n, std::vector<uint32_t> &res,
                size_t max_loop, const std::vector<uint8_t> &boundary,
                Progress &progress, sc_diag_t &diag, uint64_t max_work,
                EdgeTable *table) {
  // (Built only when needed: a table takes the pools' largest arrays.)
  std::unique_ptr<EdgeTable> own;
  if (!table) {
    own.reset(new EdgeTable);
    table = own.get();
  }
  if (table->first.empty())
    table->build(xyz, n, res, progress, false);
  if (res.empty())
    return;
  const EdgeTable &et = *table;
  const size_t unfilled = res.size() / 3;
  Neighbours nb(n, et);
  const std::vector<std::vector<uint32_t>> loops =
      holes_to_fill(xyz, n, et, res, max_loop, boundary);
  PatchScratch scratch(n);
  for (const std::vector<uint32_t> &hole : loops) {
    const size_t before = res.size();
    if (!fill_hole(xyz, hole, nb, scratch, max_work, res))
      continue;
    const size_t added = (res.size() - before) / 3;
    ++diag.holes_filled;
    diag.hole_triangles += added;
  }
  // The patches' triangles join the caller's table.
  if (!own)
    table->append(n, res, unfilled, progress);
}

double widest_loop(const double *xyz, size_t n,
                   const std::vector<uint32_t> &tris, Progress &progress) {
  if (tris.empty())
    return 0;
  EdgeTable et;
  et.build(xyz, n, tris, progress, false);
  double widest = 0;
  for_each_loop(n, et, tris, [&](const std::vector<uint32_t> &loop, bool ok) {
    widest = std::max(widest, ok && loop.size() >= 3
                                  ? loop_width(xyz, loop)
                                  : std::numeric_limits<double>::infinity());
  });
  return widest;
}

} // namespace sc
