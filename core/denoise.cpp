// Noise: the estimate every reconstruction reports, and the scale-space
// smoothing of a working copy of the points that denoising runs the
// Delaunay filtering on (docs/algorithm.md section 16).
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include "internal.hpp"
#include "parallel.hpp"
#include "prefault.hpp"

#include <CGAL/Orthogonal_k_neighbor_search.h>
#include <CGAL/Search_traits_3.h>
#include <CGAL/Search_traits_adapter.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/property_map.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>

namespace sc {

namespace {

typedef CGAL::Simple_cartesian<double> K;
typedef K::Point_3 Point;
typedef CGAL::Search_traits_3<K> BaseTraits;
// The tree holds point numbers; their coordinates come from a vector.
typedef CGAL::Pointer_property_map<Point>::type PointMap;
typedef CGAL::Search_traits_adapter<uint32_t, PointMap, BaseTraits> Traits;
typedef CGAL::Orthogonal_k_neighbor_search<Traits> Search;
typedef Search::Tree Tree;
typedef Search::Distance Distance;

// Points whose neighbourhoods the estimate looks at: enough for a stable
// median, few enough to cost a small fraction of the triangulation.
constexpr size_t kEstimateSamples = 1024;
// Neighbours of the estimate: the point and its 19 nearest, and the first
// 10 of those.
constexpr size_t kEstimateNeighbours = 20;
constexpr size_t kEstimateSmall = 10;
// Smoothing's neighbourhoods hold the points within the scale, at most
// kMaxNeighbours of them (an even subset where more lie within: dense
// overlaps of scans, a large scale). Fewer than kMinPoints points are
// not smoothed.
constexpr size_t kMinPoints = 8;
constexpr size_t kMaxNeighbours = 32;
// The default scale: kScaleClean spacings, and kScalePerNoise more per
// spacing of estimated noise, up to kScaleMax; kIterations projections.
// Measured with shortcrust-noise-table and on the merged bunny scans
// (README, "Noise"): the registered scans need 6.5 to 9 spacings to become
// one sheet, and beyond 8 to 9 the thin parts of the genus-2 surface at
// 20 000 points start to fold.
constexpr double kScaleClean = 4;
constexpr double kScalePerNoise = 16;
constexpr double kScaleMax = 8;
constexpr int kIterations = 4;

// A k-d tree of the points, for points crowded into a few cells.
struct KdTree {
  std::vector<Point> pts;
  std::unique_ptr<Tree> tree;
  KdTree(const double *xyz, size_t n) : pts(n) {
    for (size_t i = 0; i < n; ++i)
      pts[i] = Point(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    std::vector<uint32_t> ids(n);
    for (size_t i = 0; i < n; ++i)
      ids[i] = uint32_t(i);
    tree.reset(new Tree(ids.begin(), ids.end(), Tree::Splitter(),
                        Traits(CGAL::make_property_map(pts))));
    tree->build();
  }
  // The k nearest points of point i (itself first, usually), nearest first,
  // into ids and their squared distances into d2.
  void nearest(size_t i, size_t k, uint32_t *ids, double *d2) {
    Distance dist(CGAL::make_property_map(pts));
    Search s(*tree, pts[i], unsigned(k), 0, true, dist, true);
    size_t j = 0;
    for (auto it = s.begin(); it != s.end() && j < k; ++it, ++j) {
      ids[j] = it->first;
      d2[j] = it->second;
    }
    for (; j < k; ++j) {
      ids[j] = uint32_t(i);
      d2[j] = 0;
    }
  }
};

// The k nearest points of a few points among all of them, exactly (ties by
// index). The estimate asks for 1024 points' neighbours: a k-d tree of all
// the points costs many times its queries (most of the estimate, 0.4 s at a
// million points), while bucketing them by the cells of a hash grid is two
// passes over them. A query looks at the cells around its point shell by
// shell until no closer point can be left outside.
class Neighbours {
public:
  // At most this many neighbours a query.
  static constexpr size_t kMaxK = 32;

