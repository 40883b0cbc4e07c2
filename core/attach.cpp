// Attaching the samples that no triangle uses: each goes into the nearest
// triangle (or edge) when it is close enough, keeping the surface a
// manifold and its description up to date.
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include "edges.hpp"

#include <unordered_map>

namespace sc {
namespace {

// Passes over the samples left out at most (see attach_samples()): on the
// models measured the last sample came in by the third.
constexpr int kAttachPasses = 8;

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

// Stars that change as triangles split: each vertex's triangles at the
// start, then those it gained, in a list per vertex in the order gained
// (a vector per vertex cost an allocation each and 24 bytes a vertex). A
// triangle split away from a vertex never comes back to it, so a star is
// read as the triangles that still have the vertex.
class GrowingStars {
public:
  GrowingStars(size_t n, const std::vector<uint32_t> &tris)
      : tris_(tris), gain_first_(n, UINT32_MAX), gain_last_(n, UINT32_MAX) {
    star0_.build(n, tris, [](size_t) { return true; });
  }
  // Vertex v is a corner of triangle t now.
  void gain(uint32_t v, uint32_t t) {
    const uint32_t i = uint32_t(gains_.size());
    gains_.push_back({t, UINT32_MAX});
    (gain_last_[v] == UINT32_MAX ? gain_first_[v]
                                 : gains_[gain_last_[v]].next) = i;
    gain_last_[v] = i;
  }
  // Calls visit(t) on every triangle t at vertex v.
  template <class Visit> void for_star(uint32_t v, Visit &&visit) const {
    for (uint32_t i = star0_.first[v]; i < star0_.first[v + 1]; ++i)
      if (has(star0_.tris[i], v))
        visit(star0_.tris[i]);
    for (uint32_t i = gain_first_[v]; i != UINT32_MAX; i = gains_[i].next)
      if (has(gains_[i].tri, v))
        visit(gains_[i].tri);
  }

private:
  bool has(uint32_t t, uint32_t v) const {
    const uint32_t *u = &tris_[3 * size_t(t)];
    return u[0] == v || u[1] == v || u[2] == v;
  }
  struct Gain {
    uint32_t tri, next;
  };
  const std::vector<uint32_t> &tris_;
  VertexStar star0_;
  std::vector<Gain> gains_;
  std::vector<uint32_t> gain_first_, gain_last_;
};

// The grid's cell size: twice the mean edge length of the triangles.
double grid_cell(const double *xyz, const std::vector<uint32_t> &tris) {
  const size_t nt = tris.size() / 3;
  double edge_sum = 0;
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t *v = &tris[3 * t];
    double sum = 0;
    for (int k = 0; k < 3; ++k)
      sum += std::sqrt(
          dist2(xyz + 3 * size_t(v[k]), xyz + 3 * size_t(v[(k + 1) % 3])));
    edge_sum += sum;
  }
  return 2 * edge_sum / double(3 * nt);
}

// A hash grid of the used vertices. Each key's run of the grid (its
// vertices in increasing order) is found in a flat table with linear
// probing: one lookup per cell looked at, which mostly finds the slot the
// previous sample found (a node-based map cost a cache miss each time).
// The table doubles as keys arrive, so that it stays at most half full;
// the runs are laid out by a counting pass over it, not a sort.
class VertexGrid {
public:
  VertexGrid(const double *xyz, size_t n, const std::vector<uint8_t> &used,
             double cell)
      : cell_(cell), runs_(16, Run{0, 0, 0}), mask_(runs_.size() - 1) {
    size_t occupied = 0;
    std::vector<uint64_t> vkey;
    for (uint32_t v = 0; v < n; ++v) {
      if (!used[v])
        continue;
      const uint64_t k = key(cell_of(xyz + 3 * size_t(v)));
      vkey.push_back(k);
      Run &r = runs_[slot(k)];
      if (r.last != 0) {
        ++r.last; // the run's length, until the layout below
        continue;
      }
      r = Run{k, 0, 1};
      if (2 * ++occupied > runs_.size()) {
        std::vector<Run> old(2 * runs_.size(), Run{0, 0, 0});
        old.swap(runs_);
        mask_ = runs_.size() - 1;
        for (const Run &o : old)
          if (o.last != 0)
            runs_[slot(o.key)] = o;
      }
    }
    grid_.resize(vkey.size());
    std::vector<uint32_t> fill(runs_.size());
    uint32_t at = 0;
    for (size_t h = 0; h < runs_.size(); ++h)
      if (runs_[h].last != 0) {
        fill[h] = runs_[h].first = at;
        at += runs_[h].last;
        runs_[h].last = at;
      }
    size_t i = 0;
    for (uint32_t v = 0; v < n; ++v)
      if (used[v])
        grid_[fill[slot(vkey[i++])]++] = v;
  }

