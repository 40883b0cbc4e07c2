// Watertight mode's closure by labels: every Delaunay cell is labelled
// inside or outside across the oriented surface, and the boundary of the
// inside cells, repaired into a manifold, replaces the surface.
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include "delaunay.hpp"

#include <array>
#include <numeric>

namespace sc {
namespace dt {
namespace {

// The labelling of one triangulation, and the scratch of its repair.
template <class DT> class Labelling {
public:
  typedef typename DT::Vertex_handle Vh;
  typedef typename DT::Cell_handle Ch;

  explicit Labelling(DT &t) : dt_(t) {}

  // Watertight mode: label every cell inside or outside across the
  // oriented surface and take the boundary of the inside cells.
  //  - Seeds: the cell behind an outward triangle is inside, the one in
  //    front outside (a cell that several triangles touch takes the
  //    majority); infinite cells are outside.
  //  - A multi-source breadth-first search through the facets that are not
  //    surface triangles labels the rest, so that the inside and outside
  //    fronts meet in the middle of each hole.
  //  - The boundary of the union of the inside cells is closed, but may
  //    touch itself at an edge or a vertex. Around each vertex the cells of
  //    each label must form one piece (joined across facets at the vertex);
  //    that also rules out pinched edges. Where they do not, the smallest
  //    offending piece moves to the other label, and the neighbours are
  //    checked again.
  bool label_and_close(std::vector<uint32_t> &tris, Progress &progress,
                       sc_diag_t &diag) {
    const size_t m = dt_.number_of_vertices();
    vh_.assign(m, Vh());
    for (auto v = dt_.finite_vertices_begin(); v != dt_.finite_vertices_end();
         ++v)
      vh_[v->info().idx] = v;
    for (auto c = dt_.all_cells_begin(); c != dt_.all_cells_end(); ++c)
      c->info().w = CellLabel{0, 0, 0, kUnlabelled, 0, 0};

    // Open components may come out of extraction facing inward; the hull
    // tells: a triangle on the hull must face the infinite cell. Flip a
    // component whose hull triangles mostly face inward.
    const size_t nt = tris.size() / 3;
    std::vector<Ch> fc(nt);
    std::vector<int8_t> fi(nt, -1);
    std::vector<int8_t> hull_vote(nt, 0);
    find_facets(tris, progress, fc, fi, hull_vote);
    flip_inward_components(tris, hull_vote);

    std::vector<Ch> queue = seed(tris, fc, fi);
    progress.tick(nt, 4 * nt + 1);
    spread(std::move(queue));
    progress.tick(2 * nt, 4 * nt + 1);
    repair(diag);
    progress.tick(3 * nt, 4 * nt + 1);
    std::vector<uint32_t> res = boundary_of_inside();
    if (res.empty())
      return false;
    tris.swap(res);
    return true;
  }

private:
  // The Delaunay facet of each surface triangle t, as cell fc[t] and its
  // facet fi[t] (-1 for a triangle that is not a facet), and the vote of
  // each hull triangle on its orientation (see flip_inward_components()).
  void find_facets(const std::vector<uint32_t> &tris, Progress &progress,
                   std::vector<Ch> &fc, std::vector<int8_t> &fi,
                   std::vector<int8_t> &hull_vote) {
    const size_t nt = tris.size() / 3;
    for (size_t t = 0; t < nt; ++t) {
      progress.tick(t, 4 * nt + 1);
      const uint32_t *v = &tris[3 * t];
      int i, j, l;
      Ch c;
      if (!dt_.is_facet(vh_[v[0]], vh_[v[1]], vh_[v[2]], c, i, j, l))
        continue; // a hole-filling triangle: not a Delaunay facet
      int f = 6 - i - j - l;
      fc[t] = c;
      fi[t] = int8_t(f);
      Ch nb = c->neighbor(f);
      bool c_front = in_front(v, c, f);
      if (dt_.is_infinite(c))
        hull_vote[t] = c_front ? 1 : -1;
      else if (dt_.is_infinite(nb))
        hull_vote[t] = c_front ? -1 : 1;
    }
  }

  // The seeds: the votes of the surface triangles on the cells on either
  // side of them, which they also bar from each other; returns the cells
  // labelled, infinite ones included.
  std::vector<Ch> seed(const std::vector<uint32_t> &tris,
                       const std::vector<Ch> &fc,
                       const std::vector<int8_t> &fi) {
    const size_t nt = tris.size() / 3;
    std::vector<Ch> queue;
    for (size_t t = 0; t < nt; ++t) {
      if (fi[t] < 0)
        continue;
      Ch c = fc[t], nb = c->neighbor(fi[t]);
      bool c_front = in_front(&tris[3 * t], c, fi[t]);
      vote(c, c_front ? kOutside : kInside);
      vote(nb, c_front ? kInside : kOutside);
      c->info().w.barrier |= uint8_t(1u << fi[t]);
      nb->info().w.barrier |= uint8_t(1u << nb->index(c));
    }
    for (auto c = dt_.all_cells_begin(); c != dt_.all_cells_end(); ++c) {
      CellLabel &w = c->info().w;
      if (dt_.is_infinite(c))
        w.label = kOutside;
      else if (w.vin || w.vout)
        w.label = w.vin > w.vout ? kInside : kOutside;
      if (w.label != kUnlabelled)
        queue.push_back(c);
    }
    return queue;
  }

  // Labels the rest from the cells in queue, across every facet that is not
  // a surface triangle. Level by level, so that the result does not depend
  // on the order of the cells in memory: a cell reached from the last level
  // takes the label of most of its neighbours there (outside on a tie),
  // counted in w.local (inside in the high half).
  void spread(std::vector<Ch> queue) {
    std::vector<Ch> next;
    while (!queue.empty()) {
      next.clear();
      for (Ch c : queue) {
        const CellLabel w = c->info().w;
        for (int f = 0; f < 4; ++f) {
          if (w.barrier & (1u << f))
            continue;
          CellLabel &v = c->neighbor(f)->info().w;
          if (v.label != kUnlabelled)
            continue;
          if (v.local == 0)
            next.push_back(c->neighbor(f));
          v.local += w.label == kInside ? 1u << 16 : 1u;
        }
      }
      for (Ch c : next) {
        CellLabel &w = c->info().w;
        w.label = (w.local >> 16) > (w.local & 0xFFFFu) ? kInside : kOutside;
        w.local = 0;
      }
      queue.swap(next);
    }
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
    // Rounds: a vertex at which no piece may move waits for the next round,
    // which allows more moves per cell.
    std::vector<Vh> unresolved, moved;
    for (int round = 0; round < 6; ++round) {
      // The first rounds leave the cells next to the surface where the
      // surface put them, so that the repair reshapes the caps over the
      // holes, not the surface; later rounds move any cell, more often.
      const bool keep_seeds = round < 3;
      const uint8_t max_moves = uint8_t(2 << (2 * (round % 3)));
      for (Vh v : unresolved)
        if (!queued[v->info().idx]) {
          queued[v->info().idx] = 1;
          work.push_back(v);
        }
      unresolved.clear();
      while (!work.empty() && !gave_up) {
        gave_up = ++steps > budget;
        Vh v = work.back();
        work.pop_back();
        queued[v->info().idx] = 0;
        moved.clear();
        if (!repair_vertex(v, max_moves, keep_seeds, moved, diag))
          unresolved.push_back(v);
        std::sort(moved.begin(), moved.end(), [](Vh a, Vh b) {
          return a->info().idx < b->info().idx;
        });
        for (Vh u : moved)
          if (!queued[u->info().idx]) {
            queued[u->info().idx] = 1;
            work.push_back(u);
          }
      }
    }
    (void)gave_up;
  }

  // The boundary of the inside cells, each triangle facing out of them.
  std::vector<uint32_t> boundary_of_inside() const {
    std::vector<uint32_t> res;
    for (auto c = dt_.finite_cells_begin(); c != dt_.finite_cells_end(); ++c) {
      if (c->info().w.label != kInside)
        continue;
      for (int f = 0; f < 4; ++f) {
        if (c->neighbor(f)->info().w.label == kInside)
          continue;
        uint32_t t[3];
        for (int j = 0; j < 3; ++j)
          t[j] = c->vertex((f + 1 + j) % 4)->info().idx;
        // Outward: the cell's own fourth vertex must be behind.
        if (front(t, c->vertex(f)))
          std::swap(t[1], t[2]);
        res.insert(res.end(), t, t + 3);
      }
    }
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
  // repair ends; so does one next to a surface triangle if keep_seeds.
  // Returns false when no piece could move.
  bool repair_vertex(Vh v, uint8_t max_moves, bool keep_seeds,
                     std::vector<Vh> &touched, sc_diag_t &diag) {
    std::vector<Ch> &inc = star_;
    inc.clear();
    dt_.incident_cells(v, std::back_inserter(inc));
    // In an order that depends on the vertices only, not on the memory.
    std::sort(inc.begin(), inc.end(),
              [&](Ch a, Ch b) { return cell_key(a) < cell_key(b); });
    const size_t k = inc.size();
    for (size_t i = 0; i < k; ++i)
      inc[i]->info().w.local = uint32_t(i);
    std::vector<uint32_t> &parent = parent_;
    parent.resize(k);
    std::iota(parent.begin(), parent.end(), 0u);
    auto find = [&](uint32_t x) {
      while (parent[x] != x)
        x = parent[x] = parent[parent[x]];
      return x;
    };
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
    std::vector<uint32_t> &size = size_;
    size.assign(k, 0);
    std::vector<uint8_t> fixed(k, 0);
    int pieces[3] = {0, 0, 0};
    for (size_t i = 0; i < k; ++i) {
      uint32_t r = find(uint32_t(i));
      if (size[r]++ == 0)
        ++pieces[inc[r]->info().w.label];
      const CellLabel &w = inc[i]->info().w;
      if (dt_.is_infinite(inc[i]) || w.moved >= max_moves ||
          (keep_seeds && (w.vin || w.vout)))
        fixed[r] = 1;
    }
    if (pieces[kInside] <= 1 && pieces[kOutside] <= 1)
      return true;
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
  // Whether cell c lies in front of its facet f, the triangle t.
  bool in_front(const uint32_t *t, Ch c, int f) const {
    if (!dt_.is_infinite(c->vertex(f)))
      return front(t, c->vertex(f));
    Ch nb = c->neighbor(f);
    return !front(t, nb->vertex(nb->index(c)));
  }

  // Flips every edge-connected component of tris whose votes (+1 for a
  // hull triangle facing the infinite cell, -1 for one facing away) add up
  // to less than zero.
  static void flip_inward_components(std::vector<uint32_t> &tris,
                                     const std::vector<int8_t> &votes) {
    const size_t nt = tris.size() / 3;
    std::vector<std::pair<uint64_t, uint32_t>> edges;
    edges.reserve(3 * nt);
    for (size_t t = 0; t < nt; ++t)
      for (int k = 0; k < 3; ++k) {
        uint64_t a = tris[3 * t + k], b = tris[3 * t + (k + 1) % 3];
        edges.emplace_back(a < b ? (a << 32) | b : (b << 32) | a,
                           uint32_t(t));
      }
    std::sort(edges.begin(), edges.end());
    std::vector<uint32_t> parent(nt);
    std::iota(parent.begin(), parent.end(), 0u);
    auto find = [&](uint32_t x) {
      while (parent[x] != x)
        x = parent[x] = parent[parent[x]];
      return x;
    };
    for (size_t i = 1; i < edges.size(); ++i)
      if (edges[i].first == edges[i - 1].first) {
        uint32_t a = find(edges[i].second), b = find(edges[i - 1].second);
        if (a != b)
          parent[std::max(a, b)] = std::min(a, b);
      }
    std::vector<int64_t> score(nt, 0);
    for (size_t t = 0; t < nt; ++t)
      score[find(uint32_t(t))] += votes[t];
    for (size_t t = 0; t < nt; ++t)
      if (score[find(uint32_t(t))] < 0)
        std::swap(tris[3 * t + 1], tris[3 * t + 2]);
  }

  void vote(Ch c, uint8_t label) {
    CellLabel &w = c->info().w;
    if (label == kInside && w.vin < UINT16_MAX)
      ++w.vin;
    if (label == kOutside && w.vout < UINT16_MAX)
      ++w.vout;
  }

private:
  DT &dt_;
  std::vector<Vh> vh_; // vertex number -> handle
  std::vector<Ch> star_; // scratch of repair_vertex()
  std::vector<uint32_t> parent_, size_;
};

} // namespace

template <class DT>
bool label_and_close(DT &dt, std::vector<uint32_t> &tris, Progress &progress,
                     sc_diag_t &diag) {
  return Labelling<DT>(dt).label_and_close(tris, progress, diag);
}

template bool label_and_close<DtSeq>(DtSeq &, std::vector<uint32_t> &,
                                     Progress &, sc_diag_t &);
#ifdef CGAL_LINKED_WITH_TBB
template bool label_and_close<DtPar>(DtPar &, std::vector<uint32_t> &,
                                     Progress &, sc_diag_t &);
#endif

} // namespace dt
} // namespace sc