  Neighbours(const double *xyz, size_t n) : xyz_(xyz), n_(n) {
    double lo[3], hi[3];
    for (int a = 0; a < 3; ++a)
      lo[a] = HUGE_VAL, hi[a] = -HUGE_VAL;
    for (size_t i = 0; i < n; ++i)
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], xyz[3 * i + a]);
        hi[a] = std::max(hi[a], xyz[3 * i + a]);
      }
    // A side that gives cells of a few points on a surface filling its
    // box (the volume's), a plane (the largest face's) or a curve (the
    // length's), whichever the points spread over. (Cells 1.5 and 2 times
    // as wide, for fewer shells, measured slower: more points looked at.)
    double e[3];
    for (int a = 0; a < 3; ++a) {
      e[a] = hi[a] - lo[a];
      lo_[a] = lo[a];
    }
    std::sort(e, e + 3);
    const double dn = double(n);
    side_ = std::max({std::cbrt(e[0] * e[1] * e[2] / dn),
                      std::sqrt(e[1] * e[2] / dn), e[2] / dn});
    if (!(side_ > 0) || !std::isfinite(side_))
      side_ = 1; // every point the same
    size_t buckets = 1;
    while (buckets < n)
      buckets <<= 1;
    mask_ = buckets - 1;
    start_.assign(buckets + 1, 0);
    // Cell coordinates are at most the largest extent over the side,
    // itself at least that extent over n: they fit 32 bits.
    MappedVector<Cell> cells(n);
    MappedVector<uint32_t> bucket(n);
    for (size_t i = 0; i < n; ++i) {
      cells[i] = cell(&xyz[3 * i]);
      bucket[i] = uint32_t(hash(cells[i]));
      ++start_[bucket[i] + 1];
    }
    size_t most = 0;
    for (size_t b = 0; b < buckets; ++b) {
      most = std::max<size_t>(most, start_[b + 1]);
      start_[b + 1] += start_[b];
    }
    if (most > kCrowded) {
      tree_.reset(new KdTree(xyz, n));
      start_.clear();
      return;
    }
    order_.resize(n);
    cells_.resize(n);
    MappedVector<uint32_t> fill(start_.begin(), start_.end() - 1);
    for (size_t i = 0; i < n; ++i) {
      const uint32_t o = fill[bucket[i]]++;
      order_[o] = uint32_t(i);
      cells_[o] = cells[i];
    }
  }

  // The k nearest points of point i (itself among them), nearest first,
  // into ids and their squared distances into d2; where fewer than k
  // points exist, the rest repeat i at distance 0. k is at most kMaxK.
  void nearest(size_t i, size_t k, uint32_t *ids, double *d2) const {
    if (tree_) {
      tree_->nearest(i, k, ids, d2);
      return;
    }
    Best best(k);
    const double *p = &xyz_[3 * i];
    const Cell c = cell(p);
    // How far p lies inside its cell from each of the cell's faces:
    // points beyond shell d lie at least d sides plus the least of these
    // away.
    double margin = HUGE_VAL;
    for (int a = 0; a < 3; ++a) {
      const double below = p[a] - (lo_[a] + double(c[a]) * side_);
      margin = std::min(
          {margin, std::max(0.0, below), std::max(0.0, side_ - below)});
    }
    margin = std::max(0.0, margin - 1e-9 * side_); // for rounding
    size_t looked = 0;
    for (int64_t d = 0;; ++d) {
      for (int64_t dx = -d; dx <= d; ++dx)
        for (int64_t dy = -d; dy <= d; ++dy) {
          const bool side = dx == -d || dx == d || dy == -d || dy == d;
          // Only the shell: all of z on its sides, the two ends inside.
          for (int64_t dz = -d; dz <= d;
               dz += side ? 1 : std::max<int64_t>(1, 2 * d)) {
            const int64_t q[3] = {int64_t(c[0]) + dx, int64_t(c[1]) + dy,
                                  int64_t(c[2]) + dz};
            ++looked;
            // No point has a negative coordinate or one past 32 bits.
            if (q[0] < 0 || q[1] < 0 || q[2] < 0 || q[0] > kCellMax ||
                q[1] > kCellMax || q[2] > kCellMax)
              continue;
            scan(p, Cell{uint32_t(q[0]), uint32_t(q[1]), uint32_t(q[2])}, best);
          }
        }
      const double reach = double(d) * side_ + margin;
      if (best.full() && best.worst() <= reach * reach)
        break;
      if (looked > kMaxCells) { // an isolated point: look at all
        best = Best(k);
        for (size_t j = 0; j < n_; ++j)
          best.offer(distance2(p, j), uint32_t(j));
        break;
      }
    }
    size_t j = 0;
    for (; j < best.size(); ++j) {
      d2[j] = best.d2[j];
      ids[j] = best.id[j];
    }
    for (; j < k; ++j) {
      ids[j] = uint32_t(i);
      d2[j] = 0;
    }
  }

private:
  typedef std::array<uint32_t, 3> Cell;
  static constexpr int64_t kCellMax = int64_t(UINT32_MAX);
  // Cells with more points than this in one bucket make the grid not pay
  // (a far outlier stretching the box, many copies of a point);
  // a query that has looked at this many cells looks at every point.
  static constexpr size_t kCrowded = 1024;
  static constexpr size_t kMaxCells = 8192;

