// Boundary detection: which samples are interior, and which lie where the
// surface ends or is undersampled (see classify()).
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include "delaunay.hpp"

namespace sc {
namespace dt {
namespace {

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

// On the hull the Voronoi cell is unbounded, in the directions of the
// outward normals of the hull facets around the sample, and the pole is
// their average, so the ratio test sees nothing of that part of the
// cell. Where the surface goes on beyond a hull sample these normals
// stay close together; where it ends there (the rim of a hemisphere or
// of a scan, whose hull facets span the missing part) they fan out. So r
// is infinite when two of them are more than (pi/2 - theta) / 2 apart:
// the cell then opens up sideways, whatever the true normal is.
template <class DT>
void open_hull_cells(DT &dt,
                     const std::vector<typename DT::Cell_handle> &infinite,
                     double cocone_theta) {
  typedef typename DT::Vertex_handle Vh;
  typedef typename DT::Cell_handle Ch;
  const float kInf = std::numeric_limits<float>::infinity();
  const double cos_fan = std::cos((M_PI / 2 - cocone_theta) / 2);
  // One normal per hull facet, and per hull vertex the list of the
  // facet corners at it (sorting corners by vertex cost more than the
  // rest of this stage on small input, and a vector of (vertex, normal)
  // pairs grown one by one was most of its memory).
  const std::vector<Ch> &outside = infinite;
  auto corner = [&](uint32_t i) {
    Ch c = outside[i / 3];
    return c->vertex((c->index(dt.infinite_vertex()) + 1 + i % 3) % 4);
  };
  // In a tile (tiles.cpp) the vertices carry the numbers of all the
  // points, beyond the tile's own count of vertices.
  uint32_t top = 0;
  for (uint32_t i = 0; i < 3 * outside.size(); ++i)
    top = std::max(top, corner(i)->info().idx + 1);
  std::vector<V3> hull(outside.size());
  std::vector<uint32_t> head(top, UINT32_MAX), next(3 * outside.size());
  for (uint32_t f = 0; f < outside.size(); ++f) {
    V3 pts[3];
    hull[f] = hull_normal(outside[f],
                          outside[f]->index(dt.infinite_vertex()), pts);
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
}

// The ratio test's r and h, the nearest neighbours and the disagreeing
// poles, from one pass over the cells; returns, per cell in the order
// visited, the links that grow_interior() may follow (2 bytes a cell).
template <class DT>
std::vector<uint16_t> measure_cells(DT &dt, double sin2_c, double cos_a,
                                    Progress &progress) {
  const size_t cells = dt.number_of_cells();
  size_t k = 0;
  std::vector<uint16_t> cell_links(cells);
  V3 pole[4];
  bool in_cone[4], grow_cone[4];
  for_cells(dt, false, [&](auto c) {
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
    // (From the corner with the smallest number: how a cell orders its
    // corners depends on the order of insertion, and where the test is
    // close, so would its outcome, in tiles as against one triangulation.)
    int first = 0;
    for (int j = 1; j < 4; ++j)
      if (c->vertex(j)->info().idx < c->vertex(first)->info().idx)
        first = j;
    const bool trusted = norm2(cc - P[first]) <= kMaxCentreRatio2 * longest2;
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

  return cell_links;
}

// The ratio test (kVRatio): of the samples that pass it, those whose poles
// agree with every cocone neighbour's are the seeds, interior (state 1);
// the others wait (state 2). With own, only the tile's own samples.
template <class DT>
void ratio_test(DT &dt, double rho, std::vector<uint8_t> &state,
                const Ownership *own) {
  const float rho2 = float(rho * rho);
  for (auto v = dt.finite_vertices_begin(); v != dt.finite_vertices_end();
       ++v) {
    VertexData &d = v->info();
    if (own && !(*own)(d.idx))
      continue;
    d.flags &= uint8_t(~(kVRatio | kVInterior));
    if ((d.h2 > 0 && d.r2 <= rho2 * d.h2) || d.r2 <= kNearRatio2 * d.nn2)
      d.flags |= kVRatio;
    if (d.flags & kVRatio)
      state[d.idx] = (d.flags & kVDisagree) ? 2 : 1;
  }
}

// Makes interior (state 1) the waiting samples (state 2) that links
// (from, to) reach from the samples in grown, which are interior; frees
// links.
void follow_links(std::vector<std::pair<uint32_t, uint32_t>> &links,
                  std::vector<uint32_t> &grown, std::vector<uint8_t> &state) {
  const size_t m = state.size();
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
  while (!grown.empty()) {
    const uint32_t v = grown.back();
    grown.pop_back();
    for (uint32_t i = first[v]; i < first[v + 1]; ++i)
      if (state[to[i]] == 2) {
        state[to[i]] = 1;
        grown.push_back(to[i]);
      }
  }
}

// Growth from agreeing neighbours: a sample that passes the ratio test
// becomes interior when a cell around it whose circumcentre lies in the
// cocone of an interior neighbour joins it to that neighbour with poles
// that agree, until nothing changes. Only the samples that pass the
// ratio test but whose poles disagree (waiting) can change, so only the
// cells around them are looked at below, instead of the star of every
// interior sample.
// Makes interior (state 1) the waiting samples that the links reach from
// an interior one; frees cell_links.
template <class DT>
void grow_interior(DT &dt, std::vector<uint16_t> &cell_links,
                   std::vector<uint8_t> &state, Progress &progress) {
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
  const size_t cells = dt.number_of_cells();
  size_t k = 0;
  for_cells(dt, false, [&](auto c) {
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
  cell_links = {};
  follow_links(links, grown, state);
}

} // namespace

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
template <class DT>
void classify(DT &dt, const std::vector<typename DT::Cell_handle> &infinite,
              const sc_params_t &params, Progress &progress,
              std::vector<uint8_t> &boundary, sc_diag_t &diag) {
  std::vector<uint8_t> state(dt.number_of_vertices(), 0);
  std::vector<uint16_t> cell_links =
      classify_measure(dt, infinite, params, progress, state, nullptr);
  grow_interior(dt, cell_links, state, progress);
  classify_end(params, state, boundary, diag);
  mark_interior(dt, state);
}

template <class DT>
std::vector<uint16_t>
classify_measure(DT &dt, const std::vector<typename DT::Cell_handle> &infinite,
                 const sc_params_t &params, Progress &progress,
                 std::vector<uint8_t> &state, const Ownership *own) {
  const double rho =
      params.boundary_rho > 0 ? params.boundary_rho : kDefaultRho;
  const double alpha =
      params.boundary_alpha > 0 ? params.boundary_alpha : kDefaultAlpha;
  const double sin2_c = Criteria(params).sin2_cocone;
  const double cos_a = std::cos(alpha);
  open_hull_cells(dt, infinite, params.cocone_theta);
  std::vector<uint16_t> cell_links =
      measure_cells(dt, sin2_c, cos_a, progress);
  ratio_test(dt, rho, state, own);
  return cell_links;
}

template <class DT>
void classify_links(DT &dt, std::vector<uint16_t> &cell_links,
                    const Ownership &own, const std::vector<uint8_t> &state,
                    std::vector<std::pair<uint32_t, uint32_t>> &links) {
  size_t k = 0;
  for_cells(dt, false, [&](auto c) {
    const uint16_t mask = cell_links[k++];
    if (!mask)
      return;
    uint32_t idx[4], low = UINT32_MAX;
    for (int j = 0; j < 4; ++j) {
      idx[j] = c->vertex(j)->info().idx;
      low = std::min(low, idx[j]);
    }
    if (!own(low))
      return;
    for (int j = 0; j < 4; ++j)
      if (state[idx[j]] != 0)
        for (int i = 0; i < 4; ++i)
          if (((mask >> (4 * j + i)) & 1) && state[idx[i]] == 2)
            links.emplace_back(idx[j], idx[i]);
  });
  cell_links = {};
}

void classify_join(const sc_params_t &params, std::vector<uint8_t> &state,
                   std::vector<std::pair<uint32_t, uint32_t>> &links,
                   std::vector<uint8_t> &boundary, sc_diag_t &diag) {
  std::vector<uint32_t> grown;
  for (const auto &l : links)
    if (state[l.first] == 1 && state[l.second] == 2) {
      state[l.second] = 1;
      grown.push_back(l.second);
    }
  follow_links(links, grown, state);
  classify_end(params, state, boundary, diag);
}

// Auto and watertight mode: when most samples are not interior the
// sample is too sparse or too small to tell a boundary from undersampling
// (every sample of a tetrahedron is a boundary sample, and two thirds of a
// sparse genus-2 surface's), and boundary mode would keep little, or would
// open true handles that watertight mode then cuts; run the closed-surface
// algorithm instead (watertight mode still closes what it leaves open).
void classify_end(const sc_params_t &params, std::vector<uint8_t> &state,
                  std::vector<uint8_t> &boundary, sc_diag_t &diag) {
  const size_t m = state.size();
  const size_t interior = size_t(std::count(state.begin(), state.end(), 1));
  if ((params.mode == SC_MODE_AUTO || params.mode == SC_MODE_WATERTIGHT) &&
      2 * interior < m) {
    state.assign(m, 1);
    boundary.clear();
    return;
  }
  boundary.assign(m, 0);
  for (size_t v = 0; v < m; ++v) {
    if (state[v] == 1)
      continue;
    boundary[v] = state[v] == 2 ? kBoundarySample : kOpenSample;
    ++diag.boundary_samples;
  }
}

template <class DT>
void mark_interior(DT &dt, const std::vector<uint8_t> &state) {
  for (auto v = dt.finite_vertices_begin(); v != dt.finite_vertices_end();
       ++v) {
    VertexData &d = v->info();
    d.flags = uint8_t(state[d.idx] == 1 ? d.flags | kVInterior
                                        : d.flags & ~kVInterior);
  }
}

template void classify<DtSeq>(DtSeq &, const std::vector<DtSeq::Cell_handle> &,
                              const sc_params_t &, Progress &,
                              std::vector<uint8_t> &, sc_diag_t &);
template std::vector<uint16_t>
classify_measure<DtSeq>(DtSeq &, const std::vector<DtSeq::Cell_handle> &,
                        const sc_params_t &, Progress &, std::vector<uint8_t> &,
                        const Ownership *);
template void
classify_links<DtSeq>(DtSeq &, std::vector<uint16_t> &, const Ownership &,
                      const std::vector<uint8_t> &,
                      std::vector<std::pair<uint32_t, uint32_t>> &);
template void mark_interior<DtSeq>(DtSeq &, const std::vector<uint8_t> &);

} // namespace dt
} // namespace sc
