// The triangulation: insertion (in chunks), duplicates and the vertex
// numbering, then the stages that need it, in order (filter(): poles,
// boundary detection, the one pass over the Delaunay facets that selects
// candidate triangles; each in its own file, see delaunay.hpp). The
// triangulation is freed before pruning starts, except in watertight mode,
// which labels its cells after extraction to close the holes of the surface
// (close()).
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include "delaunay.hpp"

#include <thread>

#include <CGAL/Spatial_sort_traits_adapter_3.h>
#include <CGAL/hilbert_sort.h>
#include <CGAL/spatial_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

namespace sc {
namespace dt {
namespace {

// The points of an xyz array by index, as a property map for CGAL's sorts.
struct XyzMap {
  const double *xyz;
  typedef uint32_t key_type;
  typedef Point value_type;
  typedef Point reference;
  typedef boost::readable_property_map_tag category;
  friend Point get(const XyzMap &m, uint32_t i) {
    return Point(m.xyz[3 * size_t(i)], m.xyz[3 * size_t(i) + 1],
                 m.xyz[3 * size_t(i) + 2]);
  }
};

} // namespace

namespace {

typedef CGAL::Spatial_sort_traits_adapter_3<K, XyzMap> SortTraits;
template <int axis, bool up>
using HilbertCmp = CGAL::internal::Hilbert_cmp_3<SortTraits, axis, up>;

} // namespace

// As CGAL::hilbert_sort() sorts (hilbert_sort.h, Hilbert_sort_median_3.h):
// a shuffle by rand48 with its default seed, then the first level of the
// recursion, its seven splits at the median and its eight sorts, whose
// axes and directions are those of the level's call with x the first axis
// and nothing reversed.
void HilbertSort::split() {
  if (all_ > 0) {
    reserve_resident(idx_, all_);
    idx_.resize(all_);
    std::iota(idx_.begin(), idx_.end(), 0u);
  }
  boost::rand48 random;
  boost::random_number_generator<boost::rand48, std::ptrdiff_t> rng(random);
  CGAL::cpp98::random_shuffle(idx_.begin(), idx_.end(), rng);
  const SortTraits t{XyzMap{xyz_}};
  const auto b = idx_.begin();
  auto at = [&](size_t i) { return b + std::ptrdiff_t(cut_[i]); };
  auto cut = [&](size_t i, size_t lo, size_t hi, auto cmp) {
    cut_[i] = size_t(CGAL::internal::hilbert_split(at(lo), at(hi), cmp) - b);
  };
  cut_[0] = 0;
  cut_[8] = idx_.size();
  if (idx_.size() <= 1) {
    for (size_t i = 1; i < 8; ++i)
      cut_[i] = idx_.size();
    return;
  }
  cut(4, 0, 8, HilbertCmp<0, false>(t));
  cut(2, 0, 4, HilbertCmp<1, false>(t));
  cut(1, 0, 2, HilbertCmp<2, false>(t));
  cut(3, 2, 4, HilbertCmp<2, true>(t));
  cut(6, 4, 8, HilbertCmp<1, true>(t));
  cut(5, 4, 6, HilbertCmp<2, false>(t));
  cut(7, 6, 8, HilbertCmp<2, true>(t));
}

void HilbertSort::part(size_t i) {
  begin();
  const CGAL::Hilbert_sort_median_3<SortTraits, CGAL::Sequential_tag> sort(
      SortTraits{XyzMap{xyz_}});
  const auto b = idx_.begin() + std::ptrdiff_t(cut_[i]),
             e = idx_.begin() + std::ptrdiff_t(cut_[i + 1]);
  switch (i) {
  case 0:
    sort.recursive_sort<2, false, false, false>(b, e);
    break;
  case 1:
  case 2:
    sort.recursive_sort<1, false, false, false>(b, e);
    break;
  case 3:
  case 4:
    sort.recursive_sort<0, false, true, true>(b, e);
    break;
  case 5:
  case 6:
    sort.recursive_sort<1, true, false, true>(b, e);
    break;
  default:
    sort.recursive_sort<2, true, true, false>(b, e);
    break;
  }
}

namespace {

// Every part of sort, on this thread; its indices sorted.
std::vector<uint32_t> sort_here(HilbertSort &sort) {
  for (size_t i = 0; i < HilbertSort::kParts; ++i)
    sort.part(i);
  return sort.take();
}

} // namespace

void hilbert_sort(const double *xyz, std::vector<uint32_t> &idx) {
  HilbertSort sort(xyz, std::move(idx));
  idx = sort_here(sort);
}

std::vector<uint32_t> hilbert_order(const double *xyz, size_t n) {
  HilbertSort sort(xyz, n);
  return sort_here(sort);
}

namespace {

// The round of point i in a biased randomized insertion order: r with
// probability 3/4^(r+1), from a hash of the index (splitmix64's finaliser),
// so that the order depends on nothing else.
constexpr int kRounds = 24;
inline int brio_round(uint32_t i) {
  uint64_t z = uint64_t(i) + 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return z == 0 ? kRounds : std::min(kRounds, __builtin_ctzll(z) / 2);
}

// Where to start looking for a point in a triangulation that already
// covers its region (a later chunk, in the daemon): a vertex near it. The
// vertices go into the cells of a uniform grid, about two per occupied
// cell when they sample a surface, kept in an open-addressing hash table
// of the occupied cells (16 bytes per vertex at most), one vertex per
// cell. Without it, each point of a chunk spread over the whole surface
// walked from the previous one, a few spacings away, through cells no
// longer in the cache: a chunk of 16k points into 300k inserted at 42 us
// a point, against 34 with the grid (17 for the points of one sorted
// insertion).
template <class Vh> class HintGrid {
public:
  template <class DT> void build(const DT &dt) {
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL},
           hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    size_t nv = 0;
    for (auto v = dt.finite_vertices_begin(); v != dt.finite_vertices_end();
         ++v, ++nv)
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], v->point()[a]);
        hi[a] = std::max(hi[a], v->point()[a]);
      }
    built_for_ = nv;
    slots_.clear();
    const double ext = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
    if (!(ext > 0) || nv == 0)
      return;
    // k^2 cells of the k^3 hold a surface, roughly.
    k_ = uint64_t(std::clamp(std::sqrt(double(nv) / 2), 1.0, 1e6));
    inv_ = double(k_) / ext;
    for (int a = 0; a < 3; ++a)
      lo_[a] = lo[a];
    size_t cap = 16;
    while (cap < 2 * nv)
      cap *= 2;
    slots_.assign(cap, Slot{0, Vh()});
    used_ = 0;
    for (auto v = dt.finite_vertices_begin(); v != dt.finite_vertices_end();
         ++v)
      put(v->point(), v);
  }
  size_t built_for() const { return built_for_; }
  bool empty() const { return slots_.empty(); }
  // A vertex in the cell of p, or the null handle.
  template <class P> Vh get(const P &p) const {
    const Slot *s = find(key(p));
    return s && s->key ? s->v : Vh();
  }
  // Makes v the vertex of the cell of p; a new cell only while the table
  // is at most half full.
  template <class P> void put(const P &p, Vh v) {
    const uint64_t k = key(p);
    Slot *s = const_cast<Slot *>(find(k));
    if (s->key == 0) {
      if (2 * (used_ + 1) > slots_.size())
        return;
      ++used_;
      s->key = k;
    }
    s->v = v;
  }