  // The k nearest found so far, in (distance, index) order.
  struct Best {
    explicit Best(size_t k) : k_(k) {}
    size_t size() const { return n_; }
    bool full() const { return n_ == k_; }
    double worst() const { return d2[n_ - 1]; }
    void offer(double e, uint32_t j) {
      if (n_ == k_ && !(e < d2[n_ - 1] || (e == d2[n_ - 1] && j < id[n_ - 1])))
        return;
      size_t at = n_ == k_ ? n_ - 1 : n_++;
      for (; at > 0 && (e < d2[at - 1] || (e == d2[at - 1] && j < id[at - 1]));
           --at) {
        d2[at] = d2[at - 1];
        id[at] = id[at - 1];
      }
      d2[at] = e;
      id[at] = j;
    }
    double d2[kMaxK];
    uint32_t id[kMaxK];

  private:
    size_t k_, n_ = 0;
  };

  Cell cell(const double *p) const {
    Cell c;
    for (int a = 0; a < 3; ++a)
      c[a] = uint32_t(std::floor((p[a] - lo_[a]) / side_));
    return c;
  }
  size_t hash(const Cell &c) const {
    uint64_t h = uint64_t(c[0]) * 0x9E3779B97F4A7C15ull ^
                 uint64_t(c[1]) * 0xC2B2AE3D27D4EB4Full ^
                 uint64_t(c[2]) * 0x165667B19E3779F9ull;
    return size_t(h ^ (h >> 29)) & mask_;
  }
  double distance2(const double *p, size_t j) const {
    const double *y = &xyz_[3 * j];
    const double dx = y[0] - p[0], dy = y[1] - p[1], dz = y[2] - p[2];
    return dx * dx + dy * dy + dz * dz;
  }
  // The points of cell q, less those of other cells in the same bucket.
  void scan(const double *p, const Cell &q, Best &best) const {
    const size_t b = hash(q);
    for (uint32_t o = start_[b]; o < start_[b + 1]; ++o)
      if (cells_[o][0] == q[0] && cells_[o][1] == q[1] && cells_[o][2] == q[2])
        best.offer(distance2(p, order_[o]), order_[o]);
  }

  const double *xyz_;
  size_t n_;
  double lo_[3], side_;
  size_t mask_;
  std::unique_ptr<KdTree> tree_;
  // (Mapped apart: the estimate may run on a thread of its own.)
  MappedVector<uint32_t> start_, order_;
  MappedVector<Cell> cells_;
};
static_assert(kEstimateNeighbours <= Neighbours::kMaxK, "too many neighbours");

// The weighted moments of points about a point p: sum w, sum w d and
// sum w d d^T (d = point - p), from which the weighted least-squares plane
// of the points follows.
struct Moments {
  double sw = 0, m1[3] = {0, 0, 0}, m2[6] = {0, 0, 0, 0, 0, 0};
  void add(double dx, double dy, double dz, double w) {
    sw += w;
    m1[0] += w * dx, m1[1] += w * dy, m1[2] += w * dz;
    m2[0] += w * dx * dx, m2[1] += w * dx * dy, m2[2] += w * dx * dz;
    m2[3] += w * dy * dy, m2[4] += w * dy * dz, m2[5] += w * dz * dz;
  }
  // The plane: its centroid c (relative to p) and unit normal (the
  // eigenvector of the covariance's smallest eigenvalue); the eigenvalues,
  // ascending, in ev (the first is the weighted mean squared distance to
  // the plane). False when every weight is 0.
  bool plane(double c[3], double normal[3], double ev[3]) const {
    if (!(sw > 0))
      return false;
    for (int a = 0; a < 3; ++a)
      c[a] = m1[a] / sw;
    Eigen::Matrix3d cov;
    cov(0, 0) = m2[0] / sw - c[0] * c[0];
    cov(0, 1) = cov(1, 0) = m2[1] / sw - c[0] * c[1];
    cov(0, 2) = cov(2, 0) = m2[2] / sw - c[0] * c[2];
    cov(1, 1) = m2[3] / sw - c[1] * c[1];
    cov(1, 2) = cov(2, 1) = m2[4] / sw - c[1] * c[2];
    cov(2, 2) = m2[5] / sw - c[2] * c[2];
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
    es.computeDirect(cov);
    for (int a = 0; a < 3; ++a) {
      normal[a] = es.eigenvectors()(a, 0);
      ev[a] = std::max(0.0, es.eigenvalues()[a]);
    }
    return true;
  }
};

// Two unit tangents t1, t2 completing a unit normal to a right-handed
// frame.
void tangents(const double normal[3], Eigen::Vector3d &t1,
              Eigen::Vector3d &t2) {
  const Eigen::Vector3d nv(normal[0], normal[1], normal[2]);
  t1 = std::fabs(nv[0]) < 0.6 ? Eigen::Vector3d(1, 0, 0)
                              : Eigen::Vector3d(0, 1, 0);
  t1 = (t1 - t1.dot(nv) * nv).normalized();
  t2 = nv.cross(t1);
}

