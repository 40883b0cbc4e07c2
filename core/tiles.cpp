// Tiled filtering (docs/algorithm.md section 17): the points split into
// tiles that are triangulated apart, on threads, each grown with the points
// of its neighbours until every Delaunay cell around its own samples is
// certified to be a cell of the triangulation of all the points. The poles
// of a tile's samples and the candidate test of the facets it owns are then
// exactly those of the single triangulation, and so is the mesh.
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include "delaunay.hpp"
#include "parallel.hpp"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <numeric>
#include <optional>
#include <string>

namespace sc {
namespace dt {
namespace {

typedef DtSeq::Vertex_handle Vh;
typedef DtSeq::Cell_handle Ch;
typedef CGAL::Exact_predicates_exact_constructions_kernel Exact;

// A tile smaller than this is not worth a triangulation of its own.
constexpr size_t kMinTilePoints = 2000;
// VertexData::flags while a tile's own points go in: the vertex has an
// index.
constexpr uint8_t kSeen = 0x80;
// CellData while the tiles are certified (the poles stage writes the
// circumcentre over it): the cell is final or needs no check (`checked`),
// or its check was left to the sweep (`open`); NaNs no arithmetic gives,
// a pair for each round of certify().
struct Marks {
  uint32_t checked, open;
};
constexpr Marks kFirstRound{0x7fc5a5a6u, 0x7fc5a5a8u};
constexpr Marks kRingRound{0x7fc5a5a7u, 0x7fc5a5a9u};
// Neither: a cell whose check found a point to insert, which may leave it
// standing (certify()).
constexpr uint32_t kUnchecked = 0;
// A cell's own search for a point in its ball reads at most this many
// leaves of the tree before it leaves the cell to the sweep (certify()).
constexpr size_t kLeafBudget = 48;
// ... or once it has met this many points on the cell's sphere (to
// rounding), where the filters fail and each test is exact: on samples of
// a sphere, whose inner balls all pass near every sample, the leaves' worth
// of exact tests made tiles cost 50 to 200 times one triangulation.
constexpr size_t kOnSphere = 4;
// A tile that takes in more foreign points than this many times its own,
// or whose certification costs more than this many leaves of the tree (see
// kCellCost below) for each point it owns, gives up, and the job runs on
// one triangulation instead (certify()). Scans cost 2 to 40 (the merged
// bunny scans in 4 to 64 tiles; the dearest of 64 tiles 103); samples of
// closed surfaces, where tiles cost more than one triangulation, 200 to
// 20 000.
constexpr double kMostForeign = 1.0;
constexpr double kMostWork = 200;
// Before its first pass over the cells, a tile that may give up checks
// every kSampleStride-th of them, and gives up at once where the whole
// pass, at the cost of that sample, would already cost more than
// kMostWork a point it owns (from at least kLeastSample cells). The cells
// lie in memory about in the order of insertion, along the tile's
// space-filling curve, and the costly ones where the balls reach across a
// side: the pass's cost so far said little of its whole (a tile of the
// merged bunny scans paid two thirds of it in its last 3% of cells), and
// samples of closed surfaces reached the bound only after a quarter to
// four fifths of theirs. The sample projects the pass within a tenth
// there (the merged scans: 0.55 and 0.73 million leaves, against 0.58
// and 0.75).
constexpr size_t kSampleStride = 32;
constexpr size_t kLeastSample = 256;
// Thrown by certify() when a tile gives up.
struct NotTileable {
  size_t foreign; // the points the tile had taken in, or was to take in
};
// Thrown by certify() when a tile within a memory limit grows past the
// memory the limit leaves it (Shared::most_bytes).
struct OverLimit {
  double bytes;        // what the tile's triangulation had come to
  size_t own, foreign; // its own points and those it had taken in
};

// What the open cells cost (certify()), in leaves of the tree read: a
// cell's own search without a budget, about (with the cells that the
// points it finds make), and the sweep, for each point it locates.
constexpr double kCellCost = 256;
// Once this many cells have searched alone, a mean cost above twice
// what the choice between searching and sweeping assumed makes the choice
// again (certify()).
constexpr size_t kCostSample = 4;
constexpr double kSweepCost = 512;
// ... and a point's test against a cell's ball (exact when it is nearly on
// the sphere, as all are in a sample of a sphere).
constexpr double kTestCost = 16;
// The sweep takes its points in this many bands of distance from the
// reach, out to the farthest open ball.
constexpr double kSweepBands = 32;

// A box; a side at infinity where the tile reaches the outside.
struct Box {
  double lo[3], hi[3];
};

// Box b grown by d on every side.
inline Box grown(const Box &b, double d) {
  Box g;
  for (int a = 0; a < 3; ++a)
    g.lo[a] = b.lo[a] - d, g.hi[a] = b.hi[a] + d;
  return g;
}

// A static k-d tree over the distinct points, by vertex number: which
// points lie in a ball. Read by every tile's thread at once; nothing in it
// changes after construction.
class PointTree {
public:
  // Built on `threads` threads: the same tree on any number.
  PointTree(const double *pts, size_t m, unsigned threads, Progress &progress)
      : pts_(pts) {
    // (Its arrays resident at once: prefault.hpp.)
    reserve_resident(idx_, m);
    idx_.resize(m);
    std::iota(idx_.begin(), idx_.end(), 0u);
    std::map<size_t, int32_t> counts;
    nodes_.resize(m ? size_t(node_count(m, counts)) : 0);
    if (m) {
      // The top levels here, the subtrees below them (about four a thread)
      // on the threads: each writes its own nodes and range of idx_.
      int depth = 0;
      while (threads > 1 && (size_t(1) << depth) < 4 * size_t(threads))
        ++depth;
      std::vector<Subtree> below;
      build(0, m, 0, depth, counts, &below);
      run_parallel(below.size(), threads, progress, [&](size_t i, Progress &) {
        build(below[i].b, below[i].e, below[i].id, 0, counts, nullptr);
      });
    }
    // The points again in the tree's order, so that a leaf's are together.
    reserve_resident(xyz_, 3 * m);
    xyz_.resize(3 * m);
    for (size_t i = 0; i < m; ++i)
      std::memcpy(&xyz_[3 * i], pts_ + 3 * size_t(idx_[i]), 3 * sizeof(double));
  }

  // The nearest to c of the points v within distance sqrt(r2) of c, outside
  // the box `skip`, that f(v) accepts; UINT32_MAX for none. Nearer parts
  // of the tree first, and the radius shrinks to each point accepted, so
  // that a ball holding many points costs little more than an empty one.
  // At most `leaves` leaves are read: when the search needs more it stops
  // and sets `leaves` to 0, and what it returns is a point in the ball, if
  // one was found, but maybe not the nearest.
  template <class F>
  uint32_t nearest_in_ball(const double c[3], double r2,
                           const double skip_lo[3], const double skip_hi[3],
                           F &&f, size_t &leaves) const {
    uint32_t best = UINT32_MAX;
    if (!nodes_.empty())
      visit(0, box_d2(nodes_[0], c), c, r2, skip_lo, skip_hi, f, best, leaves);
    return best;
  }

  // Calls f(v) on every point v in the closed box [lo, hi] outside the box
  // `skip`.
  template <class F>
  void in_box(const double lo[3], const double hi[3], const double skip_lo[3],
              const double skip_hi[3], F &&f) const {
    if (!nodes_.empty())
      box_visit(0, lo, hi, skip_lo, skip_hi, f);
  }

  // How many points lie in the closed box [lo, hi].
  size_t count_in_box(const double lo[3], const double hi[3]) const {
    return nodes_.empty() ? 0 : box_count(0, lo, hi);
  }

  // The nearest to c of the points v on the outer side of the plane
  // through a with normal nrm, or within tol of it (and maybe a few more),
  // outside the box `skip`, that f(v) accepts; UINT32_MAX for none. As
  // nearest_in_ball(): nearer parts first, and the radius shrinks to each
  // point accepted, so that a half-space holding most of the points costs
  // little more than an empty one.
  template <class F>
  uint32_t nearest_beyond(const double c[3], const double a[3],
                          const double nrm[3], double tol,
                          const double skip_lo[3], const double skip_hi[3],
                          F &&f) const {
    uint32_t best = UINT32_MAX;
    double r2 = HUGE_VAL;
    if (!nodes_.empty())
      visit_beyond(0, box_d2(nodes_[0], c), c, r2, a, nrm, tol, skip_lo,
                   skip_hi, f, best);
    return best;
  }
  // The box of all the points.
  Box bounds() const {
    Box b;
    for (int a = 0; a < 3; ++a)
      b.lo[a] = nodes_.empty() ? 0 : nodes_[0].lo[a],
      b.hi[a] = nodes_.empty() ? 0 : nodes_[0].hi[a];
    return b;
  }
  // The length of the diagonal of the box of all the points.
  double extent() const {
    if (nodes_.empty())
      return 0;
    double d2 = 0;
    for (int a = 0; a < 3; ++a)
      d2 += (nodes_[0].hi[a] - nodes_[0].lo[a]) *
            (nodes_[0].hi[a] - nodes_[0].lo[a]);
    return std::sqrt(d2);
  }

private:
  static constexpr size_t kLeaf = 8;

  // Whether p lies in the closed box [lo, hi].
  static bool in_skip(const double *p, const double lo[3], const double hi[3]) {
    return p[0] >= lo[0] && p[0] <= hi[0] && p[1] >= lo[1] && p[1] <= hi[1] &&
           p[2] >= lo[2] && p[2] <= hi[2];
  }