private:
  struct Slot {
    uint64_t key; // the cell's number plus one; 0 for an empty slot
    Vh v;
  };
  template <class P> uint64_t key(const P &p) const {
    uint64_t c = 0;
    for (int a = 2; a >= 0; --a) {
      const double t = (p[a] - lo_[a]) * inv_;
      const uint64_t i = t < 0 ? 0 : t >= double(k_) ? k_ - 1 : uint64_t(t);
      c = c * k_ + i;
    }
    return c + 1;
  }
  // The slot holding key k, or the empty slot where it would go.
  const Slot *find(uint64_t k) const {
    const size_t mask = slots_.size() - 1;
    size_t i = size_t((k * 0x9E3779B97F4A7C15ull) >> 20) & mask;
    while (slots_[i].key != 0 && slots_[i].key != k)
      i = (i + 1) & mask;
    return &slots_[i];
  }

  std::vector<Slot> slots_;
  double lo_[3] = {0, 0, 0}, inv_ = 1;
  uint64_t k_ = 1;
  size_t used_ = 0, built_for_ = 0;
};

} // namespace

std::vector<uint32_t> brio_order(const std::vector<uint32_t> &hilbert) {
  // A counting sort by round, the last (largest) round last: bucket
  // kRounds - r, of kRounds + 1, starts at start[kRounds - r].
  std::array<size_t, kRounds + 2> start{};
  for (uint32_t i : hilbert)
    ++start[size_t(kRounds - brio_round(i)) + 1];
  for (int b = 0; b <= kRounds; ++b)
    start[size_t(b) + 1] += start[size_t(b)];
  std::vector<uint32_t> brio(hilbert.size());
  for (uint32_t i : hilbert)
    brio[start[size_t(kRounds - brio_round(i))]++] = i;
  return brio;
}

