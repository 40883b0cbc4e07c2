// What the stages that need the Delaunay triangulation share: the
// triangulation's types, with what each vertex and cell carries, the
// geometry on them, and the stages (one file each) that delaunay.cpp runs
// in order. Only the files of those stages include this header, and it must
// come before any CGAL header in them (see CGAL_ALLOCATOR below).
//
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef SC_CORE_DELAUNAY_HPP
#define SC_CORE_DELAUNAY_HPP

#include "internal.hpp"
#include "prefault.hpp"

#ifdef CGAL_CONFIG_H
#error "delaunay.hpp must come before any CGAL header"
#endif
// Blocks of cells and vertices come with their pages resident (see
// prefault.hpp); CGAL's own default is std::allocator. The macro is CGAL's
// hook for its containers' default allocator, and it must come before
// CGAL's headers. It changes the instantiations of the files that include
// this header, which are the only files of the core to include CGAL: they
// all see the same allocator, so the triangulation types they share
// (declared below, in a namespace of their own) are the same everywhere.
// Other programs that link the core and include CGAL themselves (the modes
// table) instantiate only CGAL's own vertex and cell types, never these.
#define CGAL_ALLOCATOR(T) sc::PrefaultAllocator<T>
#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Delaunay_triangulation_cell_base_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_cell_base_with_info_3.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <type_traits>
#include <vector>