  template <class F>
  void visit_beyond(int32_t id, double d2, const double c[3], double &r2,
                    const double a[3], const double nrm[3], double tol,
                    const double skip_lo[3], const double skip_hi[3], F &f,
                    uint32_t &best) const {
    const Node &nd = nodes_[size_t(id)];
    if (d2 > r2)
      return;
    double top = 0;
    bool inside = true;
    for (int k = 0; k < 3; ++k) {
      top += nrm[k] * ((nrm[k] > 0 ? nd.hi[k] : nd.lo[k]) - a[k]);
      inside = inside && nd.lo[k] >= skip_lo[k] && nd.hi[k] <= skip_hi[k];
    }
    if (top < -tol || inside)
      return;
    if (nd.left < 0) {
      for (uint32_t i = nd.begin; i < nd.end; ++i) {
        const double *p = &xyz_[3 * size_t(i)];
        if (nrm[0] * (p[0] - a[0]) + nrm[1] * (p[1] - a[1]) +
                    nrm[2] * (p[2] - a[2]) <
                -tol ||
            in_skip(p, skip_lo, skip_hi))
          continue;
        const double dx = p[0] - c[0], dy = p[1] - c[1], dz = p[2] - c[2];
        const double e2 = dx * dx + dy * dy + dz * dz;
        if (e2 <= r2 && f(idx_[i])) {
          r2 = e2;
          best = idx_[i];
        }
      }
      return;
    }
    const double dl = box_d2(nodes_[size_t(nd.left)], c),
                 dr = box_d2(nodes_[size_t(nd.right)], c);
    if (dl <= dr) {
      visit_beyond(nd.left, dl, c, r2, a, nrm, tol, skip_lo, skip_hi, f, best);
      visit_beyond(nd.right, dr, c, r2, a, nrm, tol, skip_lo, skip_hi, f, best);
    } else {
      visit_beyond(nd.right, dr, c, r2, a, nrm, tol, skip_lo, skip_hi, f, best);
      visit_beyond(nd.left, dl, c, r2, a, nrm, tol, skip_lo, skip_hi, f, best);
    }
  }
  struct Node {
    double lo[3], hi[3];
    uint32_t begin, end;
    int32_t left = -1, right = -1;
  };

  // A subtree left to a thread: points b to e of idx_, root node id.
  struct Subtree {
    size_t b, e;
    int32_t id;
  };

  // The nodes of the tree of s points (counts remembers, by size: each
  // level has at most two sizes).
  static int32_t node_count(size_t s, std::map<size_t, int32_t> &counts) {
    if (s <= kLeaf)
      return 1;
    const auto it = counts.find(s);
    if (it != counts.end())
      return it->second;
    const int32_t c =
        1 + node_count(s / 2, counts) + node_count(s - s / 2, counts);
    counts.emplace(s, c);
    return c;
  }

  // The subtree of points b to e of idx_, in preorder from node id; `depth`
  // levels down, with `below`, the subtrees are left there instead. counts:
  // node_count()'s, which holds every size of the tree's subtrees.
  void build(size_t b, size_t e, int32_t id, int depth,
             const std::map<size_t, int32_t> &counts,
             std::vector<Subtree> *below) {
    if (below && depth == 0) {
      below->push_back({b, e, id});
      return;
    }
    Node nd;
    for (int a = 0; a < 3; ++a)
      nd.lo[a] = HUGE_VAL, nd.hi[a] = -HUGE_VAL;
    for (size_t i = b; i < e; ++i)
      for (int a = 0; a < 3; ++a) {
        const double x = pts_[3 * size_t(idx_[i]) + a];
        nd.lo[a] = std::min(nd.lo[a], x);
        nd.hi[a] = std::max(nd.hi[a], x);
      }
    nd.begin = uint32_t(b), nd.end = uint32_t(e);
    if (e - b > kLeaf) {
      int axis = 0;
      for (int a = 1; a < 3; ++a)
        if (nd.hi[a] - nd.lo[a] > nd.hi[axis] - nd.lo[axis])
          axis = a;
      const size_t mid = b + (e - b) / 2;
      std::nth_element(idx_.begin() + long(b), idx_.begin() + long(mid),
                       idx_.begin() + long(e), [&](uint32_t p, uint32_t q) {
                         return pts_[3 * size_t(p) + axis] <
                                pts_[3 * size_t(q) + axis];
                       });
      nd.left = id + 1;
      nd.right = id + 1 + (mid - b <= kLeaf ? 1 : counts.at(mid - b));
      build(b, mid, nd.left, depth - 1, counts, below);
      build(mid, e, nd.right, depth - 1, counts, below);
    }
    nodes_[size_t(id)] = nd;
  }

  // The squared distance from c to the box of nd.
  static double box_d2(const Node &nd, const double c[3]) {
    double d2 = 0;
    for (int a = 0; a < 3; ++a) {
      const double d = c[a] < nd.lo[a]   ? nd.lo[a] - c[a]
                       : c[a] > nd.hi[a] ? c[a] - nd.hi[a]
                                         : 0.0;
      d2 += d * d;
    }
    return d2;
  }

  // Whether node nd lies in the closed box [lo, hi].
  static bool node_in(const Node &nd, const double lo[3], const double hi[3]) {
    return nd.lo[0] >= lo[0] && nd.hi[0] <= hi[0] && nd.lo[1] >= lo[1] &&
           nd.hi[1] <= hi[1] && nd.lo[2] >= lo[2] && nd.hi[2] <= hi[2];
  }
  // Whether node nd meets the closed box [lo, hi].
  static bool node_meets(const Node &nd, const double lo[3],
                         const double hi[3]) {
    return nd.hi[0] >= lo[0] && nd.lo[0] <= hi[0] && nd.hi[1] >= lo[1] &&
           nd.lo[1] <= hi[1] && nd.hi[2] >= lo[2] && nd.lo[2] <= hi[2];
  }

  template <class F>
  void box_visit(int32_t id, const double lo[3], const double hi[3],
                 const double skip_lo[3], const double skip_hi[3], F &f) const {
    const Node &nd = nodes_[size_t(id)];
    if (!node_meets(nd, lo, hi) || node_in(nd, skip_lo, skip_hi))
      return;
    if (nd.left >= 0) {
      box_visit(nd.left, lo, hi, skip_lo, skip_hi, f);
      box_visit(nd.right, lo, hi, skip_lo, skip_hi, f);
      return;
    }
    for (uint32_t i = nd.begin; i < nd.end; ++i) {
      const double *p = &xyz_[3 * size_t(i)];
      if (in_skip(p, lo, hi) && !in_skip(p, skip_lo, skip_hi))
        f(idx_[i]);
    }
  }

  size_t box_count(int32_t id, const double lo[3], const double hi[3]) const {
    const Node &nd = nodes_[size_t(id)];
    if (!node_meets(nd, lo, hi))
      return 0;
    if (node_in(nd, lo, hi))
      return nd.end - nd.begin;
    if (nd.left >= 0)
      return box_count(nd.left, lo, hi) + box_count(nd.right, lo, hi);
    size_t k = 0;
    for (uint32_t i = nd.begin; i < nd.end; ++i)
      k += in_skip(&xyz_[3 * size_t(i)], lo, hi);
    return k;
  }

  template <class F>
  void visit(int32_t id, double d2, const double c[3], double &r2,
             const double skip_lo[3], const double skip_hi[3], F &f,
             uint32_t &best, size_t &leaves) const {
    const Node &nd = nodes_[size_t(id)];
    if (d2 > r2 || leaves == 0 || node_in(nd, skip_lo, skip_hi))
      return;
    if (nd.left < 0) {
      --leaves;
      for (uint32_t i = nd.begin; i < nd.end; ++i) {
        const double *p = &xyz_[3 * size_t(i)];
        const double dx = p[0] - c[0], dy = p[1] - c[1], dz = p[2] - c[2];
        const double e2 = dx * dx + dy * dy + dz * dz;
        if (e2 <= r2 && !in_skip(p, skip_lo, skip_hi) && f(idx_[i])) {
          r2 = e2;
          best = idx_[i];
        }
      }
      return;
    }
    const double dl = box_d2(nodes_[size_t(nd.left)], c),
                 dr = box_d2(nodes_[size_t(nd.right)], c);
    if (dl <= dr) {
      visit(nd.left, dl, c, r2, skip_lo, skip_hi, f, best, leaves);
      visit(nd.right, dr, c, r2, skip_lo, skip_hi, f, best, leaves);
    } else {
      visit(nd.right, dr, c, r2, skip_lo, skip_hi, f, best, leaves);
      visit(nd.left, dl, c, r2, skip_lo, skip_hi, f, best, leaves);
    }
  }

  const double *pts_;
  std::vector<uint32_t> idx_;
  std::vector<double> xyz_; // idx_'s points, in its order
  std::vector<Node> nodes_;
};

struct Tile {
  uint16_t id = 0;
  Box region;                // the space whose points the tile owns
  Box reach;                 // region grown by the margin: all points in it
  std::vector<uint32_t> own; // input indices, ascending
  DtSeq dt;
  std::vector<std::pair<uint32_t, uint32_t>> dups; // (duplicate, first)
  // By vertex number: a foreign vertex inserted (a bit each: with many
  // tiles of many points, a byte each would add up).
  std::vector<bool> member;
  std::vector<Ch> infinite;
  std::vector<uint32_t> tris; // candidates
  Checks check;               // shortcrust mode's (section 6.5)
  // Within a memory limit: the vertex numbers of the tile's final
  // triangulation, its own and the foreign ones certification took, kept
  // between its two passes.
  std::vector<uint32_t> vertices;
  sc_diag_t diag;
  bool numbered = false; // vertices carry vertex numbers, not input indices
  size_t foreign = 0;    // points of other tiles inserted
  double work = 0;       // of certify(): leaves of the tree read, and sweeping
  // Planes of hull facets that no point outside the tile lies beyond
  // (check_hull()).
  struct ClearPlane {
    Point a, b, c; // three points of the plane
    V3 normal;     // unit, outward
    double offset; // normal . a
  };
  std::vector<ClearPlane> clear_planes;
  Tile() { std::memset(&diag, 0, sizeof diag); }
  // The memory of its triangulation, in bytes: the cells and vertices it
  // has room for (freed cells are kept for the next insertion), and the
  // marks of the points it holds. A triangulation of a closed surface's
  // sample has about 16 cells a vertex, a scan's about 6.
  double bytes() const {
    return double(dt.tds().cells().capacity()) * sizeof(DtSeq::Cell) +
           double(dt.tds().vertices().capacity()) * sizeof(DtSeq::Vertex) +
           double(member.capacity()) / 8;
  }
};

// Splits idx[b, e) (input indices) into k tiles by counts: at the median
// of the longest side of the points' box, points below the splitting value
// on one side and the others (equal points too, so that duplicates stay
// together) on the other.
void split(const double *xyz, std::vector<uint32_t> &idx, size_t b, size_t e,
           size_t k, const Box &region, std::vector<Tile> &tiles) {
  auto leaf = [&] {
    tiles.emplace_back();
    Tile &t = tiles.back();
    t.region = region;
    t.own.assign(idx.begin() + long(b), idx.begin() + long(e));
    std::sort(t.own.begin(), t.own.end());
  };
  if (k <= 1 || e - b < 2 * kMinTilePoints) {
    leaf();
    return;
  }
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL},
         hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (size_t i = b; i < e; ++i)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], xyz[3 * size_t(idx[i]) + a]);
      hi[a] = std::max(hi[a], xyz[3 * size_t(idx[i]) + a]);
    }
  int axes[3] = {0, 1, 2};
  std::sort(axes, axes + 3,
            [&](int p, int q) { return hi[p] - lo[p] > hi[q] - lo[q]; });
  const size_t kl = k / 2;
  for (int axis : axes) {
    auto coord = [&](uint32_t i) { return xyz[3 * size_t(i) + axis]; };
    const size_t want = b + (e - b) * kl / k;
    std::nth_element(
        idx.begin() + long(b), idx.begin() + long(want), idx.begin() + long(e),
        [&](uint32_t p, uint32_t q) { return coord(p) < coord(q); });
    const double s = coord(idx[want]);
    const size_t mid =
        size_t(std::partition(idx.begin() + long(b), idx.begin() + long(e),
                              [&](uint32_t i) { return coord(i) < s; }) -
               idx.begin());
    if (mid - b < kMinTilePoints || e - mid < kMinTilePoints)
      continue;
    Box left = region, right = region;
    left.hi[axis] = s;
    right.lo[axis] = s;
    split(xyz, idx, b, mid, kl, left, tiles);
    split(xyz, idx, mid, e, k - kl, right, tiles);
    return;
  }
  leaf();
}

