// The stages that need the Delaunay triangulation: insertion (in chunks),
// duplicates, poles, boundary detection, and the one pass over the Delaunay
// facets that selects candidate triangles. The triangulation is freed before
// pruning starts, except in watertight mode, which labels its cells after
// extraction to close the holes of the surface (close()).
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include "internal.hpp"
#include "prefault.hpp"

// Blocks of cells and vertices come with their pages resident (see
// prefault.hpp); CGAL's own default is std::allocator. The macro is CGAL's
// hook for its containers' default allocator, and it must come before
// CGAL's headers; it changes only this file's instantiations, whose cell
// and vertex types are this file's own.
#define CGAL_ALLOCATOR(T) sc::PrefaultAllocator<T>
#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Delaunay_triangulation_cell_base_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_cell_base_with_info_3.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>
#include <CGAL/hilbert_sort.h>
#include <CGAL/spatial_sort.h>
#include <CGAL/Spatial_sort_traits_adapter_3.h>
#ifdef CGAL_LINKED_WITH_TBB
#include <tbb/task_arena.h>
#endif

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <tuple>

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
  // Boundary detection (boundary, watertight and auto modes): squared
  // distances to the farthest Voronoi vertex inside the cocone (r) and to
  // the negative pole (h), and the kV* flags below.
  float r2 = 0, h2 = 0;
  float nn2 = std::numeric_limits<float>::infinity(); // nearest neighbour
  uint8_t flags = 0;
  VertexData() = default;
  VertexData(uint32_t i) : idx(i) {}
};
enum : uint8_t {
  kVRatio = 1,    // r <= rho h: the Voronoi cell is long and thin
  kVDisagree = 2, // some cocone neighbour's pole is more than alpha away
  kVInterior = 4, // an interior sample; the others are boundary samples
};
// Single precision is ample for where a Voronoi vertex lies relative to the
// cocones and balls it is tested against, and keeps cells at 80 bytes.
// Once the candidates are chosen the circumcentre is not needed any more,
// and watertight mode reuses its bytes for the cell's label.
struct CellLabel {
  uint32_t local;      // scratch: the cell's place in a vertex's star
  uint16_t vin, vout;  // surface triangles that put the cell inside, outside
  uint8_t label;       // kUnlabelled, kInside, kOutside
  uint8_t barrier;     // bit f: facet f is a surface triangle
  uint8_t moved;       // relabelled once already: stays as it is now
};
enum : uint8_t { kUnlabelled = 0, kInside = 1, kOutside = 2 };
// Boundary detection ignores, for the extent of a cell in the cocone, a
// circumcentre farther than this from the cell's vertices, relative to the
// cell's longest edge (squared).
constexpr double kMaxCentreRatio2 = 8.0 * 8.0;
// A cell that reaches no farther into the cocone than this many times the
// distance to the nearest sample passes the ratio test whatever the height
// (squared): where the surface is thin (a bunny's ear) the negative pole
// comes close and the ratio fails, but the cell does not open sideways the
// way it does where the surface ends.
constexpr float kNearRatio2 = 3.0f * 3.0f;
struct CellData {
  union {
    float cc[3];  // circumcentre (guarded), set by the poles stage
    CellLabel w;  // watertight mode, after the candidates
  };
  CellData() : cc{0, 0, 0} {}
  // An infinite cell has no circumcentre: the poles stage marks it with a
  // NaN that no arithmetic on finite points gives (a NaN made by arithmetic
  // has no payload), so that the candidates tell it by the bytes they read
  // anyway.
  static constexpr uint32_t kInfinite = 0x7fc5a5a5u;
  void mark_infinite() { std::memcpy(&cc[0], &kInfinite, sizeof kInfinite); }
  bool infinite() const {
    uint32_t bits;
    std::memcpy(&bits, &cc[0], sizeof bits);
    return bits == kInfinite;
  }
};
typedef CGAL::Triangulation_vertex_base_with_info_3<VertexData, K> Vb;
typedef CGAL::Triangulation_cell_base_with_info_3<
    CellData, K, CGAL::Delaunay_triangulation_cell_base_3<K>>
    Cb;
typedef CGAL::Triangulation_data_structure_3<Vb, Cb, CGAL::Sequential_tag>
    TdsSeq;
typedef CGAL::Delaunay_triangulation_3<K, TdsSeq> DtSeq;
// Cells are most of the memory of a reconstruction: a byte more in
// CellData makes them 88 bytes, and the peak 8% higher.
static_assert(sizeof(TdsSeq::Cell) <= 80, "a cell grew beyond 80 bytes");
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

// The points of an xyz array by index, as a property map for CGAL's sorts.
struct XyzMap {
  const double *xyz;
  typedef uint32_t key_type;
  typedef Point value_type;
  typedef Point reference;
  typedef boost::readable_property_map_tag category;
  friend Point get(const XyzMap &m, uint32_t i) {
    return Point(m.xyz[3 * size_t(i)], m.xyz[3 * size_t(i) + 1],
                 m.xyz[3 * size_t(i) + 2]);
  }
};

// Sorts point indices along a Hilbert curve of their points (CGAL's median
// policy).
void hilbert_sort(const double *xyz, std::vector<uint32_t> &idx) {
  CGAL::hilbert_sort(idx.begin(), idx.end(),
                     CGAL::Spatial_sort_traits_adapter_3<K, XyzMap>(
                         XyzMap{xyz}));
}

// The round of point i in a biased randomized insertion order: r with
// probability 3/4^(r+1), from a hash of the index (splitmix64's finaliser),
// so that the order depends on nothing else.
constexpr int kRounds = 24;
inline int brio_round(uint32_t i) {
  uint64_t z = uint64_t(i) + 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return z == 0 ? kRounds : std::min(kRounds, __builtin_ctzll(z) / 2);
}

// The thresholds of the candidate tests, computed once from the parameters.
struct Criteria {
  int mode;
  double cos_theta1; // criterion 1: |cos(n_t, p_s)| >= this
  double tan_phi;    // criterion 2: dual edge meets [-R tan phi, R tan phi]
  double sin2_cocone; // cocone: cos^2(y - s, p_s) <= this