// Solves a x = b for a symmetric positive definite 6 x 6 matrix a
// (a = L D L^T, L in place in a's lower triangle): the normal equations of a
// quadric fit, solved a million times per smoothing, with one division per
// column and no square root. False when a pivot is not clearly positive: the
// points do not determine the quadric.
bool ldlt_solve6(double a[6][6], const double b[6], double x[6]) {
  double d[6], inv[6];
  for (int j = 0; j < 6; ++j) {
    double w[6]; // row j of L times D
    double dj = a[j][j];
    for (int k = 0; k < j; ++k) {
      w[k] = a[j][k] * d[k];
      dj -= a[j][k] * w[k];
    }
    if (!(dj > 1e-12 * a[j][j]))
      return false;
    d[j] = dj;
    inv[j] = 1 / dj;
    for (int i = j + 1; i < 6; ++i) {
      double t = a[i][j];
      for (int k = 0; k < j; ++k)
        t -= a[i][k] * w[k];
      a[i][j] = t * inv[j];
    }
  }
  for (int i = 0; i < 6; ++i) {
    double t = b[i];
    for (int k = 0; k < i; ++k)
      t -= a[i][k] * x[k];
    x[i] = t;
  }
  for (int i = 5; i >= 0; --i) {
    double t = x[i] * inv[i];
    for (int k = i + 1; k < 6; ++k)
      t -= a[k][i] * x[k];
    x[i] = t;
  }
  return true;
}

// The weighted least-squares quadric w = a + b u + c v + d u^2 + e u v +
// f v^2 through points given in a local frame (u, v along the tangents,
// w along the normal; u and v divided by a length near the neighbourhood's
// size, so that the system is well conditioned).
struct Quadric {
  // Weighted sums of the monomials u^i v^j (i + j <= 4) and of w times
  // those of degree at most 2: the normal equations, without forming
  // each point's outer product.
  double s1 = 0, su = 0, sv = 0, suu = 0, suv = 0, svv = 0, suuu = 0, suuv = 0,
         suvv = 0, svvv = 0, suuuu = 0, suuuv = 0, suuvv = 0, suvvv = 0,
         svvvv = 0;
  double sw = 0, swu = 0, swv = 0, swuu = 0, swuv = 0, swvv = 0, sww = 0;
  // Adds k points at once, from arrays: a few sums per loop, so that they
  // stay in registers (and in vector registers: the loops are `omp simd`
  // reductions, whose order of additions is fixed by the code).
  void add(const double *u, const double *v, const double *w,
           const double *weight, size_t k) {
#pragma omp simd reduction(+ : s1, su, sv, suu, suv, svv)
    for (size_t i = 0; i < k; ++i) {
      const double a = weight[i], au = a * u[i], av = a * v[i];
      s1 += a, su += au, sv += av;
      suu += au * u[i], suv += au * v[i], svv += av * v[i];
    }
#pragma omp simd reduction(+ : suuu, suuv, suvv, svvv, suuuu, suuuv, suuvv,   \
                               suvvv, svvvv)
    for (size_t i = 0; i < k; ++i) {
      const double uu = u[i] * u[i], vv = v[i] * v[i], uv = u[i] * v[i];
      const double auu = weight[i] * uu, avv = weight[i] * vv;
      suuu += auu * u[i], suuv += auu * v[i], suvv += avv * u[i],
          svvv += avv * v[i];
      suuuu += auu * uu, suuuv += auu * uv, suuvv += auu * vv,
          suvvv += avv * uv, svvvv += avv * vv;
    }
#pragma omp simd reduction(+ : sw, swu, swv, swuu, swuv, swvv, sww)
    for (size_t i = 0; i < k; ++i) {
      const double aw = weight[i] * w[i], awu = aw * u[i], awv = aw * v[i];
      sw += aw, swu += awu, swv += awv;
      swuu += awu * u[i], swuv += awu * v[i], swvv += awv * v[i];
      sww += aw * w[i];
    }
  }
  void add(double u, double v, double w, double weight) {
    const double uu = u * u, uv = u * v, vv = v * v;
    const double a = weight, aw = weight * w;
    s1 += a, su += a * u, sv += a * v;
    suu += a * uu, suv += a * uv, svv += a * vv;
    suuu += a * uu * u, suuv += a * uu * v, suvv += a * u * vv,
        svvv += a * vv * v;
    suuuu += a * uu * uu, suuuv += a * uu * uv, suuvv += a * uu * vv,
        suvvv += a * uv * vv, svvvv += a * vv * vv;
    sw += aw, swu += aw * u, swv += aw * v;
    swuu += aw * uu, swuv += aw * uv, swvv += aw * vv, sww += aw * w;
  }
  // The coefficients; false when the points do not determine them.
  // bound: the largest height at the origin to believe (the
  // neighbourhood's size).
  bool solve(Eigen::Matrix<double, 6, 1> &beta, double bound) const {
    double a[6][6] = {{s1, su, sv, suu, suv, svv},
                      {su, suu, suv, suuu, suuv, suvv},
                      {sv, suv, svv, suuv, suvv, svvv},
                      {suu, suuu, suuv, suuuu, suuuv, suuvv},
                      {suv, suuv, suvv, suuuv, suuvv, suvvv},
                      {svv, suvv, svvv, suuvv, suvvv, svvvv}};
    const double b[6] = {sw, swu, swv, swuu, swuv, swvv};
    double x[6];
    if (!ldlt_solve6(a, b, x))
      return false;
    for (int i = 0; i < 6; ++i)
      beta[i] = x[i];
    if (!beta.allFinite() || !(std::fabs(beta[0]) <= bound))
      return false;
    double bx = 0;
    for (int i = 0; i < 6; ++i)
      bx += b[i] * x[i];
    residual2_ = s1 > 0 ? std::max(0.0, sww - bx) / s1 : 0;
    return true;
  }
  // The weighted mean squared residual of the last solve() (at the least-
  // squares solution, sum w r^2 = sum w w^2 - beta . b).
  double residual2() const { return residual2_; }

