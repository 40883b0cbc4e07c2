// The stages that need the Delaunay triangulation: insertion (in chunks),
// duplicates, poles, and the one pass over the Delaunay facets that selects
// candidate triangles. The triangulation is freed before pruning starts.
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include "internal.hpp"

#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Delaunay_triangulation_cell_base_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_cell_base_with_info_3.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>
#include <CGAL/spatial_sort.h>
#include <CGAL/Spatial_sort_traits_adapter_3.h>
#ifdef CGAL_LINKED_WITH_TBB
#include <tbb/task_arena.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>

namespace sc {
namespace {

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef K::Point_3 Point;
// What the filtering keeps on each vertex and cell, so that the pass over
// the facets reads only the two cells of a facet and their vertices, never
// arrays indexed by input order (which is random and would miss the cache at
// every access on large inputs).
struct VertexData {
  uint32_t idx = 0; // index of the point in the input
  float best = -1;  // squared distance to the pole so far; inf on the hull
  double pole[3] = {0, 0, 0}; // pole direction, unit once computed
  VertexData() = default;
  VertexData(uint32_t i) : idx(i) {}
};
// Single precision is ample for where a Voronoi vertex lies relative to the
// cocones and balls it is tested against, and keeps cells at 80 bytes.
struct CellData {
  float cc[3]; // circumcentre (guarded), set by the poles stage
};
typedef CGAL::Triangulation_vertex_base_with_info_3<VertexData, K> Vb;
typedef CGAL::Triangulation_cell_base_with_info_3<
    CellData, K, CGAL::Delaunay_triangulation_cell_base_3<K>>
    Cb;
typedef CGAL::Triangulation_data_structure_3<Vb, Cb, CGAL::Sequential_tag>
    TdsSeq;
typedef CGAL::Delaunay_triangulation_3<K, TdsSeq> DtSeq;
#ifdef CGAL_LINKED_WITH_TBB
typedef CGAL::Triangulation_data_structure_3<Vb, Cb, CGAL::Parallel_tag>
    TdsPar;
typedef CGAL::Delaunay_triangulation_3<
    K, TdsPar, CGAL::Default,
    CGAL::Spatial_lock_grid_3<CGAL::Tag_priority_blocking>>
    DtPar;
#endif

struct V3 {
  double x, y, z;
};
inline V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 operator*(double s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }
inline double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline V3 cross(V3 a, V3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z,
          a.x * b.y - a.y * b.x};
}
inline double norm2(V3 a) { return dot(a, a); }
inline V3 v3(const Point &p) { return {p.x(), p.y(), p.z()}; }
inline bool finite(V3 a) {
  return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}

// Circumcentre of triangle abc; returns false when it is degenerate.
bool tri_circumcentre(V3 a, V3 b, V3 c, V3 &out) {
  V3 u = b - a, v = c - a, w = cross(u, v);
  double w2 = norm2(w);
  if (!(w2 > 0))
    return false;
  V3 num = norm2(u) * cross(v, w) + norm2(v) * cross(w, u);
  out = a + (0.5 / w2) * num;
  return finite(out);
}

// Circumcentre of a tetrahedron. Nearly flat cells (cospherical points on
// grid-like scans) give a centre that is huge or not finite; those fall back
// to the circumcentre of their largest facet and set `guarded`.
V3 cell_circumcentre(V3 a, V3 b, V3 c, V3 d, bool &guarded) {
  V3 u = b - a, v = c - a, w = d - a;
  V3 vw = cross(v, w);
  double det = dot(u, vw);
  double scale = std::sqrt(norm2(u) * norm2(v) * norm2(w));
  guarded = false;
  if (std::fabs(det) > 1e-10 * scale) {
    V3 num = norm2(u) * vw + norm2(v) * cross(w, u) + norm2(w) * cross(u, v);
    V3 cc = a + (0.5 / det) * num;
    if (finite(cc))
      return cc;
  }
  guarded = true;
  const V3 p[4] = {a, b, c, d};
  double best = -1;
  V3 out = 0.25 * (a + b + c + d);
  for (int i = 0; i < 4; ++i) {
    V3 x = p[(i + 1) % 4], y = p[(i + 2) % 4], z = p[(i + 3) % 4];
    double area2 = norm2(cross(y - x, z - x));
    V3 cc;
    if (area2 > best && tri_circumcentre(x, y, z, cc)) {
      best = area2;
      out = cc;
    }
  }
  return out;
}

// The thresholds of the candidate tests, computed once from the parameters.
struct Criteria {
  int mode;
  double cos_theta1; // criterion 1: |cos(n_t, p_s)| >= this
  double tan_phi;    // criterion 2: dual edge meets [-R tan phi, R tan phi]
  double sin_cocone; // cocone: |cos(y - s, p_s)| <= this