// Phase 1: a tile's own points, triangulated (vertices carry input
// indices), duplicates resolved as the single triangulation resolves them
// (each vertex keeps the smallest index of its point).
void triangulate_own(const double *xyz, Tile &t, Progress &progress) {
  const size_t n = t.own.size();
  std::vector<double> local(3 * n);
  for (size_t i = 0; i < n; ++i)
    std::memcpy(&local[3 * i], xyz + 3 * size_t(t.own[i]), 3 * sizeof(double));
  const std::vector<uint32_t> order =
      brio_order(hilbert_order(local.data(), n));
  Ch hint;
  for (size_t k = 0; k < n; ++k) {
    progress.tick(k, n);
    const double *p = &local[3 * size_t(order[k])];
    Vh v = t.dt.insert(Point(p[0], p[1], p[2]), hint);
    // A repeated point comes back as the vertex it repeats (flagged when
    // it was made), which keeps the smaller index.
    if (!(v->info().flags & kSeen)) {
      v->info().idx = t.own[order[k]];
      v->info().flags = kSeen;
    } else {
      const uint32_t j = v->info().idx, i = t.own[order[k]];
      v->info().idx = std::min(i, j);
      t.dups.emplace_back(std::max(i, j), std::min(i, j));
    }
    hint = v->cell();
  }
  for (auto v = t.dt.finite_vertices_begin(); v != t.dt.finite_vertices_end();
       ++v)
    v->info().flags = 0;
  // Of three or more copies, one may have been paired with another that is
  // not the first: each names the vertex's index, the smallest.
  if (!t.dups.empty()) {
    for (auto &d : t.dups) {
      Point p(xyz[3 * size_t(d.first)], xyz[3 * size_t(d.first) + 1],
              xyz[3 * size_t(d.first) + 2]);
      DtSeq::Locate_type lt;
      int li, lj;
      Ch c = t.dt.locate(p, lt, li, lj);
      d.second = c->vertex(li)->info().idx;
    }
  }
}

// Within a memory limit no tile's own points are triangulated before the
// numbering: the distinct points come from a sort instead. is_vertex[i]
// is set for the first (smallest) index of each point, and each other
// index is paired with it in dups, as the triangulations pair them.
void distinct_points(const double *xyz, size_t n,
                     std::vector<uint8_t> &is_vertex,
                     std::vector<std::pair<uint32_t, uint32_t>> &dups) {
  std::vector<uint32_t> idx(n);
  std::iota(idx.begin(), idx.end(), 0u);
  auto less = [&](uint32_t a, uint32_t b) {
    const double *p = xyz + 3 * size_t(a), *q = xyz + 3 * size_t(b);
    if (p[0] != q[0])
      return p[0] < q[0];
    if (p[1] != q[1])
      return p[1] < q[1];
    if (p[2] != q[2])
      return p[2] < q[2];
    return a < b;
  };
  std::sort(idx.begin(), idx.end(), less);
  for (size_t k = 0; k < n;) {
    const uint32_t first = idx[k];
    const double *p = xyz + 3 * size_t(first);
    is_vertex[first] = 1;
    size_t e = k + 1;
    for (; e < n; ++e) {
      const double *q = xyz + 3 * size_t(idx[e]);
      if (q[0] != p[0] || q[1] != p[1] || q[2] != p[2])
        break;
      dups.emplace_back(idx[e], first);
    }
    k = e;
  }
}

// Triangulates the vertices `verts` (vertex numbers, ascending: a Hilbert
// order) of pts into t.dt, in a biased randomized order.
void triangulate_vertices(const double *pts, const std::vector<uint32_t> &verts,
                          Tile &t, Progress &progress) {
  const std::vector<uint32_t> order = brio_order(verts);
  Ch hint;
  for (size_t k = 0; k < order.size(); ++k) {
    progress.tick(k, order.size());
    const double *p = pts + 3 * size_t(order[k]);
    Vh v = t.dt.insert(Point(p[0], p[1], p[2]), hint);
    v->info() = VertexData(order[k]);
    hint = v->cell();
  }
}

// A ball that surely holds the circumscribed ball of cell c: its centre
// and radius.
void enclosing_ball(Ch c, double centre[3], double &radius) {
  V3 p[4];
  for (int j = 0; j < 4; ++j)
    p[j] = v3(c->vertex(j)->point());
  const V3 u = p[1] - p[0], v = p[2] - p[0], w = p[3] - p[0];
  const V3 vw = cross(v, w);
  const double det = dot(u, vw);
  const double u2 = norm2(u), v2 = norm2(v), w2 = norm2(w);
  if (det * det > 1e-12 * u2 * v2 * w2) {
    // Well conditioned: the centre in double precision is off by far less
    // than a millionth of the cell's size (every edge is at most twice the
    // longest from p[0]).
    const V3 num = u2 * vw + v2 * cross(w, u) + w2 * cross(u, v);
    const V3 cc = p[0] + (0.5 / det) * num;
    if (finite(cc)) {
      double r2 = 0;
      for (int j = 0; j < 4; ++j)
        r2 = std::max(r2, norm2(cc - p[j]));
      const double r = std::sqrt(r2);
      radius = r + 1e-6 * (r + 2 * std::sqrt(std::max({u2, v2, w2})));
      centre[0] = cc.x, centre[1] = cc.y, centre[2] = cc.z;
      return;
    }
  }
  // Nearly flat: the exact centre, rounded outward to a box; the ball
  // about the box's middle that holds every ball centred in the box.
  Exact::Point_3 e[4];
  for (int j = 0; j < 4; ++j)
    e[j] = Exact::Point_3(p[j].x, p[j].y, p[j].z);
  const Exact::Point_3 ec = CGAL::circumcenter(e[0], e[1], e[2], e[3]);
  double lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    const std::pair<double, double> iv = CGAL::to_interval(ec[a]);
    lo[a] = iv.first, hi[a] = iv.second;
  }
  double far2 = 0, half2 = 0;
  for (int a = 0; a < 3; ++a) {
    centre[a] = 0.5 * (lo[a] + hi[a]);
    half2 += 0.25 * (hi[a] - lo[a]) * (hi[a] - lo[a]);
  }
  for (int j = 0; j < 4; ++j) {
    const double q[3] = {p[j].x, p[j].y, p[j].z};
    double d2 = 0;
    for (int a = 0; a < 3; ++a) {
      const double d =
          std::max(std::fabs(q[a] - lo[a]), std::fabs(q[a] - hi[a]));
      d2 += d * d;
    }
    far2 = std::max(far2, d2);
  }
  const double r = (std::sqrt(far2) + std::sqrt(half2)) * (1 + 1e-9);
  radius = std::isfinite(r) ? r : HUGE_VAL;
}

// Whether the ball lies inside the box, away from its sides.
inline bool ball_in(const Box &box, const double c[3], double r) {
  for (int a = 0; a < 3; ++a)
    if (!(c[a] - r > box.lo[a] && c[a] + r < box.hi[a]))
      return false;
  return true;
}

struct Shared {
  const double *pts;     // distinct points by vertex number
  const uint16_t *owner; // by vertex number
  const PointTree *tree;
  // Within a memory limit: the most a tile's triangulation may take
  // (Tile::bytes()); HUGE_VAL otherwise.
  double most_bytes = HUGE_VAL;
};

// Throws OverLimit when tile t, with `owned` points of its own, has
// outgrown what the memory limit leaves it (s.most_bytes).
void keep_within(const Shared &s, const Tile &t, size_t owned) {
  const double bytes = t.bytes();
  if (bytes > s.most_bytes)
    throw OverLimit{bytes, owned, t.foreign};
}

// Inserts the vertices `add` (vertex numbers, sorted) into tile t; returns
// their handles.
std::vector<Vh> insert_foreign(const Shared &s, Tile &t,
                               const std::vector<uint32_t> &add,
                               Progress &progress) {
  std::vector<Vh> made;
  made.reserve(add.size());
  Ch hint;
  for (size_t k = 0; k < add.size(); ++k) {
    progress.tick(k, add.size());
    const uint32_t v = add[k];
    const double *p = s.pts + 3 * size_t(v);
    Vh h = t.dt.insert(Point(p[0], p[1], p[2]), hint);
    h->info() = VertexData(v);
    t.member[v] = true;
    hint = h->cell();
    made.push_back(h);
  }
  t.foreign += add.size();
  return made;
}

inline uint32_t mark_of(Ch c) {
  uint32_t bits;
  std::memcpy(&bits, &c->info().cc[0], sizeof bits);
  return bits;
}
inline void set_mark(Ch c, uint32_t bits) {
  std::memcpy(&c->info().cc[0], &bits, sizeof bits);
}

// The distance from p to the box (0 inside).
inline double box_distance(const Box &box, const double p[3]) {
  double d2 = 0;
  for (int a = 0; a < 3; ++a) {
    const double d = std::max({box.lo[a] - p[a], p[a] - box.hi[a], 0.0});
    d2 += d * d;
  }
  return std::sqrt(d2);
}

