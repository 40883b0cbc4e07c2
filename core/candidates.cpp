// The candidate triangles: the one pass over the Delaunay facets that keeps
// those whose dual Voronoi edge passes the test of the mode (the cocone's,
// or the two criteria of the shortcrust mode).
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include "delaunay.hpp"

namespace sc {
namespace dt {
namespace {

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

} // namespace

template <class DT>
void select_candidates(DT &dt, std::vector<typename DT::Cell_handle> &infinite,
                       const sc_params_t &params, Progress &progress,
                       std::vector<uint32_t> &tris, sc_diag_t &diag,
                       const Ownership *own, Checks *check) {
  typedef typename DT::Vertex_handle Vh;
  typedef typename DT::Cell_handle Ch;
  // Room for the candidates (a closed surface has two triangles per
  // sample, the candidates a few more), and the part of it surely filled
  // resident at once (prefault.hpp; a tile's triangulation holds its
  // neighbours' points too, an open scan fewer triangles): growing the
  // list by doubling touched every page twice, a fault each.
  const size_t have = tris.size(), nv = dt.number_of_vertices();
  if (tris.capacity() < have + 15 * nv / 2) {
    tris.reserve(have + 15 * nv / 2);
    prefault(tris.data() + have, 9 * nv / 2 * sizeof(uint32_t));
  }
  Criteria cr(params);
  // The check's test: the cocone's (at every vertex: shortcrust mode
  // detects no boundary).
  Criteria cocone_cr(params);
  cocone_cr.mode = SC_MODE_COCONE;
  const NearR near(params);
  const bool detect = detects_boundary(params.mode);
  size_t cells = dt.number_of_cells(), k = 0;
  V3 cc, P[3], poles[3], CP[4], Cpoles[4];
  bool interior[3] = {true, true, true}, Cinterior[4];
  int side1[3] = {0, 0, 0}, Cside[4] = {0, 0, 0, 0};
  uint32_t idx[3], Cidx[4];
  const bool cocone = cr.mode == SC_MODE_COCONE || check;
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
    // The corners in the order of their vertex numbers: how a cell orders
    // its vertices depends on the order of insertion, and the rounding of
    // the tests on the order of the corners; this way a facet gets the same
    // answer whichever of its cells, and whichever triangulation (one, or a
    // tile's), reports it.
    int ci[3] = {(f + 1) % 4, (f + 2) % 4, (f + 3) % 4};
    auto order = [&](int a, int b) {
      if (Cidx[ci[b]] < Cidx[ci[a]])
        std::swap(ci[a], ci[b]);
    };
    order(0, 1), order(1, 2), order(0, 1);
    if (own && !(*own)(Cidx[ci[0]]))
      return;
    ++diag.delaunay_facets;
    for (int j = 0; j < 3; ++j) {
      const int i = ci[j];
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
    if (!check) {
      if (is_candidate(cr, P, poles, interior, side1, cc, other, ray))
        tris.insert(tris.end(), idx, idx + 3);
      return;
    }
    // Shortcrust mode with its check: the criteria once, at every r near.
    const int least = near.least(P, poles, cc, other, ray);
    if (least <= kNearR / 2)
      tris.insert(tris.end(), idx, idx + 3);
    if (least < kNearR)
      check->near[least].insert(check->near[least].end(), idx, idx + 3);
    if (is_candidate(cocone_cr, P, poles, interior, side1, cc, other, ray))
      check->cocone.insert(check->cocone.end(), idx, idx + 3);
  };
  // Each facet between two finite cells is handled from the cell at the
  // lower address, which reads nothing of the other cell but its
  // circumcentre (for_cells() asks for that in advance); the facets of the
  // hull come after.
  for_cells(dt, true, [&](auto c) {
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
  for (Ch o : infinite) {
    Ch c = o->neighbor(o->index(dt.infinite_vertex()));
    load(c);
    facet(c->index(o), {0, 0, 0}, true);
  }
  infinite = {};
}

template void select_candidates<DtSeq>(DtSeq &,
                                       std::vector<DtSeq::Cell_handle> &,
                                       const sc_params_t &, Progress &,
                                       std::vector<uint32_t> &, sc_diag_t &,
                                       const Ownership *, Checks *);

} // namespace dt
} // namespace sc