  explicit Criteria(const sc_params_t &p)
      : mode(p.mode == SC_MODE_SHORTCRUST ? SC_MODE_SHORTCRUST
                                          : SC_MODE_COCONE) {
    double r = p.r;
    double a = std::asin(std::min(1.0, r / (1 - r)));
    double b = std::asin(std::min(1.0, std::sqrt(3.0) * r / (1 - r)));
    double theta1 = 2 * a + b;
    double phi = std::asin(std::min(1.0, r / (2 * (1 - r)))) + b;
    cos_theta1 = theta1 >= M_PI / 2 ? 0.0 : std::cos(theta1);
    tan_phi = phi >= M_PI / 2 ? std::numeric_limits<double>::infinity()
                              : std::tan(phi);
    sin2_cocone = std::sin(p.cocone_theta) * std::sin(p.cocone_theta);
  }
};

// Where a point of the dual Voronoi edge lies relative to the cocone of a
// sample: -1 or +1 in one of the two cones around the pole, 0 inside the
// cocone.
// (Compared squared: no square root or division in this test, which runs
// six times a facet.)
inline int cone_side(V3 dir, V3 pole_unit, double sin2_cocone) {
  const double len2 = norm2(dir);
  if (!(len2 > 0))
    return 0;
  const double d = dot(dir, pole_unit);
  if (d * d <= sin2_cocone * len2)
    return 0;
  return d > 0 ? 1 : -1;
}