// How far from box `reach` a point of `all` in the ball (centre c, radius
// r) can be: the farthest corner of the ball's box clipped to `all`. (A
// nearly flat cell's ball is huge, but only a thin lens of it holds
// points.)
inline double ball_extent(const Box &reach, const Box &all, const double c[3],
                          double r) {
  double d2 = 0;
  for (int a = 0; a < 3; ++a) {
    const double lo = std::max(c[a] - r, all.lo[a]),
                 hi = std::min(c[a] + r, all.hi[a]);
    const double d = std::max({reach.lo[a] - lo, hi - reach.hi[a], 0.0});
    d2 += d * d;
  }
  return std::sqrt(d2);
}

// Which cells certify() makes final: those with a vertex for which want
// is true. Always the tile's own vertices; in a tile job also their
// neighbours (certify()).
struct Wanted {
  const Ownership &own;
  const std::vector<bool> *ring; // by vertex number, or null
  bool operator()(uint32_t v) const { return own(v) || (ring && (*ring)[v]); }
};

// Whether a vertex of finite cell c is wanted.
inline bool wanted_cell(const Wanted &want, Ch c) {
  for (int j = 0; j < 4; ++j)
    if (want(c->vertex(j)->info().idx))
      return true;
  return false;
}

// Checks finite cell c of tile t (see certify()), reading at most `leaves`
// leaves of the tree, and (with a budget) meeting at most kOnSphere points
// on its sphere; a point that makes it wrong goes into add. True when the
// check needed more and found no such point: it is the sweep's.
bool check_cell(const Shared &s, Tile &t, const Ownership &own,
                const Wanted &want, Ch c, std::vector<uint32_t> &add,
                size_t leaves) {
  if (!wanted_cell(want, c))
    return false;
  double centre[3], r;
  enclosing_ball(c, centre, r);
  if (ball_in(t.reach, centre, r))
    return false;
  const size_t budget = leaves;
  const double r2 = r * r;
  const Point &p0 = c->vertex(0)->point(), &p1 = c->vertex(1)->point(),
              &p2 = c->vertex(2)->point(), &p3 = c->vertex(3)->point();
  // Of the points inside, the one nearest the centre goes in: it splits
  // the cell, and the cells it makes are checked in the next round.
  // (Taking every point inside a wrong ball, which may be far larger than
  // any cell of all, took in most of the other tiles.)
  size_t on_sphere = 0;
  const uint32_t best = s.tree->nearest_in_ball(
      centre, r2, t.reach.lo, t.reach.hi,
      [&](uint32_t v) {
        if (own(v) || t.member[v])
          return false;
        t.work += kTestCost;
        const double *q = s.pts + 3 * size_t(v);
        const bool in = CGAL::side_of_bounded_sphere(p0, p1, p2, p3,
                                                     Point(q[0], q[1], q[2])) !=
                        CGAL::ON_UNBOUNDED_SIDE;
        // A point the distance puts in the ball and the predicate outside
        // is on its sphere, to rounding: past a few, the budget is spent.
        if (!in && ++on_sphere > kOnSphere && budget != SIZE_MAX)
          leaves = 0;
        return in;
      },
      leaves);
  t.work += double(budget - leaves);
  if (best != UINT32_MAX) {
    add.push_back(best);
    return false;
  }
  return leaves == 0;
}

// A hull facet whose full search (check_hull()) met at least this many
// points exactly in its plane, and found none that makes it wrong, leaves
// its plane to the tile's clear planes.
constexpr size_t kCoplanarToRemember = 16;
// At most this many clear planes a tile.
constexpr size_t kClearPlanes = 64;

// Checks infinite cell c of tile t: its hull facet is one of all the points
// only if no point lies beyond its plane (or on it, inside its circle,
// where the perturbation decides). The point beyond nearest to the facet
// goes into add.
//
// Where many points lie exactly in the plane (a face of a box sampled on a
// grid, a planar face of a CAD part's vertex set), every hull facet of the
// tile in that plane would read them all, each with exact predicates (the
// filters cannot decide a point in the plane). So once a facet's search
// has met many such points and found none beyond, its plane is
// remembered: no point outside the tile lies beyond it, then or later (the
// tile only takes points in). A later facet in the same plane (its corners
// in it, by the exact orientation) needs only the points in its circle,
// which lie in a small ball; the nearest of those accepted is the point
// the whole search would have taken.
void check_hull(const Shared &s, Tile &t, const Ownership &own,
                const Wanted &want, Ch c, std::vector<uint32_t> &add) {
  const int inf = c->index(t.dt.infinite_vertex());
  Vh fv[3];
  bool mine = false;
  for (int j = 0; j < 3; ++j) {
    fv[j] = c->vertex((inf + 1 + j) % 4);
    mine = mine || want(fv[j]->info().idx);
  }
  if (!mine)
    return;
  const Point &pa = fv[0]->point(), &pb = fv[1]->point(), &pc = fv[2]->point();
  Ch in = c->neighbor(inf);
  const Point &po = in->vertex(in->index(c))->point();
  const CGAL::Orientation inner = CGAL::orientation(pa, pb, pc, po);
  // The outward unit normal, as the poles stage has it.
  V3 corner[3];
  const V3 unit = hull_normal(c, inf, corner);
  const double a[3] = {pa.x(), pa.y(), pa.z()},
               nv[3] = {unit.x, unit.y, unit.z};
  const double extent = s.tree->extent();
  const double tol = 1e-9 * extent;
  const V3 mid = (1.0 / 3) * (v3(pa) + v3(pb) + v3(pc));
  const double centre[3] = {mid.x, mid.y, mid.z};
  auto in_circle = [&](const Point &pq) {
    return CGAL::coplanar_side_of_bounded_circle(pa, pb, pc, pq) !=
           CGAL::ON_UNBOUNDED_SIDE;
  };

  // In a clear plane: the points in the facet's circle, within a ball
  // about the centre that holds the circle (where the circle is well
  // conditioned).
  const double offset = dot(unit, v3(pa));
  V3 cc;
  if (tri_circumcentre(v3(pa), v3(pb), v3(pc), cc)) {
    const double r = std::sqrt(
        std::max({norm2(cc - v3(pa)), norm2(cc - v3(pb)), norm2(cc - v3(pc))}));
    const double far = std::sqrt(norm2(cc - mid)) + r;
    for (const Tile::ClearPlane &cp : t.clear_planes) {
      if (!(dot(cp.normal, unit) > 1 - 1e-9 &&
            std::fabs(cp.offset - offset) <= 1e-9 * extent &&
            CGAL::orientation(cp.a, cp.b, cp.c, pa) == CGAL::COPLANAR &&
            CGAL::orientation(cp.a, cp.b, cp.c, pb) == CGAL::COPLANAR &&
            CGAL::orientation(cp.a, cp.b, cp.c, pc) == CGAL::COPLANAR))
        continue;
      // (A nearly flat facet, whose circle is a million times its edge or
      // more, is searched in full: its centre is not to be trusted.)
      if (!(r < 1e6 * std::sqrt(norm2(v3(pb) - v3(pa)))) || !std::isfinite(far))
        break;
      const double reach = far + 1e-6 * far + 1e-9 * extent;
      size_t leaves = SIZE_MAX;
      const uint32_t best = s.tree->nearest_in_ball(
          centre, reach * reach, t.reach.lo, t.reach.hi,
          [&](uint32_t v) {
            if (own(v) || t.member[v])
              return false;
            const double *q = s.pts + 3 * size_t(v);
            const Point pq(q[0], q[1], q[2]);
            return CGAL::orientation(pa, pb, pc, pq) == CGAL::COPLANAR &&
                   in_circle(pq);
          },
          leaves);
      if (best != UINT32_MAX)
        add.push_back(best);
      return;
    }
  }

  size_t coplanar = 0;
  const uint32_t best = s.tree->nearest_beyond(
      centre, a, nv, tol, t.reach.lo, t.reach.hi, [&](uint32_t v) {
        if (own(v) || t.member[v])
          return false;
        const double *q = s.pts + 3 * size_t(v);
        const Point pq(q[0], q[1], q[2]);
        const CGAL::Orientation o = CGAL::orientation(pa, pb, pc, pq);
        if (o == inner)
          return false;
        if (o != CGAL::COPLANAR)
          return true;
        ++coplanar;
        return in_circle(pq);
      });
  if (best != UINT32_MAX)
    add.push_back(best);
  else if (coplanar >= kCoplanarToRemember &&
           t.clear_planes.size() < kClearPlanes)
    t.clear_planes.push_back({pa, pb, pc, unit, offset});
}

// Whether point p, which lies in cell c of tile t's triangulation, lies
// in the closed ball of a cell with a wanted corner (for an infinite cell:
// beyond its hull facet, or in its plane and in its closed circle). The
// cells whose closed balls hold p make one region, joined across facets,
// about the cell that holds it (walking from any of them toward p stays in
// the region), so a search from c across the facets of that region finds
// them all. Closed balls, not the insertion's perturbed test: a point on
// the sphere of a cell that the perturbation leaves outside it may fall
// inside the perturbed sphere of a cell that a later point makes on the
// same sphere (eight corners of a box of a CAD part's vertex set on one
// sphere), while a point in none of the closed wanted balls of its moment
// is in none later (see certify()). region and stack are scratch.
bool in_wanted_ball(const DtSeq &dt, const Point &p, Ch c, const Wanted &want,
                    std::vector<Ch> &region, std::vector<Ch> &stack) {
  bool hit = false;
  region.assign(1, c);
  stack.assign(1, c);
  c->tds_data().mark_in_conflict();
  while (!stack.empty() && !hit) {
    const Ch x = stack.back();
    stack.pop_back();
    for (int j = 0; j < 4 && !hit; ++j)
      hit = !dt.is_infinite(x->vertex(j)) && want(x->vertex(j)->info().idx);
    for (int f = 0; f < 4 && !hit; ++f) {
      const Ch y = x->neighbor(f);
      if (!y->tds_data().is_clear() ||
          dt.side_of_sphere(y, p) == CGAL::ON_UNBOUNDED_SIDE)
        continue;
      y->tds_data().mark_in_conflict();
      region.push_back(y);
      stack.push_back(y);
    }
  }
  for (Ch x : region)
    x->tds_data().clear();
  return hit;
}