namespace sc {
namespace dt {

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
  uint32_t local; // scratch: the cell's number, or place in a vertex's star
  uint8_t label;  // kUnlabelled, kInside, kOutside
  uint8_t moved;  // times the repair moved it
};
enum : uint8_t { kUnlabelled = 0, kInside = 1, kOutside = 2 };
// Boundary detection ignores, for the extent of a cell in the cocone, a
// circumcentre farther than this from the cell's vertices, relative to the
// cell's longest edge (squared).
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
// CGAL_ALLOCATOR above reached the containers of cells and vertices.
static_assert(std::is_same<TdsSeq::Cell_range::allocator_type,
                           PrefaultAllocator<TdsSeq::Cell>>::value &&
                  std::is_same<TdsSeq::Vertex_range::allocator_type,
                               PrefaultAllocator<TdsSeq::Vertex>>::value,
              "the triangulation's blocks bypass PrefaultAllocator");

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

// Where a point of the dual Voronoi edge, at dir from a sample, lies
// relative to the sample's cocone (docs/algorithm.md section 6.3): -1 or +1
// in one of the two cones around the pole, 0 inside the cocone.
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

// Circumcentre of triangle abc; returns false when it is degenerate.
inline bool tri_circumcentre(V3 a, V3 b, V3 c, V3 &out) {
  V3 u = b - a, v = c - a, w = cross(u, v);
  double w2 = norm2(w);
  if (!(w2 > 0))
    return false;
  V3 num = norm2(u) * cross(v, w) + norm2(v) * cross(w, u);
  out = a + (0.5 / w2) * num;
  return finite(out);
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

// A cell is nearly flat where the triple product of its edge vectors from
// one corner is at most this times the product of their lengths.
constexpr double kFlatCell = 1e-10;

// The circumcentre of a finite cell, its corners p[0..3] in the order of
// their numbers (corners_by_number()); a nearly flat cell's is guarded, and
// sets `guarded` (docs/algorithm.md section 4.1).
V3 cell_circumcentre(const Point *p, bool &guarded);

// The four vertices of finite cell c into v, in the order of their
// numbers: how a cell orders its vertices depends on the order of
// insertion, and what is computed from them in that order would round
// differently in another triangulation of the same points (tiles, a
// daemon's chunks, one built again).
template <class Ch, class Vh> void corners_by_number(Ch c, Vh (&v)[4]) {
  for (int j = 0; j < 4; ++j)
    v[j] = c->vertex(j);
  auto order = [&](int i, int j) {
    if (v[j]->info().idx < v[i]->info().idx)
      std::swap(v[i], v[j]);
  };
  order(0, 1), order(2, 3), order(0, 2), order(1, 3), order(1, 2);
}

// The circumcentre of finite cell c, from its corners in the order of their
// numbers (on nearly flat cells the rounding of the centre is enough to
// change the surface), as cell_circumcentre() gives it.
template <class Ch> V3 cell_circumcentre(Ch c, bool &guarded) {
  decltype(c->vertex(0)) v[4];
  corners_by_number(c, v);
  const Point p[4] = {v[0]->point(), v[1]->point(), v[2]->point(),
                      v[3]->point()};
  return cell_circumcentre(p, guarded);
}

// Outward unit normal of the hull facet of infinite cell c (its infinite
// vertex is vertex inf).
template <class Ch> V3 hull_normal(Ch c, int inf, V3 *pts) {
  // From the corner with the smallest vertex number, in the cell's cyclic
  // order, so that the rounding does not depend on the order of insertion.
  int first = 0;
  for (int k = 1; k < 3; ++k)
    if (c->vertex((inf + 1 + k) % 4)->info().idx <
        c->vertex((inf + 1 + first) % 4)->info().idx)
      first = k;
  const Point *corner[3];
  for (int k = 0; k < 3; ++k) {
    corner[k] = &c->vertex((inf + 1 + (first + k) % 3) % 4)->point();
    pts[k] = v3(*corner[k]);
  }
  V3 n = cross(pts[1] - pts[0], pts[2] - pts[0]);
  // Away from the finite cell's fourth corner, by the exact orientation:
  // where that corner lies nearly in the facet's plane (a flat face of the
  // hull, sampled), the rounded dot product can come out 0 or of either
  // sign, and would turn the normal inward in one triangulation and not
  // in another.
  Ch inner = c->neighbor(inf);
  if (CGAL::orientation(*corner[0], *corner[1], *corner[2],
                        inner->vertex(inner->index(c))->point()) ==
      CGAL::POSITIVE)
    n = -1.0 * n;
  double l = std::sqrt(norm2(n));
  return l > 0 ? (1 / l) * n : V3{0, 0, 0};
}

// Calls visit(c) on every finite cell c, asking a few cells ahead for the
// vertices and, with `neighbours`, for the data of the neighbouring cells
// at higher addresses (what the candidates read): they are scattered over
// memory, and waiting for each in turn was most of the time of these
// passes.
template <class It, class Visit>
void for_cells_in(It begin, It end, bool neighbours, Visit &&visit) {
  constexpr int kAhead = 4;
  auto ahead = begin;
  for (int i = 0; i < kAhead && ahead != end; ++i)
    ++ahead;
  for (auto c = begin; c != end; ++c) {
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
template <class DT, class Visit>
void for_cells(DT &dt, bool neighbours, Visit &&visit) {
  for_cells_in(dt.finite_cells_begin(), dt.finite_cells_end(), neighbours,
               visit);
}

// The cells of dt in k slices of about equal shares of its cell container,
// in the container's order: slice i runs from bounds[i] to bounds[i + 1]
// (k + 1 bounds, the last the end), each of all the cells, infinite ones
// too. Found from the container's blocks, without a pass over the cells.
template <class DT>
std::vector<typename DT::Cell_iterator> cell_slices(DT &dt, size_t k) {
  auto &cells = dt.tds().cells();
  const size_t cap = cells.capacity();
  std::vector<typename DT::Cell_iterator> bounds;
  bounds.push_back(cells.begin());
  for (size_t i = 1; i < k; ++i) {
    size_t j = cap * i / k;
    while (j < cap && !cells.is_used(j))
      ++j;
    bounds.push_back(j < cap ? cells.iterator_to(cells[j]) : cells.end());
  }
  bounds.push_back(cells.end());
  return bounds;
}

// A sort of point indices along a Hilbert curve of their points: CGAL's
// hilbert_sort() with its median policy (the same shuffle, the same
// splits, the same order), in parts that may run on threads. begin(), or
// else the first part() to run, makes the shuffle and the first level's
// splits (the others wait for it); each part then sorts an eighth of the
// indices alone. The order does not depend on which parts run where, or
// when.
class HilbertSort {
public:
  static constexpr size_t kParts = 8;
  HilbertSort(const double *xyz, std::vector<uint32_t> idx)
      : xyz_(xyz), idx_(std::move(idx)) {}
  // The indices 0 .. n-1, made (resident at once: prefault.hpp) by
  // begin(), on its thread.
  HilbertSort(const double *xyz, size_t n) : xyz_(xyz), all_(n) {}
  void begin() {
    std::call_once(split_once_, [this] { split(); });
  }
  void part(size_t i);
  // The sorted indices, once every part has run.
  std::vector<uint32_t> take() { return std::move(idx_); }

private:
  void split();
  const double *xyz_;
  std::vector<uint32_t> idx_;
  size_t all_ = 0;
  std::once_flag split_once_;
  size_t cut_[kParts + 1] = {};
};
// Sorts point indices along a Hilbert curve of their points (HilbertSort,
// on this thread).
void hilbert_sort(const double *xyz, std::vector<uint32_t> &idx);
// The indices 0 .. n-1 of the points in Hilbert order (resident at once:
// prefault.hpp).
std::vector<uint32_t> hilbert_order(const double *xyz, size_t n);
// A biased randomized insertion order (Amenta, Choi and Rote) drawn from a
// Hilbert order of the indices: rounds, each a quarter of the size of the
// next, each in Hilbert order (delaunay.cpp).
std::vector<uint32_t> brio_order(const std::vector<uint32_t> &hilbert);

// Which vertices a tile of a tiled filtering owns (tiles.cpp): by vertex
// number, the tile of each. A tile counts, and decides, only what belongs
// to it: a cell or a facet belongs to the tile of its lowest-numbered
// vertex. Null for the whole triangulation.
struct Ownership {
  const uint16_t *owner;
  uint16_t tile;
  bool operator()(uint32_t vertex) const { return owner[vertex] == tile; }
};

// The stages, in the order delaunay.cpp runs them, each in its own file.

// Poles (poles.cpp): each vertex's pole direction, unit, and each finite
// cell's circumcentre (CellData::cc); infinite receives the infinite cells,
// marked as such, for the stages after.
// With own, the counts in diag are of what the tile owns, and the poles
// of its own vertices are the whole triangulation's when every cell around
// them is (tiles.cpp); the others' are not used.
template <class DT>
void compute_poles(DT &dt, std::vector<typename DT::Cell_handle> &infinite,
                   Progress &progress, sc_diag_t &diag,
                   const Ownership *own = nullptr);

// Boundary detection (boundary.cpp), after the poles: marks the interior
// samples (kVInterior) and fills boundary by vertex number (or leaves it
// empty, every sample interior, when too few are).
template <class DT>
void classify(DT &dt, const std::vector<typename DT::Cell_handle> &infinite,
              const sc_params_t &params, Progress &progress,
              std::vector<uint8_t> &boundary, sc_diag_t &diag);

// The same over tiles (tiles.cpp), in its steps. A sample's state, by
// vertex number: 0 when it fails the ratio test, 1 interior, 2 waiting (a
// boundary sample unless the growth reaches it).
//  - classify_measure(), in each tile once the poles of all its vertices
//    are set: the states of the samples own allows (all without it); it
//    returns the links of every cell, for classify_links();
//  - classify_links(), in each tile once every state is in: the links of
//    the cells the tile owns (by their lowest-numbered vertex) that the
//    growth may follow, (from, to) by vertex number; frees cell_links;
//  - classify_join(), once: the growth over all the links, then
//    classify_end(), which fills boundary and diag (and makes every sample
//    interior where too few are);
//  - mark_interior(), in each tile: kVInterior from the states.
template <class DT>
std::vector<uint16_t>
classify_measure(DT &dt, const std::vector<typename DT::Cell_handle> &infinite,
                 const sc_params_t &params, Progress &progress,
                 std::vector<uint8_t> &state, const Ownership *own);
template <class DT>
void classify_links(DT &dt, std::vector<uint16_t> &cell_links,
                    const Ownership &own, const std::vector<uint8_t> &state,
                    std::vector<std::pair<uint32_t, uint32_t>> &links);
void classify_join(const sc_params_t &params, std::vector<uint8_t> &state,
                   std::vector<std::pair<uint32_t, uint32_t>> &links,
                   std::vector<uint8_t> &boundary, sc_diag_t &diag);
void classify_end(const sc_params_t &params, std::vector<uint8_t> &state,
                  std::vector<uint8_t> &boundary, sc_diag_t &diag);
template <class DT>
void mark_interior(DT &dt, const std::vector<uint8_t> &state);

// The candidate triangles (candidates.cpp), by vertex number, from the one
// pass over the Delaunay facets; frees infinite.
// With own, only the facets the tile owns are tested and counted. With
// check (shortcrust mode), what its check needs goes there too (section
// 6.5), not yet in canonical order. On `threads` threads (without own,
// and into an empty tris), in any order, with the rest of the candidates
// in the lists of `later`, to be joined to tris.
template <class DT>
void select_candidates(DT &dt, std::vector<typename DT::Cell_handle> &infinite,
                       const sc_params_t &params, Progress &progress,
                       std::vector<uint32_t> &tris, sc_diag_t &diag,
                       const Ownership *own, Checks *check, unsigned threads,
                       std::vector<std::vector<uint32_t>> &later);
template <class DT>
void select_candidates(DT &dt, std::vector<typename DT::Cell_handle> &infinite,
                       const sc_params_t &params, Progress &progress,
                       std::vector<uint32_t> &tris, sc_diag_t &diag,
                       const Ownership *own = nullptr,
                       Checks *check = nullptr) {
  std::vector<std::vector<uint32_t>> later; // stays empty on one thread
  select_candidates(dt, infinite, params, progress, tris, diag, own, check, 1,
                    later);
}

// A Triangulator (delaunay.cpp) that takes over dt, whose vertices carry
// input indices (dt is left empty), with the points of rest (input indices)
// inserted: all of them then, as if insert() had inserted them.
std::unique_ptr<Triangulator> adopt_triangulation(DtSeq &dt, const double *xyz,
                                                  std::vector<uint32_t> rest,
                                                  Progress &progress);

// Watertight mode's labelling of the cells (labels.cpp): see
// Triangulator::close().
template <class DT>
bool label_and_close(DT &dt, std::vector<uint32_t> &tris, Progress &progress,
                     sc_diag_t &diag, double cocone_theta);

} // namespace dt
} // namespace sc

#endif
