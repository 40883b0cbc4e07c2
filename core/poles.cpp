// The poles: for each sample, the direction to the farthest vertex of its
// Voronoi cell (on the hull, the average outward normal of the hull facets
// around it), which the candidate tests and the normals take for the
// surface normal's line. Each cell keeps its circumcentre for the stages
// after.
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include "delaunay.hpp"

#include <tuple>

namespace sc {
namespace dt {

// A nearly flat cell's power (below) at most this times the squared radius
// of its largest facet's circle: its four points are taken for points of
// one circle, as on grids and rings of samples, whose rounding gives
// powers many orders of magnitude smaller.
constexpr double kCocircular = 1e-6;

V3 cell_circumcentre(const Point *p, bool &guarded) {
  const V3 a = v3(p[0]), b = v3(p[1]), c = v3(p[2]), d = v3(p[3]);
  V3 u = b - a, v = c - a, w = d - a;
  V3 vw = cross(v, w);
  double det = dot(u, vw);
  double scale = std::sqrt(norm2(u) * norm2(v) * norm2(w));
  guarded = false;
  if (std::fabs(det) > kFlatCell * scale) {
    V3 num = norm2(u) * vw + norm2(v) * cross(w, u) + norm2(w) * cross(u, v);
    V3 cc = a + (0.5 / det) * num;
    if (finite(cc))
      return cc;
  }
  guarded = true;
  const V3 q[4] = {a, b, c, d};
  double best = -1;
  int facet = -1;
  V3 out = 0.25 * (a + b + c + d);
  for (int i = 0; i < 4; ++i) {
    V3 x = q[(i + 1) % 4], y = q[(i + 2) % 4], z = q[(i + 3) % 4];
    double area2 = norm2(cross(y - x, z - x));
    V3 cc;
    if (area2 > best && tri_circumcentre(x, y, z, cc)) {
      best = area2;
      out = cc;
      facet = i;
    }
  }
  if (facet < 0)
    return out;
  // Off the circle of that facet, the fourth point puts the centre far
  // along the facet's normal, t = power / (2 h) from its circle's centre
  // (power: the fourth point's against the facet's smallest sphere; h: its
  // height over the facet), on the side that the signs of the two give,
  // the height's taken exactly. The height is too small to measure: the
  // distance is the least it can be under the guard. On one circle, or in
  // one plane exactly, the facet's circumcentre stands.
  const int i = facet;
  const V3 x = q[(i + 1) % 4], y = q[(i + 2) % 4], z = q[(i + 3) % 4];
  const double r2 = norm2(out - x), power = norm2(q[i] - out) - r2;
  if (!(std::fabs(power) > kCocircular * r2))
    return out;
  const CGAL::Orientation side =
      CGAL::orientation(p[(i + 1) % 4], p[(i + 2) % 4], p[(i + 3) % 4], p[i]);
  if (side == CGAL::COPLANAR)
    return out;
  const V3 nrm = cross(y - x, z - x);
  const double len = std::sqrt(norm2(nrm));
  const double t = power * len / (2 * kFlatCell * scale);
  const V3 far = out + ((side == CGAL::POSITIVE ? t : -t) / len) * nrm;
  return finite(far) ? far : out;
}

namespace {

// The circumcentre of cell c (counting a guarded one in diag, if given).
template <class DT> V3 centre(typename DT::Cell_handle c, sc_diag_t *diag) {
  bool guarded;
  const V3 cc = cell_circumcentre(c, guarded);
  if (guarded && diag)
    ++diag->degenerate_cells;
  return cc;
}

} // namespace

template <class DT>
void compute_poles(DT &dt, std::vector<typename DT::Cell_handle> &infinite,
                   Progress &progress, sc_diag_t &diag, const Ownership *own) {
  typedef typename DT::Vertex_handle Vh;
  typedef typename DT::Cell_handle Ch;
  const float kHull = std::numeric_limits<float>::infinity();

  // Samples on the convex hull: the pole is at infinity, in the direction
  // of the average outward normal of the hull facets around them. The
  // infinite cells are kept for boundary detection and the candidates.
  // A cell, or a facet of the hull, belongs to a tile by its
  // lowest-numbered vertex.
  auto owns = [own](Ch c, int skip) {
    if (!own)
      return true;
    uint32_t low = UINT32_MAX;
    for (int j = 0; j < 4; ++j)
      if (j != skip)
        low = std::min(low, c->vertex(j)->info().idx);
    return (*own)(low);
  };
  infinite.clear();
  dt.incident_cells(dt.infinite_vertex(), std::back_inserter(infinite));
  for (Ch c : infinite) {
    c->info().mark_infinite();
    int inf = c->index(dt.infinite_vertex());
    diag.hull_facets += owns(c, inf);
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
  size_t cells = dt.number_of_cells(), k = 0;
  for_cells(dt, false, [&](auto c) {
    progress.tick(k++, cells);
    const bool mine = owns(c, -1);
    diag.delaunay_cells += mine;
    V3 cc = centre<DT>(c, mine ? &diag : nullptr);
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
  for (auto v = dt.finite_vertices_begin(); v != dt.finite_vertices_end();
       ++v) {
    VertexData &d = v->info();
    if (d.best == kHull && (!own || (*own)(d.idx)))
      ++diag.hull_vertices;
    double l = std::sqrt(d.pole[0] * d.pole[0] + d.pole[1] * d.pole[1] +
                         d.pole[2] * d.pole[2]);
    if (l > 0)
      d.pole[0] /= l, d.pole[1] /= l, d.pole[2] /= l;
  }
}

template void compute_poles<DtSeq>(DtSeq &, std::vector<DtSeq::Cell_handle> &,
                                   Progress &, sc_diag_t &, const Ownership *);

} // namespace dt
} // namespace sc