private:
  mutable double residual2_ = 0;
};

// The RMS distance of the first count points of ids (about p) to the
// quadric that fits them best in the frame of their plane (centroid c
// relative to p, normal): noise, without the curvature that a distance to
// the plane would count too. Scaled by sqrt(k / (k - 6)) for the six
// coefficients fitted; h scales u and v.
double quadric_residual(const double *xyz, const double *p, const uint32_t *ids,
                        size_t count, const double c[3], const double normal[3],
                        double h, double *curvature = nullptr) {
  Eigen::Vector3d t1, t2;
  tangents(normal, t1, t2);
  const Eigen::Vector3d nv(normal[0], normal[1], normal[2]);
  const Eigen::Vector3d origin =
      Eigen::Vector3d(p[0], p[1], p[2]) + Eigen::Vector3d(c[0], c[1], c[2]);
  Quadric fit;
  for (size_t j = 0; j < count; ++j) {
    const double *y = xyz + 3 * size_t(ids[j]);
    const Eigen::Vector3d d = Eigen::Vector3d(y[0], y[1], y[2]) - origin;
    fit.add(d.dot(t1) / h, d.dot(t2) / h, d.dot(nv), 1.0);
  }
  Eigen::Matrix<double, 6, 1> beta;
  if (!fit.solve(beta, 10 * h))
    return 0;
  if (curvature) {
    // The larger principal curvature times h: the eigenvalues of the
    // Hessian [2 b3, b4; b4, 2 b5] / h^2, times h.
    const double tr = beta[3] + beta[5],
                 det = 4 * beta[3] * beta[5] - beta[4] * beta[4];
    const double disc = std::sqrt(std::max(0.0, tr * tr - det));
    *curvature = (std::fabs(tr) + disc) / h;
  }
  const double k = double(count);
  return std::sqrt(fit.residual2() * k / (k - 6));
}

double median(std::vector<double> &v) {
  if (v.empty())
    return 0;
  std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
  return v[v.size() / 2];
}

} // namespace

NoiseEstimate estimate_noise(const double *xyz, size_t n, Progress &progress) {
  NoiseEstimate e;
  if (n < kEstimateNeighbours)
    return e;
  const Neighbours index(xyz, n);
  progress.report(0); // a cancel request is honoured here
  // Points spread evenly over the input order: the same points whatever
  // the chunks they arrived in, so that a daemon job and a local run agree.
  const size_t samples = std::min(n, kEstimateSamples);
  std::vector<double> noise, spacing, curv;
  noise.reserve(samples);
  spacing.reserve(samples);
  uint32_t ids[kEstimateNeighbours];
  double d2[kEstimateNeighbours];
  for (size_t k = 0; k < samples; ++k) {
    const size_t i = k * n / samples;
    index.nearest(i, kEstimateNeighbours, ids, d2);
    const double *p = xyz + 3 * i;
    Moments m;
    for (size_t j = 0; j < kEstimateNeighbours; ++j) {
      const double *y = xyz + 3 * size_t(ids[j]);
      m.add(y[0] - p[0], y[1] - p[1], y[2] - p[2], 1.0);
    }
    double c[3], normal[3], ev[3];
    if (!m.plane(c, normal, ev))
      continue;
    // A uniform disc of k points at spacing h has a radius of
    // h sqrt(k / pi) and a variance of h^2 k / (4 pi) along each of its
    // two axes: the spacing from the variance in the plane.
    const double h2 = (ev[1] + ev[2]) * 2 * SC_PI / double(kEstimateNeighbours);
    if (!(h2 > 0))
      continue;
    spacing.push_back(std::sqrt(h2));
    // At two sizes of neighbourhood, the smaller residual: noise gives
    // about the same at both, while the curvature of a coarse sample (its
    // third-order terms) grows with the size.
    const double h = std::sqrt(h2);
    double curvature = 0;
    noise.push_back(
        std::min(quadric_residual(xyz, p, ids, kEstimateSmall, c, normal, h),
                 quadric_residual(xyz, p, ids, kEstimateNeighbours, c, normal,
                                  h, &curvature)));
    curv.push_back(curvature);
  }
  e.spacing = median(spacing);
  e.noise = e.spacing > 0 ? median(noise) / e.spacing : 0;
  e.curvature = median(curv);
  return e;
}