  // Calls visit(u) on each used vertex u in the grid cell of point p and in
  // the 26 around it, in the grid's order. The runs of those 27 cells are
  // kept for the next sample, which is mostly in the same cell (samples go
  // in vertex order, which follows the surface).
  template <class Visit> void for_around(const double *p, Visit &&visit) {
    const CellXyz c = cell_of(p);
    if (!around_set_ || c.x != around_.c.x || c.y != around_.c.y ||
        c.z != around_.c.z) {
      for (int j = 0; j < 27; ++j) {
        const Run &run = runs_[slot(
            key({c.x + j / 9 - 1, c.y + j / 3 % 3 - 1, c.z + j % 3 - 1}))];
        around_.first[j] = run.first, around_.last[j] = run.last;
      }
      around_.c = c;
      around_set_ = true;
    }
    for (int j = 0; j < 27; ++j)
      for (uint32_t i = around_.first[j]; i < around_.last[j]; ++i)
        visit(grid_[i]);
  }

private:
  struct CellXyz {
    int64_t x, y, z;
  };
  struct Run {
    uint64_t key;
    uint32_t first, last; // last == 0: an empty slot
  };
  CellXyz cell_of(const double *p) const {
    return CellXyz{int64_t(std::floor(p[0] / cell_)),
                   int64_t(std::floor(p[1] / cell_)),
                   int64_t(std::floor(p[2] / cell_))};
  }
  static uint64_t key(const CellXyz &c) {
    return uint64_t(c.x * 73856093) ^ uint64_t(c.y * 19349663) ^
           uint64_t(c.z * 83492791);
  }
  size_t slot(uint64_t k) const {
    size_t h = size_t((k * 0x9E3779B97F4A7C15ull) >> 32) & mask_;
    while (runs_[h].last != 0 && runs_[h].key != k)
      h = (h + 1) & mask_;
    return h;
  }

