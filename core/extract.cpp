// Manifold extraction: a walk over the pruned candidates that grows each
// component from a seed triangle, keeping it an oriented manifold.
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include "edges.hpp"

#include <optional>

namespace sc {
namespace {

// The bit of edge-use flags for the direction a -> b.
inline uint8_t dir_bit(uint32_t a, uint32_t b) { return a < b ? 1 : 2; }

// The vertices of the live triangles by decreasing x. The sort moves each x
// with its vertex, for reading it through the vertex number was a cache miss
// per comparison; it compares x alone, as before, so the order (ties
// included) is the same.
std::vector<uint32_t> by_decreasing_x(const double *xyz, size_t n,
                                      const VertexStar &star) {
  struct ByX {
    double x;
    uint32_t v;
  };
  std::vector<ByX> by_x;
  reserve_resident(by_x, n);
  for (uint32_t v = 0; v < n; ++v)
    if (star.first[v + 1] > star.first[v])
      by_x.push_back({xyz[3 * size_t(v)], v});
  std::sort(by_x.begin(), by_x.end(),
            [](const ByX &a, const ByX &b) { return a.x > b.x; });
  std::vector<uint32_t> order(by_x.size());
  for (size_t i = 0; i < by_x.size(); ++i)
    order[i] = by_x[i].v;
  return order;
}

// The walk never crosses to a triangle that bends back onto the one it
// comes from by more than 120 degrees (a fold into a pocket of extra
// candidates), nor to one whose longest edge is more than 4 times that of
// the one it comes from (a bridge across a gap): section 8.
constexpr double kMinFlat = -0.5;
constexpr double kMaxGrowth = 4;

// The walk: grow each component from a seed triangle, crossing every edge
// to the first triangle met when rotating about it from the outer side,
// the flattest continuation first (docs/algorithm.md section 8).
// A triangle joins only if it keeps every directed edge used at most once
// (edge-manifold, consistently oriented) and touches no vertex of an
// earlier component.
class Walk {
public:
  Walk(const double *xyz, size_t n, const std::vector<uint32_t> &live,
       const EdgeTable &et, const VertexStar &star, Progress &progress)
      : xyz_(xyz), live_(live), et_(et), star_(star), progress_(progress),
        nl_(live.size() / 3) {
    // (Each array resident at once: prefault.hpp.)
    reserve_resident(otri, live.size());
    otri.assign(live.begin(), live.end());
    reserve_resident(in, nl_);
    in.assign(nl_, 0);
    reserve_resident(used_, et.edges());
    used_.assign(et.edges(), 0);
    reserve_resident(owner_, n);
    owner_.assign(n, -1);
    // The triangles of the edge table alone, side by side: the walk reads
    // little else of an entry, at every edge it crosses.
    reserve_resident(etri_, et.entries.size());
    etri_.resize(et.entries.size());
    for (size_t i = 0; i < etri_.size(); ++i)
      etri_[i] = et.entries[i].tri;
  }

  // Grows a component from each vertex of order in turn that no component
  // has reached.
  void run(const std::vector<uint32_t> &order) {
    int32_t comps = 0;
    for (uint32_t s : order) {
      if (owner_[s] != -1)
        continue;
      double sign = 1;
      const uint32_t best = seed_at(s, sign);
      if (best == UINT32_MAX)
        continue;
      const uint32_t *v = &live_[3 * size_t(best)];
      uint32_t b1 = sign > 0 ? v[1] : v[2], c1 = sign > 0 ? v[2] : v[1];
      walk(best, v[0], b1, c1, comps);
      if (members_.empty())
        continue;
      // The walk keeps to the outer side of its seed's orientation. If the
      // component came out facing inward, the seed was oriented wrongly and
      // the walk followed the inner candidates: walk again the other way.
      if (volume() < 0) {
        undo();
        walk(best, v[0], c1, b1, comps);
        if (members_.empty())
          continue;
      }
      ++comps;
    }
  }