double default_scale(const NoiseEstimate &e) {
  return e.spacing *
         std::min(kScaleMax, kScaleClean + kScalePerNoise * e.noise);
}

namespace {

// The points in the cells of a uniform grid of a given side (or larger,
// where the points spread over more than 2^21 - 6 sides). Cells are
// numbered by 21-bit coordinates packed in a key, x first, so that the
// cells of a column along z have consecutive keys; the points are sorted
// by key.
class Grid {
public:
  Grid(const double *xyz, size_t n, double side) {
    double lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = HUGE_VAL;
      hi[a] = -HUGE_VAL;
    }
    for (size_t i = 0; i < n; ++i)
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], xyz[3 * i + a]);
        hi[a] = std::max(hi[a], xyz[3 * i + a]);
      }
    // At most 2^21 - 5 cells along an axis, leaving room for two
    // neighbours on each side.
    side_ = side;
    for (int a = 0; a < 3; ++a) {
      side_ = std::max(side_, (hi[a] - lo[a]) / double((1 << 21) - 6));
      lo_[a] = lo[a] - 2 * side_;
    }
    order_.resize(n);
    keys_.resize(n);
    PrefaultVector<std::pair<uint64_t, uint32_t>> kv(n);
    for (size_t i = 0; i < n; ++i)
      kv[i] = {key_of(&xyz[3 * i]), uint32_t(i)};
    std::sort(kv.begin(), kv.end());
    for (size_t i = 0; i < n; ++i) {
      keys_[i] = kv[i].first;
      order_[i] = kv[i].second;
    }
  }
  uint64_t key_of(const double *p) const {
    uint64_t key = 0;
    for (int a = 0; a < 3; ++a)
      key = (key << 21) | uint64_t((p[a] - lo_[a]) / side_);
    return key;
  }
  // The points sorted by cell (for the taking), and their keys.
  PrefaultVector<uint32_t> &order() { return order_; }
  const PrefaultVector<uint64_t> &keys() const { return keys_; }

private:
  double side_, lo_[3];
  PrefaultVector<uint32_t> order_;
  PrefaultVector<uint64_t> keys_;
};

// Points per block of smoothing's loops, which run on the job's threads.
constexpr size_t kBlock = 4096;

// Runs fn(first, last) over the blocks of [0, n) on `threads` threads,
// reporting progress from `from` to `to` (one thread runs them in order,
// here). A point's result must not depend on another block's work: then it
// is the same with any number of threads.
template <class F>
void for_blocks(size_t n, unsigned threads, Progress &progress, double from,
                double to, F &&fn) {
  const size_t k = (n + kBlock - 1) / kBlock;
  auto block = [&](size_t b) { fn(b * kBlock, std::min(n, (b + 1) * kBlock)); };
  if (threads <= 1) {
    for (size_t b = 0; b < k; ++b) {
      block(b);
      progress.report(from + (to - from) * double(b + 1) / double(k));
    }
    return;
  }
  run_parallel(
      k, threads, progress, [&](size_t b, Progress &) { block(b); }, from, to);
}

// The neighbours of each point within r, found once, as lists of
// positions in the grid's order (point q's are the first count[q] of the
// kMaxNeighbours slots at of(q)), and the points in that order.
struct Neighbourhoods {
  PrefaultVector<uint32_t> order; // position -> input index
  PrefaultVector<uint8_t> count;
  std::unique_ptr<uint32_t[]> list;
  const uint32_t *of(size_t q) const { return &list[q * kMaxNeighbours]; }
};