  double cell_;
  std::vector<Run> runs_;
  size_t mask_;
  std::vector<uint32_t> grid_;
  struct Around {
    CellXyz c;
    uint32_t first[27], last[27];
  } around_{{0, 0, 0}, {}, {}};
  bool around_set_ = false;
};

// The triangles that the vertex grid cannot find: those whose box is more
// than a grid cell across, such as the patches over holes, whose corners
// may all lie beyond the 27 cells about a sample right above them. Each is
// listed in every cell that its box, grown by a cell, meets.
class LargeTriangles {
public:
  explicit LargeTriangles(double cell) : cell_(cell) {}
  // Lists triangle t (corners v) if it is large.
  void add(const double *xyz, const uint32_t *v, uint32_t t) {
    int64_t lo[3], hi[3];
    int64_t cells = 1;
    bool large = false;
    for (int k = 0; k < 3; ++k) {
      double a = xyz[3 * size_t(v[0]) + k], b = a;
      for (int j = 1; j < 3; ++j) {
        a = std::min(a, xyz[3 * size_t(v[j]) + k]);
        b = std::max(b, xyz[3 * size_t(v[j]) + k]);
      }
      large = large || b - a > cell_;
      lo[k] = int64_t(std::floor(a / cell_)) - 1;
      hi[k] = int64_t(std::floor(b / cell_)) + 1;
      cells *= hi[k] - lo[k] + 1;
    }
    // (A sliver across the whole surface would take too many cells; the
    // fallback of nearest() still finds it from its corners.)
    if (!large || cells > kMaxCells)
      return;
    for (int64_t x = lo[0]; x <= hi[0]; ++x)
      for (int64_t y = lo[1]; y <= hi[1]; ++y)
        for (int64_t z = lo[2]; z <= hi[2]; ++z)
          cells_[key(x, y, z)].push_back(t);
  }
  // The squared distance within which a sample takes a large triangle.
  double reach2() const { return cell_ * cell_; }
  // Calls visit(t) on each triangle listed in the cell of point p.
  template <class Visit> void for_cell(const double *p, Visit &&visit) const {
    if (cells_.empty())
      return;
    const auto it = cells_.find(key(int64_t(std::floor(p[0] / cell_)),
                                    int64_t(std::floor(p[1] / cell_)),
                                    int64_t(std::floor(p[2] / cell_))));
    if (it != cells_.end())
      for (uint32_t t : it->second)
        visit(t);
  }

private:
  static constexpr int64_t kMaxCells = 1 << 15;
  static uint64_t key(int64_t x, int64_t y, int64_t z) {
    return uint64_t(x * 73856093) ^ uint64_t(y * 19349663) ^
           uint64_t(z * 83492791);
  }
  double cell_;
  std::unordered_map<uint64_t, std::vector<uint32_t>> cells_;
};

// The nearest triangle found for a sample so far: its squared distance,
// the barycentric weights of its closest point, and its number.
struct Nearest {
  double d = std::numeric_limits<double>::infinity();
  double w[3] = {0, 0, 0};
  uint32_t t = UINT32_MAX;
};

// Finds each sample's triangle and splits it at the sample, keeping the
// counts of describe() in surf up to date (one split across a boundary
// edge makes its loop an edge longer); where edges or vertices are not
// manifold, it asks for a count again instead (recount()).
class Attacher {
public:
  Attacher(const double *xyz, size_t n, Surface &surf, GrowingStars &stars,
           VertexGrid &grid, LargeTriangles &large, bool recount)
      : xyz_(xyz), surf_(surf), tris_(surf.tris), stars_(stars), grid_(grid),
        large_(large), vstamp_(n, UINT32_MAX), recount_(recount) {}

  // Splits the triangle nearest sample s at it, if there is one near
  // enough; returns whether there was.
  bool attach(uint32_t s) {
    const double *p = xyz_ + 3 * size_t(s);
    const Nearest best = nearest(s, p);
    if (best.t == UINT32_MAX)
      return false;
    split(s, p, best);
    return true;
  }
  bool recount() const { return recount_; }
  bool loops_grew() const { return loops_grew_; }

private:
  // The nearest triangle, if the sample is closer to it than its longest
  // edge (farther samples are outliers and stay out), among those around
  // the used vertex nearest to the sample: the triangles with a corner at
  // that vertex or at one of its neighbours. (The first found of equals.)
  Nearest nearest(uint32_t s, const double *p) {
    stamp_.resize(tris_.size() / 3, UINT32_MAX);
    Nearest best;
    // The nearest used vertex, in the sample's grid cell and the 26 around
    // it (of equals, the first in the grid).
    double near = std::numeric_limits<double>::infinity();
    uint32_t nu = UINT32_MAX;
    grid_.for_around(p, [&](uint32_t u) {
      const double d = dist2(p, xyz_ + 3 * size_t(u));
      if (d < near)
        near = d, nu = u;
    });
    // Each triangle near a sample is looked at once, though it is in the
    // stars of three vertices.
    auto visit = [&](uint32_t t) {
      if (stamp_[t] != s) {
        stamp_[t] = s;
        consider(p, t, best);
      }
    };
    if (nu != UINT32_MAX) {
      vstamp_[nu] = s;
      stars_.for_star(nu, [&](uint32_t t) {
        const uint32_t *v = &tris_[3 * size_t(t)];
        for (int k = 0; k < 3; ++k)
          if (vstamp_[v[k]] != s) {
            vstamp_[v[k]] = s;
            stars_.for_star(v[k], visit);
          }
        visit(t);
      });
    }
    // The large triangles about it, whose corners may all be far: within
    // a grid cell of the sample (their longest edges would let a sample
    // far off a patch over the unscanned side of a scan in).
    // (Not stamped: the last resort below may take them on the usual
    // terms.)
    large_.for_cell(p,
                    [&](uint32_t t) { consider(p, t, best, large_.reach2()); });
    // None near enough there (the sample is off the edge of the surface,
    // or nearer another layer of it than its own): every triangle with a
    // corner in those grid cells.
    if (best.t == UINT32_MAX)
      grid_.for_around(p, [&](uint32_t u) { stars_.for_star(u, visit); });
    return best;
  }