  std::vector<uint32_t> otri;    // oriented copy of the live triangles
  std::vector<uint8_t> in;       // per live triangle: the walk took it
  std::vector<uint32_t> new_fan; // vertices that may have several fans

private:
  // The id of the edge x-y of live triangle t.
  uint32_t edge_of(uint32_t t, uint32_t x, uint32_t y) const {
    const uint64_t key = edge_key(x, y);
    for (int j = 0; j < 3; ++j)
      if (edge_key(live_[3 * size_t(t) + j],
                   live_[3 * size_t(t) + (j + 1) % 3]) == key)
        return et_.tri_edge[3 * size_t(t) + j];
    return uint32_t(UINT32_MAX);
  }

  // Whether live triangle t, as a -> b -> c, may join component comp; its
  // edges' ids in e. Once false, false for the rest of the walk: owners
  // and used directions are only added.
  bool may_join(uint32_t t, uint32_t a, uint32_t b, uint32_t c, int32_t comp,
                uint32_t e[3]) const {
    const uint32_t v[3] = {a, b, c};
    for (int k = 0; k < 3; ++k) {
      if (owner_[v[k]] != -1 && owner_[v[k]] != comp)
        return false;
    }
    for (int k = 0; k < 3; ++k) {
      uint32_t x = v[k], y = v[(k + 1) % 3];
      e[k] = edge_of(t, x, y);
      if (used_[e[k]] & dir_bit(x, y))
        return false;
    }
    return true;
  }

  // Adds live triangle t, as a -> b -> c, to component comp if it may join.
  bool try_add(uint32_t t, uint32_t a, uint32_t b, uint32_t c, int32_t comp) {
    const uint32_t v[3] = {a, b, c};
    uint32_t e[3];
    if (!may_join(t, a, b, c, comp, e))
      return false;
    // A corner already in the component that shares neither of its edges
    // with a triangle of it starts a second fan there, which later
    // triangles may or may not join to the first.
    for (int k = 0; k < 3; ++k)
      if (owner_[v[k]] == comp && !used_[e[k]] && !used_[e[(k + 2) % 3]])
        new_fan.push_back(v[k]);
    for (int k = 0; k < 3; ++k) {
      used_[e[k]] |= dir_bit(v[k], v[(k + 1) % 3]);
      owner_[v[k]] = comp;
      otri[3 * size_t(t) + k] = v[k];
    }
    in[t] = 1;
    return true;
  }

  // A clean triangle has exactly two live triangles on each edge: the walk
  // starts there, away from pockets of extra candidates.
  bool clean(uint32_t t) const {
    for (int j = 0; j < 3; ++j) {
      uint32_t e = et_.tri_edge[3 * size_t(t) + j];
      if (et_.first[e + 1] - et_.first[e] != 2)
        return false;
    }
    return true;
  }

  // The seed at vertex s, the extreme vertex of what is left: the clean
  // triangle whose normal is closest to +x, to be oriented to face +x
  // (outward there) by sign. UINT32_MAX when there is none.
  uint32_t seed_at(uint32_t s, double &sign) const {
    uint32_t best = UINT32_MAX;
    double best_nx = -1;
    for (uint32_t i = star_.first[s]; i < star_.first[s + 1]; ++i) {
      uint32_t t = star_.tris[i];
      const uint32_t *v = &live_[3 * size_t(t)];
      if (in[t] || owner_[v[0]] != -1 || owner_[v[1]] != -1 ||
          owner_[v[2]] != -1 || !clean(t))
        continue;
      double nrm[3];
      triangle_normal(xyz_, v[0], v[1], v[2], nrm);
      const double l = std::sqrt(dot3(nrm, nrm));
      if (!(l > 0))
        continue;
      if (std::fabs(nrm[0]) / l > best_nx) {
        best_nx = std::fabs(nrm[0]) / l;
        best = t;
        sign = nrm[0] >= 0 ? 1 : -1;
      }
    }
    return best;
  }