// Phase 2: grows tile t until every cell with a vertex of its own is
// certified: a finite cell's circumscribed ball, closed, holds no point of
// all that the tile lacks; a hull facet has none beyond it. A ball inside
// the tile's reach is certified as it is; the others ask the tree, and
// the exact predicates decide. Points that make a cell wrong go in, and the
// cells they make, which are all around them, are checked in turn. A
// certified cell stays so: no point of all is in its ball, so nothing
// inserted later destroys it.
//
// A ball that the surface touches along a whole circle (the inner balls
// of a closed surface's samples) has many points just outside it, and the
// tree reads them all, for each such cell. So a cell's own search stops
// after kLeafBudget leaves (or kOnSphere points found on its sphere, each
// test exact), and the cells left open are certified
// together by a sweep over the points instead: each point the tile lacks
// within reach of an open ball, nearest the tile first, is located in the
// tile's triangulation and goes in when it conflicts with a wanted cell.
// That suffices: when a point q goes in, each new cell (q and a facet f of
// the hole) has its ball inside the balls of the two cells that had f
// (the three spheres pass through f's circle), and those have f's
// vertices, so were wanted if the new cell is. So every wanted ball, at
// any time, lies in the union of the wanted balls at the start of the
// sweep, and a point found in none of the wanted balls of its moment is
// in none later. The sweep ends at the first point farther from the reach
// than every open ball extends (docs/algorithm.md section 17.2).
//
// Where the balls of the cells reach far across the tiles (samples of a
// closed surface: the inner balls of a sphere's sample hold nearly all of
// it), a tile takes in most of the others' points, and the tiles would
// cost many times one triangulation of all. With `give_up`, a tile that
// takes in more than kMostForeign times its own points, or whose
// certification costs more than kMostWork leaves of the tree a point it
// owns, throws NotTileable.
//
// A tile job (tile_job()) runs alone: nothing gives it the poles of the
// foreign vertices of the facets it tests. With `ring`, a second round
// then certifies every cell around the neighbours of its own vertices too
// (their neighbour sets are final once the first round is done), so that
// the tile computes their poles itself, exactly.
void certify(const Shared &s, Tile &t, Progress &progress, bool ring,
             bool give_up) {
  const Ownership own{s.owner, t.id};
  const Box all = s.tree->bounds();
  size_t owned = 0;
  for (auto v = t.dt.finite_vertices_begin(); v != t.dt.finite_vertices_end();
       ++v)
    owned += own(v->info().idx);
  const double most_foreign = give_up ? kMostForeign * double(owned) : HUGE_VAL;
  const double most_work = give_up ? kMostWork * double(owned) : HUGE_VAL;
  auto too_many = [&]() {
    if (double(t.foreign) > most_foreign || t.work > most_work)
      throw NotTileable{t.foreign};
    keep_within(s, t, owned);
  };
  std::vector<uint32_t> add;
  std::vector<Ch> around;
  auto round = [&](const Wanted &want, const Marks marks) {
    // One cell's check, once.
    auto check = [&](Ch c) {
      const uint32_t m = mark_of(c);
      if (m == marks.checked || m == marks.open)
        return;
      const size_t found = add.size();
      set_mark(c, marks.checked);
      if (t.dt.is_infinite(c))
        check_hull(s, t, own, want, c, add);
      else if (check_cell(s, t, own, want, c, add, kLeafBudget))
        set_mark(c, marks.open);
      // A point in the ball or beyond the facet goes in, and nearly always
      // destroys the cell; but one on its sphere (or in its plane, on its
      // circle) may leave it standing, where the perturbation puts it
      // outside, with other points on the sphere still to take: such a
      // cell is checked again.
      if (add.size() > found)
        set_mark(c, kUnchecked);
      too_many();
    };
    // The points in add go in, and the cells they make are checked.
    auto insert_and_check = [&](const std::vector<uint32_t> &pts) {
      const std::vector<Vh> made = insert_foreign(s, t, pts, progress);
      too_many();
      for (Vh v : made) {
        around.clear();
        t.dt.incident_cells(v, std::back_inserter(around));
        for (Ch c : around)
          check(c);
      }
    };
    // A tile that may give up and has many points to take in takes every
    // kSampleStride-th of them first, once, and gives up at once where
    // all of them, at what the sample's cells cost a point, would cost
    // more than kMostWork a point it owns (as its first pass does). The
    // points that sample's cells find join the rest; a tile may then take
    // in a few points more than in one batch, never fewer than its cells
    // need, so its cells and the mesh are the same.
    bool drain_sampled = !give_up;
    std::vector<uint32_t> batch;
    auto drain = [&]() {
      while (!add.empty()) {
        std::sort(add.begin(), add.end());
        add.erase(std::unique(add.begin(), add.end()), add.end());
        // Every point found goes in: a tile that will then hold too many
        // gives up before it pays for their insertion.
        if (double(t.foreign + add.size()) > most_foreign)
          throw NotTileable{t.foreign + add.size()};
        batch.swap(add);
        add.clear();
        if (!drain_sampled && batch.size() >= kSampleStride * kLeastSample) {
          drain_sampled = true;
          std::vector<uint32_t> sample, rest;
          for (size_t i = 0; i < batch.size(); ++i)
            (i % kSampleStride == 0 ? sample : rest).push_back(batch[i]);
          const double before = t.work;
          insert_and_check(sample);
          if (t.work + (t.work - before) * double(rest.size()) /
                           double(sample.size()) >
              most_work)
            throw NotTileable{t.foreign + rest.size()};
          add.insert(add.end(), rest.begin(), rest.end());
          continue;
        }
        insert_and_check(batch);
      }
    };
    // The wanted finite cells not yet certified, with how far beyond the
    // reach their balls extend; the farthest such extent (-1 for none).
    std::vector<std::pair<double, Ch>> open;
    auto uncertified = [&](bool list) {
      double most = -1;
      open.clear();
      for_cells(t.dt, false, [&](Ch c) {
        if (mark_of(c) == marks.checked)
          return;
        double centre[3], r;
        if (wanted_cell(want, c)) {
          enclosing_ball(c, centre, r);
          // Extent 0: what of the ball holds points is in the reach.
          const double e = ball_in(t.reach, centre, r)
                               ? 0
                               : ball_extent(t.reach, all, centre, r);
          if (e > 0) {
            most = std::max(most, e);
            if (list)
              open.emplace_back(e, c);
            return;
          }
        }
        set_mark(c, marks.checked);
      });
      return most;
    };
    // What a cell's own search has cost so far, on average (kCellCost at
    // least): far more where many points lie nearly on the balls' spheres.
    double searched_work = 0;
    size_t searched = 0;
    auto cell_cost = [&] {
      return searched ? std::max(kCellCost, searched_work / double(searched))
                      : kCellCost;
    };
    // Sweeps the points within `extent` of the reach (see above), in
    // bands of distance, and in each band in vertex order, which is a
    // Hilbert order: each point is located near the one before.
    std::vector<std::pair<uint32_t, uint32_t>> cand; // band, vertex
    std::vector<Ch> region, stack;
    auto sweep = [&](double extent) {
      const Box out = grown(t.reach, extent);
      const double band = extent / kSweepBands;
      cand.clear();
      s.tree->in_box(out.lo, out.hi, t.reach.lo, t.reach.hi, [&](uint32_t v) {
        if (!own(v) && !t.member[v])
          cand.emplace_back(
              uint32_t(
                  std::min(box_distance(t.reach, s.pts + 3 * size_t(v)) / band,
                           double(2 * kSweepBands))),
              v);
      });
      std::sort(cand.begin(), cand.end());
      Ch hint;
      size_t rescan = 1024;
      for (size_t k = 0; k < cand.size(); ++k) {
        progress.tick(k, cand.size());
        // The open balls shrink as points go in: look again now and then.
        const double near = cand[k].first * band;
        if (near > extent || k == rescan) {
          extent = uncertified(false);
          rescan *= 2;
          if (near > extent)
            break;
        }
        const uint32_t v = cand[k].second;
        const double *q = s.pts + 3 * size_t(v);
        const Point p(q[0], q[1], q[2]);
        const Ch c = t.dt.locate(p, hint);
        t.work += kSweepCost;
        if (!in_wanted_ball(t.dt, p, c, want, region, stack)) {
          hint = c;
          continue;
        }
        const Vh w = t.dt.insert(p, c);
        w->info() = VertexData(v);
        t.member[v] = true;
        ++t.foreign;
        too_many();
        hint = w->cell();
      }
    };

    size_t cells = t.dt.number_of_cells(), k = 0;
    if (give_up && cells >= kSampleStride * kLeastSample) {
      const double before = t.work;
      size_t finite = 0, sampled = 0;
      for_cells(t.dt, false, [&](Ch c) {
        if (finite++ % kSampleStride == 0) {
          check(c);
          ++sampled;
        }
      });
      if (sampled >= kLeastSample &&
          (t.work - before) * double(finite) / double(sampled) > most_work)
        throw NotTileable{t.foreign};
    }
    for_cells(t.dt, false, [&](Ch c) {
      progress.tick(k++, cells);
      check(c);
    });
    // The hull facets not yet checked.
    std::vector<Ch> hull;
    auto check_hull_cells = [&]() {
      hull.clear();
      t.dt.incident_cells(t.dt.infinite_vertex(), std::back_inserter(hull));
      for (Ch c : hull)
        check(c);
    };
    check_hull_cells();
    drain();
    for (;;) {
      if (uncertified(true) < 0) {
        // No finite cell open; a hull facet that a point on its circle
        // left standing is checked again.
        check_hull_cells();
        if (add.empty())
          break;
        drain();
        continue;
      }
      // The open balls that reach farthest search alone, the others are
      // swept: as many of each as cost the least, a search costing what
      // the searches so far did (cell_cost()).
      std::sort(
          open.begin(), open.end(),
          [](const std::pair<double, Ch> &a, const std::pair<double, Ch> &b) {
            return a.first > b.first;
          });
      const size_t inside = s.tree->count_in_box(t.reach.lo, t.reach.hi);
      auto cost = [&](size_t alone) {
        double c = cell_cost() * double(alone);
        if (alone < open.size()) {
          const Box out = grown(t.reach, open[alone].first);
          c += kSweepCost *
               double(s.tree->count_in_box(out.lo, out.hi) - inside);
        }
        return c;
      };
      size_t first = open.size();
      double least = cost(first);
      for (size_t i = 0; i < open.size(); i = 2 * i + 1) {
        const double c = cost(i);
        if (c < least)
          least = c, first = i;
      }
      // Where the searches cost more than twice what the choice assumed
      // (their balls' spheres hold many points: each search reads them
      // all), the choice is made again with what they did cost.
      const double modelled = cell_cost();
      bool dearer = false;
      for (size_t i = 0; i < first && !dearer; ++i) {
        const size_t found = add.size();
        const double before = t.work;
        set_mark(open[i].second, marks.checked);
        (void)check_cell(s, t, own, want, open[i].second, add, SIZE_MAX);
        if (add.size() > found)
          set_mark(open[i].second, kUnchecked);
        ++searched;
        searched_work += t.work - before;
        dearer = searched >= kCostSample && cell_cost() > 2 * modelled;
        too_many();
      }
      if (dearer && add.empty())
        continue;
      if (!add.empty()) {
        drain();
        continue;
      }
      if (first < open.size())
        sweep(open[first].first);
      // The hull facets the sweep made (it adds none that are wanted, by
      // the argument above; this checks it).
      check_hull_cells();
      if (add.empty())
        break;
      drain();
    }
  };
  round(Wanted{own, nullptr}, kFirstRound);
  if (!ring)
    return;
  std::vector<bool> near(t.member.size(), false);
  for_cells(t.dt, false, [&](Ch c) {
    bool mine = false;
    for (int j = 0; j < 4; ++j)
      mine = mine || own(c->vertex(j)->info().idx);
    if (mine)
      for (int j = 0; j < 4; ++j)
        near[c->vertex(j)->info().idx] = true;
  });
  round(Wanted{own, &near}, kRingRound);
}

} // namespace

} // namespace dt

