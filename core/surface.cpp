// Sharp-edge pruning and manifold extraction over the candidate triangles.
// Nothing here needs the Delaunay triangulation: only the points and the
// candidates, so the triangulation is freed before these stages run.
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include "internal.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>

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
// canonical_order() sorts in two passes, first to at most this many ranges
// of vertex numbers.
constexpr uint64_t kCanonRanges = 2048;

double dot3(const double *x, const double *y) {
  return x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
}

inline uint64_t edge_key(uint32_t a, uint32_t b) {
  return a < b ? (uint64_t(a) << 32) | b : (uint64_t(b) << 32) | a;
}
inline uint32_t key_lo(uint64_t k) { return uint32_t(k >> 32); }

// A stable sort of one bucket of a counting sort. Buckets are nearly always
// a few items, for which an inline insertion sort costs least (a call to
// std::sort per bucket cost more than the sorting).
template <class T, class Less> void sort_bucket(T *b, size_t m, Less less) {
  if (m > 32) {
    std::stable_sort(b, b + m, less);
    return;
  }
  for (size_t i = 1; i < m; ++i) {
    const T x = b[i];
    size_t j = i;
    for (; j > 0 && less(x, b[j - 1]); --j)
      b[j] = b[j - 1];
    b[j] = x;
  }
}

// The large arrays of the edge tables and vertex stars, which one
// reconstruction builds a dozen times over, go back to a per-thread pool
// when their table is done, and the next table takes the largest: pages the
// kernel has already mapped, instead of fresh ones faulted in one at a time
// (a fifth of the extraction time on the merged scans). release_scratch()
// empties the pools at the end of each reconstruction.
template <class T> struct Pool {
  std::vector<std::vector<T>> spare;
  std::vector<T> take() {
    if (spare.empty())
      return {};
    auto best = std::max_element(spare.begin(), spare.end(),
                                 [](const std::vector<T> &a,
                                    const std::vector<T> &b) {
                                   return a.capacity() < b.capacity();
                                 });
    std::vector<T> v = std::move(*best);
    spare.erase(best);
    v.clear();
    return v;
  }
  void give(std::vector<T> &v) {
    if (v.capacity() >= (size_t(1) << 16) && spare.size() < 8)
      spare.push_back(std::move(v));
  }
};
thread_local Pool<uint32_t> u32_pool;

} // namespace

// Every candidate edge with its triangles in the cyclic order in which they
// appear when rotating about the edge, right-handed about the direction from
// its smaller to its larger vertex index.
struct EdgeTable {
  struct Entry {
    uint64_t key;
    uint32_t tri;
    uint8_t corner; // the edge is (v[corner], v[corner + 1]) of tri
    // Left uninitialised: build() writes every entry of a table sized up
    // front, and zeroing it first was a pass over memory of its own.
    Entry() {}
    Entry(uint64_t k, uint32_t t, uint8_t c) : key(k), tri(t), corner(c) {}
  };
  std::vector<Entry> entries;   // grouped by edge, each group by angle
  std::vector<uint32_t> first;  // edge id -> first entry; one extra at end
  // 3 per triangle: edge (v[k], v[k+1]). Only pruning and the walk find
  // edges by triangle: tables built without angles, or appended to, leave
  // it empty, and so does keep_live() unless asked (filling it was a
  // scattered write per entry).
  std::vector<uint32_t> tri_edge;
  // Per entry, its triangle's angle about the edge in quarter turns
  // (Frame::quarters()), from build() with angles until keep_live(): only
  // pruning compares angles, and the passes after it read 16-byte entries.
  std::vector<double> angle;

  static thread_local Pool<Entry> entry_pool;
  EdgeTable()
      : entries(entry_pool.take()), first(u32_pool.take()),
        tri_edge(u32_pool.take()) {}
  ~EdgeTable() {
    entry_pool.give(entries);
    u32_pool.give(first);
    u32_pool.give(tri_edge);
  }
  EdgeTable(const EdgeTable &) = delete;
  EdgeTable &operator=(const EdgeTable &) = delete;

  size_t edges() const { return first.size() - 1; }

  // Without `angles`, the triangles of an edge come in the order of their
  // numbers, and `angle` and tri_edge are empty: enough for finding edges
  // and their triangles, and it saves a frame per edge. (With them, an edge
  // of a single triangle has angle 0 too, for nothing compares it, and an
  // edge of two has angles 0 and 0 or 2 quarters: see below.)
  void build(const double *xyz, size_t n, const std::vector<uint32_t> &tris,
             Progress &progress, bool angles = true) {
    const size_t nt = tris.size() / 3;
    // Bucket the entries by their smaller vertex (a counting sort), then
    // sort each small bucket: linear overall, unlike one global sort.
    std::vector<uint32_t> count(n + 1, 0);
    for (size_t i = 0; i < 3 * nt; ++i) {
      uint32_t a = tris[i], b = tris[i % 3 == 2 ? i - 2 : i + 1];
      ++count[std::min(a, b) + 1];
    }
    for (size_t v = 0; v < n; ++v)
      count[v + 1] += count[v];
    entries.resize(3 * nt);
    std::vector<uint32_t> fill(count.begin(), count.end() - 1);
    for (size_t t = 0; t < nt; ++t) {
      progress.tick(t, 2 * nt);
      for (int k = 0; k < 3; ++k) {
        uint32_t a = tris[3 * t + k], b = tris[3 * t + (k + 1) % 3];
        entries[fill[std::min(a, b)]++] = {edge_key(a, b), uint32_t(t),
                                           uint8_t(k)};
      }
    }
    // A bucket holds a vertex's edges, filled in triangle order: a stable
    // sort by key alone, which keeps that order among the triangles of an
    // edge, sorts it by (key, triangle).
    for (size_t v = 0; v < n; ++v)
      sort_bucket(entries.data() + count[v], count[v + 1] - count[v],
                  [](const Entry &x, const Entry &y) { return x.key < y.key; });
    index_edges(nt, &progress, angles);
    angle.clear();
    if (!angles)
      return;
    angle.resize(entries.size());
    // Each edge's frame once, then its triangles by angle (ties by number).
    for (size_t e = 0; e + 1 < first.size(); ++e) {
      Entry *x = &entries[first[e]];
      double *ang = &angle[first[e]];
      const uint32_t k = first[e + 1] - first[e];
      if (k < 2) {
        ang[0] = 0;
        continue;
      }
      if (k == 2) {
        // Two triangles are in either order about their edge, and all
        // that is asked of their angles is whether they are less than a
        // right angle apart (is_sharp()): angles 0 and 0 if they are, 0
        // and a half turn if not. The sign of the dot product of the two
        // triangles' directions across the edge tells, without an atan2.
        const double *a = xyz + 3 * size_t(key_lo(x->key)),
                     *b = xyz + 3 * size_t(uint32_t(x->key));
        const double *p = xyz + 3 * size_t(third(tris, x[0])),
                     *q = xyz + 3 * size_t(third(tris, x[1]));
        double u[3], w1[3], w2[3];
        for (int j = 0; j < 3; ++j)
          u[j] = b[j] - a[j], w1[j] = p[j] - a[j], w2[j] = q[j] - a[j];
        const double across =
            dot3(w1, w2) * dot3(u, u) - dot3(w1, u) * dot3(w2, u);
        ang[0] = 0;
        ang[1] = across > 0 ? 0.0 : 2.0;
        continue;
      }
      const Frame f(xyz, key_lo(x->key), uint32_t(x->key));
      for (uint32_t i = 0; i < k; ++i)
        ang[i] = f.quarters(xyz, third(tris, x[i]));
      for (uint32_t i = 1; i < k; ++i)
        for (uint32_t j = i;
             j > 0 && (ang[j] < ang[j - 1] ||
                       (ang[j] == ang[j - 1] && x[j].tri < x[j - 1].tri));
             --j) {
          std::swap(x[j], x[j - 1]);
          std::swap(ang[j], ang[j - 1]);
        }
    }
  }