  explicit Criteria(const sc_params_t &p) : mode(p.mode) {
    double r = p.r;
    double a = std::asin(std::min(1.0, r / (1 - r)));
    double b = std::asin(std::min(1.0, std::sqrt(3.0) * r / (1 - r)));
    double theta1 = 2 * a + b;
    double phi = std::asin(std::min(1.0, r / (2 * (1 - r)))) + b;
    cos_theta1 = theta1 >= M_PI / 2 ? 0.0 : std::cos(theta1);
    tan_phi = phi >= M_PI / 2 ? std::numeric_limits<double>::infinity()
                              : std::tan(phi);
    sin_cocone = std::sin(p.cocone_theta);
  }
};

// Where a point of the dual Voronoi edge lies relative to the cocone of a
// sample: -1 or +1 in one of the two cones around the pole, 0 inside the
// cocone.
inline int cone_side(V3 dir, V3 pole_unit, double sin_cocone) {
  double len = std::sqrt(norm2(dir));
  if (!(len > 0))
    return 0;
  double c = dot(dir, pole_unit) / len;
  if (std::fabs(c) <= sin_cocone)
    return 0;
  return c > 0 ? 1 : -1;
}

// The candidate test for triangle abc with indices idx. The dual Voronoi
// edge runs from v1 to v2, or from v1 along direction v2 when `ray`.
bool is_candidate(const Criteria &cr, const V3 *P, const V3 *poles, V3 v1,
                  V3 v2, bool ray) {
  V3 n = cross(P[1] - P[0], P[2] - P[0]);
  double n2 = norm2(n);
  if (!(n2 > 0))
    return false;
  n = (1 / std::sqrt(n2)) * n;

  if (cr.mode == SC_MODE_COCONE) {
    for (int k = 0; k < 3; ++k) {
      const V3 &pole = poles[k];
      int s1 = cone_side(v1 - P[k], pole, cr.sin_cocone);
      if (s1 == 0)
        continue;
      int s2 = cone_side(ray ? v2 : v2 - P[k], pole, cr.sin_cocone);
      if (s2 == 0 || s2 != s1)
        continue;
      return false;
    }
    return true;
  }

  // Criterion 1: the normal at the vertex with the largest angle, which is
  // the vertex opposite the longest edge.
  double l0 = norm2(P[1] - P[2]), l1 = norm2(P[0] - P[2]),
         l2 = norm2(P[0] - P[1]);
  int s = l0 >= l1 ? (l0 >= l2 ? 0 : 2) : (l1 >= l2 ? 1 : 2);
  if (std::fabs(dot(n, poles[s])) < cr.cos_theta1)
    return false;

  // Criterion 2: the dual edge's height interval above the triangle's
  // circumcentre must meet [-R tan phi, R tan phi].
  V3 ct;
  if (!tri_circumcentre(P[0], P[1], P[2], ct))
    return false;
  double R = std::sqrt(norm2(P[0] - ct));
  double lim = R * cr.tan_phi;
  double h1 = dot(v1 - ct, n);
  double lo, hi;
  if (ray) {
    double d = dot(v2, n);
    lo = d >= 0 ? h1 : -std::numeric_limits<double>::infinity();
    hi = d >= 0 ? std::numeric_limits<double>::infinity() : h1;
  } else {
    double h2 = dot(v2 - ct, n);
    lo = std::min(h1, h2);
    hi = std::max(h1, h2);
  }
  return hi >= -lim && lo <= lim;
}

template <class DT> class TriangulatorImpl : public Triangulator {
public:
  template <class... A> explicit TriangulatorImpl(A &&...a) : dt_(a...) {}

  void insert(const double *xyz, size_t first, size_t n,
              Progress &progress) override {
    // One spatial sort of the whole range, then batches along it: the
    // batches give progress and cancellation points, and each continues
    // where the last one ended, so insertion keeps the locality of a single
    // sorted insert.
    std::vector<Point> pts;
    pts.reserve(n);
    for (size_t i = first; i < first + n; ++i)
      pts.emplace_back(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    std::vector<std::size_t> order(n);
    std::iota(order.begin(), order.end(), std::size_t(0));
    typedef CGAL::Spatial_sort_traits_adapter_3<
        K, CGAL::Pointer_property_map<Point>::const_type>
        SortTraits;
    CGAL::spatial_sort(order.begin(), order.end(),
                       SortTraits(CGAL::make_property_map(
                           static_cast<const std::vector<Point> &>(pts))));
    const size_t batch = std::max<size_t>(1u << 14, n / 64);
    Ch hint;
    for (size_t done = 0; done < n; done += batch) {
      progress.report(double(done) / double(n));
      size_t m = std::min(batch, n - done);
      for (size_t k = done; k < done + m; ++k) {
        Vh v = dt_.insert(pts[order[k]], hint);
        v->info().idx = uint32_t(first + order[k]);
        hint = v->cell();
      }
    }
    progress.report(1.0);
  }

  int dimension() const override { return dt_.dimension(); }

  void filter(const double *xyz, size_t n, const sc_params_t &params,
              Progress &progress, Filtered &out, sc_diag_t &diag,
              double seconds[SC_STAGE_COUNT]) override {
    Stopwatch sw;
    progress.stage(SC_STAGE_DELAUNAY);
    resolve_duplicates(xyz, n, out.dups);
    diag.duplicates_merged = out.dups.size();
    diag.delaunay_vertices = dt_.number_of_vertices();
    // From here on vertices go by their rank in the triangulation's own
    // order, which follows the spatial sort: every later array indexed by
    // vertex is then read with locality, whatever the input order.
    out.to_input.clear();
    out.to_input.reserve(dt_.number_of_vertices());
    for (auto v = dt_.finite_vertices_begin(); v != dt_.finite_vertices_end();
         ++v) {
      out.to_input.push_back(v->info().idx);
      v->info().idx = uint32_t(out.to_input.size() - 1);
    }
    seconds[SC_STAGE_DELAUNAY] += sw.lap();

    progress.stage(SC_STAGE_POLES);
    compute_poles(out.to_input.size(), progress, out.poles, diag);
    seconds[SC_STAGE_POLES] += sw.lap();

    progress.stage(SC_STAGE_CANDIDATES);
    select_candidates(params, progress, out.tris, diag);
    diag.candidates = out.tris.size() / 3;
    // The triangulation is not needed any more: free it before pruning so
    // that the peak memory is the triangulation's alone.
    dt_.clear();
    seconds[SC_STAGE_CANDIDATES] += sw.lap();
  }

private:
  typedef typename DT::Vertex_handle Vh;
  typedef typename DT::Cell_handle Ch;

  // Range insertion keeps one of several equal points, with whatever index
  // came last in its spatial order. Find each missing index, record it as a
  // duplicate, and make the vertex carry the smallest index of its point so
  // every output index is the first occurrence.
  void resolve_duplicates(const double *xyz, size_t n,
                          std::vector<std::pair<uint32_t, uint32_t>> &dups) {
    if (dt_.number_of_vertices() == n)
      return;
    std::vector<bool> seen(n, false);
    for (auto v = dt_.finite_vertices_begin(); v != dt_.finite_vertices_end();
         ++v)
      seen[v->info().idx] = true;
    Ch hint;
    for (size_t i = 0; i < n; ++i) {
      if (seen[i])
        continue;
      Point p(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
      typename DT::Locate_type lt;
      int li, lj;
      Ch c = dt_.locate(p, lt, li, lj, hint);
      if (lt != DT::VERTEX)
        throw Error(SC_EINTERNAL, "a point missing from the triangulation");
      hint = c;
      Vh v = c->vertex(li);
      uint32_t j = v->info().idx;
      if (j > i) {
        dups.emplace_back(j, uint32_t(i));
        v->info().idx = uint32_t(i);
      } else {
        dups.emplace_back(uint32_t(i), j);
      }
    }
  }

  V3 centre(Ch c, sc_diag_t *diag) const {
    bool guarded;
    V3 cc = cell_circumcentre(v3(c->vertex(0)->point()), v3(c->vertex(1)->point()),
                              v3(c->vertex(2)->point()), v3(c->vertex(3)->point()),
                              guarded);
    if (guarded && diag)
      ++diag->degenerate_cells;
    return cc;
  }

  // Outward unit normal of the hull facet of infinite cell c.
  V3 hull_normal(Ch c, int inf, V3 *pts) const {
    for (int k = 0; k < 3; ++k)
      pts[k] = v3(c->vertex((inf + 1 + k) % 4)->point());
    V3 n = cross(pts[1] - pts[0], pts[2] - pts[0]);
    Ch inner = c->neighbor(inf);
    V3 o = v3(inner->vertex(inner->index(c))->point());
    if (dot(n, o - pts[0]) > 0)
      n = -1.0 * n;
    double l = std::sqrt(norm2(n));
    return l > 0 ? (1 / l) * n : V3{0, 0, 0};
  }

  void compute_poles(size_t n, Progress &progress, std::vector<double> &poles,
                     sc_diag_t &diag) {
    const float kHull = std::numeric_limits<float>::infinity();

    // Samples on the convex hull: the pole is at infinity, in the direction
    // of the average outward normal of the hull facets around them.
    for (auto c = dt_.all_cells_begin(); c != dt_.all_cells_end(); ++c) {
      if (!dt_.is_infinite(c))
        continue;
      int inf = c->index(dt_.infinite_vertex());
      V3 pts[3];
      V3 nrm = hull_normal(c, inf, pts);
      for (int k = 0; k < 3; ++k) {
        VertexData &d = c->vertex((inf + 1 + k) % 4)->info();
        d.pole[0] += nrm.x, d.pole[1] += nrm.y, d.pole[2] += nrm.z;
        d.best = kHull;
      }
    }

    // Interior samples: the farthest Voronoi vertex of their cell. Each
    // cell keeps its circumcentre for the candidate pass.
    size_t cells = dt_.number_of_cells(), k = 0;
    for (auto c = dt_.finite_cells_begin(); c != dt_.finite_cells_end();
         ++c, ++k) {
      progress.tick(k, cells);
      ++diag.delaunay_cells;
      V3 cc = centre(c, &diag);
      c->info().cc[0] = float(cc.x), c->info().cc[1] = float(cc.y),
      c->info().cc[2] = float(cc.z);
      for (int j = 0; j < 4; ++j) {
        Vh v = c->vertex(j);
        VertexData &d = v->info();
        if (d.best == kHull)
          continue;
        V3 dv = cc - v3(v->point());
        float d2 = float(norm2(dv));
        if (d2 > d.best) {
          d.best = d2;
          d.pole[0] = dv.x, d.pole[1] = dv.y, d.pole[2] = dv.z;
        }
      }
    }
    // Unit poles, also copied out by input index: the triangulation is gone
    // before the normals are made.
    poles.assign(3 * n, 0.0);
    for (auto v = dt_.finite_vertices_begin(); v != dt_.finite_vertices_end();
         ++v) {
      VertexData &d = v->info();
      if (d.best == kHull)
        ++diag.hull_vertices;
      double l = std::sqrt(d.pole[0] * d.pole[0] + d.pole[1] * d.pole[1] +
                           d.pole[2] * d.pole[2]);
      if (l > 0)
        d.pole[0] /= l, d.pole[1] /= l, d.pole[2] /= l;
      std::memcpy(&poles[3 * size_t(d.idx)], d.pole, sizeof d.pole);
    }
  }

  void select_candidates(const sc_params_t &params, Progress &progress,
                         std::vector<uint32_t> &tris, sc_diag_t &diag) {
    Criteria cr(params);
    size_t cells = dt_.number_of_cells(), k = 0;
    V3 P[3], poles[3];
    uint32_t idx[3];
    const Vh inf = dt_.infinite_vertex();
    for (auto c = dt_.finite_cells_begin(); c != dt_.finite_cells_end();
         ++c, ++k) {
      progress.tick(k, cells);
      const float *ccc = c->info().cc;
      V3 cc = {ccc[0], ccc[1], ccc[2]};
      for (int f = 0; f < 4; ++f) {
        Ch nb = c->neighbor(f);
        // Each facet between two finite cells is handled from the cell at
        // the lower address; that comparison needs no access to nb.
        if (&*nb < &*c && !nb->has_vertex(inf))
          continue;
        bool ray = nb->has_vertex(inf);
        ++diag.delaunay_facets;
        for (int j = 0; j < 3; ++j) {
          Vh v = c->vertex((f + 1 + j) % 4);
          const VertexData &d = v->info();
          P[j] = v3(v->point());
          poles[j] = {d.pole[0], d.pole[1], d.pole[2]};
          idx[j] = d.idx;
        }
        V3 other;
        if (ray) {
          // The dual of a hull facet is a ray leaving the hull outward.
          V3 nrm = cross(P[1] - P[0], P[2] - P[0]);
          V3 o = v3(c->vertex(f)->point());
          other = dot(nrm, o - P[0]) > 0 ? -1.0 * nrm : nrm;
        } else {
          const float *oc = nb->info().cc;
          other = {oc[0], oc[1], oc[2]};
        }
        if (is_candidate(cr, P, poles, cc, other, ray)) {
          tris.push_back(idx[0]);
          tris.push_back(idx[1]);
          tris.push_back(idx[2]);
        }
      }
    }
  }

  DT dt_;
};

#ifdef CGAL_LINKED_WITH_TBB
typedef CGAL::Spatial_lock_grid_3<CGAL::Tag_priority_blocking> LockGrid;

// The lock grid must outlive the triangulation that points to it, so it sits
// in a base class constructed first.
struct LockHolder {
  LockGrid lock;
  tbb::task_arena arena;
  LockHolder(const double *b, int threads)
      : lock(CGAL::Bbox_3(b[0], b[1], b[2], b[3], b[4], b[5]), 50),
        arena(threads > 0 ? threads : tbb::task_arena::automatic) {}
};

class ParallelTriangulator final : private LockHolder,
                                   public TriangulatorImpl<DtPar> {
public:
  ParallelTriangulator(const double *b, int threads)
      : LockHolder(b, threads), TriangulatorImpl<DtPar>(K(), &lock) {}
  // The arena bounds this job's threads without touching the process-wide
  // TBB settings, so concurrent jobs can each have their own count.
  void insert(const double *xyz, size_t first, size_t n,
              Progress &progress) override {
    arena.execute(
        [&] { TriangulatorImpl<DtPar>::insert(xyz, first, n, progress); });
  }
};
#endif

} // namespace

std::unique_ptr<Triangulator> make_triangulator(int threads,
                                                const double *bbox6) {
#ifdef CGAL_LINKED_WITH_TBB
  // The lock grid needs a box up front; points outside it (later chunks) are
  // clamped to its border cells, which costs contention, not correctness.
  if (threads != 1)
    return std::make_unique<ParallelTriangulator>(bbox6, threads);
#endif
  (void)threads;
  (void)bbox6;
  return std::make_unique<TriangulatorImpl<DtSeq>>();
}

} // namespace sc
