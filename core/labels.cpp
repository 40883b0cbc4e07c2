// Watertight mode's closure by labels: every Delaunay cell is labelled
// inside or outside by the shape of the empty balls, and the boundary of
// the inside cells, repaired into a manifold, replaces the surface.
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include "delaunay.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

namespace sc {
namespace dt {
namespace {

// A heap of four children a node, in v: half the depth of a binary heap,
// so half the places a sift reads. later(a, b): a comes out after b.
template <class T, class Later>
void quad_push(std::vector<T> &v, const T &x, const Later &later) {
  size_t i = v.size();
  v.push_back(x);
  while (i > 0) {
    const size_t up = (i - 1) / 4;
    if (!later(v[up], x))
      break;
    v[i] = v[up];
    i = up;
  }
  v[i] = x;
}
template <class T, class Later>
void quad_pop(std::vector<T> &v, const Later &later) {
  const T x = v.back();
  v.pop_back();
  const size_t n = v.size();
  if (n == 0)
    return;
  size_t i = 0;
  for (;;) {
    const size_t first = 4 * i + 1;
    if (first >= n)
      break;
    size_t next = first;
    for (size_t k = first + 1; k < std::min(first + 4, n); ++k)
      if (later(v[next], v[k]))
        next = k;
    if (!later(x, v[next]))
      break;
    v[i] = v[next];
    i = next;
  }
  v[i] = x;
}

// A priority queue of entries whose priority (T::prio) lies in [lo, hi]:
// buckets of equal width, each a heap of its own. A higher bucket holds
// only higher priorities, so the entries come out in the very order of one
// heap over all of them (ties by later(), within a bucket); but each sift
// runs over the few entries of one bucket, which stay in cache, where one
// heap of a large labelling's entries did not.
template <class T, class Later> class BucketQueue {
public:
  BucketQueue(Later later, float lo, float hi, size_t buckets)
      : later_(later), lo_(lo), scale_(float(buckets) / (hi - lo)),
        heaps_(buckets), bits_((buckets + 63) / 64, 0) {}
  bool empty() const { return size_ == 0; }
  const T &top() const { return heaps_[top_].front(); }
  void push(const T &x) {
    const size_t b = bucket(x.prio);
    quad_push(heaps_[b], x, later_);
    bits_[b / 64] |= uint64_t(1) << (b % 64);
    if (size_++ == 0 || b > top_)
      top_ = b;
  }
  void pop() {
    std::vector<T> &h = heaps_[top_];
    quad_pop(h, later_);
    if (--size_ == 0 || !h.empty())
      return;
    // The highest bucket left below.
    bits_[top_ / 64] &= ~(uint64_t(1) << (top_ % 64));
    size_t w = top_ / 64;
    while (bits_[w] == 0)
      --w;
    top_ = 64 * w + 63 - size_t(__builtin_clzll(bits_[w]));
  }

private:
  // Non-decreasing in the priority, as the float arithmetic rounds.
  size_t bucket(float prio) const {
    const float f = (prio - lo_) * scale_;
    if (!(f > 0))
      return 0;
    return std::min(heaps_.size() - 1, size_t(f));
  }
  Later later_;
  float lo_, scale_;
  std::vector<std::vector<T>> heaps_;
  std::vector<uint64_t> bits_; // the buckets that hold entries
  size_t size_ = 0, top_ = 0;
};

// The labelling of one triangulation, and the scratch of its repair.
template <class DT> class Labelling {
public:
  typedef typename DT::Vertex_handle Vh;
  typedef typename DT::Cell_handle Ch;

  // cocone_theta: the cocone test's, for surface_between(); 0 for none.
  Labelling(DT &t, double cocone_theta)
      : dt_(t), sin2_cocone_(std::sin(cocone_theta) * std::sin(cocone_theta)) {}

  // Watertight mode: label every cell inside or outside by the shape of
  // the empty balls (weigh()), repair the boundary of the inside cells
  // into a manifold and put it in tris. Returns false, leaving tris as it
  // was, when no cell is inside.
  bool label_and_close(std::vector<uint32_t> &tris, Progress &progress,
                       sc_diag_t &diag) {
    progress_ = &progress;
    const size_t m = dt_.number_of_vertices();
    vh_.assign(m, Vh());
    for (auto v = dt_.finite_vertices_begin(); v != dt_.finite_vertices_end();
         ++v)
      vh_[v->info().idx] = v;
    for (auto c = dt_.all_cells_begin(); c != dt_.all_cells_end(); ++c)
      c->info().w = CellLabel{0, kUnlabelled, 0};
    progress.tick(0, 3);
    weigh(progress);
    progress.tick(1, 3);
    repair(diag);
    progress.tick(2, 3);
    std::vector<uint32_t> res = boundary_of_inside();
    if (res.empty())
      return false;
    tris.swap(res);
    return true;
  }

private:
  // The labelling of the power crust (Amenta, Choi and Kolluri 2001), on
  // the Delaunay cells: every cell's circumscribing ball is empty, and the
  // balls of a closed surface's inside and outside meet it at a shallow
  // angle from either side, while balls on one side overlap deeply.
  //  - The infinite cells are outside.
  //  - A labelled cell tells each neighbour across a facet to take its
  //    label, with the weight -cos of the angle at which their spheres
  //    cross (1 where one ball holds the other's circle deep inside, up to
  //    0 where they cross at right angles; shallower crossings tell
  //    nothing). The outer half-space of a hull facet is the infinite
  //    cell's ball.
  //  - The two poles of a sample (section 4.2) lie on either side of the
  //    surface: a labelled pole tells the sample's other pole to take the
  //    other label, with the weight -cos of the angle between them at the
  //    sample. A sample on the hull has the outside as its first pole.
  //  - The cell with the clearest evidence is labelled next: the larger of
  //    its two weights where it has only one, and their difference less one
  //    where it has both, so that conflicting cells wait. Ties go by the
  //    cells' vertex numbers, not their places in memory.
  //  - Except across a facet that the surface passes through where the
  //    sample is coarse (surface_between()): there the balls overlap
  //    deeply across the surface, and no label crosses by them.
  // A cell no weight reaches stays outside.
  //
  // Weighing reads arrays indexed by the cells' numbers (number_cells()),
  // not the cells; where numbers would decide (ties), the cells' keys do
  // (cell_key()), so that nothing depends on where the cells lie in
  // memory.
  void weigh(Progress &progress) {
    const size_t n = number_cells();
    progress.tick(0, 4);
    // Per cell: its neighbours' numbers and its ball (for an infinite
    // cell, r2 < 0 and o[0] the crossing with its finite neighbour, see
    // crossing()).
    node_.resize(n);
    for (auto c = dt_.all_cells_begin(); c != dt_.all_cells_end(); ++c) {
      poll(c->info().w.local);
      Node &d = node_[c->info().w.local];
      for (int f = 0; f < 4; ++f)
        d.nbr[f] = c->neighbor(f)->info().w.local;
      if (dt_.is_infinite(c))
        continue; // after the finite ones, below
      // From the corners in the order of their numbers, so that the labels
      // of a triangulation built again, in tiles or in a daemon's chunks,
      // are the same; the radius to the first of them.
      bool guarded;
      const V3 o = cell_circumcentre(c, guarded);
      d.o[0] = o.x, d.o[1] = o.y, d.o[2] = o.z;
      d.r2 = norm2(o - v3(vh_[kmin_[c->info().w.local]]->point()));
    }
    for (auto c = dt_.all_cells_begin(); c != dt_.all_cells_end(); ++c)
      if (dt_.is_infinite(c)) {
        Node &d = node_[c->info().w.local];
        d.o[0] = hull_crossing(c, c->index(dt_.infinite_vertex()));
        d.r2 = -1;
      }
    progress.tick(1, 4);
    find_poles();
    progress.tick(2, 4);

    auto priority = [](const Node &d) {
      const float a = d.ein, b = d.eout;
      return a > 0 && b > 0 ? std::fabs(a - b) - 1 : std::max(a, b);
    };
    // The clearest evidence first; of equal evidence, the smaller key.
    struct Entry {
      float prio;
      uint32_t cell;
    };
    auto later = [&](const Entry &a, const Entry &b) {
      if (a.prio != b.prio)
        return a.prio < b.prio;
      return a.cell != b.cell && key_less(b.cell, a.cell);
    };
    // Priorities lie in [-1, 2]; a bucket for about every 16 cells, up to
    // 4096 (more measured slower on the merged bunny scans: 2.3M cells,
    // 4M entries, 1.3 s at 1024 to 4096 buckets, 1.6 at 16384, 1.8 at
    // 65536, against 1.9 s for one heap).
    BucketQueue<Entry, decltype(later)> queue(
        later, -1, 2, std::min<size_t>(4096, std::max<size_t>(64, n / 16)));
    for (size_t i = 0; i < n; ++i)
      if (node_[i].r2 < 0) {
        node_[i].eout = 2; // above any weight
        queue.push(Entry{2, uint32_t(i)});
      }
    // Samples on the hull: the outside is their first pole.
    for (const Link &h : hull_poles_) {
      Node &d = node_[h.cell];
      if (h.w > d.ein) {
        d.ein = h.w;
        queue.push(Entry{priority(d), h.cell});
      }
    }

    size_t done = 0, pops = 0;
    while (!queue.empty()) {
      poll(pops++);
      const Entry e = queue.top();
      queue.pop();
      // The cells are visited all over the triangulation: ask for the next
      // one, and for this one's neighbours, before reading them.
      if (!queue.empty())
        __builtin_prefetch(&node_[queue.top().cell]);
      const uint32_t i = e.cell;
      Node &d = node_[i];
      if (d.label != kUnlabelled || e.prio != priority(d))
        continue; // labelled already, or its evidence has grown since
      for (int f = 0; f < 4; ++f)
        __builtin_prefetch(&node_[d.nbr[f]]);
      if ((++done & 0xFFFF) == 0)
        progress.tick(3, 4);
      d.label = d.ein > d.eout ? kInside : kOutside;
      const bool in = d.label == kInside;
      for (int f = 0; f < 4; ++f) {
        const uint32_t j = d.nbr[f];
        Node &b = node_[j];
        if (b.label != kUnlabelled)
          continue;
        const float w = -crossing(d, b);
        float &same = in ? b.ein : b.eout;
        if (w > same && !surface_between(i, f, d, b)) {
          same = w;
          queue.push(Entry{priority(b), j});
        }
      }
      // The samples whose pole this cell is: their other poles.
      for (uint32_t k = d.link_at; k < d.link_at + d.links; ++k) {
        const Link &l = links_[k];
        Node &b = node_[l.cell];
        if (b.label != kUnlabelled)
          continue;
        float &other = in ? b.eout : b.ein;
        if (l.w > other) {
          other = l.w;
          queue.push(Entry{priority(b), l.cell});
        }
      }
    }
    for (auto c = dt_.all_cells_begin(); c != dt_.all_cells_end(); ++c) {
      CellLabel &w = c->info().w;
      w.label = node_[w.local].label == kInside ? kInside : kOutside;
      w.local = 0;
    }
    node_ = {};
    links_ = {};
    hull_poles_ = {};
    axis_ = {};
    cells_ = {};
    kmin_ = {};
  }

  // Numbers every cell, in w.local, in memory order, and notes each one's
  // handle and smallest vertex number; returns how many. (Ordering the
  // cells around the vertices along the insertion's space-filling curve
  // instead was measured: no faster.)
  size_t number_cells() {
    const size_t n = dt_.tds().number_of_cells();
    cells_.resize(n);
    kmin_.resize(n);
    uint32_t i = 0;
    for (auto c = dt_.all_cells_begin(); c != dt_.all_cells_end(); ++c, ++i) {
      poll(i);
      c->info().w.local = i;
      cells_[i] = c;
      uint32_t k = UINT32_MAX;
      for (int j = 0; j < 4; ++j)
        if (!dt_.is_infinite(c->vertex(j)))
          k = std::min(k, c->vertex(j)->info().idx);
      kmin_[i] = k;
    }
    return n;
  }
  // Whether cell i's key is smaller than cell j's.
  bool key_less(uint32_t i, uint32_t j) const {
    return kmin_[i] != kmin_[j] ? kmin_[i] < kmin_[j]
                                : cell_key(cells_[i]) < cell_key(cells_[j]);
  }

  // Every so many steps of a long loop, whether the work is to stop (a
  // cancel, or the labelling beside the extraction not needed: LabelTask).
  void poll(size_t step) {
    if ((step & 0x1FFF) == 0)
      progress_->poll();
  }
  Progress *progress_ = nullptr;

  // What weighing reads of a cell, together.
  struct Node {
    uint32_t nbr[4];  // the neighbours' numbers
    double o[3];      // the circumcentre
    double r2;        // squared radius; negative for an infinite cell
    float ein = 0, eout = 0; // the evidence for inside, and for outside
    uint32_t link_at = 0;    // its first pole link (links_)
    uint8_t links = 0;       // and how many (at most one a vertex)
    uint8_t label = kUnlabelled;
  };
  // A sample's poles: the cells of its farthest circumcentre (first) and of
  // the farthest on the other side (second); on the hull, the outside is
  // the first (dir, the sum of the outward normals of its hull facets).
  struct Poles {
    uint32_t first = UINT32_MAX, second = UINT32_MAX;
    float dir[3] = {0, 0, 0}; // from the sample toward the first pole
    float far2 = -1;          // scratch: the farthest distance so far
    bool hull = false;
  };
  // Evidence from a pole to the sample's other pole (cell), of weight w.
  struct Link {
    uint32_t cell;
    float w;
  };

  // The poles of every sample (section 4.2), from the circumcentres, in two
  // passes over the cells; then the evidence each pole gives the other
  // (links_, by cell: Node::link_at and links), and the hull samples'
  // (hull_poles_).
  void find_poles() {
    const size_t m = vh_.size();
    std::vector<Poles> poles(m);
    // Hull facets, in the order of their keys (the sums below are of
    // floats): each one's outward normal goes to its three samples.
    std::vector<uint32_t> hull;
    for (uint32_t i = 0; i < node_.size(); ++i)
      if (node_[i].r2 < 0)
        hull.push_back(i);
    std::sort(hull.begin(), hull.end(),
              [&](uint32_t a, uint32_t b) { return key_less(a, b); });
    for (const uint32_t h : hull) {
      const Ch c = cells_[h];
      const int k = c->index(dt_.infinite_vertex());
      V3 corner[3];
      const V3 nrm = hull_normal(c, k, corner);
      if (!(norm2(nrm) > 0))
        continue;
      for (int j = 1; j < 4; ++j) {
        Poles &p = poles[c->vertex((k + j) % 4)->info().idx];
        p.hull = true;
        p.dir[0] += float(nrm.x), p.dir[1] += float(nrm.y),
            p.dir[2] += float(nrm.z);
      }
    }
    for (auto c = dt_.finite_cells_begin(); c != dt_.finite_cells_end(); ++c) {
      const uint32_t i = c->info().w.local;
      const Node &b = node_[i];
      poll(i);
      for (int j = 0; j < 4; ++j) {
        Poles &p = poles[c->vertex(j)->info().idx];
        const float d2 = dist2(c->vertex(j)->point(), b.o);
        // Of equal distances, the smaller key.
        if (d2 > p.far2 || (d2 == p.far2 && key_less(i, p.first))) {
          p.far2 = d2;
          p.first = i;
        }
      }
    }
    for (size_t v = 0; v < m; ++v) {
      Poles &p = poles[v];
      if (p.hull) {
        p.first = UINT32_MAX;
      } else if (p.first != UINT32_MAX) {
        const Point &s = vh_[v]->point();
        const double *o = node_[p.first].o;
        p.dir[0] = float(o[0] - s.x()), p.dir[1] = float(o[1] - s.y()),
        p.dir[2] = float(o[2] - s.z());
      }
      p.far2 = -1;
    }
    // Each sample's pole direction, unit, for surface_between().
    axis_.assign(3 * m, 0.0f);
    for (size_t v = 0; v < m; ++v) {
      const Poles &p = poles[v];
      const double l2 = double(p.dir[0]) * p.dir[0] +
                        double(p.dir[1]) * p.dir[1] +
                        double(p.dir[2]) * p.dir[2];
      if (l2 > 0)
        for (int k = 0; k < 3; ++k)
          axis_[3 * v + k] = float(p.dir[k] / std::sqrt(l2));
    }
    for (auto c = dt_.finite_cells_begin(); c != dt_.finite_cells_end(); ++c) {
      const uint32_t i = c->info().w.local;
      const double *o = node_[i].o;
      poll(i);
      for (int j = 0; j < 4; ++j) {
        Poles &p = poles[c->vertex(j)->info().idx];
        const Point &s = c->vertex(j)->point();
        const float a[3] = {float(o[0] - s.x()), float(o[1] - s.y()),
                            float(o[2] - s.z())};
        if (a[0] * p.dir[0] + a[1] * p.dir[1] + a[2] * p.dir[2] >= 0)
          continue;
        const float d2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
        if (d2 > p.far2 || (d2 == p.far2 && key_less(i, p.second))) {
          p.far2 = d2;
          p.second = i;
        }
      }
    }
    // Each labelled pole tells the sample's other pole to take the other
    // label, with the weight -cos of the angle between them at the sample.
    auto weight = [&](const Point &s, uint32_t from, uint32_t to) {
      const float a[3] = {float(node_[from].o[0] - s.x()),
                          float(node_[from].o[1] - s.y()),
                          float(node_[from].o[2] - s.z())};
      return -cos_at(s, a, node_[to].o);
    };
    for (size_t v = 0; v < m; ++v) {
      const Poles &p = poles[v];
      if (p.first != UINT32_MAX && p.second != UINT32_MAX) {
        ++node_[p.first].links;
        ++node_[p.second].links;
      }
    }
    uint32_t total = 0;
    for (Node &d : node_) {
      d.link_at = total;
      total += d.links;
      d.links = 0; // counted again as they are filled in
    }
    links_.resize(total);
    hull_poles_.clear();
    for (size_t v = 0; v < m; ++v) {
      const Poles &p = poles[v];
      const Point &s = vh_[v]->point();
      if (p.hull && p.second != UINT32_MAX)
        hull_poles_.push_back(
            Link{p.second, -cos_at(s, p.dir, node_[p.second].o)});
      if (p.first == UINT32_MAX || p.second == UINT32_MAX)
        continue;
      Node &a = node_[p.first], &b = node_[p.second];
      links_[a.link_at + a.links++] = Link{p.second, weight(s, p.first, p.second)};
      links_[b.link_at + b.links++] = Link{p.first, weight(s, p.second, p.first)};
    }
  }

  // The cosine of the angle at which the sphere of the finite neighbour of
  // infinite cell c (across its hull facet, opposite vertex k, the
  // infinite one) crosses the outer half-space of that facet: the finite
  // cell's centre is h above the facet (outward), and the cosine -h / r.
  // (The normal, hull_normal(), as the poles stage has it.)
  float hull_crossing(Ch c, int k) const {
    const Node &b = node_[c->neighbor(k)->info().w.local];
    V3 corner[3];
    const V3 nrm = hull_normal(c, k, corner);
    if (!(norm2(nrm) > 0))
      return 0;
    const double h = nrm.x * (b.o[0] - corner[0].x) +
                     nrm.y * (b.o[1] - corner[0].y) +
                     nrm.z * (b.o[2] - corner[0].z);
    return float(std::max(-1.0, std::min(1.0, -h / std::sqrt(double(b.r2)))));
  }

  // Whether the surface passes between finite cells d (number i) and b,
  // across d's facet f, where the balls cannot tell. In a coarse sample
  // the ball of a cell can reach through the surface (a cell across a thin
  // tube or a horn's tip, its centre outside): both circumcentres then
  // lie on the same side of the facet, and the two balls overlap deeply
  // although the cells lie on either side. The facet is taken for the
  // surface's where, besides, its dual Voronoi edge, from one
  // circumcentre to the other, passes the cocone test at its three samples
  // (section 6.3, with the poles found here): b does not take d's label by
  // their balls there. (Corners by number, so that the answer does not
  // depend on the order of the cell's vertices in memory.)
  bool surface_between(uint32_t i, int f, const Node &d, const Node &b) const {
    if (!(sin2_cocone_ > 0) || d.r2 < 0 || b.r2 < 0)
      return false;
    const Ch c = cells_[i];
    Vh v[3] = {c->vertex((f + 1) % 4), c->vertex((f + 2) % 4),
               c->vertex((f + 3) % 4)};
    std::sort(v, v + 3,
              [](Vh x, Vh y) { return x->info().idx < y->info().idx; });
    const V3 p0 = v3(v[0]->point());
    const V3 nrm = cross(v3(v[1]->point()) - p0, v3(v[2]->point()) - p0);
    const V3 od{d.o[0], d.o[1], d.o[2]}, ob{b.o[0], b.o[1], b.o[2]};
    if (!(dot(nrm, od - p0) * dot(nrm, ob - p0) > 0))
      return false;
    for (const Vh &x : v) {
      const float *a = &axis_[3 * size_t(x->info().idx)];
      const V3 axis{a[0], a[1], a[2]}, s = v3(x->point());
      const int side = cone_side(od - s, axis, sin2_cocone_);
      if (side != 0 && side == cone_side(ob - s, axis, sin2_cocone_))
        return false;
    }
    return true;
  }

  // The cosine of the angle at which the spheres of neighbouring cells p
  // and q cross: 1 where they only touch, -1 where one holds the
  // other. An infinite cell's ball is the outer half-space of its hull
  // facet (see hull_crossing()).
  static float crossing(const Node &p, const Node &q) {
    if (p.r2 < 0 && q.r2 < 0)
      return -1;
    if (p.r2 < 0 || q.r2 < 0)
      return p.r2 < 0 ? p.o[0] : q.o[0];
    double d2 = 0;
    for (int k = 0; k < 3; ++k)
      d2 += (p.o[k] - q.o[k]) * (p.o[k] - q.o[k]);
    const double den = 2 * std::sqrt(p.r2 * q.r2);
    if (!(den > 0))
      return 0;
    return float(std::max(-1.0, std::min(1.0, (d2 - p.r2 - q.r2) / den)));
  }

  static float dist2(const Point &s, const double o[3]) {
    const float a[3] = {float(o[0] - s.x()), float(o[1] - s.y()),
                        float(o[2] - s.z())};
    return a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
  }
  // The cosine of the angle at sample s between direction a and point o.
  static float cos_at(const Point &s, const float a[3], const double o[3]) {
    const float b[3] = {float(o[0] - s.x()), float(o[1] - s.y()),
                        float(o[2] - s.z())};
    const float aa = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
    const float bb = b[0] * b[0] + b[1] * b[1] + b[2] * b[2];
    if (!(aa > 0 && bb > 0))
      return 0;
    return (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / std::sqrt(aa * bb);
  }

  // Repairs the pinches of the inside cells' boundary (see repair_vertex()).
  // Only vertices with cells of both labels around them can be pinched.
  void repair(sc_diag_t &diag) {
    const size_t m = vh_.size();
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
        work.push_back(vh_[i]);
        queued[i] = 1;
      }
    const uint64_t budget = 64 * uint64_t(work.size()) + 10000;
    uint64_t steps = 0;
    bool gave_up = false;
    // Most vertices need nothing; those are found at once (fine_links()),
    // and repair_vertex() looks only at the others and at the vertices of
    // cells that moved.
    std::vector<uint8_t> fine = fine_links(m);
    // Rounds: a vertex at which no piece may move waits for the next round,
    // which allows more moves per cell.
    std::vector<Vh> unresolved, moved;
    for (int round = 0; round < 3; ++round) {
      const uint8_t max_moves = uint8_t(2 << (2 * round));
      for (Vh v : unresolved)
        if (!queued[v->info().idx]) {
          queued[v->info().idx] = 1;
          work.push_back(v);
        }
      unresolved.clear();
      while (!work.empty() && !gave_up) {
        poll(steps);
        gave_up = ++steps > budget;
        Vh v = work.back();
        work.pop_back();
        queued[v->info().idx] = 0;
        if (fine[v->info().idx])
          continue;
        moved.clear();
        if (!repair_vertex(v, max_moves, moved, diag))
          unresolved.push_back(v);
        std::sort(moved.begin(), moved.end(), [](Vh a, Vh b) {
          return a->info().idx < b->info().idx;
        });
        for (Vh u : moved) {
          fine[u->info().idx] = 0; // its star changed
          if (!queued[u->info().idx]) {
            queued[u->info().idx] = 1;
            work.push_back(u);
          }
        }
      }
    }
    (void)gave_up;
  }

  // Per vertex, whether the facets between inside and other cells about it
  // make one simple cycle in its link (each link vertex on two of them,
  // all joined). The link of a vertex is a sphere (infinite cells
  // included) whose triangles are the vertex's cells: two regions of a
  // sphere, joined across edges, are each one piece exactly when the
  // edges between them make one simple cycle. So a vertex marked here is
  // one that repair_vertex() would leave as it is.
  std::vector<uint8_t> fine_links(size_t m) const {
    // The link edges (a, b) of each vertex v, from each facet (v, a, b).
    auto each = [&](auto &&take) {
      for_each_interface([&](Ch, int, const uint32_t t[3]) {
        take(t[0], t[1], t[2]);
        take(t[1], t[2], t[0]);
        take(t[2], t[0], t[1]);
      });
    };
    std::vector<uint32_t> at(m + 1, 0);
    each([&](uint32_t v, uint32_t, uint32_t) { ++at[v + 1]; });
    for (size_t v = 0; v < m; ++v)
      at[v + 1] += at[v];
    std::vector<std::array<uint32_t, 2>> edge(at[m]);
    {
      std::vector<uint32_t> put(at.begin(), at.end() - 1);
      each([&](uint32_t v, uint32_t a, uint32_t b) {
        edge[put[v]++] = {a, b};
      });
    }
    std::vector<uint8_t> fine(m, 0);
    std::vector<uint32_t> ends;
    for (size_t v = 0; v < m; ++v) {
      const std::array<uint32_t, 2> *e = edge.data() + at[v];
      const size_t k = at[v + 1] - at[v];
      if (k < 3)
        continue;
      // Every link vertex on exactly two of the edges...
      ends.clear();
      for (size_t i = 0; i < k; ++i)
        ends.insert(ends.end(), e[i].begin(), e[i].end());
      std::sort(ends.begin(), ends.end());
      bool two = true;
      for (size_t i = 0; i < ends.size() && two; i += 2)
        two = ends[i] == ends[i + 1] &&
              (i + 2 == ends.size() || ends[i + 2] != ends[i]);
      if (!two)
        continue;
      // ... and all of them on one cycle: walk it from the first edge.
      size_t steps = 1, last = 0;
      uint32_t at_end = e[0][1];
      while (at_end != e[0][0] && steps <= k) {
        size_t next = k;
        for (size_t i = 0; i < k && next == k; ++i)
          if (i != last && (e[i][0] == at_end || e[i][1] == at_end))
            next = i;
        if (next == k)
          break;
        at_end = e[next][0] == at_end ? e[next][1] : e[next][0];
        last = next;
        ++steps;
      }
      fine[v] = at_end == e[0][0] && steps == k;
    }
    return fine;
  }

  // Calls take(c, f, t) for each facet f of an inside cell c whose
  // neighbour is not inside, t its vertex numbers (vertices f + 1, f + 2,
  // f + 3 of c).
  template <class Take> void for_each_interface(Take &&take) const {
    for (auto c = dt_.finite_cells_begin(); c != dt_.finite_cells_end(); ++c) {
      if (c->info().w.label != kInside)
        continue;
      for (int f = 0; f < 4; ++f) {
        if (c->neighbor(f)->info().w.label == kInside)
          continue;
        uint32_t t[3];
        for (int j = 0; j < 3; ++j)
          t[j] = c->vertex((f + 1 + j) % 4)->info().idx;
        take(Ch(c), f, t);
      }
    }
  }

  // The boundary of the inside cells, each triangle facing out of them.
  std::vector<uint32_t> boundary_of_inside() const {
    std::vector<uint32_t> res;
    for_each_interface([&](Ch c, int f, const uint32_t t[3]) {
      uint32_t o[3] = {t[0], t[1], t[2]};
      // Outward: the cell's own fourth vertex must be behind.
      if (front(o, c->vertex(f)))
        std::swap(o[1], o[2]);
      res.insert(res.end(), o, o + 3);
    });
    return res;
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
  // repair ends. Returns false when no piece could move.
  bool repair_vertex(Vh v, uint8_t max_moves, std::vector<Vh> &touched,
                     sc_diag_t &diag) {
    std::vector<Ch> &inc = star_;
    inc.clear();
    dt_.incident_cells(v, std::back_inserter(inc));
    const size_t k = inc.size();
    std::vector<uint32_t> &parent = parent_;
    auto find = [&](uint32_t x) {
      while (parent[x] != x)
        x = parent[x] = parent[parent[x]];
      return x;
    };
    // The pieces of each label about v, joined across the facets at v, by
    // union-find over the cells in inc's order (each root the first of its
    // piece).
    int pieces[3];
    auto join = [&] {
      for (size_t i = 0; i < k; ++i)
        inc[i]->info().w.local = uint32_t(i);
      parent.resize(k);
      std::iota(parent.begin(), parent.end(), 0u);
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
      pieces[0] = pieces[1] = pieces[2] = 0;
      for (size_t i = 0; i < k; ++i)
        if (find(uint32_t(i)) == i)
          ++pieces[inc[i]->info().w.label];
    };
    join();
    if (pieces[kInside] <= 1 && pieces[kOutside] <= 1)
      return true; // most vertices: nothing to move
    // Which piece moves is decided in an order that depends on the
    // vertices only, not on the memory (each cell's key made once).
    keyed_.clear();
    for (Ch c : inc)
      keyed_.emplace_back(cell_key(c), c);
    std::sort(keyed_.begin(), keyed_.end(),
              [](const std::pair<std::array<uint32_t, 4>, Ch> &a,
                 const std::pair<std::array<uint32_t, 4>, Ch> &b) {
                return a.first < b.first;
              });
    for (size_t i = 0; i < k; ++i)
      inc[i] = keyed_[i].second;
    join();
    std::vector<uint32_t> &size = size_;
    size.assign(k, 0);
    std::vector<uint8_t> &fixed = fixed_;
    fixed.assign(k, 0);
    for (size_t i = 0; i < k; ++i) {
      uint32_t r = find(uint32_t(i));
      ++size[r];
      const CellLabel &w = inc[i]->info().w;
      if (dt_.is_infinite(inc[i]) || w.moved >= max_moves)
        fixed[r] = 1;
    }
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

private:
  DT &dt_;
  std::vector<Vh> vh_; // vertex number -> handle
  const double sin2_cocone_;
  std::vector<float> axis_; // per vertex number: the unit pole direction
  std::vector<Ch> star_; // scratch of repair_vertex()
  std::vector<std::pair<std::array<uint32_t, 4>, Ch>> keyed_; // likewise
  std::vector<uint32_t> parent_, size_;
  std::vector<uint8_t> fixed_;
  // While weigh() runs: by cell number, what it reads of each cell; the
  // pole links, and the hull samples' evidence for inside (to their
  // second poles).
  std::vector<Node> node_;
  std::vector<Link> links_;
  std::vector<Link> hull_poles_;
  std::vector<Ch> cells_;       // number -> handle
  std::vector<uint32_t> kmin_;  // number -> smallest vertex number
};

} // namespace

template <class DT>
bool label_and_close(DT &dt, std::vector<uint32_t> &tris, Progress &progress,
                     sc_diag_t &diag, double cocone_theta) {
  return Labelling<DT>(dt, cocone_theta).label_and_close(tris, progress, diag);
}

template bool label_and_close<DtSeq>(DtSeq &, std::vector<uint32_t> &,
                                     Progress &, sc_diag_t &, double);

} // namespace dt
} // namespace sc