  // Keeps only the entries of triangles with alive[t] set, renumbered in
  // order (the k-th live triangle becomes k): the table that build() would
  // give for the live triangles alone, without sorting or angles again.
  // The angles go: the order of each edge's triangles stays.
  void keep_live(const std::vector<uint8_t> &alive, bool with_tri_edge) {
    angle = std::vector<double>();
    std::vector<uint32_t> renum(alive.size());
    uint32_t nl = 0;
    for (size_t t = 0; t < alive.size(); ++t)
      renum[t] = alive[t] ? nl++ : UINT32_MAX;
    tri_edge.assign(with_tri_edge ? 3 * size_t(nl) : 0, 0);
    size_t out = 0, edges = 0;
    for (size_t e = 0; e + 1 < first.size(); ++e) {
      const size_t start = out;
      for (uint32_t i = first[e]; i < first[e + 1]; ++i) {
        const Entry &x = entries[i];
        if (!alive[x.tri])
          continue;
        entries[out] = {x.key, renum[x.tri], x.corner};
        if (with_tri_edge)
          tri_edge[3 * size_t(entries[out].tri) + x.corner] = uint32_t(edges);
        ++out;
      }
      if (out > start)
        first[edges++] = uint32_t(start);
    }
    entries.resize(out);
    first.resize(edges);
    first.push_back(uint32_t(out));
  }

  // Adds the triangles from number first_new of tris on (those before it
  // are the table's): the table of all of tris, as build() would give it
  // without angles but for the order of each edge's old triangles, which
  // stay as they were, before the new ones. Merging the new triangles'
  // sorted entries into the table, from the back and in place (no fresh
  // memory), costs less than building the table again.
  void append(size_t n, const std::vector<uint32_t> &tris, size_t first_new,
              Progress &progress) {
    const size_t nt = tris.size() / 3;
    if (first_new >= nt)
      return;
    angle = std::vector<double>();
    const std::vector<uint32_t> added(tris.begin() + 3 * first_new,
                                      tris.end());
    EdgeTable more;
    more.build(nullptr, n, added, progress, false);
    size_t i = entries.size(), j = more.entries.size();
    entries.resize(i + j);
    for (size_t out = entries.size(); j > 0; --out) {
      // Of equal keys the new entries go last.
      if (i > 0 && entries[i - 1].key > more.entries[j - 1].key) {
        entries[out - 1] = entries[--i];
      } else {
        entries[out - 1] = more.entries[--j];
        entries[out - 1].tri += uint32_t(first_new);
      }
    }
    index_edges(nt, nullptr, false);
  }

  // first, and tri_edge if asked, from the entries, sorted by key, of nt
  // triangles (ticking the second half of build()'s progress when given).
  void index_edges(size_t nt, Progress *progress, bool with_tri_edge) {
    first.clear();
    tri_edge.assign(with_tri_edge ? 3 * nt : 0, 0);
    for (size_t i = 0; i < entries.size(); ++i) {
      if (progress)
        progress->tick(nt + i / 3, 2 * nt);
      if (i == 0 || entries[i].key != entries[i - 1].key)
        first.push_back(uint32_t(i));
      if (with_tri_edge)
        tri_edge[3 * size_t(entries[i].tri) + entries[i].corner] =
            uint32_t(first.size() - 1);
    }
    first.push_back(uint32_t(entries.size()));
  }

  // The vertex of entry x's triangle that is not on its edge.
  static uint32_t third(const std::vector<uint32_t> &tris, const Entry &x) {
    return tris[3 * size_t(x.tri) + (x.corner + 2) % 3];
  }

