// The candidates' edge table and the vertex stars, which the stages after
// the triangulation (pruning, extraction, hole filling, description,
// attaching samples) build over and over, and the small helpers they share.
// Nothing after the candidates needs the Delaunay triangulation: only the
// points and the candidates, so the triangulation is freed before these
// stages run.
//
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef SC_CORE_EDGES_HPP
#define SC_CORE_EDGES_HPP

#include "internal.hpp"
#include "parallel.hpp"
#include "prefault.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>

namespace sc {

inline double dot3(const double *x, const double *y) {
  return x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
}

// The squared distance of points x and y.
inline double dist2(const double *x, const double *y) {
  const double d[3] = {x[0] - y[0], x[1] - y[1], x[2] - y[2]};
  return d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
}

// The normal of triangle a -> b -> c of the points xyz, (b - a) x (c - a):
// twice its area long.
inline void triangle_normal(const double *xyz, uint32_t a, uint32_t b,
                            uint32_t c, double n[3]) {
  const double *p = xyz + 3 * size_t(a), *q = xyz + 3 * size_t(b),
               *r = xyz + 3 * size_t(c);
  const double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
  const double w[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
  n[0] = u[1] * w[2] - u[2] * w[1];
  n[1] = u[2] * w[0] - u[0] * w[2];
  n[2] = u[0] * w[1] - u[1] * w[0];
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
    auto best =
        std::max_element(spare.begin(), spare.end(),
                         [](const std::vector<T> &a, const std::vector<T> &b) {
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
// The pool of the tables' and stars' arrays of vertex and edge numbers
// (edges.cpp).
extern thread_local Pool<uint32_t> u32_pool;

// Edge tables of fewer triangles than this are built on one thread
// whatever the threads (EdgeTable::build()).
constexpr size_t kParallelTriangles = 16384;

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
  std::vector<Entry> entries;  // grouped by edge, each group by angle
  std::vector<uint32_t> first; // edge id -> first entry; one extra at end
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
  // On `threads` threads, the buckets' sorts and the angles run in slices:
  // the same table on any number.
  void build(const double *xyz, size_t n, const std::vector<uint32_t> &tris,
             Progress &progress, bool angles = true, unsigned threads = 1) {
    // (Slices, where it pays: see kParallelTriangles.)
    const bool parallel = tris.size() >= 3 * kParallelTriangles;
    auto sliced = [&](size_t count, double from, double to, auto &&body) {
      run_sliced(count, threads, parallel, progress, body, from, to);
    };
    const size_t nt = tris.size() / 3;
    // Bucket the entries by their smaller vertex (a counting sort), then
    // sort each small bucket: linear overall, unlike one global sort.
    PrefaultVector<uint32_t> count(n + 1, 0);
    for (size_t i = 0; i < 3 * nt; ++i) {
      uint32_t a = tris[i], b = tris[i % 3 == 2 ? i - 2 : i + 1];
      ++count[std::min(a, b) + 1];
    }
    for (size_t v = 0; v < n; ++v)
      count[v + 1] += count[v];
    reserve_resident(entries, 3 * nt);
    entries.resize(3 * nt);
    PrefaultVector<uint32_t> fill(count.begin(), count.end() - 1);
    for (size_t t = 0; t < nt; ++t) {
      progress.tick(t, 4 * nt);
      for (int k = 0; k < 3; ++k) {
        uint32_t a = tris[3 * t + k], b = tris[3 * t + (k + 1) % 3];
        entries[fill[std::min(a, b)]++] = {edge_key(a, b), uint32_t(t),
                                           uint8_t(k)};
      }
    }
    // A bucket holds a vertex's edges, filled in triangle order: a stable
    // sort by key alone, which keeps that order among the triangles of an
    // edge, sorts it by (key, triangle).
    sliced(n, 0.25, 0.4, [&](size_t b, size_t e) {
      for (size_t v = b; v < e; ++v)
        sort_bucket(
            entries.data() + count[v], count[v + 1] - count[v],
            [](const Entry &x, const Entry &y) { return x.key < y.key; });
    });
    {
      Progress::Span span(progress, 0.4, 0.5);
      index_edges(nt, &progress, angles);
    }
    angle.clear();
    if (!angles)
      return;
    reserve_resident(angle, entries.size());
    angle.resize(entries.size());
    // Each edge's frame once, then its triangles by angle (ties by number).
    sliced(edges(), 0.5, 1, [&](size_t b, size_t end) {
      for (size_t e = b; e < end; ++e)
        sort_by_angle(xyz, tris, e);
    });
  }

  // The angles of the triangles of edge e, which build() sorts them by.
  void sort_by_angle(const double *xyz, const std::vector<uint32_t> &tris,
                     size_t e) {
    Entry *x = &entries[first[e]];
    double *ang = &angle[first[e]];
    const uint32_t k = first[e + 1] - first[e];
    if (k < 2) {
      ang[0] = 0;
      return;
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
      return;
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
    const std::vector<uint32_t> added(tris.begin() + 3 * first_new, tris.end());
    EdgeTable more;
    more.build(nullptr, n, added, progress, false);
    size_t i = entries.size(), j = more.entries.size();
    // Exactly the room needed: a table is appended to once or twice, and
    // resize() alone would double the largest array of the closing step.
    entries.reserve(i + j);
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
    // Edges are about half the entries (a surface's edges have two
    // triangles each).
    reserve_resident(first, entries.size() / 2 + 1);
    tri_edge.clear();
    reserve_resident(tri_edge, with_tri_edge ? 3 * nt : 0);
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
    first.clear();
    reserve_resident(first, n + 1);
    first.assign(n + 1, 0);
    const size_t nt = t.size() / 3;
    for (size_t i = 0; i < nt; ++i)
      if (keep(i))
        for (int k = 0; k < 3; ++k)
          ++first[t[3 * i + k] + 1];
    for (size_t v = 0; v < n; ++v)
      first[v + 1] += first[v];
    reserve_resident(tris, first[n]);
    tris.resize(first[n]);
    PrefaultVector<uint32_t> fill(first.begin(), first.end() - 1);
    for (size_t i = 0; i < nt; ++i)
      if (keep(i))
        for (int k = 0; k < 3; ++k)
          tris[fill[t[3 * i + k]]++] = uint32_t(i);
  }
};

// Six times the signed volume of the tetrahedron of triangle t and point o.
inline double signed_volume6(const double *xyz, const uint32_t *t,
                             const double *o) {
  const double *a = xyz + 3 * size_t(t[0]), *b = xyz + 3 * size_t(t[1]),
               *c = xyz + 3 * size_t(t[2]);
  double p[3] = {a[0] - o[0], a[1] - o[1], a[2] - o[2]};
  double q[3] = {b[0] - o[0], b[1] - o[1], b[2] - o[2]};
  double r[3] = {c[0] - o[0], c[1] - o[1], c[2] - o[2]};
  return p[0] * (q[1] * r[2] - q[2] * r[1]) -
         p[1] * (q[0] * r[2] - q[2] * r[0]) +
         p[2] * (q[0] * r[1] - q[1] * r[0]);
}

// fix_fans() over the stars ostar of the triangles (those with in[t]
// clear are passed over, so a star of more triangles will do), starting
// from the vertices in work (any order, repeats allowed): every vertex that
// may have several fans. They are taken in vertex order, which decides
// between fans of equal size, so any list that holds those vertices gives
// the result of looking at every vertex.
void fix_fans_in(const VertexStar &ostar, const std::vector<uint32_t> &otri,
                 std::vector<uint8_t> &in, std::vector<uint32_t> work);

} // namespace sc

#endif