// The candidate test for triangle abc with indices idx. The dual Voronoi
// edge runs from v1 to v2, or from v1 along direction v2 when `ray`.
// interior says which vertices the cocone test is made at: all three except
// in boundary mode, and at least one. In cocone mode side1[k] is
// cone_side(v1 - P[k], poles[k]) for the interior vertices: the same for
// every facet of v1's cell at that vertex, so it is computed once a cell.
bool is_candidate(const Criteria &cr, const V3 *P, const V3 *poles,
                  const bool *interior, const int *side1, V3 v1, V3 v2,
                  bool ray) {
  if (cr.mode == SC_MODE_COCONE) {
    if (!interior[0] && !interior[1] && !interior[2])
      return false;
    for (int k = 0; k < 3; ++k) {
      if (!interior[k] || side1[k] == 0)
        continue;
      int s2 = cone_side(ray ? v2 : v2 - P[k], poles[k], cr.sin2_cocone);
      if (s2 == 0 || s2 != side1[k])
        continue;
      return false;
    }
    // A degenerate triangle never is (tested last: most facets fail the
    // cocone test).
    return norm2(cross(P[1] - P[0], P[2] - P[0])) > 0;
  }
  V3 n = cross(P[1] - P[0], P[2] - P[0]);
  double n2 = norm2(n);
  if (!(n2 > 0))
    return false;
  n = (1 / std::sqrt(n2)) * n;

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
    // A biased randomized insertion order (Amenta, Choi and Rote), the one
    // CGAL's spatial_sort() makes: rounds, each a quarter of the size of
    // the next, each in Hilbert order. It is drawn from one Hilbert sort of
    // the range, whose subsequences are in Hilbert order too; when the range
    // is the whole input, that sort is also the vertex numbering (see
    // number_vertices()), which then costs no second sort. Batches along
    // the order give progress and cancellation points, and each continues
    // where the last one ended, so insertion keeps the locality of a single
    // sorted insert.
    std::vector<uint32_t> order(n);
    std::iota(order.begin(), order.end(), uint32_t(first));
    hilbert_sort(xyz, order);
    std::vector<uint32_t> brio(n);
    {
      // A counting sort by round, the last (largest) round last: bucket
      // kRounds - r, of kRounds + 1, starts at start[kRounds - r].
      std::array<size_t, kRounds + 2> start{};
      for (uint32_t i : order)
        ++start[size_t(kRounds - brio_round(i)) + 1];
      for (int b = 0; b <= kRounds; ++b)
        start[size_t(b) + 1] += start[size_t(b)];
      for (uint32_t i : order)
        brio[start[size_t(kRounds - brio_round(i))]++] = i;
    }
    if (first == 0)
      hilbert_.swap(order);
    else
      hilbert_.clear();
    order = {};
    const size_t batch = std::max<size_t>(1u << 14, n / 64);
    Ch hint;
    for (size_t done = 0; done < n; done += batch) {
      progress.report(double(done) / double(n));
      size_t m = std::min(batch, n - done);
      for (size_t k = done; k < done + m; ++k) {
        // The points are in input order, scattered along the insertion
        // order: ask for the next one while this one goes in.
        if (k + 1 < n)
          __builtin_prefetch(xyz + 3 * size_t(brio[k + 1]));
        const double *p = xyz + 3 * size_t(brio[k]);
        Vh v = dt_.insert(Point(p[0], p[1], p[2]), hint);
        v->info().idx = brio[k];
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
    // From here on vertices go by their rank in a Hilbert order of the
    // points: every later array indexed by vertex is then read with
    // locality, whatever the input order; and the numbering depends only on
    // the points, not on the order in which they were inserted (all at once
    // here, in chunks as they arrive in the daemon), so neither do the
    // candidates, pruning and walk, and both give the same mesh.
    number_vertices(xyz, n, out.to_input);
    seconds[SC_STAGE_DELAUNAY] += sw.lap();

    progress.stage(SC_STAGE_POLES);
    compute_poles(progress, diag);
    if (detects_boundary(params.mode))
      classify(params, progress, out.boundary, diag);
    seconds[SC_STAGE_POLES] += sw.lap();

    progress.stage(SC_STAGE_CANDIDATES);
    select_candidates(params, progress, out.tris, diag);
    diag.candidates = out.tris.size() / 3;
    // The unit poles by vertex number, for the normals: copied out last, so
    // that the array takes memory that boundary detection has freed instead
    // of pages of its own.
    out.poles.assign(3 * out.to_input.size(), 0.0);
    for (auto v = dt_.finite_vertices_begin(); v != dt_.finite_vertices_end();
         ++v)
      std::memcpy(&out.poles[3 * size_t(v->info().idx)], v->info().pole,
                  sizeof v->info().pole);
    // The triangulation is not needed any more: free it before pruning so
    // that the peak memory is the triangulation's alone.
    dt_.clear();
    // Which cell reports a facet, and when, depends on heap addresses; the
    // later stages break ties by the order of the candidates. They carry no
    // orientation: the walk gives them one.
    canonical_order(out.tris, false);
    seconds[SC_STAGE_CANDIDATES] += sw.lap();
  }

  bool close(std::vector<uint32_t> &tris, Progress &progress,
             sc_diag_t &diag) override {
    bool ok = label_and_close(tris, progress, diag);
    dt_.clear();
    return ok;
  }

private:
  typedef typename DT::Vertex_handle Vh;
  typedef typename DT::Cell_handle Ch;

  // Numbers the vertices 0, 1, ... in the Hilbert order of all the points
  // (indices 0 .. n-1 sorted; of equal points, the vertex keeps the first
  // index) and fills to_input (vertex number -> input index).
  void number_vertices(const double *xyz, size_t n,
                       std::vector<uint32_t> &to_input) {
    std::vector<uint32_t> order;
    if (hilbert_.size() == n) {
      order.swap(hilbert_);
    } else {
      order.resize(n);
      std::iota(order.begin(), order.end(), 0u);
      hilbert_sort(xyz, order);
    }
    hilbert_ = {};
    std::vector<uint8_t> is_vertex(n, 0);
    for (auto v = dt_.finite_vertices_begin(); v != dt_.finite_vertices_end();
         ++v)
      is_vertex[v->info().idx] = 1;
    to_input.clear();
    to_input.reserve(dt_.number_of_vertices());
    for (uint32_t i : order)
      if (is_vertex[i])
        to_input.push_back(i);
    order = {};
    std::vector<uint32_t> rank(n);
    for (size_t i = 0; i < to_input.size(); ++i)
      rank[to_input[i]] = uint32_t(i);
    for (auto v = dt_.finite_vertices_begin(); v != dt_.finite_vertices_end();
         ++v)
      v->info().idx = rank[v->info().idx];
  }

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
    // Taken in the order of the vertex numbers: how a cell happens to order
    // its vertices depends on the order of insertion, and on nearly flat
    // cells the rounding of the centre is enough to change the surface.
    Vh v[4] = {c->vertex(0), c->vertex(1), c->vertex(2), c->vertex(3)};
    auto order = [&](int i, int j) {
      if (v[j]->info().idx < v[i]->info().idx)
        std::swap(v[i], v[j]);
    };
    order(0, 1), order(2, 3), order(0, 2), order(1, 3), order(1, 2);
    bool guarded;
    V3 cc = cell_circumcentre(v3(v[0]->point()), v3(v[1]->point()),
                              v3(v[2]->point()), v3(v[3]->point()), guarded);
    if (guarded && diag)
      ++diag->degenerate_cells;
    return cc;
  }

  // Outward unit normal of the hull facet of infinite cell c.
  V3 hull_normal(Ch c, int inf, V3 *pts) const {
    // From the corner with the smallest vertex number, in the cell's cyclic
    // order, so that the rounding does not depend on the order of insertion.
    int first = 0;
    for (int k = 1; k < 3; ++k)
      if (c->vertex((inf + 1 + k) % 4)->info().idx <
          c->vertex((inf + 1 + first) % 4)->info().idx)
        first = k;
    for (int k = 0; k < 3; ++k)
      pts[k] = v3(c->vertex((inf + 1 + (first + k) % 3) % 4)->point());
    V3 n = cross(pts[1] - pts[0], pts[2] - pts[0]);
    Ch inner = c->neighbor(inf);
    V3 o = v3(inner->vertex(inner->index(c))->point());
    if (dot(n, o - pts[0]) > 0)
      n = -1.0 * n;
    double l = std::sqrt(norm2(n));
    return l > 0 ? (1 / l) * n : V3{0, 0, 0};
  }

  // Calls visit(c) on every finite cell c, asking a few cells ahead for the
  // vertices and, with `neighbours`, for the data of the neighbouring cells
  // at higher addresses (what the candidates read): they are scattered over
  // memory, and waiting for each in turn was most of the time of these
  // passes.
  template <class Visit> void for_cells(bool neighbours, Visit &&visit) {
    constexpr int kAhead = 4;
    const auto end = dt_.finite_cells_end();
    auto ahead = dt_.finite_cells_begin();
    for (int i = 0; i < kAhead && ahead != end; ++i)
      ++ahead;
    for (auto c = dt_.finite_cells_begin(); c != end; ++c) {
      if (ahead != end) {
        for (int j = 0; j < 4; ++j) {
          const char *v = reinterpret_cast<const char *>(&*ahead->vertex(j));
          __builtin_prefetch(v);
          __builtin_prefetch(v + 64);
          if (neighbours && &*ahead < &*ahead->neighbor(j))
            __builtin_prefetch(&ahead->neighbor(j)->info());
        }
        ++ahead;
      }
      visit(c);
    }
  }

  void compute_poles(Progress &progress, sc_diag_t &diag) {
    const float kHull = std::numeric_limits<float>::infinity();

    // Samples on the convex hull: the pole is at infinity, in the direction
    // of the average outward normal of the hull facets around them. The
    // infinite cells are kept for boundary detection and the candidates.
    infinite_.clear();
    dt_.incident_cells(dt_.infinite_vertex(), std::back_inserter(infinite_));
    for (Ch c : infinite_) {
      c->info().mark_infinite();
      int inf = c->index(dt_.infinite_vertex());
      V3 pts[3];
      V3 nrm = hull_normal(c, inf, pts);
      // On a grid of 2^-30: sums of such numbers are exact, so they do not
      // depend on the order of the cells.
      for (double *x : {&nrm.x, &nrm.y, &nrm.z})
        *x = std::ldexp(std::nearbyint(std::ldexp(*x, 30)), -30);
      for (int k = 0; k < 3; ++k) {
        VertexData &d = c->vertex((inf + 1 + k) % 4)->info();
        d.pole[0] += nrm.x, d.pole[1] += nrm.y, d.pole[2] += nrm.z;
        d.best = kHull;
      }
    }

    // Interior samples: the farthest Voronoi vertex of their cell. Each
    // cell keeps its circumcentre for the candidate pass.
    size_t cells = dt_.number_of_cells(), k = 0;
    for_cells(false, [&](auto c) {
      progress.tick(k++, cells);
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
        // Of Voronoi vertices equally far in single precision, the one whose
        // offset is the larger in lexicographic order, whichever cell comes
        // first: the order of the cells in memory depends on the order of
        // insertion.
        if (d2 > d.best ||
            (d2 == d.best &&
             std::tie(dv.x, dv.y, dv.z) >
                 std::tie(d.pole[0], d.pole[1], d.pole[2]))) {
          d.best = d2;
          d.pole[0] = dv.x, d.pole[1] = dv.y, d.pole[2] = dv.z;
        }
      }
    });
    // Unit poles.
    for (auto v = dt_.finite_vertices_begin(); v != dt_.finite_vertices_end();
         ++v) {
      VertexData &d = v->info();
      if (d.best == kHull)
        ++diag.hull_vertices;
      double l = std::sqrt(d.pole[0] * d.pole[0] + d.pole[1] * d.pole[1] +
                           d.pole[2] * d.pole[2]);
      if (l > 0)
        d.pole[0] /= l, d.pole[1] /= l, d.pole[2] /= l;
    }
  }

  // Boundary detection, after Dey and Giesen ("Detecting undersampling in
  // surface reconstruction", 2001). Where the surface is well sampled and
  // has no boundary, the Voronoi cell of a sample is long and thin along
  // the normal: everything of it inside the cocone is close to the sample
  // (r, the farthest Voronoi vertex in the cocone) compared with the
  // negative pole (h). At a boundary the cell opens up sideways, in the
  // tangent plane, and r grows to the size of the gap beyond the boundary
  // (to infinity on the convex hull). So:
  //  - ratio test: r <= rho h;
  //  - seeds: samples that pass it and whose pole agrees, within alpha
  //    (unoriented), with the pole of every cocone neighbour (a sample q
  //    sharing a Delaunay cell with s whose circumcentre lies in the cocone
  //    of s: the Voronoi facet between s and q then meets that cocone; we
  //    look only at Voronoi vertices, not at crossings of facet edges, which
  //    is what one pass over the cells gives);
  //  - growth: a neighbour that passes the ratio test and agrees with an
  //    interior sample becomes interior.
  // The rest are boundary samples.
  void classify(const sc_params_t &params, Progress &progress,
                std::vector<uint8_t> &boundary, sc_diag_t &diag) {
    const double rho =
        params.boundary_rho > 0 ? params.boundary_rho : kDefaultRho;
    const double alpha =
        params.boundary_alpha > 0 ? params.boundary_alpha : kDefaultAlpha;
    const double sin2_c = Criteria(params).sin2_cocone;
    const double cos_a = std::cos(alpha);
    const float kInf = std::numeric_limits<float>::infinity();

    // On the hull the Voronoi cell is unbounded, in the directions of the
    // outward normals of the hull facets around the sample, and the pole is
    // their average, so the ratio test sees nothing of that part of the
    // cell. Where the surface goes on beyond a hull sample these normals
    // stay close together; where it ends there (the rim of a hemisphere or
    // of a scan, whose hull facets span the missing part) they fan out. So r
    // is infinite when two of them are more than (pi/2 - theta) / 2 apart:
    // the cell then opens up sideways, whatever the true normal is.
    const double cos_fan = std::cos((M_PI / 2 - params.cocone_theta) / 2);
    // One normal per hull facet, and per hull vertex the list of the
    // facet corners at it (sorting corners by vertex cost more than the
    // rest of this stage on small input, and a vector of (vertex, normal)
    // pairs grown one by one was most of its memory).
    const std::vector<Ch> &outside = infinite_;
    std::vector<V3> hull(outside.size());
    std::vector<uint32_t> head(dt_.number_of_vertices(), UINT32_MAX),
        next(3 * outside.size());
    auto corner = [&](uint32_t i) {
      Ch c = outside[i / 3];
      return c->vertex((c->index(dt_.infinite_vertex()) + 1 + i % 3) % 4);
    };
    for (uint32_t f = 0; f < outside.size(); ++f) {
      V3 pts[3];
      hull[f] = hull_normal(outside[f],
                            outside[f]->index(dt_.infinite_vertex()), pts);
      for (uint32_t i = 3 * f; i < 3 * f + 3; ++i) {
        const uint32_t v = corner(i)->info().idx;
        next[i] = head[v];
        head[v] = i;
      }
    }
    for (uint32_t i = 0; i < next.size(); ++i) {
      Vh v = corner(i);
      if (head[v->info().idx] != i)
        continue;
      for (uint32_t a = i; a != UINT32_MAX; a = next[a])
        for (uint32_t b = next[a]; b != UINT32_MAX; b = next[b])
          if (dot(hull[a / 3], hull[b / 3]) < cos_fan)
            v->info().r2 = kInf;
    }
    hull = {};
    next = {};
    head = {};

    size_t cells = dt_.number_of_cells(), k = 0;
    // Per cell in the order visited: the links found below (2 bytes a
    // cell, for the pass after the ratio test).
    std::vector<uint16_t> cell_links(cells);
    V3 pole[4];
    bool in_cone[4], grow_cone[4];
    for_cells(false, [&](auto c) {
      progress.tick(k++, 2 * cells);
      const float *ccc = c->info().cc;
      V3 cc = {ccc[0], ccc[1], ccc[2]};
      // A circumcentre much farther than the cell is long comes from a
      // nearly degenerate cell (points close to a common circle, as on an
      // exact cylinder or sphere), where it is ill-conditioned: rounding
      // moves it anywhere along the circle's axis. It still counts for the
      // pole and the negative pole, which lie along the axis anyway, but
      // not for the extent of the cell in the cocone.
      V3 P[4];
      double len[4][4]; // squared edge lengths
      double longest2 = 0;
      for (int j = 0; j < 4; ++j) {
        P[j] = v3(c->vertex(j)->point());
        for (int i = 0; i < j; ++i) {
          len[i][j] = len[j][i] = norm2(P[i] - P[j]);
          longest2 = std::max(longest2, len[i][j]);
        }
      }
      const bool trusted = norm2(cc - P[0]) <= kMaxCentreRatio2 * longest2;
      for (int j = 0; j < 4; ++j) {
        VertexData &d = c->vertex(j)->info();
        for (int i = 0; i < 4; ++i)
          if (i != j)
            d.nn2 = std::min(d.nn2, float(len[i][j]));
        pole[j] = {d.pole[0], d.pole[1], d.pole[2]};
        V3 dv = cc - P[j];
        double len2 = norm2(dv), dp = dot(dv, pole[j]);
        const double reach2 = sin2_c * len2;
        in_cone[j] = dp * dp <= reach2;
        // The growth below counts the cell as in the cocone unless it is
        // clearly outside.
        grow_cone[j] = !(dp * dp > reach2);
        // As maxima with 0 (h and r start at 0): the conditions are as
        // likely true as false, and branches on them were mispredicted.
        const float l2 = float(len2);
        d.h2 = std::max(d.h2, dp < 0 ? l2 : 0.0f);
        d.r2 = std::max(d.r2, in_cone[j] && trusted ? l2 : 0.0f);
      }
      // Poles that agree, and the links the growth below may follow: bit
      // 4 j + i when the circumcentre is in j's cocone and the poles of i
      // and j agree.
      uint16_t links = 0;
      bool disagrees[4] = {false, false, false, false};
      for (int j = 0; j < 4; ++j)
        for (int i = 0; i < j; ++i) {
          const bool agree = std::fabs(dot(pole[i], pole[j])) >= cos_a;
          disagrees[j] |= !agree && in_cone[j];
          disagrees[i] |= !agree && in_cone[i];
          links |= uint16_t(agree && grow_cone[j]) << (4 * j + i);
          links |= uint16_t(agree && grow_cone[i]) << (4 * i + j);
        }
      for (int j = 0; j < 4; ++j)
        c->vertex(j)->info().flags |= uint8_t(disagrees[j] ? kVDisagree : 0);
      cell_links[k - 1] = links;
    });

    // Growth from agreeing neighbours: a sample that passes the ratio test
    // becomes interior when a cell around it whose circumcentre lies in the
    // cocone of an interior neighbour joins it to that neighbour with poles
    // that agree, until nothing changes. Only the samples that pass the
    // ratio test but whose poles disagree (waiting) can change, so only the
    // cells around them are looked at below, instead of the star of every
    // interior sample.
    std::vector<Vh> waiting;
    const size_t m = dt_.number_of_vertices();
    std::vector<uint8_t> state(m, 0); // by vertex number: 1 interior, 2 waiting
    const float rho2 = float(rho * rho);
    for (auto v = dt_.finite_vertices_begin(); v != dt_.finite_vertices_end();
         ++v) {
      VertexData &d = v->info();
      d.flags &= uint8_t(~(kVRatio | kVInterior));
      if ((d.h2 > 0 && d.r2 <= rho2 * d.h2) || d.r2 <= kNearRatio2 * d.nn2)
        d.flags |= kVRatio;
      if (!(d.flags & kVRatio))
        continue;
      if (!(d.flags & kVDisagree)) {
        d.flags |= kVInterior;
        state[d.idx] = 1;
      } else {
        waiting.push_back(v);
        state[d.idx] = 2;
      }
    }
    // The links along which a waiting sample q can become interior: from a
    // neighbour v that passes the ratio test, through a cell whose
    // circumcentre is in v's cocone, when their poles agree. One pass over
    // the cells that have a waiting sample, then a search along the links.
    // A link from an interior sample is followed at once, and only links
    // from samples still waiting are kept for the search, which starts from
    // the samples that became interior in the pass: the same samples become
    // interior as in a search over every link (merged scans: 343 000 links
    // kept of 1.8 million, 7 MB of fresh memory instead of 28).
    std::vector<std::pair<uint32_t, uint32_t>> links;
    std::vector<uint32_t> grown;
    k = 0;
    for_cells(false, [&](auto c) {
      const uint16_t mask = cell_links[k];
      progress.tick(cells + k++, 2 * cells);
      if (!mask)
        return;
      uint32_t idx[4];
      bool any = false;
      for (int j = 0; j < 4; ++j) {
        idx[j] = c->vertex(j)->info().idx;
        any = any || state[idx[j]] == 2;
      }
      if (!any)
        return;
      for (int j = 0; j < 4; ++j) {
        if (state[idx[j]] == 0)
          continue;
        for (int i = 0; i < 4; ++i)
          if (((mask >> (4 * j + i)) & 1) && state[idx[i]] == 2) {
            if (state[idx[j]] == 1) {
              state[idx[i]] = 1;
              grown.push_back(idx[i]);
            } else {
              links.emplace_back(idx[j], idx[i]);
            }
          }
      }
    });
    std::vector<uint32_t> first(m + 1, 0), to(links.size());
    for (const auto &l : links)
      ++first[l.first + 1];
    for (size_t v = 0; v < m; ++v)
      first[v + 1] += first[v];
    {
      std::vector<uint32_t> fill(first.begin(), first.end() - 1);
      for (const auto &l : links)
        to[fill[l.first]++] = l.second;
    }
    links = {};
    cell_links = {};
    while (!grown.empty()) {
      const uint32_t v = grown.back();
      grown.pop_back();
      for (uint32_t i = first[v]; i < first[v + 1]; ++i)
        if (state[to[i]] == 2) {
          state[to[i]] = 1;
          grown.push_back(to[i]);
        }
    }
    for (Vh q : waiting)
      if (state[q->info().idx] == 1)
        q->info().flags |= kVInterior;

    // Auto and watertight mode: when most samples are not interior the
    // sample is too sparse or too small to tell a boundary from
    // undersampling (every sample of a tetrahedron is a boundary sample,
    // and two thirds of a sparse genus-2 surface's), and boundary mode
    // would keep little, or would open true handles that watertight mode
    // then cuts; run the closed-surface algorithm instead (watertight mode
    // still closes what it leaves open).
    size_t interior = 0;
    for (auto v = dt_.finite_vertices_begin(); v != dt_.finite_vertices_end();
         ++v)
      interior += (v->info().flags & kVInterior) != 0;
    if ((params.mode == SC_MODE_AUTO || params.mode == SC_MODE_WATERTIGHT) &&
        2 * interior < m) {
      for (auto v = dt_.finite_vertices_begin();
           v != dt_.finite_vertices_end(); ++v)
        v->info().flags |= kVInterior;
      boundary.clear();
      return;
    }
    boundary.assign(m, 0);
    for (auto v = dt_.finite_vertices_begin(); v != dt_.finite_vertices_end();
         ++v) {
      VertexData &d = v->info();
      if (d.flags & kVInterior)
        continue;
      boundary[d.idx] = (d.flags & kVRatio) ? kBoundarySample : kOpenSample;
      ++diag.boundary_samples;
    }
  }

  // Watertight mode: label every cell inside or outside across the
  // oriented surface and take the boundary of the inside cells.
  //  - Seeds: the cell behind an outward triangle is inside, the one in
  //    front outside (a cell that several triangles touch takes the
  //    majority); infinite cells are outside.
  //  - A multi-source breadth-first search through the facets that are not
  //    surface triangles labels the rest, so that the inside and outside
  //    fronts meet in the middle of each hole.
  //  - The boundary of the union of the inside cells is closed, but may
  //    touch itself at an edge or a vertex. Around each vertex the cells of
  //    each label must form one piece (joined across facets at the vertex);
  //    that also rules out pinched edges. Where they do not, the smallest
  //    offending piece moves to the other label, and the neighbours are
  //    checked again.
  bool label_and_close(std::vector<uint32_t> &tris, Progress &progress,
                       sc_diag_t &diag) {
    const size_t m = dt_.number_of_vertices();
    std::vector<Vh> &vh = vh_;
    vh.assign(m, Vh());
    for (auto v = dt_.finite_vertices_begin(); v != dt_.finite_vertices_end();
         ++v)
      vh[v->info().idx] = v;
    for (auto c = dt_.all_cells_begin(); c != dt_.all_cells_end(); ++c)
      c->info().w = CellLabel{0, 0, 0, kUnlabelled, 0, 0};

    // Open components may come out of extraction facing inward; the hull
    // tells: a triangle on the hull must face the infinite cell. Flip a
    // component whose hull triangles mostly face inward.
    const size_t nt = tris.size() / 3;
    std::vector<Ch> fc(nt);
    std::vector<int8_t> fi(nt, -1);
    std::vector<int8_t> hull_vote(nt, 0);
    for (size_t t = 0; t < nt; ++t) {
      progress.tick(t, 4 * nt + 1);
      const uint32_t *v = &tris[3 * t];
      int i, j, l;
      Ch c;
      if (!dt_.is_facet(vh[v[0]], vh[v[1]], vh[v[2]], c, i, j, l))
        continue; // a hole-filling triangle: not a Delaunay facet
      int f = 6 - i - j - l;
      fc[t] = c;
      fi[t] = int8_t(f);
      Ch nb = c->neighbor(f);
      bool c_front = in_front(v, c, f);
      if (dt_.is_infinite(c))
        hull_vote[t] = c_front ? 1 : -1;
      else if (dt_.is_infinite(nb))
        hull_vote[t] = c_front ? -1 : 1;
    }
    flip_inward_components(tris, hull_vote);

    std::vector<Ch> queue;
    for (size_t t = 0; t < nt; ++t) {
      if (fi[t] < 0)
        continue;
      Ch c = fc[t], nb = c->neighbor(fi[t]);
      bool c_front = in_front(&tris[3 * t], c, fi[t]);
      vote(c, c_front ? kOutside : kInside);
      vote(nb, c_front ? kInside : kOutside);
      c->info().w.barrier |= uint8_t(1u << fi[t]);
      nb->info().w.barrier |= uint8_t(1u << nb->index(c));
    }
    for (auto c = dt_.all_cells_begin(); c != dt_.all_cells_end(); ++c) {
      CellLabel &w = c->info().w;
      if (dt_.is_infinite(c))
        w.label = kOutside;
      else if (w.vin || w.vout)
        w.label = w.vin > w.vout ? kInside : kOutside;
      if (w.label != kUnlabelled)
        queue.push_back(c);
    }
    progress.tick(nt, 4 * nt + 1);
    // Level by level, so that the result does not depend on the order of
    // the cells in memory: a cell reached from the last level takes the
    // label of most of its neighbours there (outside on a tie), counted in
    // w.local (inside in the high half).
    std::vector<Ch> next;
    while (!queue.empty()) {
      next.clear();
      for (Ch c : queue) {
        const CellLabel w = c->info().w;
        for (int f = 0; f < 4; ++f) {
          if (w.barrier & (1u << f))
            continue;
          CellLabel &v = c->neighbor(f)->info().w;
          if (v.label != kUnlabelled)
            continue;
          if (v.local == 0)
            next.push_back(c->neighbor(f));
          v.local += w.label == kInside ? 1u << 16 : 1u;
        }
      }
      for (Ch c : next) {
        CellLabel &w = c->info().w;
        w.label = (w.local >> 16) > (w.local & 0xFFFFu) ? kInside : kOutside;
        w.local = 0;
      }
      queue.swap(next);
    }
    queue = std::vector<Ch>();
    progress.tick(2 * nt, 4 * nt + 1);

    // Repair. Only vertices with cells of both labels around them can be
    // pinched.
    std::vector<uint8_t> seen(m, 0);
    for (auto c = dt_.finite_cells_begin(); c != dt_.finite_cells_end(); ++c)
      for (int j = 0; j < 4; ++j)
        seen[c->vertex(j)->info().idx] |= c->info().w.label;
    for (auto c = dt_.all_cells_begin(); c != dt_.all_cells_end(); ++c)
      if (dt_.is_infinite(c))
        for (int j = 0; j < 4; ++j)
          if (!dt_.is_infinite(c->vertex(j)))
            seen[c->vertex(j)->info().idx] |= kOutside;
    std::vector<Vh> work;
    std::vector<uint8_t> queued(m, 0);
    for (size_t i = 0; i < m; ++i)
      if (seen[i] == (kInside | kOutside)) {
        work.push_back(vh[i]);
        queued[i] = 1;
      }
    const uint64_t budget = 64 * uint64_t(work.size()) + 10000;
    uint64_t steps = 0;
    bool gave_up = false;
    // Rounds: a vertex at which no piece may move waits for the next round,
    // which allows more moves per cell.
    std::vector<Vh> unresolved, moved;
    for (int round = 0; round < 6; ++round) {
      // The first rounds leave the cells next to the surface where the
      // surface put them, so that the repair reshapes the caps over the
      // holes, not the surface; later rounds move any cell, more often.
      const bool keep_seeds = round < 3;
      const uint8_t max_moves = uint8_t(2 << (2 * (round % 3)));
      for (Vh v : unresolved)
        if (!queued[v->info().idx]) {
          queued[v->info().idx] = 1;
          work.push_back(v);
        }
      unresolved.clear();
      while (!work.empty() && !gave_up) {
        gave_up = ++steps > budget;
        Vh v = work.back();
        work.pop_back();
        queued[v->info().idx] = 0;
        moved.clear();
        if (!repair_vertex(v, max_moves, keep_seeds, moved, diag))
          unresolved.push_back(v);
        std::sort(moved.begin(), moved.end(), [](Vh a, Vh b) {
          return a->info().idx < b->info().idx;
        });
        for (Vh u : moved)
          if (!queued[u->info().idx]) {
            queued[u->info().idx] = 1;
            work.push_back(u);
          }
      }
    }
    progress.tick(3 * nt, 4 * nt + 1);
    (void)gave_up;

    std::vector<uint32_t> res;
    for (auto c = dt_.finite_cells_begin(); c != dt_.finite_cells_end(); ++c) {
      if (c->info().w.label != kInside)
        continue;
      for (int f = 0; f < 4; ++f) {
        if (c->neighbor(f)->info().w.label == kInside)
          continue;
        uint32_t t[3];
        for (int j = 0; j < 3; ++j)
          t[j] = c->vertex((f + 1 + j) % 4)->info().idx;
        // Outward: the cell's own fourth vertex must be behind.
        if (front(t, c->vertex(f)))
          std::swap(t[1], t[2]);
        res.insert(res.end(), t, t + 3);
      }
    }
    if (res.empty())
      return false;
    tris.swap(res);
    return true;
  }

  // The vertex numbers of a cell, ascending (the infinite vertex last): a
  // key that does not depend on where the cell lies in memory.
  std::array<uint32_t, 4> cell_key(Ch c) const {
    std::array<uint32_t, 4> k;
    for (int j = 0; j < 4; ++j)
      k[j] = dt_.is_infinite(c->vertex(j)) ? UINT32_MAX
                                            : c->vertex(j)->info().idx;
    std::sort(k.begin(), k.end());
    return k;
  }

  // Around vertex v, the cells of each label must form one piece, joined
  // across the facets at v. If they do not, moves the smallest piece that
  // may move (of a split label if possible; otherwise of the other label,
  // which then takes the whole star and v leaves the surface), and appends
  // the vertices of the moved cells to `touched`. A piece that holds an
  // infinite cell, or a cell moved max_moves times already, stays, so the
  // repair ends; so does one next to a surface triangle if keep_seeds.
  // Returns false when no piece could move.
  bool repair_vertex(Vh v, uint8_t max_moves, bool keep_seeds,
                     std::vector<Vh> &touched, sc_diag_t &diag) {
    std::vector<Ch> &inc = star_;
    inc.clear();
    dt_.incident_cells(v, std::back_inserter(inc));
    // In an order that depends on the vertices only, not on the memory.
    std::sort(inc.begin(), inc.end(),
              [&](Ch a, Ch b) { return cell_key(a) < cell_key(b); });
    const size_t k = inc.size();
    for (size_t i = 0; i < k; ++i)
      inc[i]->info().w.local = uint32_t(i);
    std::vector<uint32_t> &parent = parent_;
    parent.resize(k);
    std::iota(parent.begin(), parent.end(), 0u);
    auto find = [&](uint32_t x) {
      while (parent[x] != x)
        x = parent[x] = parent[parent[x]];
      return x;
    };
    for (size_t i = 0; i < k; ++i) {
      Ch c = inc[i];
      for (int f = 0; f < 4; ++f) {
        Ch nb = c->neighbor(f);
        if (c->vertex(f) == v || nb->info().w.label != c->info().w.label)
          continue;
        uint32_t a = find(uint32_t(i)), b = find(nb->info().w.local);
        if (a != b)
          parent[std::max(a, b)] = std::min(a, b);
      }
    }
    std::vector<uint32_t> &size = size_;
    size.assign(k, 0);
    std::vector<uint8_t> fixed(k, 0);
    int pieces[3] = {0, 0, 0};
    for (size_t i = 0; i < k; ++i) {
      uint32_t r = find(uint32_t(i));
      if (size[r]++ == 0)
        ++pieces[inc[r]->info().w.label];
      const CellLabel &w = inc[i]->info().w;
      if (dt_.is_infinite(inc[i]) || w.moved >= max_moves ||
          (keep_seeds && (w.vin || w.vout)))
        fixed[r] = 1;
    }
    if (pieces[kInside] <= 1 && pieces[kOutside] <= 1)
      return true;
    uint32_t pick = UINT32_MAX;
    bool pick_split = false;
    for (size_t i = 0; i < k; ++i) {
      if (find(uint32_t(i)) != i || fixed[i])
        continue;
      bool split = pieces[inc[i]->info().w.label] > 1;
      if (pick == UINT32_MAX || (split && !pick_split) ||
          (split == pick_split && size[i] < size[pick])) {
        pick = uint32_t(i);
        pick_split = split;
      }
    }
    if (pick == UINT32_MAX)
      return false;
    const uint8_t to =
        inc[pick]->info().w.label == kInside ? kOutside : kInside;
    for (size_t i = 0; i < k; ++i) {
      if (find(uint32_t(i)) != pick)
        continue;
      inc[i]->info().w.label = to;
      ++inc[i]->info().w.moved;
      ++diag.cells_relabelled;
      for (int j = 0; j < 4; ++j)
        if (!dt_.is_infinite(inc[i]->vertex(j)))
          touched.push_back(inc[i]->vertex(j));
    }
    return true;
  }

  // Whether vertex d lies in front of (on the normal side of) the oriented
  // triangle t (vertex numbers), by an exact predicate: no Delaunay cell is
  // flat, so the answer is never a tie.
  bool front(const uint32_t *t, Vh d) const {
    return CGAL::orientation(vh_[t[0]]->point(), vh_[t[1]]->point(),
                             vh_[t[2]]->point(),
                             d->point()) == CGAL::POSITIVE;
  }
  // Whether cell c lies in front of its facet f, the triangle t.
  bool in_front(const uint32_t *t, Ch c, int f) const {
    if (!dt_.is_infinite(c->vertex(f)))
      return front(t, c->vertex(f));
    Ch nb = c->neighbor(f);
    return !front(t, nb->vertex(nb->index(c)));
  }

  // Flips every edge-connected component of tris whose votes (+1 for a
  // hull triangle facing the infinite cell, -1 for one facing away) add up
  // to less than zero.
  static void flip_inward_components(std::vector<uint32_t> &tris,
                                     const std::vector<int8_t> &votes) {
    const size_t nt = tris.size() / 3;
    std::vector<std::pair<uint64_t, uint32_t>> edges;
    edges.reserve(3 * nt);
    for (size_t t = 0; t < nt; ++t)
      for (int k = 0; k < 3; ++k) {
        uint64_t a = tris[3 * t + k], b = tris[3 * t + (k + 1) % 3];
        edges.emplace_back(a < b ? (a << 32) | b : (b << 32) | a,
                           uint32_t(t));
      }
    std::sort(edges.begin(), edges.end());
    std::vector<uint32_t> parent(nt);
    std::iota(parent.begin(), parent.end(), 0u);
    auto find = [&](uint32_t x) {
      while (parent[x] != x)
        x = parent[x] = parent[parent[x]];
      return x;
    };
    for (size_t i = 1; i < edges.size(); ++i)
      if (edges[i].first == edges[i - 1].first) {
        uint32_t a = find(edges[i].second), b = find(edges[i - 1].second);
        if (a != b)
          parent[std::max(a, b)] = std::min(a, b);
      }
    std::vector<int64_t> score(nt, 0);
    for (size_t t = 0; t < nt; ++t)
      score[find(uint32_t(t))] += votes[t];
    for (size_t t = 0; t < nt; ++t)
      if (score[find(uint32_t(t))] < 0)
        std::swap(tris[3 * t + 1], tris[3 * t + 2]);
  }

  void vote(Ch c, uint8_t label) {
    CellLabel &w = c->info().w;
    if (label == kInside && w.vin < UINT16_MAX)
      ++w.vin;
    if (label == kOutside && w.vout < UINT16_MAX)
      ++w.vout;
  }

  void select_candidates(const sc_params_t &params, Progress &progress,
                         std::vector<uint32_t> &tris, sc_diag_t &diag) {
    Criteria cr(params);
    const bool detect = detects_boundary(params.mode);
    size_t cells = dt_.number_of_cells(), k = 0;
    V3 cc, P[3], poles[3], CP[4], Cpoles[4];
    bool interior[3] = {true, true, true}, Cinterior[4];
    int side1[3] = {0, 0, 0}, Cside[4] = {0, 0, 0, 0};
    uint32_t idx[3], Cidx[4];
    const bool cocone = cr.mode == SC_MODE_COCONE;
    // A cell's circumcentre and four vertices, read once for the facets it
    // handles.
    auto load = [&](Ch c) {
      const float *ccc = c->info().cc;
      cc = {ccc[0], ccc[1], ccc[2]};
      for (int j = 0; j < 4; ++j) {
        Vh v = c->vertex(j);
        const VertexData &d = v->info();
        CP[j] = v3(v->point());
        Cpoles[j] = {d.pole[0], d.pole[1], d.pole[2]};
        Cidx[j] = d.idx;
        Cinterior[j] = !detect || (d.flags & kVInterior) != 0;
        if (cocone && Cinterior[j])
          Cside[j] = cone_side(cc - CP[j], Cpoles[j], cr.sin2_cocone);
      }
    };
    // Facet f of the cell loaded, whose dual Voronoi edge runs from its
    // circumcentre to `other`, or leaves the hull outward when `ray`.
    auto facet = [&](int f, V3 other, bool ray) {
      ++diag.delaunay_facets;
      for (int j = 0; j < 3; ++j) {
        const int i = (f + 1 + j) % 4;
        P[j] = CP[i];
        poles[j] = Cpoles[i];
        idx[j] = Cidx[i];
        interior[j] = Cinterior[i];
        side1[j] = Cside[i];
      }
      if (ray) {
        V3 nrm = cross(P[1] - P[0], P[2] - P[0]);
        V3 o = CP[f];
        other = dot(nrm, o - P[0]) > 0 ? -1.0 * nrm : nrm;
      }
      if (is_candidate(cr, P, poles, interior, side1, cc, other, ray)) {
        tris.push_back(idx[0]);
        tris.push_back(idx[1]);
        tris.push_back(idx[2]);
      }
    };
    // Each facet between two finite cells is handled from the cell at the
    // lower address, which reads nothing of the other cell but its
    // circumcentre (for_cells() asks for that in advance); the facets of the
    // hull come after.
    for_cells(true, [&](auto c) {
      progress.tick(k++, cells);
      bool loaded = false;
      for (int f = 0; f < 4; ++f) {
        Ch nb = c->neighbor(f);
        if (&*nb < &*c || nb->info().infinite())
          continue;
        if (!loaded) {
          load(c);
          loaded = true;
        }
        const float *oc = nb->info().cc;
        facet(f, {oc[0], oc[1], oc[2]}, false);
      }
    });
    for (Ch o : infinite_) {
      Ch c = o->neighbor(o->index(dt_.infinite_vertex()));
      load(c);
      facet(c->index(o), {0, 0, 0}, true);
    }
    infinite_ = {};
  }

  DT dt_;
  // The Hilbert order of the points 0 .. n-1 when they were inserted as one
  // range (see insert()); empty otherwise.
  std::vector<uint32_t> hilbert_;
  std::vector<Vh> vh_; // vertex number -> handle, while closing
  std::vector<Ch> star_; // scratch of repair_vertex()
  std::vector<Ch> infinite_; // from the poles stage to the candidates
  std::vector<uint32_t> parent_, size_;
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