void find_neighbours(const double *xyz, size_t n, double r, unsigned threads,
                     Progress &progress, Neighbourhoods &nb) {
  // Cells have half the radius as side: the ball about a point of a cell
  // lies in the 5 x 5 x 5 cells around it, less the four columns at the
  // corners, whose nearest point is farther than r. Each column of five
  // cells along z is a run of consecutive keys.
  Grid grid(xyz, n, r / 2);
  const PrefaultVector<uint64_t> &keys = grid.keys();
  nb.order.swap(grid.order());
  PrefaultVector<double> xs(n), ys(n), zs(n);
  for (size_t q = 0; q < n; ++q) {
    const double *c = &xyz[3 * size_t(nb.order[q])];
    xs[q] = c[0], ys[q] = c[1], zs[q] = c[2];
  }
  const double r2 = r * r;
  constexpr uint64_t kAxis = (uint64_t(1) << 21) - 1;
  nb.count.assign(n, 0);
  nb.list.reset(new uint32_t[n * kMaxNeighbours]);
  prefault(nb.list.get(), n * kMaxNeighbours * sizeof(uint32_t));
  // A block starts its first cell where the block starts: a point's
  // neighbours depend on its cell only.
  for_blocks(n, threads, progress, 0, 0.4, [&](size_t begin, size_t end) {
    std::vector<uint32_t> found;
    size_t ranges[21][2];
    for (size_t first = begin; first < end;) {
      const uint64_t key = keys[first];
      size_t last = first;
      while (last < end && keys[last] == key)
        ++last;
      const uint64_t cx = key >> 42, cy = (key >> 21) & kAxis;
      int nr = 0;
      for (int dx = -2; dx <= 2; ++dx)
        for (int dy = -2; dy <= 2; ++dy) {
          if ((dx == -2 || dx == 2) && (dy == -2 || dy == 2))
            continue;
          const uint64_t k0 = (uint64_t(int64_t(cx) + dx) << 42) |
                              (uint64_t(int64_t(cy) + dy) << 21) |
                              ((key & kAxis) - 2);
          // Columns after this cell's start after the points of it.
          const bool after = dx > 0 || (dx == 0 && dy > 0);
          const auto lo = std::lower_bound(
              keys.begin() + (after ? long(first) : 0), keys.end(), k0);
          const auto hi = std::upper_bound(lo, keys.end(), k0 + 4);
          ranges[nr][0] = size_t(lo - keys.begin());
          ranges[nr][1] = size_t(hi - keys.begin());
          if (ranges[nr][0] < ranges[nr][1])
            ++nr;
        }
      size_t candidates = 0;
      for (int c = 0; c < nr; ++c)
        candidates += ranges[c][1] - ranges[c][0];
      if (found.size() < candidates)
        found.resize(candidates);
      // About half of the candidates lie within r. Where that is many
      // times kMaxNeighbours, every stride-th candidate is looked at, an
      // even subset from the start.
      const size_t stride =
          std::max<size_t>(1, candidates / (4 * kMaxNeighbours));
      for (size_t q = first; q < last; ++q) {
        // Every candidate is written, and kept (k advances) when within
        // r: no branch to mispredict.
        size_t k = 0, skip = 0;
        for (int c = 0; c < nr; ++c) {
          size_t o = ranges[c][0] + skip;
          for (; o < ranges[c][1]; o += stride) {
            const double dx = xs[o] - xs[q], dy = ys[o] - ys[q],
                         dz = zs[o] - zs[q];
            found[k] = uint32_t(o);
            k += dx * dx + dy * dy + dz * dz < r2;
          }
          skip = o - ranges[c][1];
        }
        // Where more lie within r (dense overlaps, a large scale), an
        // even subset of them: every (k / kMaxNeighbours)-th in the order
        // of the cells, which spreads it over the ball.
        uint32_t *out = &nb.list[q * kMaxNeighbours];
        if (k > kMaxNeighbours) {
          for (size_t j = 0; j < kMaxNeighbours; ++j)
            out[j] = found[j * k / kMaxNeighbours];
          k = kMaxNeighbours;
        } else {
          std::copy(found.begin(), found.begin() + long(k), out);
        }
        nb.count[q] = uint8_t(k);
      }
      first = last;
    }
  });
}

// The weight of a neighbour at squared distance d2 from a point, for the
// radius whose inverse square is inv: (1 - d^2 / r^2)^2, 0 beyond r.
inline double weight(double d2, double inv) {
  const double t = std::max(0.0, 1 - d2 * inv);
  return t * t;
}

// Each point's unit normal: that of its neighbours' weighted plane.
void plane_normals(const Neighbourhoods &nb, const PrefaultVector<double> &cur,
                   size_t begin, size_t end, double r,
                   PrefaultVector<double> &normals) {
  const double inv = 1.0 / (r * r);
  for (size_t q = begin; q < end; ++q) {
    const double *p = &cur[3 * q];
    const uint32_t *list = nb.of(q);
    Moments m;
    for (size_t j = 0; j < nb.count[q]; ++j) {
      const double *y = &cur[3 * size_t(list[j])];
      const double dx = y[0] - p[0], dy = y[1] - p[1], dz = y[2] - p[2];
      m.add(dx, dy, dz, weight(dx * dx + dy * dy + dz * dz, inv));
    }
    double c[3], ev[3];
    if (!m.plane(c, &normals[3 * q], ev))
      normals[3 * q + 2] = 1; // a lone point: any direction
  }
}