namespace {

template <class DT> class TriangulatorImpl : public Triangulator {
public:
  template <class... A> explicit TriangulatorImpl(A &&...a) : dt_(a...) {}

  void insert(const double *xyz, size_t first, size_t n,
              Progress &progress) override {
    std::vector<uint32_t> order(n);
    std::iota(order.begin(), order.end(), uint32_t(first));
    insert_indices(xyz, std::move(order), first == 0, progress);
  }

  // Takes over dt, whose vertices carry input indices, then inserts the
  // points of rest (input indices) into it: the tiles' fallback.
  void adopt(DT &dt, const double *xyz, std::vector<uint32_t> rest,
             Progress &progress) {
    dt_.swap(dt);
    if (!rest.empty())
      insert_indices(xyz, std::move(rest), false, progress);
  }

  // Inserts the points of xyz whose indices are in order (any order);
  // first: they are the first points, 0 .. order.size() - 1.
  void insert_indices(const double *xyz, std::vector<uint32_t> order,
                      bool first, Progress &progress) {
    const size_t n = order.size();
    // A biased randomized insertion order (Amenta, Choi and Rote), the one
    // CGAL's spatial_sort() makes: rounds, each a quarter of the size of
    // the next, each in Hilbert order. It is drawn from one Hilbert sort of
    // the range, whose subsequences are in Hilbert order too; when the range
    // is the whole input, that sort is also the vertex numbering (see
    // number_vertices()), which then costs no second sort. Batches along
    // the order give progress and cancellation points, and each continues
    // where the last one ended, so insertion keeps the locality of a single
    // sorted insert.
    hilbert_sort(xyz, order);
    std::vector<uint32_t> brio;
    // A chunk that comes after at least as many points lands in a
    // triangulation that already spans its region: there the rounds only
    // make the walk from one point to the next longer, and the plain
    // Hilbert order with a hint from the grid is faster (a chunk of 16k
    // points into 200k: 63 us a point in rounds, 41 without, 34 with the
    // grid too). The triangulation is the same whatever the order.
    const bool append = dt_.number_of_vertices() >= std::max<size_t>(n, 1000);
    if (append) {
      brio = order;
    } else {
      brio = brio_order(order);
    }
    if (first)
      hilbert_.swap(order);
    else
      hilbert_.clear();
    order = {};
    const size_t batch = std::max<size_t>(1u << 14, n / 64);
    Ch hint;
    // Built again each time the triangulation has grown fourfold.
    if (append &&
        (grid_.empty() || dt_.number_of_vertices() > 4 * grid_.built_for()))
      grid_.build(dt_);
    const bool use_grid = append && !grid_.empty();
    for (size_t done = 0; done < n; done += batch) {
      progress.report(double(done) / double(n));
      size_t m = std::min(batch, n - done);
      for (size_t k = done; k < done + m; ++k) {
        // The points are in input order, scattered along the insertion
        // order: ask for the next one while this one goes in.
        if (k + 1 < n)
          __builtin_prefetch(xyz + 3 * size_t(brio[k + 1]));
        const double *p = xyz + 3 * size_t(brio[k]);
        Point pt(p[0], p[1], p[2]);
        if (use_grid) {
          Vh near = grid_.get(pt);
          if (near != Vh())
            hint = near->cell();
        }
        Vh v = dt_.insert(pt, hint);
        v->info().idx = brio[k];
        hint = v->cell();
        if (use_grid)
          grid_.put(pt, v);
      }
    }
    progress.report(1.0);
  }

  int dimension() const override { return dt_.dimension(); }

  void translate(const double shift[3]) override {
    for (auto v = dt_.finite_vertices_begin(); v != dt_.finite_vertices_end();
         ++v) {
      const Point &p = v->point();
      v->set_point(Point(p.x() - shift[0], p.y() - shift[1], p.z() - shift[2]));
    }
    grid_ = HintGrid<Vh>(); // its cells are where the points were
  }

  void filter(const double *xyz, size_t n, const sc_params_t &params,
              Progress &progress, Filtered &out, sc_diag_t &diag,
              double seconds[SC_STAGE_COUNT]) override {
    Stopwatch sw;
    progress.stage(SC_STAGE_DELAUNAY);
    resolve_duplicates(xyz, n, out.dups);
    diag.duplicates_merged = out.dups.size();
    diag.delaunay_vertices = dt_.number_of_vertices();
    // From here on vertices go by their rank in a Hilbert order of the
    // points: every later array indexed by vertex is then read with
    // locality, whatever the input order; and the numbering depends only on
    // the points, not on the order in which they were inserted (all at once
    // here, in chunks as they arrive in the daemon), so neither do the
    // candidates, pruning and walk, and both give the same mesh.
    number_vertices(xyz, n, out.to_input);
    seconds[SC_STAGE_DELAUNAY] += sw.lap();

    progress.stage(SC_STAGE_POLES);
    compute_poles(dt_, infinite_, progress, diag);
    if (detects_boundary(params.mode))
      classify(dt_, infinite_, params, progress, out.boundary, diag);
    seconds[SC_STAGE_POLES] += sw.lap();

    progress.stage(SC_STAGE_CANDIDATES);
    const unsigned threads =
        params.threads > 0 ? unsigned(params.threads)
                           : std::max(1u, std::thread::hardware_concurrency());
    std::vector<std::vector<uint32_t>> later;
    select_candidates(dt_, infinite_, params, progress, out.tris, diag, nullptr,
                      checks(params) ? &out.check : nullptr, threads, later);
    diag.candidates = out.tris.size() / 3;
    for (const std::vector<uint32_t> &l : later)
      diag.candidates += l.size() / 3;
    // The unit poles by vertex number, for the normals: copied out last, so
    // that the array takes memory that boundary detection has freed instead
    // of pages of its own.
    out.poles.assign(3 * out.to_input.size(), 0.0);
    for (auto v = dt_.finite_vertices_begin(); v != dt_.finite_vertices_end();
         ++v)
      std::memcpy(&out.poles[3 * size_t(v->info().idx)], v->info().pole,
                  sizeof v->info().pole);
    // The triangulation is not needed any more: free it before pruning so
    // that the peak memory is the triangulation's alone (watertight mode
    // keeps it for the labelling with --labels, and where enough boundary
    // samples were found that the labelling may well run).
    if (!keep && diag.boundary_samples > 0 &&
        diag.boundary_samples >= keep_from_boundary)
      keep = true;
    if (!keep)
      dt_.clear();
    // The candidates of the slices scanned on other threads, joined in the
    // memory the triangulation left.
    if (!later.empty()) {
      out.tris.reserve(3 * diag.candidates);
      for (std::vector<uint32_t> &l : later) {
        out.tris.insert(out.tris.end(), l.begin(), l.end());
        l = {};
      }
    }
    // Which cell reports a facet, and when, depends on heap addresses; the
    // later stages break ties by the order of the candidates. They carry no
    // orientation: the walk gives them one.
    canonical_order(out.tris, false);
    out.check.canonical();
    seconds[SC_STAGE_CANDIDATES] += sw.lap();
  }

  bool close(std::vector<uint32_t> &tris, Progress &progress, sc_diag_t &diag,
             double cocone_theta) override {
    return label_and_close(dt_, tris, progress, diag, cocone_theta);
  }

  void cocone_everywhere(const sc_params_t &params, Progress &progress,
                         std::vector<uint32_t> &tris) override {
    // The labels took the circumcentres' bytes, and a triangulation that
    // filter() kept has its poles already: poles and circumcentres are
    // computed again from scratch. The counts go nowhere.
    for (auto v = dt_.finite_vertices_begin(); v != dt_.finite_vertices_end();
         ++v)
      v->info() = VertexData(v->info().idx);
    sc_diag_t scratch{};
    compute_poles(dt_, infinite_, progress, scratch);
    sc_params_t cocone = params;
    cocone.mode = SC_MODE_COCONE;
    tris.clear();
    select_candidates(dt_, infinite_, cocone, progress, tris, scratch);
    canonical_order(tris, false);
  }

private:
  typedef typename DT::Vertex_handle Vh;
  typedef typename DT::Cell_handle Ch;

  // Numbers the vertices 0, 1, ... in the Hilbert order of all the points
  // (indices 0 .. n-1 sorted; of equal points, the vertex keeps the first
  // index) and fills to_input (vertex number -> input index).
  void number_vertices(const double *xyz, size_t n,
                       std::vector<uint32_t> &to_input) {
    std::vector<uint32_t> order;
    if (hilbert_.size() == n)
      order.swap(hilbert_);
    else
      order = hilbert_order(xyz, n);
    hilbert_ = {};
    std::vector<uint8_t> is_vertex(n, 0);
    for (auto v = dt_.finite_vertices_begin(); v != dt_.finite_vertices_end();
         ++v)
      is_vertex[v->info().idx] = 1;
    to_input.clear();
    to_input.reserve(dt_.number_of_vertices());
    for (uint32_t i : order)
      if (is_vertex[i])
        to_input.push_back(i);
    order = {};
    std::vector<uint32_t> rank(n);
    for (size_t i = 0; i < to_input.size(); ++i)
      rank[to_input[i]] = uint32_t(i);
    for (auto v = dt_.finite_vertices_begin(); v != dt_.finite_vertices_end();
         ++v)
      v->info().idx = rank[v->info().idx];
  }

  // Range insertion keeps one of several equal points, with whatever index
  // came last in its spatial order. Find each missing index, record it as a
  // duplicate, and make the vertex carry the smallest index of its point so
  // every output index is the first occurrence.
  void resolve_duplicates(const double *xyz, size_t n,
                          std::vector<std::pair<uint32_t, uint32_t>> &dups) {
    if (dt_.number_of_vertices() == n)
      return;
    std::vector<bool> seen(n, false);
    for (auto v = dt_.finite_vertices_begin(); v != dt_.finite_vertices_end();
         ++v)
      seen[v->info().idx] = true;
    Ch hint;
    for (size_t i = 0; i < n; ++i) {
      if (seen[i])
        continue;
      Point p(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
      typename DT::Locate_type lt;
      int li, lj;
      Ch c = dt_.locate(p, lt, li, lj, hint);
      if (lt != DT::VERTEX)
        throw Error(SC_EINTERNAL, "a point missing from the triangulation");
      hint = c;
      Vh v = c->vertex(li);
      uint32_t j = v->info().idx;
      if (j > i) {
        dups.emplace_back(j, uint32_t(i));
        v->info().idx = uint32_t(i);
      } else {
        dups.emplace_back(uint32_t(i), j);
      }
    }
  }

  DT dt_;
  // The Hilbert order of the points 0 .. n-1 when they were inserted as one
  // range (see insert()); empty otherwise.
  std::vector<uint32_t> hilbert_;
  std::vector<Vh> vh_; // vertex number -> handle, while closing
  std::vector<Ch> infinite_; // from the poles stage to the candidates
  HintGrid<Vh> grid_;
};

} // namespace

std::unique_ptr<Triangulator> adopt_triangulation(DtSeq &dt, const double *xyz,
                                                  std::vector<uint32_t> rest,
                                                  Progress &progress) {
  auto t = std::make_unique<TriangulatorImpl<DtSeq>>();
  t->adopt(dt, xyz, std::move(rest), progress);
  return t;
}

} // namespace dt

// CGAL's concurrent triangulation was measured slower here than the
// sequential one on every input and number of threads tried (docs/
// algorithm.md section 3): the threads go to the tiles instead.
std::unique_ptr<Triangulator> make_triangulator() {
  return std::make_unique<dt::TriangulatorImpl<dt::DtSeq>>();
}

} // namespace sc
