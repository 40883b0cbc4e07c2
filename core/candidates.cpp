// The candidate triangles: the one pass over the Delaunay facets that keeps
// those whose dual Voronoi edge passes the test of the mode (the cocone's,
// or the two criteria of the shortcrust mode).
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include "delaunay.hpp"
#include "parallel.hpp"

namespace sc {
namespace dt {
namespace {

// Triangulations of at least so many cells are scanned on more threads,
// when given them.
constexpr size_t kParallelCells = 1u << 14;

// What the paper's first criterion compares with cos theta: the unit
// normal n of triangle P and c1 = |n . pole| at the vertex with the largest
// angle, the one opposite the longest edge. False for a degenerate
// triangle.
bool normal_cosine(const V3 *P, const V3 *poles, V3 &n, double &c1) {
  n = cross(P[1] - P[0], P[2] - P[0]);
  const double n2 = norm2(n);
  if (!(n2 > 0))
    return false;
  n = (1 / std::sqrt(n2)) * n;
  const double l0 = norm2(P[1] - P[2]), l1 = norm2(P[0] - P[2]),
               l2 = norm2(P[0] - P[1]);
  const int s = l0 >= l1 ? (l0 >= l2 ? 0 : 2) : (l1 >= l2 ? 1 : 2);
  c1 = std::fabs(dot(n, poles[s]));
  return true;
}

// What the second compares with R tan phi: the circumradius R of triangle P
// (unit normal n) and the heights [lo, hi] of its dual Voronoi edge (from
// v1 to v2, or from v1 along v2 when `ray`) above its circumcentre. False
// when the circumcentre is not defined.
bool dual_heights(const V3 *P, V3 n, V3 v1, V3 v2, bool ray, double &R,
                  double &lo, double &hi) {
  V3 ct;
  if (!tri_circumcentre(P[0], P[1], P[2], ct))
    return false;
  R = std::sqrt(norm2(P[0] - ct));
  const double h1 = dot(v1 - ct, n);
  if (ray) {
    const double d = dot(v2, n);
    lo = d >= 0 ? h1 : -std::numeric_limits<double>::infinity();
    hi = d >= 0 ? std::numeric_limits<double>::infinity() : h1;
  } else {
    const double h2 = dot(v2 - ct, n);
    lo = std::min(h1, h2);
    hi = std::max(h1, h2);
  }
  return true;
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
  // Criterion 1: the normal at the vertex with the largest angle.
  V3 n;
  double c1;
  if (!normal_cosine(P, poles, n, c1) || c1 < cr.cos_theta1)
    return false;
  // Criterion 2: the dual edge's height interval above the triangle's
  // circumcentre must meet [-R tan phi, R tan phi].
  double R, lo, hi;
  if (!dual_heights(P, n, v1, v2, ray, R, lo, hi))
    return false;
  const double lim = R * cr.tan_phi;
  return hi >= -lim && lo <= lim;
}

// The paper's criteria at the values of r next to the one asked for
// (Checks): which is the least that a facet passes.
class NearR {
public:
  explicit NearR(const sc_params_t &params) {
    for (int k = 0; k < kNearR; ++k) {
      sc_params_t p = params;
      p.r = Checks::r_at(params.r, k);
      const bool valid = p.r > 0;
      const Criteria c(p);
      cos_theta1_[k] = valid ? c.cos_theta1 : HUGE_VAL;
      tan_phi_[k] = valid ? c.tan_phi : -HUGE_VAL;
    }
  }
  // The least k at which the facet passes both criteria, kNearR when it
  // passes at none. The measures are is_candidate()'s, so that at the
  // middle value, r itself, the answer is exactly its answer.
  int least(const V3 *P, const V3 *poles, V3 v1, V3 v2, bool ray) const {
    V3 n;
    double c1, R, lo, hi;
    if (!normal_cosine(P, poles, n, c1) ||
        !dual_heights(P, n, v1, v2, ray, R, lo, hi))
      return kNearR;
    for (int k = 0; k < kNearR; ++k)
      if (!(c1 < cos_theta1_[k]) && hi >= -R * tan_phi_[k] &&
          lo <= R * tan_phi_[k])
        return k;
    return kNearR;
  }

private:
  double cos_theta1_[kNearR], tan_phi_[kNearR];
};

// The pass over the facets, from the cells given to visit(): each facet
// between two finite cells from the cell at the lower address, which reads
// nothing of the other cell but its circumcentre; the hull's facets from
// hull(). Whatever cells one scan is given, it writes only its own
// lists, so that scans of separate cells may run on separate threads.
template <class DT> class FacetScan {
public:
  typedef typename DT::Vertex_handle Vh;
  typedef typename DT::Cell_handle Ch;

  FacetScan(const sc_params_t &params, const Ownership *own,
            std::vector<uint32_t> &tris, Checks *check)
      : cr_(params), cocone_cr_(params), near_(params),
        detect_(detects_boundary(params.mode)),
        cocone_(cr_.mode == SC_MODE_COCONE || check), own_(own), tris_(tris),
        check_(check) {
    // The check's test: the cocone's (at every vertex: shortcrust mode
    // detects no boundary).
    cocone_cr_.mode = SC_MODE_COCONE;
  }

  // The facets that cell c reports.
  template <class It> void cell(It c) {
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
  }

  // The facet of the hull of infinite cell o.
  void hull(Ch o, Vh infinite) {
    Ch c = o->neighbor(o->index(infinite));
    load(c);
    facet(c->index(o), {0, 0, 0}, true);
  }

  uint64_t facets() const { return facets_; }

private:
  // A cell's circumcentre and four vertices, read once for the facets it
  // handles.
  template <class It> void load(It c) {
    const float *ccc = c->info().cc;
    cc_ = {ccc[0], ccc[1], ccc[2]};
    for (int j = 0; j < 4; ++j) {
      Vh v = c->vertex(j);
      const VertexData &d = v->info();
      CP_[j] = v3(v->point());
      Cpoles_[j] = {d.pole[0], d.pole[1], d.pole[2]};
      Cidx_[j] = d.idx;
      Cinterior_[j] = !detect_ || (d.flags & kVInterior) != 0;
      if (cocone_ && Cinterior_[j])
        Cside_[j] = cone_side(cc_ - CP_[j], Cpoles_[j], cr_.sin2_cocone);
    }
  }

  // Facet f of the cell loaded, whose dual Voronoi edge runs from its
  // circumcentre to `other`, or leaves the hull outward when `ray`.
  void facet(int f, V3 other, bool ray) {
    // The corners in the order of their vertex numbers: how a cell orders
    // its vertices depends on the order of insertion, and the rounding of
    // the tests on the order of the corners; this way a facet gets the same
    // answer whichever of its cells, and whichever triangulation (one, or a
    // tile's), reports it.
    int ci[3] = {(f + 1) % 4, (f + 2) % 4, (f + 3) % 4};
    auto order = [&](int a, int b) {
      if (Cidx_[ci[b]] < Cidx_[ci[a]])
        std::swap(ci[a], ci[b]);
    };
    order(0, 1), order(1, 2), order(0, 1);
    if (own_ && !(*own_)(Cidx_[ci[0]]))
      return;
    ++facets_;
    V3 P[3], poles[3];
    bool interior[3];
    int side1[3];
    uint32_t idx[3];
    for (int j = 0; j < 3; ++j) {
      const int i = ci[j];
      P[j] = CP_[i];
      poles[j] = Cpoles_[i];
      idx[j] = Cidx_[i];
      interior[j] = Cinterior_[i];
      side1[j] = Cside_[i];
    }
    if (ray) {
      V3 nrm = cross(P[1] - P[0], P[2] - P[0]);
      V3 o = CP_[f];
      other = dot(nrm, o - P[0]) > 0 ? -1.0 * nrm : nrm;
    }
    if (!check_) {
      if (is_candidate(cr_, P, poles, interior, side1, cc_, other, ray))
        tris_.insert(tris_.end(), idx, idx + 3);
      return;
    }
    // Shortcrust mode with its check: the criteria once, at every r near.
    const int least = near_.least(P, poles, cc_, other, ray);
    if (least <= kNearR / 2)
      tris_.insert(tris_.end(), idx, idx + 3);
    if (least < kNearR)
      check_->near[least].insert(check_->near[least].end(), idx, idx + 3);
    if (is_candidate(cocone_cr_, P, poles, interior, side1, cc_, other, ray))
      check_->cocone.insert(check_->cocone.end(), idx, idx + 3);
  }

  const Criteria cr_;
  Criteria cocone_cr_;
  const NearR near_;
  const bool detect_, cocone_;
  const Ownership *own_;
  std::vector<uint32_t> &tris_;
  Checks *check_;
  uint64_t facets_ = 0;
  V3 cc_{0, 0, 0}, CP_[4], Cpoles_[4];
  bool Cinterior_[4] = {true, true, true, true};
  int Cside_[4] = {0, 0, 0, 0};
  uint32_t Cidx_[4] = {0, 0, 0, 0};
};

} // namespace

template <class DT>
void select_candidates(DT &dt, std::vector<typename DT::Cell_handle> &infinite,
                       const sc_params_t &params, Progress &progress,
                       std::vector<uint32_t> &tris, sc_diag_t &diag,
                       const Ownership *own, Checks *check, unsigned threads,
                       std::vector<std::vector<uint32_t>> &later) {
  // Room for the candidates (a closed surface has two triangles per
  // sample, the candidates a few more), and the part of it surely filled
  // resident at once (prefault.hpp; a tile's triangulation holds its
  // neighbours' points too, an open scan fewer triangles): growing the
  // list by doubling touched every page twice, a fault each.
  const size_t have = tris.size(), nv = dt.number_of_vertices();
  auto room = [](std::vector<uint32_t> &t, size_t vertices) {
    const size_t at = t.size();
    if (t.capacity() < at + 15 * vertices / 2) {
      t.reserve(at + 15 * vertices / 2);
      prefault(t.data() + at, 9 * vertices / 2 * sizeof(uint32_t));
    }
  };
  const size_t cells = dt.number_of_cells();
  // On more threads, the cells in slices of their container, each scanned
  // on a thread of its own into lists of its own, which are then joined:
  // the candidates are put in canonical order after, so that the order of
  // the slices does not show. On one, a single slice straight into tris.
  const size_t slices = own || threads < 2 || cells < kParallelCells || have
                            ? 1
                            : 4 * size_t(threads);
  const auto bounds = cell_slices(dt, slices);
  std::vector<std::vector<uint32_t>> found(slices > 1 ? slices : 0);
  std::vector<Checks> checks(check && slices > 1 ? slices : 0);
  std::vector<uint64_t> facets(slices, 0);
  auto out = [&](size_t i) -> std::vector<uint32_t> & {
    return slices > 1 ? found[i] : tris;
  };
  auto check_of = [&](size_t i) {
    return slices > 1 && check ? &checks[i] : check;
  };
  auto scan_slice = [&](size_t i, Progress &p) {
    room(out(i), nv / slices + 1);
    FacetScan<DT> scan(params, own, out(i), check_of(i));
    size_t k = 0;
    for_cells_in(bounds[i], bounds[i + 1], true, [&](auto c) {
      p.tick(k++, cells);
      if (!c->info().infinite())
        scan.cell(c);
    });
    facets[i] = scan.facets();
  };
  if (slices == 1)
    scan_slice(0, progress);
  else
    run_parallel(slices, threads, progress, scan_slice);
  // The hull's facets last, with the first slice.
  FacetScan<DT> scan(params, own, out(0), check_of(0));
  for (typename DT::Cell_handle o : infinite)
    scan.hull(o, dt.infinite_vertex());
  facets[0] += scan.facets();
  infinite = {};
  for (size_t i = 0; i < slices; ++i)
    diag.delaunay_facets += facets[i];
  if (slices == 1)
    return;
  // The first slice's list becomes tris (empty: no tile calls this), the
  // others wait in `later`, for the caller to join once the triangulation
  // is freed: joined here, the whole list would be a second copy of them
  // at the peak (the merged scans: 668 bytes a point on one thread, 724
  // on two).
  tris.swap(found[0]);
  for (size_t i = 1; i < slices; ++i)
    later.push_back(std::move(found[i]));
  if (!check)
    return;
  auto join = [](std::vector<uint32_t> &to, std::vector<uint32_t> &from) {
    to.insert(to.end(), from.begin(), from.end());
    from = {};
  };
  for (size_t i = 0; i < slices; ++i) {
    join(check->cocone, checks[i].cocone);
    for (int r = 0; r < kNearR; ++r)
      join(check->near[r], checks[i].near[r]);
  }
}

template void select_candidates<DtSeq>(DtSeq &,
                                       std::vector<DtSeq::Cell_handle> &,
                                       const sc_params_t &, Progress &,
                                       std::vector<uint32_t> &, sc_diag_t &,
                                       const Ownership *, Checks *, unsigned,
                                       std::vector<std::vector<uint32_t>> &);

} // namespace dt
} // namespace sc