  // Takes triangle t for best if point p is nearer to it, and nearer than
  // its longest edge.
  void consider(const double *p, uint32_t t, Nearest &best,
                double reach2 = std::numeric_limits<double>::infinity()) const {
    const uint32_t *v = &tris_[3 * size_t(t)];
    const double *a = xyz_ + 3 * size_t(v[0]), *b = xyz_ + 3 * size_t(v[1]),
                 *c = xyz_ + 3 * size_t(v[2]);
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
    if (box2 > best.d * (1 + 1e-9))
      return;
    double w[3];
    closest_on_triangle(p, a, b, c, w);
    double q[3];
    for (int k = 0; k < 3; ++k)
      q[k] = w[0] * a[k] + w[1] * b[k] + w[2] * c[k];
    double d = dist2(p, q);
    double longest = std::max(dist2(a, b), std::max(dist2(b, c), dist2(c, a)));
    if (d < best.d && d <= longest && d <= reach2) {
      best.d = d, best.t = t;
      std::copy(w, w + 3, best.w);
    }
  }

  // Splits the triangle at the sample: into three when the closest point
  // is inside it, else across the edge it is on (both triangles of an
  // inner edge, the one of a boundary edge). Either way the sample gets
  // one fan and every edge keeps its triangles: still a manifold, with
  // the orientation of the triangles split.
  void split(uint32_t s, const double *p, const Nearest &best) {
    const uint32_t bt = best.t;
    const double *bw = best.w;
    uint32_t v[3];
    std::copy(&tris_[3 * size_t(bt)], &tris_[3 * size_t(bt)] + 3, v);
    int zero = -1;
    for (int k = 0; k < 3; ++k)
      if (bw[k] < 1e-9)
        zero = zero < 0 ? k : 3; // 3: at a corner
    if (zero < 0) {
      set(bt, v[0], v[1], s);
      stars_.gain(s, bt);
      add(v[1], v[2], s, bt);
      add(v[2], v[0], s, bt);
      count_split(bt);
      return;
    }
    // The edge opposite the zero weight; at a corner, of the corner's two
    // edges the one whose other end is nearer the sample (edge c-(c+1)
    // is opposite c+2).
    int k = zero;
    if (zero == 3) {
      int c = bw[0] > 0.5 ? 0 : bw[1] > 0.5 ? 1 : 2;
      const double *n1 = xyz_ + 3 * size_t(v[(c + 1) % 3]),
                   *n2 = xyz_ + 3 * size_t(v[(c + 2) % 3]);
      k = dist2(p, n1) <= dist2(p, n2) ? (c + 2) % 3 : (c + 1) % 3;
    }
    uint32_t a = v[(k + 1) % 3], b = v[(k + 2) % 3], c = v[k];
    // The other triangle on edge a-b, running b -> a.
    uint32_t other = UINT32_MAX;
    stars_.for_star(a, [&](uint32_t t) {
      if (t == bt)
        return;
      const uint32_t *u = &tris_[3 * size_t(t)];
      for (int j = 0; j < 3; ++j)
        if (u[j] == b && u[(j + 1) % 3] == a)
          other = t;
    });
    set(bt, c, a, s);
    stars_.gain(s, bt);
    add(c, s, b, bt);
    if (other != UINT32_MAX) {
      uint32_t u[3];
      std::copy(&tris_[3 * size_t(other)], &tris_[3 * size_t(other)] + 3, u);
      int j = 0;
      while (!(u[j] == b && u[(j + 1) % 3] == a))
        ++j;
      uint32_t d = u[(j + 2) % 3];
      set(other, b, s, d);
      stars_.gain(s, other);
      add(s, a, d, bt);
      count_split(bt);
    } else {
      // A boundary edge split: one more vertex, two more edges (one of
      // them on the boundary), one more triangle, and its loop is an
      // edge longer.
      const uint32_t l = a < surf_.loop_of.size() ? surf_.loop_of[a]
                                                  : UINT32_MAX;
      if (l == UINT32_MAX) {
        recount_ = true;
      } else {
        Surface::Part &part = surf_.parts[size_t(surf_.component[bt])];
        part.vertices += 1, part.edges += 2, part.faces += 1;
        part.boundary_edges += 1;
        ++surf_.loops[l].length;
        surf_.loop_of[s] = l;
        loops_grew_ = true;
      }
    }
  }