  // The unit normal of the triangle a -> b -> c (zero if it has no area).
  void unit_normal(uint32_t a, uint32_t b, uint32_t c, double nrm[3]) const {
    triangle_normal(xyz_, a, b, c, nrm);
    const double l = std::sqrt(dot3(nrm, nrm));
    for (int k = 0; k < 3; ++k)
      nrm[k] = l > 0 ? nrm[k] / l : 0;
  }

  // The squared length of the longest edge of triangle a, b, c.
  double longest2(uint32_t a, uint32_t b, uint32_t c) const {
    const double *p = xyz_ + 3 * size_t(a), *q = xyz_ + 3 * size_t(b),
                 *r = xyz_ + 3 * size_t(c);
    return std::max(dist2(p, q), std::max(dist2(q, r), dist2(r, p)));
  }

  // A triangle that may join next, oriented a -> b -> c to follow the one
  // it was met from.
  struct Step {
    uint32_t t, a, b, c;
  };
  // The bend of a step in whole degrees, 0 to 120: the queue of each
  // degree is taken in the order its steps were met, the flattest first.
  static constexpr int kBends = 121;
  static constexpr double kDegrees = 180 / 3.14159265358979323846;

  // Offers the triangle met across each edge of t (the first when rotating
  // about the edge from t's outer side), unless it folds back onto t or
  // is much larger than t (section 8).
  void offer_next(uint32_t t, int32_t comp) {
    const uint32_t *o = &otri[3 * size_t(t)];
    double nt[3];
    unit_normal(o[0], o[1], o[2], nt);
    const double lt = longest2(o[0], o[1], o[2]);
    for (int k = 0; k < 3; ++k) {
      const uint32_t x = o[k], y = o[(k + 1) % 3];
      const uint32_t e = edge_of(t, x, y);
      const uint32_t lo = et_.first[e], cnt = et_.first[e + 1] - lo;
      // Nothing to cross to, or the other side is already taken.
      if (cnt < 2 || (used_[e] & dir_bit(y, x)))
        continue;
      uint32_t pos = 0;
      while (etri_[lo + pos] != t)
        ++pos;
      // Rotating toward the outer side of t is increasing angle when t
      // runs along the edge's reference direction, decreasing otherwise.
      const uint32_t step = x < y ? 1 : cnt - 1;
      const uint32_t nb = etri_[lo + (pos + step) % cnt];
      if (in[nb])
        continue;
      const uint32_t *w = &live_[3 * size_t(nb)];
      const uint32_t z = w[0] != x && w[0] != y   ? w[0]
                         : w[1] != x && w[1] != y ? w[1]
                                                  : w[2];
      // (What cannot join now never will: no need to queue it.)
      uint32_t ne[3];
      if (!may_join(nb, y, x, z, comp, ne))
        continue;
      double nn[3];
      unit_normal(y, x, z, nn);
      const double flat = dot3(nt, nn);
      if (flat < kMinFlat || longest2(y, x, z) > kMaxGrowth * kMaxGrowth * lt)
        continue;
      const int bend =
          std::min(kBends - 1, int(std::acos(std::min(1.0, flat)) * kDegrees));
      queue_[bend].push_back({nb, y, x, z});
      least_ = std::min(least_, bend);
    }
  }

  // Grows component comp from the seed, a -> b -> c, flattest step first;
  // its triangles are left in members_ (none if the seed could not join).
  void walk(uint32_t seed, uint32_t a, uint32_t b, uint32_t c, int32_t comp) {
    members_.clear();
    if (!try_add(seed, a, b, c, comp))
      return;
    members_.push_back(seed);
    offer_next(seed, comp);
    while (least_ < kBends) {
      std::vector<Step> &q = queue_[least_];
      if (head_[least_] == q.size()) {
        q.clear();
        head_[least_] = 0;
        ++least_;
        continue;
      }
      const Step s = q[head_[least_]++];
      if (!in[s.t] && try_add(s.t, s.a, s.b, s.c, comp)) {
        progress_.tick(++added_, nl_);
        members_.push_back(s.t);
        offer_next(s.t, comp);
      }
    }
  }

