// Attaching the samples that no triangle uses: each goes into the nearest
// triangle (or edge) when it is close enough, keeping the surface a
// manifold and its description up to date.
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include "edges.hpp"

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
      double longest =
          std::max(dist2(a, b), std::max(dist2(b, c), dist2(c, a)));
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