// One step of smoothing, in the grid's order: each point of cur moved along
// its normal onto the weighted least-squares quadric of its neighbours in
// the frame of that normal, into next; the normal becomes the quadric's at
// the new point. The plane alone would pull the points of a curved surface
// inward (section 16.3).
void project_step(const Neighbourhoods &nb, const PrefaultVector<double> &cur,
                  size_t begin, size_t end, double r,
                  PrefaultVector<double> &normals,
                  PrefaultVector<double> &next) {
  const double inv = 1.0 / (r * r), hs = 1.0 / r;
  for (size_t q = begin; q < end; ++q) {
    const double *p = &cur[3 * q];
    double *nq = &normals[3 * q];
    Eigen::Vector3d t1, t2;
    tangents(nq, t1, t2);
    // The neighbours in the frame: u, v along the tangents (in units of
    // r), w along the normal, and their weights.
    double u[kMaxNeighbours], v[kMaxNeighbours], w[kMaxNeighbours],
        wt[kMaxNeighbours];
    const uint32_t *list = nb.of(q);
    const size_t k = nb.count[q];
    for (size_t j = 0; j < k; ++j) {
      const double *y = &cur[3 * size_t(list[j])];
      const double dx = y[0] - p[0], dy = y[1] - p[1], dz = y[2] - p[2];
      u[j] = (dx * t1[0] + dy * t1[1] + dz * t1[2]) * hs;
      v[j] = (dx * t2[0] + dy * t2[1] + dz * t2[2]) * hs;
      w[j] = dx * nq[0] + dy * nq[1] + dz * nq[2];
      wt[j] = weight(dx * dx + dy * dy + dz * dz, inv);
    }
    Quadric fit;
    fit.add(u, v, w, wt, k);
    double *out = &next[3 * q];
    out[0] = p[0], out[1] = p[1], out[2] = p[2];
    Eigen::Matrix<double, 6, 1> beta;
    if (!fit.solve(beta, r))
      continue; // too few neighbours to say where the surface is
    // The point over p on the quadric, and the quadric's normal there:
    // n - (dw/du) t1 - (dw/dv) t2, with u, v in units of r.
    Eigen::Vector3d nv(nq[0], nq[1], nq[2]);
    for (int a = 0; a < 3; ++a)
      out[a] += beta[0] * nv[a];
    nv = (nv - beta[1] * hs * t1 - beta[2] * hs * t2).normalized();
    if (nv.allFinite())
      for (int a = 0; a < 3; ++a)
        nq[a] = nv[a];
  }
}

} // namespace

Smoothing smooth(const double *xyz, size_t n, double scale,
                 const NoiseEstimate &e, unsigned threads, Progress &progress,
                 std::vector<double> &out) {
  Smoothing done;
  done.scale = scale;
  out.reserve(3 * n);
  prefault(out.data(), 3 * n * sizeof(double));
  out.assign(xyz, xyz + 3 * n);
  if (n < kMinPoints || !(e.spacing > 0) || !(scale > 0))
    return done;
  Neighbourhoods nb;
  find_neighbours(xyz, n, scale, threads, progress, nb);
  // The points in the grid's order, smoothed there, then put back. Each
  // step reads cur and writes a point's own entries of next and normals.
  PrefaultVector<double> cur(3 * n), next(3 * n), normals(3 * n, 0.0);
  for (size_t q = 0; q < n; ++q)
    std::memcpy(&cur[3 * q], &xyz[3 * size_t(nb.order[q])], 3 * sizeof(double));
  for_blocks(n, threads, progress, 0.4, 0.5, [&](size_t begin, size_t end) {
    plane_normals(nb, cur, begin, end, scale, normals);
  });
  for (int it = 0; it < kIterations; ++it) {
    const double from = 0.5 + 0.5 * double(it) / kIterations;
    for_blocks(n, threads, progress, from, from + 0.5 / kIterations,
               [&](size_t begin, size_t end) {
                 project_step(nb, cur, begin, end, scale, normals, next);
               });
    cur.swap(next);
  }
  double sum = 0;
  for (size_t q = 0; q < n; ++q) {
    double *o = &out[3 * size_t(nb.order[q])];
    for (int a = 0; a < 3; ++a) {
      sum += (cur[3 * q + a] - o[a]) * (cur[3 * q + a] - o[a]);
      o[a] = cur[3 * q + a];
    }
  }
  done.shift = std::sqrt(sum / double(n)) / e.spacing;
  return done;
}

} // namespace sc