  void set(uint32_t t, uint32_t a, uint32_t b, uint32_t c) {
    tris_[3 * size_t(t)] = a, tris_[3 * size_t(t) + 1] = b,
                      tris_[3 * size_t(t) + 2] = c;
  }
  // A new triangle abc in the component of triangle bt.
  uint32_t add(uint32_t a, uint32_t b, uint32_t c, uint32_t bt) {
    uint32_t t = uint32_t(tris_.size() / 3);
    tris_.push_back(a), tris_.push_back(b), tris_.push_back(c);
    stars_.gain(a, t), stars_.gain(b, t), stars_.gain(c, t);
    surf_.component.push_back(surf_.component[bt]);
    large_.add(xyz_, &tris_[3 * size_t(t)], t);
    return t;
  }
  // Three triangles for one, or four for two: one more vertex, three
  // more edges, two more triangles, in the component of the one split.
  void count_split(uint32_t bt) {
    Surface::Part &part = surf_.parts[size_t(surf_.component[bt])];
    part.vertices += 1, part.edges += 3, part.faces += 2;
  }

  const double *xyz_;
  Surface &surf_;
  std::vector<uint32_t> &tris_;
  GrowingStars &stars_;
  VertexGrid &grid_;
  LargeTriangles &large_;
  std::vector<uint32_t> stamp_, vstamp_;
  bool recount_, loops_grew_ = false;
};

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
  GrowingStars stars(n, tris);
  const double cell = grid_cell(xyz, tris);
  if (!(cell > 0))
    return 0;
  VertexGrid grid(xyz, n, used, cell);
  LargeTriangles large(cell);
  for (size_t t = 0; t < nt; ++t)
    large.add(xyz, &tris[3 * t], uint32_t(t));
  Attacher attacher(xyz, n, surf, stars, grid, large,
                    surf.pinched != 0 || diag.nonmanifold_edges != 0);
  // In vertex-number order, then again over those left while the last
  // pass attached some: a sample beyond the end of a thin part (a horn's
  // tip, sampled more sparsely than it is thick) comes near enough only
  // once the samples between it and the surface are in.
  std::vector<uint32_t> left;
  for (uint32_t s = 0; s < n; ++s)
    if (!used[s])
      left.push_back(s);
  size_t attached = 0;
  for (int pass = 0; pass < kAttachPasses && !left.empty(); ++pass) {
    size_t kept = 0;
    for (size_t i = 0; i < left.size(); ++i) {
      progress.tick(i, left.size());
      if (!attacher.attach(left[i]))
        left[kept++] = left[i];
    }
    const size_t got = left.size() - kept;
    left.resize(kept);
    attached += got;
    if (got == 0)
      break;
  }
  if (attached == 0)
    return 0;
  if (attacher.recount()) {
    std::vector<uint32_t> res;
    res.swap(tris);
    describe(xyz, n, res, progress, surf, diag);
  } else {
    if (attacher.loops_grew())
      tally_loops(surf);
    summarise(surf, diag);
  }
  return attached;
}

} // namespace sc