// Section 17.5: the memory of a reconstruction of n points, in bytes per
// point, from the peak resident memory of `shortcrust reconstruct` (the
// caller's copy of the points included) on the merged bunny scans and on
// torus samples:
//  - one triangulation of all (closed-surface samples: about 16 cells a
//    vertex; scans about 6, and 750 bytes);
constexpr double kUntiledBytes = 1850;
//  - what a bounded run keeps while the tiles run: the points, their
//    numbering and k-d tree, poles and candidates;
constexpr double kFixedBytes = 200;
//  - the stages after the triangulation (pruning's and extraction's edge
//    tables over the candidates), which no tiling makes smaller;
constexpr double kAfterBytes = 640;
//  - a tile's triangulation, by the points in it, and the points a tile
//    holds over its own (1.1 to 1.3 on scans; on closed samples, whose
//    large inner cells reach across the seams, 1.9 in three tiles and up
//    to 3.4 in seven, which dt::tiled_filter() stops).
constexpr double kTileBytes = 1500;
constexpr double kTileGrowth = 2.0;
// And whatever the points, the process itself: its code, its libraries
// and the allocators' own (5.4 MB resident for a job of four points).
// Without it, the least limits named for jobs of 15 000 to 40 000 points
// were exceeded 1.25 to 1.93 times at the peak; with it, at most 1.17.
constexpr double kProcessBytes = 6 * 1048576.0;

namespace {
// A size for a message: "5.6 MB", or bytes below a tenth of a megabyte;
// with up, rounded up (a least size that the user may give back).
std::string size_text(double bytes, bool up = false) {
  char buf[32];
  if (bytes < 104857.6)
    std::snprintf(buf, sizeof buf, "%.0f bytes", up ? std::ceil(bytes) : bytes);
  else
    std::snprintf(buf, sizeof buf, "%.1f MB",
                  up ? std::ceil(bytes / 1048576 * 10) / 10 : bytes / 1048576);
  return buf;
}
} // namespace

size_t memory_tiles(size_t n, unsigned threads, double limit) {
  const double pts = double(n);
  if (limit >= kProcessBytes + kUntiledBytes * pts)
    return 1;
  // Tiles are split down to dt::kMinTilePoints at most: the most tiles
  // give the least memory.
  const double most =
      std::min(std::floor(pts / double(dt::kMinTilePoints)), 4096.0);
  const double per_tile_point = kTileBytes * kTileGrowth * double(threads);
  const double room = limit - kProcessBytes - kFixedBytes * pts;
  const double k =
      std::max(2.0, room > 0 ? std::ceil(per_tile_point * pts / room) : 0.0);
  if (most >= 2 && room > 0 && k <= most &&
      kProcessBytes + kAfterBytes * pts <= limit)
    return size_t(k);
  char buf[320];
  if (most < 2) {
    std::snprintf(buf, sizeof buf,
                  "%zu points are too few to split into tiles (%zu a tile), "
                  "and one triangulation of them needs a memory limit of at "
                  "least %s, got %s",
                  n, dt::kMinTilePoints,
                  size_text(kProcessBytes + kUntiledBytes * pts, true).c_str(),
                  size_text(limit).c_str());
    throw Error(SC_ENO_MEMORY, buf);
  }
  const double least_tile = pts / most;
  const double need =
      kProcessBytes + std::max(kFixedBytes * pts + per_tile_point * least_tile,
                               kAfterBytes * pts);
  std::snprintf(buf, sizeof buf,
                "%zu points need a memory limit of at least %s, got %s (the "
                "process takes about %s, the stages after the triangulation "
                "about %.0f bytes a point whatever the tiles, and %u tile%s "
                "of %.0f points at a time %s)",
                n, size_text(need, true).c_str(), size_text(limit).c_str(),
                size_text(kProcessBytes).c_str(), kAfterBytes, threads,
                threads == 1 ? "" : "s", least_tile,
                size_text(per_tile_point * least_tile).c_str());
  throw Error(SC_ENO_MEMORY, buf);
}

// Within a memory limit, a tile stops the job once its triangulation, with
// as many as large beside it and what stays through the tiles, would take
// more than this many times the limit (dt::tiled_filter()).
constexpr double kLimitSlack = 1.3;

// What a memory limit leaves each of the `threads` tiles at a time for its
// triangulation, in bytes (dt::tiled_filter()).
double tile_room(size_t n, unsigned threads, double limit) {
  return std::max(0.0, kLimitSlack * limit - kProcessBytes -
                           kFixedBytes * double(n)) /
         double(std::max(1u, threads));
}

// Throws the error of a job whose tile outgrew the memory limit (a tile of
// `own` points had taken in `foreign` others, its triangulation `bytes`).
[[noreturn]] void over_limit(size_t n, unsigned threads, double limit,
                             double bytes, size_t own, size_t foreign) {
  const unsigned at_once = std::max(1u, threads);
  char each[64] = "";
  if (at_once > 1)
    std::snprintf(each, sizeof each, " to each of the %u tiles at a time",
                  at_once);
  char buf[512];
  std::snprintf(
      buf, sizeof buf,
      "%zu points: the memory limit of %s cannot be kept: the tiles' "
      "Delaunay balls reach far across each other (as on exact samples of "
      "a closed surface), and a tile of %zu points took in %zu of the "
      "others, %s of triangulation where the limit leaves %s%s; one "
      "triangulation of all the points needs about %s (a limit of at "
      "least that does not tile)",
      n, size_text(limit).c_str(), own, foreign, size_text(bytes).c_str(),
      size_text(tile_room(n, threads, limit)).c_str(), each,
      size_text(kProcessBytes + kUntiledBytes * double(n), true).c_str());
  throw Error(SC_ENO_MEMORY, buf);
}

namespace dt {

namespace {

// The tiles of the n points: split by counts into at most `tiles`, each
// with its reach, its region grown by margin.
std::vector<Tile> make_tiles(const double *xyz, size_t n, size_t tiles,
                             double margin) {
  std::vector<Tile> ts;
  std::vector<uint32_t> idx(n);
  std::iota(idx.begin(), idx.end(), 0u);
  Box all;
  for (int a = 0; a < 3; ++a)
    all.lo[a] = -HUGE_VAL, all.hi[a] = HUGE_VAL;
  ts.reserve(tiles);
  split(xyz, idx, 0, n, tiles, all, ts);
  for (size_t i = 0; i < ts.size(); ++i) {
    ts[i].id = uint16_t(i);
    ts[i].reach = grown(ts[i].region, margin);
  }
  return ts;
}

// The numbering of number_points(): rank, input index to vertex number
// (UINT32_MAX for a duplicate); with tiles, the distinct points by vertex
// number and the tile that owns each.
struct Numbering {
  std::vector<uint32_t> rank;
  std::vector<double> pts;
  std::vector<uint16_t> owner;
};

// The vertex numbering of the single triangulation (its Hilbert order of
// all the points, the first of equal points standing for them), from
// is_vertex (freed) and out.dups: out.to_input, and the counts of diag
// that it gives. The Hilbert order may come made (`sorted`, freed).
Numbering number_points(const double *xyz, size_t n,
                        std::vector<uint8_t> &is_vertex,
                        const std::vector<Tile> *ts, Filtered &out,
                        sc_diag_t &diag, std::vector<uint32_t> &&sorted = {}) {
  Numbering num;
  {
    const std::vector<uint32_t> order =
        sorted.size() == n ? std::move(sorted) : hilbert_order(xyz, n);
    sorted = {};
    out.to_input.clear();
    reserve_resident(out.to_input, n);
    for (uint32_t i : order)
      if (is_vertex[i])
        out.to_input.push_back(i);
  }
  is_vertex = {};
  const size_t m = out.to_input.size();
  diag.duplicates_merged = out.dups.size();
  diag.delaunay_vertices = m;
  reserve_resident(num.rank, n);
  num.rank.assign(n, UINT32_MAX);
  for (size_t v = 0; v < m; ++v)
    num.rank[out.to_input[v]] = uint32_t(v);
  if (!ts)
    return num;
  reserve_resident(num.pts, 3 * m);
  num.pts.resize(3 * m);
  reserve_resident(num.owner, m);
  num.owner.resize(m);
  PrefaultVector<uint16_t> tile_of(n);
  for (const Tile &t : *ts)
    for (uint32_t i : t.own)
      tile_of[i] = t.id;
  for (size_t v = 0; v < m; ++v) {
    const uint32_t i = out.to_input[v];
    num.owner[v] = tile_of[i];
    std::memcpy(&num.pts[3 * v], xyz + 3 * size_t(i), 3 * sizeof(double));
  }
  return num;
}

// Adds what a tile counted of the triangulation to diag.
void add_tile_counts(sc_diag_t &diag, const sc_diag_t &tile) {
  diag.delaunay_cells += tile.delaunay_cells;
  diag.delaunay_facets += tile.delaunay_facets;
  diag.hull_facets += tile.hull_facets;
  diag.hull_vertices += tile.hull_vertices;
  diag.degenerate_cells += tile.degenerate_cells;
  diag.tile_points_foreign += tile.tile_points_foreign;
}

// A tile's own vertices, by vertex number, ascending; t.own freed.
std::vector<uint32_t> own_vertices(Tile &t, const std::vector<uint32_t> &rank) {
  std::vector<uint32_t> mine;
  mine.reserve(t.own.size());
  for (uint32_t i : t.own)
    if (rank[i] != UINT32_MAX)
      mine.push_back(rank[i]);
  t.own = {};
  std::sort(mine.begin(), mine.end());
  return mine;
}

// The foreign points in t's reach, by vertex number, ascending: from the
// tree, so that a tile reads the points near it, not all of them.
std::vector<uint32_t> in_reach(const Shared &s, const Tile &t) {
  std::vector<uint32_t> add;
  const double none_lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL},
               none_hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  s.tree->in_box(t.reach.lo, t.reach.hi, none_lo, none_hi, [&](uint32_t v) {
    if (s.owner[v] != t.id)
      add.push_back(v);
  });
  std::sort(add.begin(), add.end());
  return add;
}

// Grows tile t, triangulated from its own points, by the foreign points in
// its reach and then until its cells are certified (certify(); with ring,
// one ring more). False, having certified nothing, when the tile spans no
// volume; with give_up, NotTileable when the tile takes in too many
// (certify()); OverLimit when it outgrows s.most_bytes.
bool grow_tile(const Shared &s, Tile &t, size_t m, bool ring, bool give_up,
               Progress &progress) {
  t.member.assign(m, false);
  (void)insert_foreign(s, t, in_reach(s, t), progress);
  keep_within(s, t, t.dt.number_of_vertices() - t.foreign);
  if (t.dt.dimension() < 3)
    return false;
  certify(s, t, progress, ring, give_up);
  return true;
}

// The poles of tile t (computed, poles.cpp), its own vertices' into poles,
// by vertex number.
void tile_poles(Tile &t, const Ownership &own, Progress &progress,
                sc_diag_t &diag, std::vector<double> &poles) {
  compute_poles(t.dt, t.infinite, progress, diag, &own);
  for (auto v = t.dt.finite_vertices_begin(); v != t.dt.finite_vertices_end();
       ++v)
    if (own(v->info().idx))
      std::memcpy(&poles[3 * size_t(v->info().idx)], v->info().pole,
                  sizeof v->info().pole);
}

// When the tiles give up: the triangulation of the tile with the most
// vertices, with every other tile's points inserted, is the triangulation
// of all the points (a function of the points, CGAL's perturbation
// included), so the single triangulation starts from it instead of from
// nothing. The other tiles are freed first.
std::unique_ptr<Triangulator> take_over(const double *xyz,
                                        std::vector<Tile> &ts,
                                        const std::vector<uint32_t> &to_input,
                                        Progress &progress) {
  size_t best = 0;
  for (size_t i = 1; i < ts.size(); ++i)
    if (ts[i].dt.number_of_vertices() > ts[best].dt.number_of_vertices())
      best = i;
  std::vector<uint32_t> rest;
  for (size_t i = 0; i < ts.size(); ++i)
    if (i != best) {
      rest.insert(rest.end(), ts[i].own.begin(), ts[i].own.end());
      ts[i].dt.clear();
      ts[i].own = {};
      ts[i].member = {};
      ts[i].infinite = {};
    }
  Tile &t = ts[best];
  t.infinite = {};
  t.member = {};
  // Back to input indices, and nothing else of the tiles' work: the cells'
  // marks are overwritten by the poles stage.
  for (auto v = t.dt.finite_vertices_begin(); v != t.dt.finite_vertices_end();
       ++v)
    v->info() =
        VertexData(t.numbered ? to_input[v->info().idx] : v->info().idx);
  return adopt_triangulation(t.dt, xyz, std::move(rest), progress);
}

} // namespace