  // Takes the last walk's triangles out again.
  void undo() {
    for (uint32_t t : members_) {
      in[t] = 0;
      for (int k = 0; k < 3; ++k) {
        uint32_t x = otri[3 * size_t(t) + k],
                 y = otri[3 * size_t(t) + (k + 1) % 3];
        used_[edge_of(t, x, y)] &= uint8_t(~dir_bit(x, y));
        owner_[x] = -1;
      }
    }
  }

  // Six times the signed volume enclosed by the last walk's triangles.
  double volume() const {
    double v = 0;
    const double *o = xyz_ + 3 * size_t(otri[3 * size_t(members_[0])]);
    for (uint32_t t : members_)
      v += signed_volume6(xyz_, &otri[3 * size_t(t)], o);
    return v;
  }

  const double *xyz_;
  const std::vector<uint32_t> &live_;
  const EdgeTable &et_;
  const VertexStar &star_;
  Progress &progress_;
  const size_t nl_;
  std::vector<uint8_t> used_;  // per edge: the directions used (dir_bit())
  std::vector<int32_t> owner_; // per vertex: its component, or -1
  std::vector<uint32_t> etri_;
  std::vector<uint32_t> members_;
  std::vector<Step> queue_[kBends];
  size_t head_[kBends] = {};
  int least_ = kBends; // no queue below it holds a step
  size_t added_ = 0;   // triangles taken, those of walks undone included
};

// The entries of the triangles marked in `keep`.
size_t live_count(const std::vector<uint8_t> &keep) {
  return 3 * size_t(std::count_if(keep.begin(), keep.end(),
                                  [](uint8_t k) { return k != 0; }));
}

} // namespace

void extract(const double *xyz, size_t n, const std::vector<uint32_t> &cand,
             const std::vector<uint8_t> &alive, EdgeTablePtr table,
             size_t max_hole, const std::vector<uint8_t> &boundary,
             Progress &progress, Surface &out, sc_diag_t &diag,
             bool check_vertices, std::vector<uint32_t> *unfilled) {
  const size_t nt = cand.size() / 3;
  // Of extraction's time, the walk takes about half, the passes after it
  // the rest (measured on the merged bunny scans).
  std::optional<Progress::Span> step;
  step.emplace(progress, 0, 0.1);
  // Only the survivors of pruning take part.
  std::vector<uint32_t> live;
  reserve_resident(live, live_count(alive));
  for (size_t t = 0; t < nt; ++t)
    if (alive[t])
      live.insert(live.end(), &cand[3 * t], &cand[3 * t] + 3);
  const size_t nl = live.size() / 3;
  EdgeTable &et = *table;
  et.keep_live(alive, true); // the walk finds edges by triangle
  VertexStar star;
  star.build(n, live, [](size_t) { return true; });

  const std::vector<uint32_t> order = by_decreasing_x(xyz, n, star);
  Walk walk(xyz, n, live, et, star, progress);
  step.emplace(progress, 0.1, 0.6);
  walk.run(order);
  step.emplace(progress, 0.6, 1);
  std::vector<uint32_t> &otri = walk.otri;
  std::vector<uint8_t> &in = walk.in;

  // The stars of every live triangle, those the walk left out passed over;
  // only where a second fan was started can a vertex have several.
  fix_fans_in(star, otri, in, std::move(walk.new_fan));

  // The output, its components (triangles sharing an edge), and their
  // topology. Closed components facing inward are flipped.
  std::vector<uint32_t> res;
  reserve_resident(res, live_count(in));
  for (size_t t = 0; t < nl; ++t)
    if (in[t])
      res.insert(res.end(), &otri[3 * t], &otri[3 * t] + 3);
  diag.walk_rejected = nl - res.size() / 3;
  // The candidates' table, cut down to the output: the table of res (its
  // triangles about each edge in angular order, which none of the passes
  // below depends on).
  et.keep_live(in, false);
  if (unfilled)
    *unfilled = res;
  if (max_hole >= 3)
    fill_holes(xyz, n, res, max_hole, boundary, progress, diag, UINT64_MAX,
               &et);
  describe(xyz, n, res, progress, out, diag, &et, check_vertices);
}

} // namespace sc