  // Angles of the half-planes through edge lo-hi, about a frame of the
  // edge: u along it, e1 and e2 across it.
  struct Frame {
    const double *a;
    double e1[3], e2[3];
    Frame(const double *xyz, uint32_t lo, uint32_t hi) {
      a = xyz + 3 * size_t(lo);
      const double *b = xyz + 3 * size_t(hi);
      double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
      double lu = std::sqrt(dot3(u, u));
      u[0] /= lu, u[1] /= lu, u[2] /= lu;
      // A reference direction perpendicular to u, from the coordinate axis
      // least aligned with it; any fixed choice works as long as it is the
      // same for every triangle on the edge.
      int m = std::fabs(u[0]) <= std::fabs(u[1])
                  ? (std::fabs(u[0]) <= std::fabs(u[2]) ? 0 : 2)
                  : (std::fabs(u[1]) <= std::fabs(u[2]) ? 1 : 2);
      double ax[3] = {0, 0, 0};
      ax[m] = 1;
      e1[0] = u[1] * ax[2] - u[2] * ax[1];
      e1[1] = u[2] * ax[0] - u[0] * ax[2];
      e1[2] = u[0] * ax[1] - u[1] * ax[0];
      double l1 = std::sqrt(dot3(e1, e1));
      e1[0] /= l1, e1[1] /= l1, e1[2] /= l1;
      e2[0] = u[1] * e1[2] - u[2] * e1[1];
      e2[1] = u[2] * e1[0] - u[0] * e1[2];
      e2[2] = u[0] * e1[1] - u[1] * e1[0];
    }
    // The angle of the half-plane that contains point c, in quarter
    // turns: -2 to 2 as atan2 goes from -pi to pi, for a division instead
    // of an atan2. Within each quarter it is the fraction that one
    // coordinate is of the sum of their sizes, which grows with the angle,
    // and a direction turned by a quarter gets exactly 1 more; so quarters
    // order half-planes as angles do, and a gap of more than three quarters
    // is one of more than three right angles (but for rounding, which
    // moves either test only at a gap of exactly three right angles).
    double quarters(const double *xyz, uint32_t c) const {
      const double *p = xyz + 3 * size_t(c);
      double w[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
      const double x = dot3(w, e1), y = dot3(w, e2);
      if (x == 0 && y == 0)
        return 0; // c on the edge's line: no candidate is that degenerate
      if (!std::signbit(y))
        return x >= 0 ? y / (x + y) : 1 + -x / (y - x);
      return x < 0 ? -2 + -y / (-x - y) : -1 + x / (x - y);
    }
  };
};

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

struct UnionFind {
  std::vector<uint32_t> parent;
  explicit UnionFind(size_t n) : parent(n) {
    std::iota(parent.begin(), parent.end(), 0u);
  }
  uint32_t find(uint32_t x) {
    while (parent[x] != x)
      x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(uint32_t a, uint32_t b) {
    a = find(a), b = find(b);
    if (a != b)
      parent[std::max(a, b)] = std::min(a, b);
  }
};

// Vertex -> incident triangles, over the triangles that `keep` accepts.
struct VertexStar {
  std::vector<uint32_t> first, tris;
  VertexStar() : first(u32_pool.take()), tris(u32_pool.take()) {}
  ~VertexStar() {
    u32_pool.give(first);
    u32_pool.give(tris);
  }
  VertexStar(const VertexStar &) = delete;
  VertexStar &operator=(const VertexStar &) = delete;
  template <class Keep>
  void build(size_t n, const std::vector<uint32_t> &t, Keep keep) {
    first.assign(n + 1, 0);
    const size_t nt = t.size() / 3;
    for (size_t i = 0; i < nt; ++i)
      if (keep(i))
        for (int k = 0; k < 3; ++k)
          ++first[t[3 * i + k] + 1];
    for (size_t v = 0; v < n; ++v)
      first[v + 1] += first[v];
    tris.resize(first[n]);
    std::vector<uint32_t> fill(first.begin(), first.end() - 1);
    for (size_t i = 0; i < nt; ++i)
      if (keep(i))
        for (int k = 0; k < 3; ++k)
          tris[fill[t[3 * i + k]]++] = uint32_t(i);
  }
};

// The fans of triangles around vertex v: connected pieces of its link.
// Writes a fan number per incident triangle into fan_of (same order as the
// star's list) and returns the number of fans.
int count_fans(uint32_t v, const std::vector<uint32_t> &star,
               const std::vector<uint32_t> &tris, std::vector<int> &fan_of) {
  const size_t m = star.size();
  fan_of.assign(m, -1);
  // Triangles around v are adjacent when they share an edge at v, that is
  // one of their two other vertices. Stars are small: quadratic is fine.
  // The scratch lives on between calls: this runs once per vertex.
  thread_local std::vector<uint32_t> other;
  thread_local std::vector<size_t> stack;
  other.resize(2 * m);
  for (size_t i = 0; i < m; ++i) {
    const uint32_t *t = &tris[3 * size_t(star[i])];
    int j = 0;
    for (int k = 0; k < 3; ++k)
      if (t[k] != v)
        other[2 * i + j++] = t[k];
  }
  int fans = 0;
  for (size_t s = 0; s < m; ++s) {
    if (fan_of[s] >= 0)
      continue;
    fan_of[s] = fans;
    stack.assign(1, s);
    while (!stack.empty()) {
      size_t i = stack.back();
      stack.pop_back();
      for (size_t j = 0; j < m; ++j) {
        if (fan_of[j] >= 0)
          continue;
        if (other[2 * i] == other[2 * j] || other[2 * i] == other[2 * j + 1] ||
            other[2 * i + 1] == other[2 * j] ||
            other[2 * i + 1] == other[2 * j + 1]) {
          fan_of[j] = fans;
          stack.push_back(j);
        }
      }
    }
    ++fans;
  }
  return fans;
}

// Whether the triangles around vertex v are one fan, shown by a chain
// through all of them, each sharing with the next its edge at v that the
// orientation puts last in the one and first in the next (from a triangle
// that no other one precedes, if there is one). It nearly always is; when
// no such chain is found, count_fans() decides.
bool one_fan(uint32_t v, const std::vector<uint32_t> &star,
             const std::vector<uint32_t> &tris) {
  constexpr size_t kMax = 32;
  const size_t m = star.size();
  if (m <= 1)
    return true;
  if (m > kMax)
    return false;
  uint32_t a[kMax], b[kMax]; // triangle i runs v -> a[i] -> b[i]
  for (size_t i = 0; i < m; ++i) {
    const uint32_t *t = &tris[3 * size_t(star[i])];
    const int k = t[0] == v ? 0 : t[1] == v ? 1 : 2;
    a[i] = t[(k + 1) % 3];
    b[i] = t[(k + 2) % 3];
  }
  size_t i = 0;
  for (size_t s = 0; s < m; ++s) {
    bool preceded = false;
    for (size_t j = 0; j < m && !preceded; ++j)
      preceded = b[j] == a[s];
    if (!preceded) {
      i = s;
      break;
    }
  }
  uint32_t done = 1u << i;
  size_t chained = 1;
  for (;;) {
    size_t next = m;
    for (size_t j = 0; j < m && next == m; ++j)
      if (!(done >> j & 1) && a[j] == b[i])
        next = j;
    if (next == m)
      break;
    done |= 1u << next;
    ++chained;
    i = next;
  }
  return chained == m;
}

// fix_fans() over the stars ostar of the triangles (those with in[t]
// clear are passed over, so a star of more triangles will do), starting
// from the vertices in work (any order, repeats allowed): every vertex that
// may have several fans. They are taken in vertex order, which decides
// between fans of equal size, so any list that holds those vertices gives
// the result of looking at every vertex.
void fix_fans_in(const VertexStar &ostar, const std::vector<uint32_t> &otri,
                 std::vector<uint8_t> &in, std::vector<uint32_t> work) {
  std::sort(work.begin(), work.end()); // popped from the back
  work.erase(std::unique(work.begin(), work.end()), work.end());
  // A vertex is looked at again only if it lost a triangle since it was
  // last looked at: that look left it one fan, and nothing changed. (A
  // vertex that loses several triangles is pushed for each; the first
  // pop looks, the others pass.)
  std::vector<uint8_t> changed(ostar.first.size() - 1, 0);
  for (uint32_t v : work)
    changed[v] = 1;
  std::vector<uint32_t> cur;
  std::vector<int> fan_of;
  while (!work.empty()) {
    uint32_t v = work.back();
    work.pop_back();
    if (!changed[v])
      continue;
    changed[v] = 0;
    // The triangles of the vertices next in line are scattered: ask for
    // those a few places on while this one is looked at.
    constexpr size_t kAhead = 4;
    if (work.size() >= kAhead) {
      const uint32_t w = work[work.size() - kAhead];
      for (uint32_t i = ostar.first[w]; i < ostar.first[w + 1]; ++i) {
        __builtin_prefetch(&in[ostar.tris[i]]);
        __builtin_prefetch(&otri[3 * size_t(ostar.tris[i])]);
      }
    }
    cur.clear();
    for (uint32_t i = ostar.first[v]; i < ostar.first[v + 1]; ++i)
      if (in[ostar.tris[i]])
        cur.push_back(ostar.tris[i]);
    if (one_fan(v, cur, otri))
      continue;
    int fans = count_fans(v, cur, otri, fan_of);
    if (fans <= 1)
      continue;
    std::vector<size_t> size(fans, 0);
    for (int f : fan_of)
      ++size[f];
    int keep = int(std::max_element(size.begin(), size.end()) - size.begin());
    for (size_t i = 0; i < cur.size(); ++i) {
      if (fan_of[i] == keep)
        continue;
      in[cur[i]] = 0;
      for (int k = 0; k < 3; ++k) {
        const uint32_t w = otri[3 * size_t(cur[i]) + k];
        if (w != v) {
          changed[w] = 1;
          work.push_back(w);
        }
      }
    }
  }
}

} // namespace

void fix_fans(size_t n, const std::vector<uint32_t> &otri,
              std::vector<uint8_t> &in, bool one_fan_before) {
  std::vector<uint32_t> work;
  if (one_fan_before) {
    // Only a vertex that lost a triangle can have more than one fan now.
    for (size_t t = 0; t < in.size(); ++t)
      if (!in[t])
        work.insert(work.end(), &otri[3 * t], &otri[3 * t] + 3);
    if (work.empty())
      return;
  }
  VertexStar ostar;
  ostar.build(n, otri, [&](size_t t) { return in[t] != 0; });
  if (!one_fan_before)
    for (uint32_t v = 0; v < n; ++v)
      if (ostar.first[v + 1] > ostar.first[v])
        work.push_back(v);
  fix_fans_in(ostar, otri, in, std::move(work));
}

namespace {

double signed_volume6(const double *xyz, const uint32_t *t, const double *o) {
  const double *a = xyz + 3 * size_t(t[0]), *b = xyz + 3 * size_t(t[1]),
               *c = xyz + 3 * size_t(t[2]);
  double p[3] = {a[0] - o[0], a[1] - o[1], a[2] - o[2]};
  double q[3] = {b[0] - o[0], b[1] - o[1], b[2] - o[2]};
  double r[3] = {c[0] - o[0], c[1] - o[1], c[2] - o[2]};
  return p[0] * (q[1] * r[2] - q[2] * r[1]) -
         p[1] * (q[0] * r[2] - q[2] * r[0]) +
         p[2] * (q[0] * r[1] - q[1] * r[0]);
}

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

// Patches the loop (vertex numbers in order; the hole runs along it) with
// the triangulation of least total area whose chords are all new edges, and
// appends its triangles to res and its chords to `chords`. The edge from the
// last vertex back to the first is part of the loop. for_neighbours(v, f)
// calls f on every vertex joined to v by an edge; pos is scratch, n entries
// of UINT32_MAX, left so. Returns false when no such triangulation exists.
template <class ForNeighbours>
bool patch(const double *xyz, const std::vector<uint32_t> &loop,
           ForNeighbours for_neighbours, std::vector<uint32_t> &pos,
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
    for_neighbours(loop[i], [&](uint32_t w) {
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
template <class HasEdge>
bool cut_loop(const double *xyz, std::vector<uint32_t> &loop,
              std::vector<uint32_t> &rest, HasEdge has_edge) {
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
              (!new_only || !has_edge(loop[i], loop[jj])))
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
      has_edge(loop[bi], loop[bj]))
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
  // Each vertex's neighbours along the surface's edges ...
  std::vector<uint32_t> adj_first(n + 1, 0), adj(2 * et.edges());
  for (size_t e = 0; e < et.edges(); ++e) {
    const uint64_t k = et.entries[et.first[e]].key;
    ++adj_first[key_lo(k) + 1];
    ++adj_first[uint32_t(k) + 1];
  }
  for (size_t v = 0; v < n; ++v)
    adj_first[v + 1] += adj_first[v];
  {
    std::vector<uint32_t> fill(adj_first.begin(), adj_first.end() - 1);
    for (size_t e = 0; e < et.edges(); ++e) {
      const uint64_t k = et.entries[et.first[e]].key;
      adj[fill[key_lo(k)]++] = uint32_t(k);
      adj[fill[uint32_t(k)]++] = key_lo(k);
    }
  }
  // ... and along the chords added by earlier fills, which count as
  // existing edges too: two holes that share vertices must not both add the
  // same chord. A chord is two links, one in the list of each end, so that
  // the chords of a hole that cannot be filled come off again in reverse.
  struct Link {
    uint32_t other, next;
  };
  std::vector<uint32_t> chord_head(n, UINT32_MAX);
  std::vector<Link> links;
  auto add_chord = [&](uint64_t k) {
    const uint32_t a = key_lo(k), b = uint32_t(k);
    links.push_back({b, chord_head[a]});
    chord_head[a] = uint32_t(links.size() - 1);
    links.push_back({a, chord_head[b]});
    chord_head[b] = uint32_t(links.size() - 1);
  };
  auto drop_chords_to = [&](size_t mark) {
    for (; links.size() > mark; links.resize(links.size() - 2)) {
      const size_t i = links.size() - 2;
      chord_head[links[i + 1].other] = links[i].next;
      chord_head[links[i].other] = links[i + 1].next;
    }
  };
  auto for_neighbours = [&](uint32_t a, auto &&visit) {
    for (uint32_t i = adj_first[a]; i < adj_first[a + 1]; ++i)
      visit(adj[i]);
    for (uint32_t i = chord_head[a]; i != UINT32_MAX; i = links[i].next)
      visit(links[i].other);
  };
  auto has_edge = [&](uint32_t a, uint32_t b) {
    bool joined = false;
    for_neighbours(a, [&](uint32_t w) { joined = joined || w == b; });
    return joined;
  };
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
  std::vector<std::vector<uint32_t>> loops, pieces;
  std::vector<double> cost, costT;
  std::vector<uint32_t> split, pos(n, UINT32_MAX);
  std::vector<uint8_t> joined, seen(n, 0);
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
    if (!ok || v != v0 || loop.size() < 3 || loop.size() > max_loop)
      continue;
    // A loop of at least kMinOpenLoop edges, most of whose samples failed
    // the ratio test (their Voronoi cells open sideways), is where the
    // surface ends, not a hole left by a missing triangle. Loops through
    // samples that are boundary samples only for disagreeing poles (stray
    // samples, thin parts such as the bunny's ears) are closed like any
    // other hole.
    if (!boundary.empty() && loop.size() >= kMinOpenLoop) {
      size_t opens = 0;
      for (uint32_t w : loop)
        opens += boundary[w] == kOpenSample;
      if (2 * opens >= loop.size())
        continue;
    }
    // A three-edge loop around a lone triangle would be closed by a second
    // copy of that triangle.
    if (loop.size() == 3 &&
        is_triangle_of(et, res, loop[0], loop[1], loop[2]))
      continue;
    loops.push_back(loop);
  }
  // Shortest first: when the work runs out, the many small holes are
  // closed and a few long ones stay open, not the other way round.
  std::stable_sort(loops.begin(), loops.end(),
                   [](const std::vector<uint32_t> &a,
                      const std::vector<uint32_t> &b) {
                     return a.size() < b.size();
                   });
  for (const std::vector<uint32_t> &hole : loops) {
    // A long loop is first cut by short chords into pieces of at most
    // kMaxPatch edges; the pieces are patched one by one, and the hole is
    // filled only if all of them are.
    pieces.assign(1, hole);
    const size_t mark = links.size();
    bool cut_ok = true;
    for (size_t p = 0; p < pieces.size() && cut_ok; ++p) {
      while (pieces[p].size() > kMaxPatch) {
        std::vector<uint32_t> rest;
        if (!cut_loop(xyz, pieces[p], rest, has_edge)) {
          cut_ok = false;
          break;
        }
        const std::vector<uint32_t> &q = pieces[p];
        add_chord(edge_key(q.front(), q.back()));
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
      ok_all = patch(xyz, pieces[p], for_neighbours, pos, joined, cost, costT,
                     split, res, added_chords);
    if (ok_all) {
      max_work -= work;
      for (uint64_t k : added_chords)
        add_chord(k);
    } else {
      // Not all pieces could be patched: leave the hole as it was.
      res.resize(before);
      drop_chords_to(mark);
      continue;
    }
    const size_t added = (res.size() - before) / 3;
    ++diag.holes_filled;
    diag.hole_triangles += added;
  }
  // The patches' triangles join the caller's table.
  if (!own)
    table->append(n, res, unfilled, progress);
}

void prune(const double *xyz, size_t n, const std::vector<uint32_t> &cand,
           bool erode_single, const std::vector<uint8_t> &keep_vertex,
           std::vector<uint8_t> &alive, EdgeTablePtr &table,
           Progress &progress, sc_diag_t &diag) {
  table.reset(new EdgeTable);
  EdgeTable &et = *table;
  et.build(xyz, n, cand, progress);
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

void extract(const double *xyz, size_t n, const std::vector<uint32_t> &cand,
             const std::vector<uint8_t> &alive, EdgeTablePtr table,
             size_t max_hole, const std::vector<uint8_t> &boundary,
             Progress &progress, Surface &out, sc_diag_t &diag,
             bool check_vertices) {
  const size_t nt = cand.size() / 3;
  // Only the survivors of pruning take part.
  std::vector<uint32_t> live;
  for (size_t t = 0; t < nt; ++t)
    if (alive[t])
      live.insert(live.end(), &cand[3 * t], &cand[3 * t] + 3);
  const size_t nl = live.size() / 3;
  EdgeTable &et = *table;
  et.keep_live(alive, true); // the walk finds edges by triangle
  VertexStar star;
  star.build(n, live, [](size_t) { return true; });

  // The walk: grow each component from a seed triangle, crossing every edge
  // to the first triangle met when rotating about it from the outer side.
  // A triangle joins only if it keeps every directed edge used at most once
  // (edge-manifold, consistently oriented) and touches no vertex of an
  // earlier component.
  std::vector<uint32_t> otri(live); // oriented copy
  std::vector<uint8_t> in(nl, 0), used(et.edges(), 0);
  std::vector<int32_t> owner(n, -1);
  std::vector<uint32_t> new_fan; // vertices that may have several fans
  // The id of the edge x-y of live triangle t.
  auto edge_of = [&](uint32_t t, uint32_t x, uint32_t y) {
    const uint64_t key = edge_key(x, y);
    for (int j = 0; j < 3; ++j)
      if (edge_key(live[3 * size_t(t) + j], live[3 * size_t(t) + (j + 1) % 3]) ==
          key)
        return et.tri_edge[3 * size_t(t) + j];
    return uint32_t(UINT32_MAX);
  };
  auto dir_bit = [](uint32_t a, uint32_t b) -> uint8_t {
    return a < b ? 1 : 2;
  };
  auto try_add = [&](uint32_t t, uint32_t a, uint32_t b, uint32_t c,
                     int32_t comp) {
    const uint32_t v[3] = {a, b, c};
    for (int k = 0; k < 3; ++k) {
      if (owner[v[k]] != -1 && owner[v[k]] != comp)
        return false;
    }
    uint32_t e[3];
    for (int k = 0; k < 3; ++k) {
      uint32_t x = v[k], y = v[(k + 1) % 3];
      e[k] = edge_of(t, x, y);
      if (used[e[k]] & dir_bit(x, y))
        return false;
    }
    // A corner already in the component that shares neither of its edges
    // with a triangle of it starts a second fan there, which later
    // triangles may or may not join to the first.
    for (int k = 0; k < 3; ++k)
      if (owner[v[k]] == comp && !used[e[k]] && !used[e[(k + 2) % 3]])
        new_fan.push_back(v[k]);
    for (int k = 0; k < 3; ++k) {
      used[e[k]] |= dir_bit(v[k], v[(k + 1) % 3]);
      owner[v[k]] = comp;
      otri[3 * size_t(t) + k] = v[k];
    }
    in[t] = 1;
    return true;
  };

  // Vertices by decreasing x. The sort moves each x with its vertex, for
  // reading it through the vertex number was a cache miss per comparison;
  // it compares x alone, as before, so the order (ties included) is the
  // same.
  struct ByX {
    double x;
    uint32_t v;
  };
  std::vector<ByX> by_x;
  for (uint32_t v = 0; v < n; ++v)
    if (star.first[v + 1] > star.first[v])
      by_x.push_back({xyz[3 * size_t(v)], v});
  std::sort(by_x.begin(), by_x.end(),
            [](const ByX &a, const ByX &b) { return a.x > b.x; });
  std::vector<uint32_t> order(by_x.size());
  for (size_t i = 0; i < by_x.size(); ++i)
    order[i] = by_x[i].v;
  by_x = std::vector<ByX>();

  // A clean triangle has exactly two live triangles on each edge: the walk
  // starts there, away from pockets of extra candidates.
  auto clean = [&](uint32_t t) {
    for (int j = 0; j < 3; ++j) {
      uint32_t e = et.tri_edge[3 * size_t(t) + j];
      if (et.first[e + 1] - et.first[e] != 2)
        return false;
    }
    return true;
  };

  // The triangles of the edge table alone, side by side: the walk reads
  // little else of an entry, at every edge it crosses.
  std::vector<uint32_t> etri(et.entries.size());
  for (size_t i = 0; i < etri.size(); ++i)
    etri[i] = et.entries[i].tri;
  size_t added = 0;
  std::vector<uint32_t> members, queue;
  auto walk = [&](uint32_t seed, uint32_t a, uint32_t b, uint32_t c,
                  int32_t comp) {
    members.clear();
    if (!try_add(seed, a, b, c, comp))
      return;
    members.push_back(seed);
    queue.assign(1, seed);
    while (!queue.empty()) {
      progress.tick(++added, 2 * nl);
      uint32_t t = queue.back();
      queue.pop_back();
      for (int k = 0; k < 3; ++k) {
        uint32_t x = otri[3 * size_t(t) + k],
                 y = otri[3 * size_t(t) + (k + 1) % 3];
        uint32_t e = edge_of(t, x, y);
        uint32_t lo = et.first[e], cnt = et.first[e + 1] - lo;
        if (cnt < 2)
          continue;
        uint32_t pos = 0;
        while (etri[lo + pos] != t)
          ++pos;
        // Rotating toward the outer side of t is increasing angle when t
        // runs along the edge's reference direction, decreasing otherwise.
        uint32_t step = x < y ? 1 : cnt - 1;
        uint32_t nb = etri[lo + (pos + step) % cnt];
        if (in[nb])
          continue;
        const uint32_t *w = &live[3 * size_t(nb)];
        uint32_t z = w[0] != x && w[0] != y   ? w[0]
                     : w[1] != x && w[1] != y ? w[1]
                                              : w[2];
        if (try_add(nb, y, x, z, comp)) {
          members.push_back(nb);
          queue.push_back(nb);
        }
      }
    }
  };
  auto undo = [&]() {
    for (uint32_t t : members) {
      in[t] = 0;
      for (int k = 0; k < 3; ++k) {
        uint32_t x = otri[3 * size_t(t) + k],
                 y = otri[3 * size_t(t) + (k + 1) % 3];
        used[edge_of(t, x, y)] &= uint8_t(~dir_bit(x, y));
        owner[x] = -1;
      }
    }
  };
  auto volume = [&]() {
    double v = 0;
    const double *o = xyz + 3 * size_t(otri[3 * size_t(members[0])]);
    for (uint32_t t : members)
      v += signed_volume6(xyz, &otri[3 * size_t(t)], o);
    return v;
  };

  int32_t comps = 0;
  for (uint32_t s : order) {
    if (owner[s] != -1)
      continue;
    // Seed: at the extreme vertex of what is left, the clean triangle whose
    // normal is closest to +x, oriented to face +x (outward there).
    uint32_t best = UINT32_MAX;
    double best_nx = -1, sign = 1;
    for (uint32_t i = star.first[s]; i < star.first[s + 1]; ++i) {
      uint32_t t = star.tris[i];
      const uint32_t *v = &live[3 * size_t(t)];
      if (in[t] || owner[v[0]] != -1 || owner[v[1]] != -1 ||
          owner[v[2]] != -1 || !clean(t))
        continue;
      const double *a = xyz + 3 * size_t(v[0]), *b = xyz + 3 * size_t(v[1]),
                   *c = xyz + 3 * size_t(v[2]);
      double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
      double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
      double nx = u[1] * w[2] - u[2] * w[1], ny = u[2] * w[0] - u[0] * w[2],
             nz = u[0] * w[1] - u[1] * w[0];
      double l = std::sqrt(nx * nx + ny * ny + nz * nz);
      if (!(l > 0))
        continue;
      if (std::fabs(nx) / l > best_nx) {
        best_nx = std::fabs(nx) / l;
        best = t;
        sign = nx >= 0 ? 1 : -1;
      }
    }
    if (best == UINT32_MAX)
      continue;
    const uint32_t *v = &live[3 * size_t(best)];
    uint32_t b1 = sign > 0 ? v[1] : v[2], c1 = sign > 0 ? v[2] : v[1];
    walk(best, v[0], b1, c1, comps);
    if (members.empty())
      continue;
    // The walk keeps to the outer side of its seed's orientation. If the
    // component came out facing inward, the seed was oriented wrongly and
    // the walk followed the inner candidates: walk again the other way.
    if (volume() < 0) {
      undo();
      walk(best, v[0], c1, b1, comps);
      if (members.empty())
        continue;
    }
    ++comps;
  }

  // The stars of every live triangle, those the walk left out passed over;
  // only where a second fan was started can a vertex have several.
  fix_fans_in(star, otri, in, std::move(new_fan));

  // The output, its components (triangles sharing an edge), and their
  // topology. Closed components facing inward are flipped.
  std::vector<uint32_t> res;
  for (size_t t = 0; t < nl; ++t)
    if (in[t])
      res.insert(res.end(), &otri[3 * t], &otri[3 * t] + 3);
  diag.walk_rejected = nl - res.size() / 3;
  // The candidates' table, cut down to the output: the table of res (its
  // triangles about each edge in angular order, which none of the passes
  // below depends on).
  et.keep_live(in, false);
  if (max_hole >= 3)
    fill_holes(xyz, n, res, max_hole, boundary, progress, diag, UINT64_MAX,
               &et);
  describe(xyz, n, res, progress, out, diag, &et, check_vertices);
}

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

void drop_nonmanifold(const double *xyz, size_t n, std::vector<uint32_t> &tris,
                      Progress &progress) {
  const size_t nt = tris.size() / 3;
  EdgeTable et;
  et.build(xyz, n, tris, progress, false);
  std::vector<uint8_t> in(nt, 1);
  for (size_t e = 0; e < et.edges(); ++e)
    if (et.first[e + 1] - et.first[e] > 2)
      for (uint32_t i = et.first[e]; i < et.first[e + 1]; ++i)
        in[et.entries[i].tri] = 0;
  fix_fans(n, tris, in);
  std::vector<uint32_t> res;
  for (size_t t = 0; t < nt; ++t)
    if (in[t])
      res.insert(res.end(), &tris[3 * t], &tris[3 * t] + 3);
  tris.swap(res);
}

void describe(const double *xyz, size_t n, std::vector<uint32_t> &res,
              Progress &progress, Surface &out, sc_diag_t &diag,
              const EdgeTable *table, bool check_vertices) {
  const size_t nr = res.size() / 3;
  EdgeTable own;
  if (!table) {
    own.build(xyz, n, res, progress, false);
    table = &own;
  }
  const EdgeTable &rt = *table;
  UnionFind uf(nr);
  for (size_t e = 0; e < rt.edges(); ++e)
    for (uint32_t i = rt.first[e] + 1; i < rt.first[e + 1]; ++i)
      uf.unite(rt.entries[rt.first[e]].tri, rt.entries[i].tri);
  std::vector<int32_t> comp_of(nr, -1), root_comp(nr, -1);
  int32_t nc = 0;
  for (size_t t = 0; t < nr; ++t) {
    uint32_t r = uf.find(uint32_t(t));
    if (root_comp[r] < 0)
      root_comp[r] = nc++;
    comp_of[t] = root_comp[r];
  }
  std::vector<Surface::Part> parts(nc);
  for (size_t t = 0; t < nr; ++t)
    ++parts[comp_of[t]].faces;
  UnionFind bloops(n);
  for (size_t e = 0; e < rt.edges(); ++e) {
    uint32_t cnt = rt.first[e + 1] - rt.first[e];
    Surface::Part &p = parts[comp_of[rt.entries[rt.first[e]].tri]];
    ++p.edges;
    if (cnt == 1) {
      ++p.boundary_edges;
      uint64_t k = rt.entries[rt.first[e]].key;
      bloops.unite(key_lo(k), uint32_t(k));
    } else if (cnt > 2) {
      ++p.nonmanifold_edges;
    }
  }
  std::vector<int32_t> vcomp(n, -1);
  for (size_t t = 0; t < nr; ++t)
    for (int k = 0; k < 3; ++k)
      vcomp[res[3 * t + k]] = comp_of[t];
  // Loops, and their lengths in boundary edges (loops that touch at a
  // vertex count as one).
  std::vector<Surface::Loop> loops;
  std::vector<uint32_t> loop_of(n, UINT32_MAX);
  {
    std::vector<uint64_t> loop_edges(n, 0);
    for (size_t e = 0; e < rt.edges(); ++e)
      if (rt.first[e + 1] - rt.first[e] == 1)
        ++loop_edges[bloops.find(key_lo(rt.entries[rt.first[e]].key))];
    for (uint32_t v = 0; v < n; ++v) {
      if (vcomp[v] < 0)
        continue;
      ++parts[vcomp[v]].vertices;
      if (loop_edges[v] == 0)
        continue;
      loop_of[v] = uint32_t(loops.size());
      loops.push_back({vcomp[v], loop_edges[v]});
    }
    for (size_t e = 0; e < rt.edges(); ++e)
      if (rt.first[e + 1] - rt.first[e] == 1) {
        const uint64_t k = rt.entries[rt.first[e]].key;
        for (uint32_t u : {key_lo(k), uint32_t(k)})
          loop_of[u] = loop_of[bloops.find(u)];
      }
  }
  // A final check of vertex-manifoldness on the result, counted honestly:
  // the corners of triangles at a vertex that share an edge there are one
  // fan; a vertex with two fans is pinched. (Before any triangle is
  // flipped below: corners are positions in res.) Without check_vertices
  // only a closed surface is checked here: an open one is described again
  // once closed.
  bool any_open = false;
  for (const Surface::Part &p : parts)
    any_open = any_open || p.boundary_edges > 0;
  uint64_t pinched = 0;
  if (check_vertices || !any_open) {
    UnionFind corners(3 * nr);
    auto corner = [&](uint32_t t, uint32_t v) {
      const uint32_t *u = &res[3 * size_t(t)];
      return 3 * t + (u[0] == v ? 0 : u[1] == v ? 1 : 2);
    };
    for (size_t e = 0; e < rt.edges(); ++e) {
      const uint64_t k = rt.entries[rt.first[e]].key;
      const uint32_t t0 = rt.entries[rt.first[e]].tri;
      for (uint32_t i = rt.first[e] + 1; i < rt.first[e + 1]; ++i) {
        corners.unite(corner(t0, key_lo(k)),
                      corner(rt.entries[i].tri, key_lo(k)));
        corners.unite(corner(t0, uint32_t(k)),
                      corner(rt.entries[i].tri, uint32_t(k)));
      }
    }
    std::vector<uint8_t> fans(n, 0);
    for (uint32_t c = 0; c < 3 * nr; ++c)
      if (corners.find(c) == c && fans[res[c]] < 2 && ++fans[res[c]] == 2)
        ++pinched;
  }
  // Signed volumes about each component's first vertex, for precision: a
  // closed component facing inward is flipped. (An open one has no inside,
  // and keeps the orientation it has.)
  std::vector<double> vol(nc, 0.0);
  std::vector<uint32_t> origin(nc, UINT32_MAX);
  for (size_t t = 0; t < nr; ++t) {
    int32_t c = comp_of[t];
    if (parts[c].boundary_edges != 0)
      continue;
    if (origin[c] == UINT32_MAX)
      origin[c] = res[3 * t];
    vol[c] += signed_volume6(xyz, &res[3 * t], xyz + 3 * size_t(origin[c]));
  }
  for (size_t t = 0; t < nr; ++t) {
    int32_t c = comp_of[t];
    if (parts[c].boundary_edges == 0 && vol[c] < 0)
      std::swap(res[3 * t + 1], res[3 * t + 2]);
  }

  out.component.swap(comp_of);
  out.parts.swap(parts);
  out.pinched = pinched;
  out.loops.swap(loops);
  out.loop_of.swap(loop_of);
  out.tris.swap(res);
  tally_loops(out);
  summarise(out, diag);
}

void tally_loops(Surface &s) {
  for (Surface::Part &p : s.parts) {
    p.loops = p.longest_loop = 0;
    for (uint64_t &l : p.loops_by_length)
      l = 0;
  }
  for (const Surface::Loop &l : s.loops) {
    if (l.part < 0)
      continue;
    Surface::Part &p = s.parts[size_t(l.part)];
    ++p.loops;
    p.longest_loop = std::max(p.longest_loop, l.length);
    ++p.loops_by_length[l.length <= 10     ? 0
                        : l.length <= 100  ? 1
                        : l.length <= 1000 ? 2
                                           : 3];
  }
}

void summarise(Surface &s, sc_diag_t &diag) {
  diag.triangles = diag.boundary_edges = diag.boundary_loops = 0;
  diag.nonmanifold_edges = 0;
  diag.components = diag.closed_components = 0;
  diag.longest_loop = 0;
  for (uint64_t &l : diag.loops_by_length)
    l = 0;
  diag.euler = 0;
  diag.genus = 0;
  s.component_genus.assign(s.parts.size(), -1);
  uint64_t used_vertices = 0;
  for (size_t c = 0; c < s.parts.size(); ++c) {
    const Surface::Part &p = s.parts[c];
    const int64_t chi = p.vertices - p.edges + p.faces;
    diag.euler += chi;
    if (p.boundary_edges == 0) {
      ++diag.closed_components;
      s.component_genus[c] = int32_t((2 - chi) / 2);
      diag.genus += (2 - chi) / 2;
    }
    diag.boundary_edges += p.boundary_edges;
    diag.boundary_loops += p.loops;
    diag.nonmanifold_edges += p.nonmanifold_edges;
    diag.longest_loop = std::max(diag.longest_loop, p.longest_loop);
    for (int k = 0; k < 4; ++k)
      diag.loops_by_length[k] += p.loops_by_length[k];
    used_vertices += uint64_t(p.vertices);
  }
  diag.nonmanifold_vertices = s.pinched;
  diag.components = s.parts.size();
  diag.triangles = s.tris.size() / 3;
  diag.closed = diag.triangles > 0 && diag.boundary_edges == 0;
  const uint64_t distinct = diag.delaunay_vertices;
  diag.samples_unused = distinct > used_vertices ? distinct - used_vertices : 0;
}

} // namespace sc

namespace sc {
namespace {

// Closest point of triangle abc to p (Ericson, Real-Time Collision
// Detection, 5.1.5), as barycentric weights.
void closest_on_triangle(const double *p, const double *a, const double *b,
                         const double *c, double w[3]) {
  double ab[3], ac[3], ap[3];
  for (int k = 0; k < 3; ++k)
    ab[k] = b[k] - a[k], ac[k] = c[k] - a[k], ap[k] = p[k] - a[k];
  double d1 = dot3(ab, ap), d2 = dot3(ac, ap);
  if (d1 <= 0 && d2 <= 0) {
    w[0] = 1, w[1] = 0, w[2] = 0;
    return;
  }
  double bp[3], cp[3];
  for (int k = 0; k < 3; ++k)
    bp[k] = p[k] - b[k], cp[k] = p[k] - c[k];
  double d3 = dot3(ab, bp), d4 = dot3(ac, bp);
  if (d3 >= 0 && d4 <= d3) {
    w[0] = 0, w[1] = 1, w[2] = 0;
    return;
  }
  double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    double v = d1 / (d1 - d3);
    w[0] = 1 - v, w[1] = v, w[2] = 0;
    return;
  }
  double d5 = dot3(ab, cp), d6 = dot3(ac, cp);
  if (d6 >= 0 && d5 <= d6) {
    w[0] = 0, w[1] = 0, w[2] = 1;
    return;
  }
  double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    double v = d2 / (d2 - d6);
    w[0] = 1 - v, w[1] = 0, w[2] = v;
    return;
  }
  double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    double v = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    w[0] = 0, w[1] = 1 - v, w[2] = v;
    return;
  }
  double den = 1 / (va + vb + vc);
  w[1] = vb * den, w[2] = vc * den, w[0] = 1 - w[1] - w[2];
}

double dist2(const double *x, const double *y) {
  double d[3] = {x[0] - y[0], x[1] - y[1], x[2] - y[2]};
  return d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
}

} // namespace

size_t drop_small_closed(const double *xyz, size_t n, Surface &s,
                         size_t min_triangles, bool open_too,
                         Progress &progress, sc_diag_t &diag) {
  const size_t nt = s.tris.size() / 3, nc = s.parts.size();
  if (s.component.size() != nt)
    throw Error(SC_EINTERNAL, "components out of step with the surface");
  std::vector<int32_t> renumber(nc, -1);
  int32_t kept = 0;
  for (size_t c = 0; c < nc; ++c)
    if ((s.parts[c].boundary_edges != 0 && !open_too) ||
        size_t(s.parts[c].faces) >= min_triangles)
      renumber[c] = kept++;
  if (size_t(kept) == nc)
    return 0;
  size_t k = 0;
  for (size_t t = 0; t < nt; ++t) {
    const int32_t c = renumber[s.component[t]];
    if (c < 0)
      continue;
    std::memmove(&s.tris[3 * k], &s.tris[3 * t], 3 * sizeof(uint32_t));
    s.component[k] = c;
    ++k;
  }
  s.tris.resize(3 * k);
  s.component.resize(k);
  if (s.pinched) {
    // A pinched vertex may join components, and its count belongs to one
    // of them: count again.
    std::vector<uint32_t> tris;
    tris.swap(s.tris);
    describe(xyz, n, tris, progress, s, diag);
  } else {
    // Whole components went: every count of the others stands.
    for (size_t c = 0; c < nc; ++c)
      if (renumber[c] >= 0)
        s.parts[size_t(renumber[c])] = s.parts[c];
    s.parts.resize(size_t(kept));
    for (Surface::Loop &l : s.loops)
      l.part = l.part < 0 ? -1 : renumber[size_t(l.part)];
    summarise(s, diag);
  }
  return nt - k;
}

size_t attach_samples(const double *xyz, size_t n, Surface &surf,
                      Progress &progress, sc_diag_t &diag) {
  std::vector<uint32_t> &tris = surf.tris;
  size_t nt = tris.size() / 3;
  if (nt == 0)
    return 0;
  if (surf.component.size() != nt)
    throw Error(SC_EINTERNAL, "components out of step with the surface");
  std::vector<uint8_t> used(n, 0);
  for (uint32_t v : tris)
    used[v] = 1;
  if (std::count(used.begin(), used.end(), 0) == 0)
    return 0;
  // Stars that change as triangles split: each vertex's triangles at the
  // start, then those it gained, in a list per vertex in the order gained
  // (a vector per vertex cost an allocation each and 24 bytes a vertex). A
  // triangle split away from a vertex never comes back to it, so a star is
  // read as the triangles that still have the vertex.
  VertexStar star0;
  star0.build(n, tris, [](size_t) { return true; });
  struct Gain {
    uint32_t tri, next;
  };
  std::vector<Gain> gains;
  std::vector<uint32_t> gain_first(n, UINT32_MAX), gain_last(n, UINT32_MAX);
  auto gain = [&](uint32_t v, uint32_t t) {
    const uint32_t i = uint32_t(gains.size());
    gains.push_back({t, UINT32_MAX});
    (gain_last[v] == UINT32_MAX ? gain_first[v] : gains[gain_last[v]].next) =
        i;
    gain_last[v] = i;
  };
  auto has = [&](uint32_t t, uint32_t v) {
    const uint32_t *u = &tris[3 * size_t(t)];
    return u[0] == v || u[1] == v || u[2] == v;
  };
  auto for_star = [&](uint32_t v, auto &&visit) {
    for (uint32_t i = star0.first[v]; i < star0.first[v + 1]; ++i)
      if (has(star0.tris[i], v))
        visit(star0.tris[i]);
    for (uint32_t i = gain_first[v]; i != UINT32_MAX; i = gains[i].next)
      if (has(gains[i].tri, v))
        visit(gains[i].tri);
  };
  // The sum of triangle t's edge lengths (for the grid's cell size).
  auto edge_lengths = [&](size_t t) {
    const uint32_t *v = &tris[3 * t];
    double sum = 0;
    for (int k = 0; k < 3; ++k)
      sum += std::sqrt(
          dist2(xyz + 3 * size_t(v[k]), xyz + 3 * size_t(v[(k + 1) % 3])));
    return sum;
  };
  double edge_sum = 0;
  for (size_t t = 0; t < nt; ++t)
    edge_sum += edge_lengths(t);
  const double cell = 2 * edge_sum / double(3 * nt);
  if (!(cell > 0))
    return 0;
  // A hash grid of the used vertices, cells twice the mean edge long.
  struct CellXyz {
    int64_t x, y, z;
  };
  auto cell_of = [&](const double *p) {
    return CellXyz{int64_t(std::floor(p[0] / cell)),
                   int64_t(std::floor(p[1] / cell)),
                   int64_t(std::floor(p[2] / cell))};
  };
  auto key = [](const CellXyz &c) {
    return uint64_t(c.x * 73856093) ^ uint64_t(c.y * 19349663) ^
           uint64_t(c.z * 83492791);
  };
  // Each key's run of the grid (its vertices in increasing order), found
  // in a flat table with linear probing: one lookup per cell looked at,
  // which mostly finds the slot the previous sample found (a node-based
  // map cost a cache miss each time). The table doubles as keys arrive, so
  // that it stays at most half full; the runs are laid out by a counting
  // pass over it, not a sort.
  struct Run {
    uint64_t key;
    uint32_t first, last; // last == 0: an empty slot
  };
  std::vector<Run> runs(16, Run{0, 0, 0});
  size_t mask = runs.size() - 1, occupied = 0;
  auto slot = [&](uint64_t k) {
    size_t h = size_t((k * 0x9E3779B97F4A7C15ull) >> 32) & mask;
    while (runs[h].last != 0 && runs[h].key != k)
      h = (h + 1) & mask;
    return h;
  };
  std::vector<uint64_t> vkey;
  for (uint32_t v = 0; v < n; ++v) {
    if (!used[v])
      continue;
    const uint64_t k = key(cell_of(xyz + 3 * size_t(v)));
    vkey.push_back(k);
    Run &r = runs[slot(k)];
    if (r.last != 0) {
      ++r.last; // the run's length, until the layout below
      continue;
    }
    r = Run{k, 0, 1};
    if (2 * ++occupied > runs.size()) {
      std::vector<Run> old(2 * runs.size(), Run{0, 0, 0});
      old.swap(runs);
      mask = runs.size() - 1;
      for (const Run &o : old)
        if (o.last != 0)
          runs[slot(o.key)] = o;
    }
  }
  std::vector<uint32_t> grid(vkey.size());
  {
    std::vector<uint32_t> fill(runs.size());
    uint32_t at = 0;
    for (size_t h = 0; h < runs.size(); ++h)
      if (runs[h].last != 0) {
        fill[h] = runs[h].first = at;
        at += runs[h].last;
        runs[h].last = at;
      }
    size_t i = 0;
    for (uint32_t v = 0; v < n; ++v)
      if (used[v])
        grid[fill[slot(vkey[i++])]++] = v;
  }
  vkey = std::vector<uint64_t>();

  // Calls visit(u) on each used vertex u in the grid cell of point p and in
  // the 26 around it, in the grid's order. The runs of those 27 cells are
  // kept for the next sample, which is mostly in the same cell (samples go
  // in vertex order, which follows the surface).
  struct Around {
    CellXyz c;
    uint32_t first[27], last[27];
  } around{{0, 0, 0}, {}, {}};
  bool around_set = false;
  auto for_grid_around = [&](const double *p, auto &&visit) {
    const CellXyz c = cell_of(p);
    if (!around_set || c.x != around.c.x || c.y != around.c.y ||
        c.z != around.c.z) {
      for (int j = 0; j < 27; ++j) {
        const Run &run = runs[slot(
            key({c.x + j / 9 - 1, c.y + j / 3 % 3 - 1, c.z + j % 3 - 1}))];
        around.first[j] = run.first, around.last[j] = run.last;
      }
      around.c = c;
      around_set = true;
    }
    for (int j = 0; j < 27; ++j)
      for (uint32_t i = around.first[j]; i < around.last[j]; ++i)
        visit(grid[i]);
  };

  size_t attached = 0;
  // Each split below keeps the counts of describe() up to date (one across
  // a boundary edge makes its loop an edge longer); where edges or
  // vertices are not manifold, count again instead.
  bool recount = surf.pinched != 0 || diag.nonmanifold_edges != 0;
  bool loops_grew = false;
  // Each triangle near a sample is looked at once, though it is in the
  // stars of three vertices.
  std::vector<uint32_t> stamp, vstamp(n, UINT32_MAX);
  for (uint32_t s = 0; s < n; ++s) {
    progress.tick(s, n);
    if (used[s])
      continue;
    const double *p = xyz + 3 * size_t(s);
    stamp.resize(tris.size() / 3, UINT32_MAX);
    // The nearest triangle, if the sample is closer to it than its longest
    // edge (farther samples are outliers and stay out), among those around
    // the used vertex nearest to the sample: the triangles with a corner at
    // that vertex or at one of its neighbours. (The first found of equals.)
    double best = std::numeric_limits<double>::infinity(), bw[3] = {0, 0, 0};
    uint32_t bt = UINT32_MAX;
    auto consider = [&](uint32_t t) {
      const uint32_t *v = &tris[3 * size_t(t)];
      const double *a = xyz + 3 * size_t(v[0]), *b = xyz + 3 * size_t(v[1]),
                   *c = xyz + 3 * size_t(v[2]);
      // The distance to the triangle's bounding box is a lower bound: a
      // triangle whose box is already farther than the best cannot win
      // (with a margin far above rounding, so that nothing changes).
      double box2 = 0;
      for (int k = 0; k < 3; ++k) {
        const double lo = std::min(a[k], std::min(b[k], c[k])),
                     hi = std::max(a[k], std::max(b[k], c[k]));
        const double out = p[k] < lo ? lo - p[k] : p[k] > hi ? p[k] - hi : 0;
        box2 += out * out;
      }
      if (box2 > best * (1 + 1e-9))
        return;
      double w[3];
      closest_on_triangle(p, a, b, c, w);
      double q[3];
      for (int k = 0; k < 3; ++k)
        q[k] = w[0] * a[k] + w[1] * b[k] + w[2] * c[k];
      double d = dist2(p, q);
      double longest = std::max(dist2(a, b), std::max(dist2(b, c), dist2(c, a)));
      if (d < best && d <= longest) {
        best = d, bt = t;
        std::copy(w, w + 3, bw);
      }
    };
    // The nearest used vertex, in the sample's grid cell and the 26 around
    // it (of equals, the first in the grid).
    double near = std::numeric_limits<double>::infinity();
    uint32_t nu = UINT32_MAX;
    for_grid_around(p, [&](uint32_t u) {
      const double d = dist2(p, xyz + 3 * size_t(u));
      if (d < near)
        near = d, nu = u;
    });
    if (nu == UINT32_MAX)
      continue;
    auto visit = [&](uint32_t t) {
      if (stamp[t] != s) {
        stamp[t] = s;
        consider(t);
      }
    };
    vstamp[nu] = s;
    for_star(nu, [&](uint32_t t) {
      const uint32_t *v = &tris[3 * size_t(t)];
      for (int k = 0; k < 3; ++k)
        if (vstamp[v[k]] != s) {
          vstamp[v[k]] = s;
          for_star(v[k], visit);
        }
      visit(t);
    });
    // None near enough there (the sample is off the edge of the surface,
    // or nearer another layer of it than its own): every triangle with a
    // corner in those grid cells.
    if (bt == UINT32_MAX)
      for_grid_around(p, [&](uint32_t u) { for_star(u, visit); });
    if (bt == UINT32_MAX)
      continue;
    // Split the triangle at the sample: into three when the closest point
    // is inside it, else across the edge it is on (both triangles of an
    // inner edge, the one of a boundary edge). Either way the sample gets
    // one fan and every edge keeps its triangles: still a manifold, with
    // the orientation of the triangles split.
    uint32_t v[3];
    std::copy(&tris[3 * size_t(bt)], &tris[3 * size_t(bt)] + 3, v);
    int zero = -1;
    for (int k = 0; k < 3; ++k)
      if (bw[k] < 1e-9)
        zero = zero < 0 ? k : 3; // 3: at a corner
    auto set = [&](uint32_t t, uint32_t a, uint32_t b, uint32_t c) {
      tris[3 * size_t(t)] = a, tris[3 * size_t(t) + 1] = b,
                       tris[3 * size_t(t) + 2] = c;
    };
    auto add = [&](uint32_t a, uint32_t b, uint32_t c) {
      uint32_t t = uint32_t(tris.size() / 3);
      tris.push_back(a), tris.push_back(b), tris.push_back(c);
      gain(a, t), gain(b, t), gain(c, t);
      surf.component.push_back(surf.component[bt]);
      return t;
    };
    // Three triangles for one, or four for two: one more vertex, three
    // more edges, two more triangles, in the component of the one split.
    auto count_split = [&] {
      Surface::Part &part = surf.parts[size_t(surf.component[bt])];
      part.vertices += 1, part.edges += 3, part.faces += 2;
    };
    if (zero < 0) {
      set(bt, v[0], v[1], s);
      gain(s, bt);
      add(v[1], v[2], s);
      add(v[2], v[0], s);
      count_split();
    } else {
      // The edge opposite the zero weight; at a corner, of the corner's two
      // edges the one whose other end is nearer the sample (edge c-(c+1)
      // is opposite c+2).
      int k = zero;
      if (zero == 3) {
        int c = bw[0] > 0.5 ? 0 : bw[1] > 0.5 ? 1 : 2;
        const double *n1 = xyz + 3 * size_t(v[(c + 1) % 3]),
                     *n2 = xyz + 3 * size_t(v[(c + 2) % 3]);
        k = dist2(p, n1) <= dist2(p, n2) ? (c + 2) % 3 : (c + 1) % 3;
      }
      uint32_t a = v[(k + 1) % 3], b = v[(k + 2) % 3], c = v[k];
      // The other triangle on edge a-b, running b -> a.
      uint32_t other = UINT32_MAX;
      for_star(a, [&](uint32_t t) {
        if (t == bt)
          return;
        const uint32_t *u = &tris[3 * size_t(t)];
        for (int j = 0; j < 3; ++j)
          if (u[j] == b && u[(j + 1) % 3] == a)
            other = t;
      });
      set(bt, c, a, s);
      gain(s, bt);
      add(c, s, b);
      if (other != UINT32_MAX) {
        uint32_t u[3];
        std::copy(&tris[3 * size_t(other)], &tris[3 * size_t(other)] + 3, u);
        int j = 0;
        while (!(u[j] == b && u[(j + 1) % 3] == a))
          ++j;
        uint32_t d = u[(j + 2) % 3];
        set(other, b, s, d);
        gain(s, other);
        add(s, a, d);
        count_split();
      } else {
        // A boundary edge split: one more vertex, two more edges (one of
        // them on the boundary), one more triangle, and its loop is an
        // edge longer.
        const uint32_t l = a < surf.loop_of.size() ? surf.loop_of[a]
                                                   : UINT32_MAX;
        if (l == UINT32_MAX) {
          recount = true;
        } else {
          Surface::Part &part = surf.parts[size_t(surf.component[bt])];
          part.vertices += 1, part.edges += 2, part.faces += 1;
          part.boundary_edges += 1;
          ++surf.loops[l].length;
          surf.loop_of[s] = l;
          loops_grew = true;
        }
      }
    }
    used[s] = 1;
    ++attached;
  }
  if (attached == 0)
    return 0;
  if (recount) {
    std::vector<uint32_t> res;
    res.swap(tris);
    describe(xyz, n, res, progress, surf, diag);
  } else {
    if (loops_grew)
      tally_loops(surf);
    summarise(surf, diag);
  }
  return attached;
}

} // namespace sc