// See internal.hpp.
bool tiled_filter(const double *xyz, size_t n, size_t tiles, unsigned threads,
                  bool bounded, double margin, const sc_params_t &params,
                  Progress &progress, Filtered &out, sc_diag_t &diag,
                  double seconds[SC_STAGE_COUNT],
                  std::unique_ptr<Triangulator> *fallback) {
  Stopwatch sw;
  progress.stage(SC_STAGE_DELAUNAY);
  std::vector<Tile> ts = make_tiles(xyz, n, tiles, margin);
  if (ts.size() < 2)
    return false;
  const size_t k = ts.size();

  // Phase 1: each tile's own points, which also tell the distinct points.
  // Within a memory limit no triangulation is kept between phases: a sort
  // tells them.
  std::vector<uint8_t> is_vertex(n, 0);
  std::vector<uint32_t> sorted;
  // Of the triangulation stage, phase 1 takes about three quarters (the
  // merged bunny scans three times over: 2.4 s of 3.2 on 2 threads), and
  // within a memory limit, where it only sorts the points, about a
  // fiftieth (the merged scans within 300 MB: 0.04 s of 2.5 on 1 thread).
  const double phase1 = bounded ? 0.02 : 0.75;
  std::optional<Progress::Span> part;
  part.emplace(progress, 0, phase1);
  if (bounded) {
    distinct_points(xyz, n, is_vertex, out.dups);
  } else {
    // The Hilbert order of all the points, which numbers the vertices,
    // is sorted beside the tiles, in parts: it reads only the points. Its
    // indices, shuffle and first splits come first, its eight sorts after
    // the tiles, for the threads that finish their tiles first: one task,
    // it made its thread the last to finish, by the whole sort (0.4 s at
    // 1.09M points), where tiles are many and small. (Made last, the
    // indices raised the peak of a run on one thread by 6%.)
    HilbertSort sort(xyz, n);
    // The progress bar moves with the tiles' insertions: a tile weighs its
    // points, the sort's first task a fiftieth of them all and each of its
    // parts an eighth of that (about what they take).
    std::vector<double> weight(k + 1 + HilbertSort::kParts,
                               double(n) / 50 / HilbertSort::kParts);
    weight[0] = double(n) / 50;
    for (size_t i = 0; i < k; ++i)
      weight[i + 1] = double(ts[i].own.size());
    run_parallel(
        k + 1 + HilbertSort::kParts, threads, progress,
        [&](size_t i, Progress &p) {
          if (i == 0)
            sort.begin();
          else if (i <= k)
            triangulate_own(xyz, ts[i - 1], p);
          else
            sort.part(i - 1 - k);
        },
        0, 1, &weight);
    sorted = sort.take();
    for (Tile &t : ts) {
      for (auto v = t.dt.finite_vertices_begin();
           v != t.dt.finite_vertices_end(); ++v)
        is_vertex[v->info().idx] = 1;
      out.dups.insert(out.dups.end(), t.dups.begin(), t.dups.end());
      t.dups = {};
    }
  }
  part.emplace(progress, phase1, 1);
  const Numbering num =
      number_points(xyz, n, is_vertex, &ts, out, diag, std::move(sorted));
  const std::vector<uint32_t> &rank = num.rank;
  const std::vector<double> &pts = num.pts;
  const std::vector<uint16_t> &owner = num.owner;
  const size_t m = out.to_input.size();

  // (Of phase 2, the numbering and the tree take about a fifth.)
  std::optional<Progress::Span> step;
  step.emplace(progress, 0, 0.2);
  const PointTree tree(pts.data(), m, threads, progress);
  step.emplace(progress, 0.2, 1);
  Shared shared{pts.data(), owner.data(), &tree};
  // Within a memory limit, the number of tiles came from a model of their
  // growth (a tile takes in about as many points of the others as it
  // owns: memory_tiles()), which samples of closed surfaces can exceed
  // threefold (their tiles' Delaunay balls reach across the tube or the
  // solid). So a tile whose triangulation outgrows what the limit leaves
  // it, with as many as large beside it, stops the job: it fails with a
  // message rather than run far past the limit (docs/algorithm.md section
  // 17.5). What a tile may take depends on its own points alone, not on
  // which tiles run together.
  if (bounded)
    shared.most_bytes = tile_room(n, threads, params.memory_limit);

  // Phase 2: each tile numbered as the single triangulation, grown by the
  // hull and its margin, and certified.
  out.poles.assign(3 * m, 0.0);
  std::atomic<int> flat{0};
  // Tiles asked for by number are run whatever they cost; one a thread
  // (tiles 0) only while they pay (certify()).
  const bool give_up = !bounded && params.tiles == 0;
  auto grow = [&](Tile &t, Progress &p) {
    if (bounded) {
      triangulate_vertices(pts.data(), own_vertices(t, rank), t, p);
    } else {
      for (auto v = t.dt.finite_vertices_begin();
           v != t.dt.finite_vertices_end(); ++v)
        v->info() = VertexData(rank[v->info().idx]);
      t.numbered = true;
    }
    if (grow_tile(shared, t, m, false, give_up, p))
      return true;
    flat = 1;
    return false;
  };
  // Phase 3: poles, each tile's own into the shared array.
  auto poles = [&](Tile &t, Progress &p, sc_diag_t &d) {
    tile_poles(t, Ownership{owner.data(), t.id}, p, d, out.poles);
  };
  // A tile's triangulation and what points into it, freed.
  auto drop = [](Tile &t) {
    t.dt.clear();
    t.infinite = {};
    t.member = {};
  };
  // Phase 4: the candidates, each tile testing the facets it owns with the
  // poles of all.
  // The poles of the other tiles' vertices, from the shared array.
  auto take_poles = [&](Tile &t) {
    const Ownership own{owner.data(), t.id};
    for (auto v = t.dt.finite_vertices_begin(); v != t.dt.finite_vertices_end();
         ++v)
      if (!own(v->info().idx))
        std::memcpy(v->info().pole, &out.poles[3 * size_t(v->info().idx)],
                    sizeof v->info().pole);
  };
  auto candidates = [&](Tile &t, Progress &p) {
    const Ownership own{owner.data(), t.id};
    take_poles(t);
    select_candidates(t.dt, t.infinite, params, p, t.tris, t.diag, &own,
                      checks(params) ? &t.check : nullptr);
    drop(t);
    // Each tile's in canonical order on its thread; their union then
    // merges into the order of all (a facet is one tile's).
    canonical_order(t.tris, false);
  };
  if (bounded) {
    // Within a memory limit, `threads` tiles at a time: the first pass
    // grows, certifies and takes the poles of each tile, keeps its vertex
    // set and drops the triangulation; the second triangulates the same
    // vertices again (the same cells: they are certified) and tests its
    // facets once every pole is known.
    try {
      run_parallel(k, threads, progress, [&](size_t i, Progress &p) {
        Tile &t = ts[i];
        if (!grow(t, p))
          return;
        sc_diag_t scratch;
        std::memset(&scratch, 0, sizeof scratch);
        poles(t, p, scratch);
        t.vertices.reserve(t.dt.number_of_vertices());
        for (auto v = t.dt.finite_vertices_begin();
             v != t.dt.finite_vertices_end(); ++v)
          t.vertices.push_back(v->info().idx);
        drop(t);
      });
    } catch (const OverLimit &e) {
      over_limit(n, threads, params.memory_limit, e.bytes, e.own, e.foreign);
    }
    if (flat.load())
      return false;
    seconds[SC_STAGE_DELAUNAY] += sw.lap();
    progress.stage(SC_STAGE_CANDIDATES);
    run_parallel(k, threads, progress, [&](size_t i, Progress &p) {
      Tile &t = ts[i];
      std::sort(t.vertices.begin(), t.vertices.end());
      triangulate_vertices(pts.data(), t.vertices, t, p);
      t.vertices = {};
      const Ownership own{owner.data(), t.id};
      compute_poles(t.dt, t.infinite, p, t.diag, &own);
      candidates(t, p);
    });
  } else {
    try {
      run_parallel(k, threads, progress,
                   [&](size_t i, Progress &p) { (void)grow(ts[i], p); });
    } catch (const NotTileable &e) {
      diag.tile_points_foreign = e.foreign;
      if (fallback)
        *fallback = take_over(xyz, ts, out.to_input, progress);
      seconds[SC_STAGE_DELAUNAY] += sw.lap();
      return false;
    }
    if (flat.load())
      return false;
    seconds[SC_STAGE_DELAUNAY] += sw.lap();
    progress.stage(SC_STAGE_POLES);
    run_parallel(k, threads, progress,
                 [&](size_t i, Progress &p) { poles(ts[i], p, ts[i].diag); });
    if (detects_boundary(params.mode)) {
      // Boundary detection (section 5) over the tiles: each measures the
      // cells around its own samples with the poles of all, the growth
      // follows the links of every tile's cells once, and each tile's
      // vertices then learn whether they are interior.
      std::vector<uint8_t> state(m, 0);
      std::vector<std::vector<uint16_t>> cell_links(k);
      run_parallel(k, threads, progress, [&](size_t i, Progress &p) {
        take_poles(ts[i]);
        const Ownership own{owner.data(), ts[i].id};
        cell_links[i] =
            classify_measure(ts[i].dt, ts[i].infinite, params, p, state, &own);
      });
      std::vector<std::vector<std::pair<uint32_t, uint32_t>>> links(k);
      run_parallel(k, threads, progress, [&](size_t i, Progress &) {
        classify_links(ts[i].dt, cell_links[i], {owner.data(), ts[i].id}, state,
                       links[i]);
      });
      std::vector<std::pair<uint32_t, uint32_t>> all;
      for (auto &l : links) {
        all.insert(all.end(), l.begin(), l.end());
        l = {};
      }
      classify_join(params, state, all, out.boundary, diag);
      run_parallel(k, threads, progress, [&](size_t i, Progress &) {
        mark_interior(ts[i].dt, state);
      });
    }
    seconds[SC_STAGE_POLES] += sw.lap();
    progress.stage(SC_STAGE_CANDIDATES);
    run_parallel(k, threads, progress,
                 [&](size_t i, Progress &p) { candidates(ts[i], p); });
  }

  std::vector<std::vector<uint32_t>> parts(k);
  for (size_t i = 0; i < k; ++i) {
    Tile &t = ts[i];
    parts[i] = std::move(t.tris);
    t.tris = {};
    out.check.append(std::move(t.check));
    t.diag.tile_points_foreign = t.foreign;
    add_tile_counts(diag, t.diag);
  }
  merge_canonical(parts, out.tris);
  diag.tiles = k;
  diag.candidates = out.tris.size() / 3;
  out.check.canonical();
  seconds[SC_STAGE_CANDIDATES] += sw.lap();
  return true;
}

// See internal.hpp.
bool tile_job(const double *xyz, size_t n, size_t tiles, size_t index,
              double margin, const sc_params_t &params, Progress &progress,
              Filtered &out, sc_diag_t &diag, double seconds[SC_STAGE_COUNT]) {
  Stopwatch sw;
  progress.stage(SC_STAGE_DELAUNAY);
  std::vector<Tile> ts = make_tiles(xyz, n, tiles, margin);
  if (ts.size() < 2)
    return false;
  std::vector<uint8_t> is_vertex(n, 0);
  distinct_points(xyz, n, is_vertex, out.dups);
  Numbering num = number_points(xyz, n, is_vertex, &ts, out, diag);
  const std::vector<double> &pts = num.pts;
  const std::vector<uint16_t> &owner = num.owner;
  const size_t m = out.to_input.size();
  diag.tiles = ts.size();
  out.poles.assign(3 * m, 0.0);
  // Fewer tiles than asked (too few points to split so far): the tiles
  // past the last own nothing.
  if (index >= ts.size())
    return true;
  Tile &t = ts[index];
  std::vector<uint32_t> mine = own_vertices(t, num.rank);
  for (Tile &other : ts)
    other.own = {};
  num.rank = {};
  const PointTree tree(pts.data(), m, 1, progress);
  const Shared shared{pts.data(), owner.data(), &tree};
  triangulate_vertices(pts.data(), mine, t, progress);
  mine = {};
  if (!grow_tile(shared, t, m, true, false, progress))
    return false;
  seconds[SC_STAGE_DELAUNAY] += sw.lap();

  progress.stage(SC_STAGE_POLES);
  const Ownership own{owner.data(), t.id};
  tile_poles(t, own, progress, t.diag, out.poles);
  seconds[SC_STAGE_POLES] += sw.lap();

  progress.stage(SC_STAGE_CANDIDATES);
  select_candidates(t.dt, t.infinite, params, progress, out.tris, t.diag, &own,
                    checks(params) ? &out.check : nullptr);
  canonical_order(out.tris, false);
  out.check.canonical();
  t.diag.tile_points_foreign = t.foreign;
  add_tile_counts(diag, t.diag);
  diag.candidates = out.tris.size() / 3;
  seconds[SC_STAGE_CANDIDATES] += sw.lap();
  return true;
}

// See internal.hpp.
void merge_tiles(const double *xyz, size_t n, const sc_mesh_t *const *tiles,
                 size_t count, bool check, Filtered &out, sc_diag_t &diag) {
  std::vector<uint8_t> is_vertex(n, 0);
  distinct_points(xyz, n, is_vertex, out.dups);
  const std::vector<uint32_t> rank =
      number_points(xyz, n, is_vertex, nullptr, out, diag).rank;
  const size_t m = out.to_input.size();
  out.poles.assign(3 * m, 0.0);
  size_t total = 0;
  for (size_t i = 0; i < count; ++i)
    total += 3 * std::min<size_t>(tiles[i]->triangle_count,
                                  tiles[i]->diag.candidates);
  out.tris.reserve(total);
  char buf[200];
  for (size_t i = 0; i < count; ++i) {
    const sc_mesh_t &t = *tiles[i];
    if (bool(t.diag.checked) != check) {
      std::snprintf(buf, sizeof buf,
                    "tile %zu %s what shortcrust mode's check needs and the "
                    "job %s: the results are not of this job's tiles",
                    i, t.diag.checked ? "carries" : "lacks",
                    check ? "runs it" : "does not");
      throw Error(SC_EINVALID_ARGUMENT, buf);
    }
    // The runs of t's triangles: the candidates alone, or with the check,
    // the facets by their least passing value of r, then the cocone test's.
    size_t runs[kNearR + 1] = {size_t(t.triangle_count)};
    if (check) {
      const uint64_t near[kNearR] = {t.diag.tile_near_0, t.diag.tile_near_1,
                                     t.diag.tile_near_2, t.diag.tile_near_3,
                                     t.diag.tile_near_4};
      uint64_t listed = 0;
      for (int k = 0; k < kNearR; ++k)
        listed += near[k];
      if (listed > t.triangle_count ||
          near[0] + near[1] + near[2] != t.diag.candidates) {
        std::snprintf(buf, sizeof buf,
                      "tile %zu: its %zu triangles and %llu candidates are "
                      "not the runs its tile_near counts say",
                      i, t.triangle_count,
                      (unsigned long long)t.diag.candidates);
        throw Error(SC_EINVALID_ARGUMENT, buf);
      }
      for (int k = 0; k < kNearR; ++k)
        runs[k] = size_t(near[k]);
      runs[kNearR] = t.triangle_count - size_t(listed);
    }
    size_t k = 0;
    for (int run = 0; run <= (check ? kNearR : 0); ++run) {
      std::vector<uint32_t> &into = !check          ? out.tris
                                    : run == kNearR ? out.check.cocone
                                                    : out.check.near[run];
      for (const size_t end = k + 3 * runs[run]; k < end; ++k) {
        const uint32_t x = t.triangles[k];
        if (x >= n || rank[x] == UINT32_MAX) {
          std::snprintf(buf, sizeof buf,
                        "tile %zu: triangle %zu has index %u, %s", i, k / 3,
                        unsigned(x),
                        x >= n ? "past the last point"
                               : "a repeated point, which is no vertex");
          throw Error(SC_EINVALID_ARGUMENT, buf);
        }
        into.push_back(rank[x]);
      }
      // The runs up to r's are the candidates.
      if (check && run <= kNearR / 2)
        out.tris.insert(out.tris.end(), into.end() - 3 * runs[run], into.end());
    }
    // Each tile sends the poles of the points it owns, zero for the others.
    if (t.normals)
      for (size_t v = 0; v < m; ++v) {
        const double *p = t.normals + 3 * size_t(out.to_input[v]);
        if (p[0] != 0 || p[1] != 0 || p[2] != 0)
          std::memcpy(&out.poles[3 * v], p, 3 * sizeof(double));
      }
    add_tile_counts(diag, t.diag);
    diag.tiles = std::max<uint64_t>(diag.tiles, t.diag.tiles);
  }
  canonical_order(out.tris, false);
  out.check.canonical();
  for (size_t k = 3; k < out.tris.size(); k += 3)
    if (std::equal(&out.tris[k - 3], &out.tris[k], &out.tris[k])) {
      std::snprintf(buf, sizeof buf,
                    "two tiles give the triangle %u %u %u: the results are "
                    "not of one job's tiles",
                    unsigned(out.to_input[out.tris[k]]),
                    unsigned(out.to_input[out.tris[k + 1]]),
                    unsigned(out.to_input[out.tris[k + 2]]));
      throw Error(SC_EINVALID_ARGUMENT, buf);
    }
  diag.candidates = out.tris.size() / 3;
}

} // namespace dt
} // namespace sc
