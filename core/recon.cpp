// One reconstruction from input to mesh: validation, the triangulation
// stages, pruning, extraction, and the result handed back to C. The steps
// and their order: docs/algorithm.md, section 1.2.
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include "internal.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <climits>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <limits>
#include <mutex>
#include <new>
#include <thread>

namespace sc {

namespace {

constexpr size_t kMaxPoints = 0xFFFFFFFEu;
// The watertight closure by patches fills holes of any length: a long loop
// is cut into pieces of at most 16 edges first (the least-area patch
// costs the cube of the length) ...
constexpr size_t kMaxFillLoop = std::numeric_limits<size_t>::max();
// ... and all the patches together take at most this many steps of the
// dynamic programme (seconds).
constexpr uint64_t kMaxFillWork = 2000000000ull;
// Small handles of the labels' closure (section 11.5): the rings of
// triangles about a vertex looked at first and at most, and the rounds.
// Measured on random samples of the closed models
// (scripts/resample-sweep.sh): 3 then 4 rings right on 44 of 64 in
// watertight mode and 40 in auto mode; 3 alone 43 and 39 (an anchor keeps
// 6 false handles), 3 to 5 or to 6 rings 43 and 39 (true handles of that
// anchor cut).
constexpr int kSmallHandleRings = 3;
constexpr int kSmallHandleRingsMax = 4;
constexpr int kSmallHandleRounds = 12;
// Closed components of fewer triangles than this, or than a thousandth of
// the surface, are bubbles between scan layers in the modes for scans.
constexpr size_t kMinBubble = 8;
// Watertight mode keeps a triangulation of at most this many points for
// the labelling (section 11.5), about 70 MB at most, where boundary
// samples were found; the labelling's thread hands one of at most so many
// points back, for the cocone test's candidates.
constexpr size_t kKeepForLabels = 65536;
// A larger one is kept where at least one sample in this many is a
// boundary sample: there the patches have left doubt and the labelling
// has run on every input measured (0.8% to 17% of the samples boundary
// samples), and the triangulation kept is the one it labels, for the same
// peak memory and 11% to 27% less time than building it again; below (5
// to 8 boundary samples of 200 000 on noisy synthetic samples) the
// patches sufficed, and keeping it would have raised the peak by 60%.
constexpr size_t kKeepBoundaryShare = 1000;
// Auto mode takes a sample for one of a closed surface where no loop is
// left open wider than this many of its edges (section 11.6).
constexpr double kClosedLoopWidth = 3;
// The noise estimate runs beside the triangulation on jobs of at least so
// many points (below, starting a thread costs more than it saves).
constexpr size_t kEstimateBeside = 1024;

void check_finite(const double *xyz, size_t n, size_t first) {
  for (size_t i = 0; i < 3 * n; ++i) {
    if (!std::isfinite(xyz[i])) {
      char buf[160];
      std::snprintf(buf, sizeof buf,
                    "point %zu has a non-finite %c coordinate (%g)",
                    first + i / 3, "xyz"[i % 3], xyz[i]);
      throw Error(SC_ENONFINITE, buf);
    }
  }
}

template <class T> T *copy_out(const T *src, size_t count) {
  T *p = static_cast<T *>(std::malloc(std::max<size_t>(1, count) * sizeof(T)));
  if (!p)
    throw std::bad_alloc();
  if (count)
    std::memcpy(p, src, count * sizeof(T));
  return p;
}

// What decides between two closures of a surface: a closed manifold first,
// then fewer loops left open, fewer components, more samples in a
// triangle, the smaller genus. (The labelling joins the thin parts that
// extraction broke off, and passes through the samples that the walk left
// out, where the patches close the holes without them; a single sheet,
// which has no inside, closes by labelling into a thin slab in pieces
// that also leaves out its rim, and the patches win.)
struct Closure {
  bool ok;
  int64_t genus;
  uint64_t loops, components, unused;
  explicit Closure(const sc_diag_t &d)
      : ok(d.closed && !d.nonmanifold_edges && !d.nonmanifold_vertices),
        genus(d.genus), loops(d.boundary_loops), components(d.components),
        unused(d.samples_unused) {}
  bool better_than(const Closure &o) const {
    if (ok != o.ok)
      return ok;
    if (loops != o.loops)
      return loops < o.loops;
    if (components != o.components)
      return components < o.components;
    if (unused != o.unused)
      return unused < o.unused;
    return genus < o.genus;
  }
};

// Whether `unused` of m samples is more than the project's target allows:
// one in a thousand.
inline bool too_many_unused(uint64_t unused, size_t m) {
  return 1000 * unused > m;
}

// The corners of triangle k of tris, in increasing order.
inline std::array<uint32_t, 3> sorted_corners(const std::vector<uint32_t> &tris,
                                              size_t k) {
  std::array<uint32_t, 3> c = {tris[3 * k], tris[3 * k + 1], tris[3 * k + 2]};
  std::sort(c.begin(), c.end());
  return c;
}

} // namespace

struct LabelTask::State {
  std::unique_ptr<Triangulator> dt;
  std::vector<uint32_t> tris;
  sc_diag_t diag{};
  bool inside = false, done = false;
  std::exception_ptr error;
  std::atomic<int> stop{0};
  std::mutex mu;
  std::condition_variable cv;
  std::thread thread;
};

LabelTask::LabelTask(std::unique_ptr<Triangulator> dt, const double *lxyz,
                     size_t m, double cocone_theta)
    : state_(new State) {
  State &st = *state_;
  st.dt = std::move(dt);
  st.thread = std::thread([&st, lxyz, m, cocone_theta] {
    // A stop makes the next progress tick throw.
    Progress mine(
        [](void *u, sc_stage_t, double) {
          return static_cast<std::atomic<int> *>(u)->load();
        },
        &st.stop);
    try {
      if (!st.dt) {
        st.dt = make_triangulator();
        st.dt->insert(lxyz, 0, m, mine);
      }
      st.inside = st.dt->close(st.tris, mine, st.diag, cocone_theta);
    } catch (...) {
      st.error = std::current_exception();
    }
    // Kept for the cocone test's candidates (close_surface()) where it is
    // small; a large one is built again there if they are wanted.
    if (!st.inside || m > kKeepForLabels)
      st.dt.reset();
    {
      std::lock_guard<std::mutex> lock(st.mu);
      st.done = true;
    }
    st.cv.notify_all();
  });
}

LabelTask::~LabelTask() {
  state_->stop = 1;
  state_->thread.join();
}

bool LabelTask::take(std::vector<uint32_t> &tris, Progress &progress,
                     sc_diag_t &diag, std::unique_ptr<Triangulator> &dt) {
  State &st = *state_;
  {
    std::unique_lock<std::mutex> lock(st.mu);
    while (!st.done) {
      st.cv.wait_for(lock, std::chrono::milliseconds(50));
      lock.unlock();
      progress.poll(); // a cancel stops the thread (the destructor)
      lock.lock();
    }
  }
  if (st.error)
    std::rethrow_exception(st.error);
  if (!st.inside)
    return false;
  tris.swap(st.tris);
  dt = std::move(st.dt);
  diag.cells_relabelled += st.diag.cells_relabelled;
  return true;
}

// Watertight mode, after extraction (docs/algorithm.md sections 11.2 to
// 11.5): closes surf, in two ways where the first leaves doubt, and keeps
// the better (see Closure):
//  - the least-area patches over the holes of the extracted surface, after
//    cutting the handles that closed round a hole of a scan; they keep the
//    extracted surface as it is;
//  - the boundary of the inside cells, once the Delaunay cells are
//    labelled inside or outside from their empty balls alone (section
//    11.4). On the closed models measured it keeps thin parts in one piece
//    where extraction broke them off, and leaves out the false handles
//    that the candidates make across them.
// watertight_labels takes the labelling alone (the patches only when no
// cell comes out inside); watertight_patches labels only when the patches
// leave the surface open.
void Recon::close_surface(const double *lxyz, size_t m, bool cut,
                          Progress &progress, Surface &surf, sc_diag_t &diag) {
  const uint64_t loops = diag.boundary_loops, before = diag.triangles;
  // Debris, such as lone triangles between scan layers, cannot be closed:
  // small open components go (their samples may be attached later).
  auto drop_debris = [&](Surface &s, sc_diag_t &d) {
    if (!d.closed && d.components > 1 && !s.tris.empty()) {
      drop_small_closed(lxyz, m, s,
                        std::max<size_t>(kMinBubble, s.tris.size() / 3 / 1000),
                        true, progress, d);
    }
  };

  // Describes tris into s and d, a manifold: relabelling (or cutting out
  // small handles) can leave a few pinches; they are cut out and the small
  // holes that leaves closed.
  auto describe_manifold = [&](std::vector<uint32_t> &tris, Surface &s,
                               sc_diag_t &d) {
    describe(lxyz, m, tris, progress, s, d);
    if (d.nonmanifold_edges || d.nonmanifold_vertices) {
      drop_nonmanifold(lxyz, m, s.tris, progress);
      fill_holes(lxyz, m, s.tris, kMaxFillLoop, {}, progress, d, kMaxFillWork);
      describe(lxyz, m, s.tris, progress, s, d);
    }
  };

  // The components of s but the pockets under a hundredth of it, which go
  // below: they do not count.
  auto pieces = [](const Surface &s) {
    uint64_t k = 0;
    for (const Surface::Part &p : s.parts)
      k += uint64_t(100 * p.faces) >= s.tris.size() / 3;
    return k;
  };

  // The closure by labels, into a and da; false when no cell is inside.
  // With it, from the same triangulation, the candidates of the cocone
  // test at every sample into everywhere, where a third closure may be
  // taken from them (take_everywhere(), below).
  Surface a;
  sc_diag_t da = diag;
  std::vector<uint32_t> everywhere;
  auto label = [&] {
    da.labelled = 1;
    // The triangulation that filter() kept (--labels); or, where it went
    // after the candidates (by default), built again over the same points,
    // numbered as the surface's vertices are.
    // Or the labelling already under way beside the extraction.
    std::vector<uint32_t> labelled;
    std::unique_ptr<Triangulator> dt;
    if (labelling_) {
      const bool inside = labelling_->take(labelled, progress, da, dt);
      labelling_.reset();
      if (!inside)
        return false;
    } else {
      dt = std::move(kept_);
      if (!dt) {
        dt = make_triangulator();
        dt->insert(lxyz, 0, m, progress);
      }
      if (!dt->close(labelled, progress, da, label_theta()))
        return false;
    }
    canonical_order(labelled, true);
    describe_manifold(labelled, a, da);
    drop_debris(a, da);
    // The cocone test's candidates at every sample, where a third closure
    // may be taken from them (take_everywhere()): boundary detection left
    // samples out of the candidates' test, the patches closed the surface
    // in one piece, and the labels' closure has more handles than the
    // extracted surface had.
    const Closure p(diag);
    if (closing_everywhere_ && !params_.watertight_labels && p.ok &&
        pieces(surf) == 1 && da.genus > p.genus + int64_t(diag.handles_cut)) {
      if (!dt) {
        dt = make_triangulator();
        dt->insert(lxyz, 0, m, progress);
      }
      dt->cocone_everywhere(params_, progress, everywhere);
    }
    return true;
  };
  auto take_labels = [&] {
    surf = std::move(a);
    diag = da;
    diag.path = SC_PATH_WATERTIGHT;
  };

  bool open = false;
  for (size_t t = 0; t < surf.tris.size() / 3 && !open; ++t)
    open = !surf.in_closed(t);
  auto patch = [&] {
    if (open) {
      patch_surface(lxyz, m, cut, progress, surf, diag);
      drop_debris(surf, diag);
    } else {
      diag.path = SC_PATH_WATERTIGHT; // nothing was open
    }
  };
  const bool labels_only = params_.watertight_labels != 0;
  const bool patches_first = !labels_only && params_.watertight_patches != 0;
  if (!labels_only)
    patch();
  // The labelling is tried where the patches' closure shows a defect: open,
  // in pieces, samples left out, or a handle that had to be cut. Where the
  // patches give one closed piece (pockets aside) with no handle cut and
  // at least 99.9% of the samples on it before any is attached (the
  // project's own target), it is not (section 11.5).
  auto doubtful = [&] {
    const Closure c(diag);
    return !c.ok || c.loops > 0 || pieces(surf) != 1 || diag.handles_cut > 0 ||
           too_many_unused(c.unused, m);
  };
  const bool labelling =
      labels_only || (patches_first ? !Closure(diag).ok : doubtful());
  diag.labelled = labelling;
  // Where the labels' closure, in no more pieces, has more handles than
  // the extracted surface had before the patches (their genus and the
  // handles they cut), the labelling made them: tunnels along sharp edges,
  // where the candidates miss strips that the patches span, or bridges
  // between close parts. The patches' closure is kept then if, with the
  // samples near each attached (attach_samples(), on copies), it leaves
  // out no more of them than the labels' does or than one in a thousand.
  // (Before attaching, the patches leave out the samples over the strips;
  // where they cut true handles, which the labels keep, the labels' genus
  // is not above theirs and their cuts. Where the extraction misses true
  // holes that the labels find, as on the cheese, they are lost: section
  // 11.5.)
  int64_t labels_genus = 0; // before small handles were cut
  auto made_handles = [&] {
    const Closure p(diag), l(da);
    if (!p.ok || !l.ok || p.loops != l.loops || pieces(surf) > pieces(a) ||
        labels_genus <= p.genus + int64_t(diag.handles_cut))
      return false;
    Surface sp = surf, sl = a;
    sc_diag_t dp = diag, dl = da;
    attach_samples(lxyz, m, sp, progress, dp);
    attach_samples(lxyz, m, sl, progress, dl);
    return dp.samples_unused <= std::max<uint64_t>(dl.samples_unused, m / 1000);
  };
  // Small handles (section 11.5): where the labels' closure has more
  // handles than the extracted surface had (the patches' genus and the
  // handles they cut), those that fit in a few rings of triangles about a
  // vertex are cut out, tightest first and no more than that excess, and
  // the holes patched; rings are widened once no more are found, and a
  // round is kept only where the result is a closed manifold in no more
  // components, once the pieces under a hundredth of it that a cut split
  // off are dropped. Never below the extracted surface's genus: its
  // handles have the candidates' support.
  auto small_handles = [&] {
    const Closure p(diag);
    if (!p.ok)
      return;
    const int64_t bound = p.genus + int64_t(diag.handles_cut);
    // The patches' closure's triangles, sorted, once the tunnels are
    // looked for.
    std::vector<std::array<uint32_t, 3>> theirs;
    // The handles first, then the tunnels (where the poles are known),
    // each in rounds of their own.
    for (const bool tunnels : {false, true}) {
      // Tunnels only where the labels' closure is kept with its handles:
      // where the patches' is in more pieces (made_handles()). Elsewhere
      // the patches' closure wins on handles, and a sample with many true
      // holes (the cheese) paid a second for nothing.
      if (tunnels && (!closing_poles_ || pieces(surf) <= pieces(a)))
        return;
      int rings = kSmallHandleRings;
      // A round after a kept one, with the same rings, probes again only
      // near what changed.
      ProbeCache cache;
      for (int round = 0;
           round < kSmallHandleRounds && rings <= kSmallHandleRingsMax;
           ++round) {
        const Closure l(da);
        if (!l.ok || l.genus <= bound)
          return;
        std::vector<uint32_t> t = a.tris;
        // A tunnel's wall is the labelling's own: only the vertices of its
        // triangles that the patches' closure lacks are looked at.
        std::vector<uint8_t> only;
        if (tunnels) {
          if (theirs.empty()) {
            theirs.resize(surf.tris.size() / 3);
            for (size_t k = 0; k < theirs.size(); ++k)
              theirs[k] = sorted_corners(surf.tris, k);
            std::sort(theirs.begin(), theirs.end());
          }
          only.assign(m, 0);
          for (size_t k = 0; k < t.size() / 3; ++k)
            if (!std::binary_search(theirs.begin(), theirs.end(),
                                    sorted_corners(t, k)))
              for (int c = 0; c < 3; ++c)
                only[t[3 * k + c]] = 1;
        }
        const size_t sites = cut_small_handles(
            lxyz, m, t, rings, size_t(l.genus - bound),
            tunnels ? closing_poles_ : nullptr, tunnels ? &only : nullptr,
            thread_count(), progress, &cache);
        Surface b;
        sc_diag_t db = da;
        if (sites) {
          fill_holes(lxyz, m, t, kMaxFillLoop, {}, progress, db, kMaxFillWork);
          describe_manifold(t, b, db);
          // A cut across a thin part can split a small piece off: a pocket,
          // which goes as the pockets of the closing do (below).
          if (db.components > l.components)
            drop_small_closed(lxyz, m, b, b.tris.size() / 3 / 100, false,
                              progress, db);
        }
        const Closure c(db);
        if (!sites || !c.ok || c.loops > 0 || c.components > l.components ||
            c.genus >= l.genus || c.genus < bound) {
          ++rings;
          continue;
        }
        db.small_handles_cut = da.small_handles_cut + sites;
        a = std::move(b);
        da = db;
      }
    }
  };

  // A third closure, where the patches' closure stands, in one piece, and
  // the labels' closure has more handles than the extracted surface had
  // (label() took the candidates for it then): the cocone test's surface
  // at every sample (cocone mode's), its small holes filled. Boundary
  // detection can take samples of a thin tube for boundary samples (its
  // poles are short), so that extraction opens the tube and the patches
  // cap its two ends: a true handle lost. Where the cocone test's surface
  // is one closed piece with no more samples left out than one in a
  // thousand once attached, and more handles than the extracted surface
  // had but no more than the labelling found, two tests that read the
  // cells apart support its handles beyond the patches', and it is kept.
  // (Never where the patches' closure is in pieces: joining them, it could
  // join separate parts.)
  auto take_everywhere = [&] {
    if (everywhere.empty())
      return;
    const int64_t bound = Closure(diag).genus + int64_t(diag.handles_cut);
    Surface s;
    sc_diag_t d = diag;
    d.pruned = d.holes_filled = d.hole_triangles = 0;
    surface_of(lxyz, m, everywhere, {}, progress, s, d);
    everywhere = std::vector<uint32_t>();
    if (d.components > 1)
      drop_small_closed(lxyz, m, s, s.tris.size() / 3 / 100, false, progress,
                        d);
    const Closure c(d);
    if (!c.ok || c.loops > 0 || c.components != 1 || c.genus <= bound ||
        c.genus > labels_genus)
      return;
    Surface sa = s;
    sc_diag_t dc = d;
    attach_samples(lxyz, m, sa, progress, dc);
    if (too_many_unused(dc.samples_unused, m))
      return;
    surf = std::move(s);
    diag = d;
    diag.path = SC_PATH_COCONE;
  };

  if (labelling && label()) {
    labels_genus = da.genus;
    small_handles();
    if (labels_only ||
        (!Closure(diag).better_than(Closure(da)) && !made_handles()))
      take_labels();
    else
      take_everywhere();
  } else if (labels_only) {
    patch(); // no cell came out inside
  }
  kept_.reset();
  labelling_.reset(); // not needed: the patches' closure stands
  // Pockets: closing may leave small closed components inside the main one
  // (the inside of a bubble, a cap that closed on itself). Those under a
  // hundredth of the surface go; their samples may be attached later.
  if (diag.components > 1) {
    const uint64_t comps = diag.components;
    drop_small_closed(lxyz, m, surf, surf.tris.size() / 3 / 100, false,
                      progress, diag);
    diag.bubbles_dropped += comps - std::min(comps, diag.components);
  }
  // Every loop of the extracted surface was closed if the result is.
  diag.holes_filled = diag.closed ? loops : 0;
  diag.hole_triangles = diag.triangles > before ? diag.triangles - before : 0;
}

// Auto mode (section 11.6): whether to close surf as watertight mode does.
// Where it is one closed piece, there is nothing to close (samples left
// out are attached afterwards; bubbles were dropped), unless it leaves out
// more samples than watertight mode trusts. Otherwise the sample is
// taken for one of a closed surface when every loop left open, once the small
// holes and the slits are filled, is narrow: a strip or a few triangles the
// candidate tests missed (the closed models measured: 2.1 edges wide at most),
// where a surface ends, at a scan's edge or between views, is wide (the bunny
// scans' edges and holes: 4 to 38). Pieces with no loop open (a thin part
// broken off) are closed too: the closing keeps apart what the cells keep
// apart.
bool Recon::auto_closes(const double *lxyz, size_t m, const Surface &surf,
                        const sc_diag_t &diag, Progress &progress) const {
  if (params_.mode != SC_MODE_AUTO || surf.tris.empty())
    return false;
  // One closed piece is closed again where watertight mode would doubt it
  // (close_surface()): no boundary sample was found, and it leaves out
  // more than one sample in a thousand before they are attached.
  if (diag.closed && diag.components == 1)
    return diag.boundary_samples == 0 &&
           too_many_unused(diag.samples_unused, m);
  return widest_loop(lxyz, m, surf.tris, progress) <= kClosedLoopWidth;
}

// Auto mode (section 11.6), where filling the small holes closed the
// surface in one piece of the given genus: whether watertight mode's
// closing of surf, the surface before those holes were filled, is one
// closed piece of lower genus, or the cocone test's surface at every
// sample. Then surf and diag take that closure. A thin part meeting the
// body at a sharp edge (a fin, a blade) is where the first happens: the
// candidates miss a strip along the joint, the walk closes a handle round
// its end, and filling the small hole left keeps the handle, where
// watertight mode cuts it first (or labels the cells). The second is a
// thin tube that boundary detection opened and the small holes capped,
// which the closing keeps as the cocone test does (section 11.5).
bool Recon::auto_closes_unfilled(const double *lxyz, size_t m, int64_t genus,
                                 Progress &progress, Surface &surf,
                                 sc_diag_t &diag) {
  sc_diag_t d = diag;
  Surface s = surf;
  close_surface(lxyz, m, true, progress, s, d);
  if (!d.closed || d.components != 1 ||
      (d.genus >= genus && d.path != SC_PATH_COCONE))
    return false;
  surf = std::move(s);
  diag = d;
  return true;
}

// Watertight mode's least-area patches (sections 11.2 and 11.3) over the
// open components of surf, after cutting the handles that closed round a
// hole (with cut); the closed components stay as they are.
void Recon::patch_surface(const double *lxyz, size_t m, bool cut,
                          Progress &progress, Surface &surf, sc_diag_t &diag) {
  std::vector<uint32_t> open, closed_part;
  for (size_t t = 0; t < surf.tris.size() / 3; ++t)
    (surf.in_closed(t) ? closed_part : open)
        .insert((surf.in_closed(t) ? closed_part : open).end(),
                &surf.tris[3 * t], &surf.tris[3 * t] + 3);
  // Handles that closed round a hole, where the scan has no samples, would
  // stay in any closure: cut them first (see cut_handles()).
  // A handle is genus: where every open component is a disc with holes
  // (genus 0, every edge and vertex manifold), the region grown over it
  // takes every triangle, and there is nothing to cut.
  bool any_genus = surf.pinched != 0;
  for (const Surface::Part &p : surf.parts)
    if (p.boundary_edges > 0 &&
        (p.nonmanifold_edges > 0 ||
         2 - (p.vertices - p.edges + p.faces) != int64_t(p.loops)))
      any_genus = true;
  // The cut leaves the edge table of the open components, which the
  // closed ones join: the table that the patches below would build.
  // Where nothing is cut the table stays empty and the patches build it.
  EdgeTablePtr table = new_edge_table();
  const bool cutting = cut && any_genus;
  const uint64_t handles =
      cutting ? cut_handles(lxyz, m, open, progress, *table) : 0;
  if (handles) {
    surf.tris = open;
    surf.tris.insert(surf.tris.end(), closed_part.begin(), closed_part.end());
    append_edges_of(*table, m, surf.tris, open.size() / 3, progress);
  } else if (cutting && !closed_part.empty()) {
    table = new_edge_table(); // the open part's alone: not surf.tris's
  } // (with no closed part, open is surf.tris, and its table stays)
  // The surface was described after extraction, and cutting handles only
  // takes triangles out of open components: no component to flip, and
  // describe() runs once the holes are filled.
  std::vector<uint32_t> tris;
  tris.swap(surf.tris);
  fill_holes(lxyz, m, tris, kMaxFillLoop, {}, progress, diag, kMaxFillWork,
             table.get());
  describe(lxyz, m, tris, progress, surf, diag, table.get());
  diag.path = SC_PATH_WATERTIGHT_FILL;
  diag.handles_cut = handles;
}

// With --denoise the triangulation is built on the smoothed copy, which
// needs every point. (Auto mode's choice needs them too: points that come
// in chunks are inserted as they come, and inserted again, smoothed, only
// if the estimate finds noise.)
bool Recon::defer_insertion() const {
  return params_.denoise != 0 || params_.memory_limit > 0 || apart() ||
         tile_count() != 0;
}

// Within a memory limit the number of points decides (memory_tiles()), at
// least as many as asked for.
size_t Recon::tile_count() const {
  // A tile job is one tile already.
  if (apart() || !can_tile(params_))
    return 0;
  // Tiles one per thread, as long as they pay: not in watertight mode on
  // more threads, whose labelling then runs beside the extraction on the
  // single triangulation (tiles would have it built again: the merged
  // scans 7.6 to 8.1 s on 2 tiles and 2 threads, against 5.5 to 6.5 s).
  size_t k = params_.tiles == 1  ? 0
             : params_.tiles > 0 ? size_t(params_.tiles)
             : labels_beside()   ? 0
                                 : thread_count();
  if (params_.memory_limit > 0) {
    const size_t need = memory_tiles(n_, thread_count(), params_.memory_limit);
    if (need >= 2)
      k = std::max(k, need);
  }
  return k >= 2 ? k : 0;
}

bool Recon::labels_beside() const {
  return params_.mode == SC_MODE_WATERTIGHT && !params_.watertight_patches &&
         thread_count() > 1;
}

unsigned Recon::thread_count() const {
  return params_.threads > 0
             ? unsigned(params_.threads)
             : std::max(1u, std::thread::hardware_concurrency());
}

// The points in the frame of their box's lower corner where that is exact
// (section 3.4): the same points moved anywhere give the same numbers, far
// from the origin too.
const double *Recon::recentred() {
  if (!recentre(xyz_, n_, shift_))
    return xyz_;
  shifted_.resize(3 * n_);
  for (size_t i = 0; i < 3 * n_; ++i)
    shifted_[i] = xyz_[i] - shift_[i % 3];
  return shifted_.data();
}

// --denoise smooths at or above the floor (see SC_NOISE_FLOOR) where the
// sample resolves its surface, or at any noise when given a scale; auto
// mode likewise without the scale.
bool Recon::smooths(const NoiseEstimate &e) const {
  return (params_.denoise && (e.noisy() || params_.denoise_scale > 0)) ||
         (params_.mode == SC_MODE_AUTO && e.noisy());
}

// The cocone test's angle for the labelling (Triangulator::close()): 0,
// for none, where the points are noisy.
double Recon::label_theta() const {
  return noise_.noisy() ? 0 : params_.cocone_theta;
}

// Smooths a copy of base when the estimate asks for it; work_ is then the
// points to triangulate (sections 16.2 and 16.3).
void Recon::smooth_if_noisy(const double *base, Progress &progress) {
  work_ = base;
  if (!smooths(noise_))
    return;
  const double scale =
      params_.denoise_scale > 0 ? params_.denoise_scale : default_scale(noise_);
  smoothing_ =
      smooth(base, n_, scale, noise_, thread_count(), progress, smoothed_);
  work_ = smoothed_.data();
  dt_.reset(); // the raw points inserted so far
  dt_raw_ = false;
  shifted_ = {};
}

// Estimates the noise (section 16.1) and, when denoising, smooths a copy of
// the points.
void Recon::prepare(Progress &progress) {
  Stopwatch sw;
  prepared_ = true;
  const double *base = recentred();
  noise_ = estimate_noise(base, n_, progress);
  smooth_if_noisy(base, progress);
  seconds_denoise_ = sw.lap();
  seconds_[SC_STAGE_INPUT] += seconds_denoise_;
}

// As prepare(), then the triangulation of all the points, with the
// estimate on a thread of its own beside the triangulation: the estimate
// reads the points only, and unless it finds noise to smooth, the points
// triangulated are the same. Where it does (auto mode, --denoise), the
// triangulation stops at its next batch and starts again on the smoothed
// points. On the closed models the estimate took as long as a fifth of
// the whole reconstruction.
void Recon::prepare_and_insert(Progress &progress) {
  if (thread_count() < 2 || n_ < kEstimateBeside) {
    prepare(progress);
    insert_range(work_, 0, n_, progress);
    return;
  }
  Stopwatch sw;
  prepared_ = true;
  const double *base = recentred();
  seconds_[SC_STAGE_INPUT] += sw.lap();
  // The estimate stops the triangulation where it is to smooth, or where
  // it failed; the thread takes no cancel (it is short), the
  // triangulation does.
  struct Beside {
    std::atomic<int> stop{0};
    sc_progress_fn fn;
    void *user;
    static int report(void *u, sc_stage_t s, double f) {
      const Beside *b = static_cast<const Beside *>(u);
      return b->stop.load() || (b->fn && b->fn(b->user, s, f));
    }
  } beside;
  beside.fn = params_.progress;
  beside.user = params_.progress_user;
  std::exception_ptr error;
  double estimate_seconds = 0;
  std::thread estimate([&] {
    try {
      Stopwatch own;
      Progress quiet(nullptr, nullptr);
      noise_ = estimate_noise(base, n_, quiet);
      estimate_seconds = own.lap();
      if (smooths(noise_))
        beside.stop = 1;
    } catch (...) {
      error = std::current_exception();
      beside.stop = 1;
    }
  });
  struct Join {
    std::thread &t;
    ~Join() {
      if (t.joinable())
        t.join();
    }
  } join{estimate};
  std::exception_ptr cancelled;
  try {
    Progress mine(&Beside::report, &beside);
    insert_range(base, 0, n_, mine);
  } catch (...) {
    cancelled = std::current_exception();
  }
  sw.lap();
  estimate.join();
  if (error)
    std::rethrow_exception(error);
  // A cancel of the caller's, unless the estimate stopped the insertion.
  if (cancelled && !beside.stop.load())
    std::rethrow_exception(cancelled);
  // Back to the input stage only to smooth: otherwise the triangulation
  // stage goes on, where the insertion left it.
  if (smooths(noise_)) {
    progress.stage(SC_STAGE_INPUT);
  } else {
    progress.stage(SC_STAGE_DELAUNAY);
    progress.report(1.0);
  }
  smooth_if_noisy(base, progress);
  const double waited = sw.lap();
  seconds_denoise_ = estimate_seconds + waited;
  seconds_[SC_STAGE_INPUT] += waited;
  if (!dt_)
    insert_range(work_, 0, n_, progress);
}

void Recon::insert_range(const double *xyz, size_t first, size_t n,
                         Progress &progress) {
  if (n == 0)
    return;
  if (!dt_)
    dt_ = make_triangulator();
  Stopwatch sw;
  progress.stage(SC_STAGE_DELAUNAY);
  dt_->insert(xyz, first, n, progress);
  seconds_[SC_STAGE_DELAUNAY] += sw.lap();
}

void Recon::add(const double *xyz, size_t n) {
  Stopwatch sw;
  if (n > kMaxPoints - n_)
    throw Error(SC_ETOO_MANY_POINTS, sc_strerror(SC_ETOO_MANY_POINTS));
  check_finite(xyz, n, n_);
  own_.insert(own_.end(), xyz, xyz + 3 * n);
  xyz_ = own_.data();
  size_t first = n_;
  n_ += n;
  seconds_[SC_STAGE_INPUT] += sw.lap();
  if (!defer_insertion()) {
    // Each chunk counts its insertion from 0: how many will come is not
    // known. The stage then goes on from the last one's.
    progress_ = Progress(params_.progress, params_.progress_user);
    insert_range(xyz_, first, n, progress_);
    dt_raw_ = true;
  }
}

void Recon::borrow(const double *xyz, size_t n) {
  Stopwatch sw;
  if (n > kMaxPoints)
    throw Error(SC_ETOO_MANY_POINTS, sc_strerror(SC_ETOO_MANY_POINTS));
  Progress &progress = progress_;
  progress.stage(SC_STAGE_INPUT);
  check_finite(xyz, n, 0);
  xyz_ = xyz;
  n_ = n;
  // A job that cannot fit its memory limit fails before it allocates.
  (void)tile_count();
  seconds_[SC_STAGE_INPUT] += sw.lap();
  if (!tile_count() && !apart())
    prepare_and_insert(progress);
  else
    prepare(progress);
}

namespace {

// Throws unless the points span space: fewer than 4, or all on a plane,
// have no Delaunay cells to reconstruct from.
void check_spread(size_t n, const Triangulator *dt) {
  if (n < 4 || !dt || dt->dimension() < 3) {
    char buf[160];
    int dim = dt ? dt->dimension() : -1;
    if (n < 4)
      std::snprintf(buf, sizeof buf,
                    "need at least 4 points not all coplanar, got %zu", n);
    else
      std::snprintf(buf, sizeof buf, "all %zu points are %s", n,
                    dim <= 0   ? "the same point"
                    : dim == 1 ? "collinear"
                               : "coplanar");
    throw Error(SC_EDEGENERATE_INPUT, buf);
  }
}

// Per-vertex normals (docs/algorithm.md section 13), by vertex number: the
// pole direction, signed to agree with the area-weighted normal of the
// output triangles around the vertex (zero for a vertex of no triangle).
std::vector<double> vertex_normals(const std::vector<double> &lxyz, size_t m,
                                   const std::vector<uint32_t> &tris,
                                   const std::vector<double> &poles) {
  std::vector<double> acc(3 * m, 0.0);
  const size_t nt = tris.size() / 3;
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t *v = &tris[3 * t];
    const double *a = &lxyz[3 * size_t(v[0])], *b = &lxyz[3 * size_t(v[1])],
                 *c = &lxyz[3 * size_t(v[2])];
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double nrm[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2],
                     u[0] * w[1] - u[1] * w[0]};
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j)
        acc[3 * size_t(v[k]) + j] += nrm[j];
  }
  for (size_t i = 0; i < m; ++i) {
    double *a = &acc[3 * i];
    const double *p = &poles[3 * i];
    double la = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    if (!(la > 0))
      continue; // not a vertex of the output: the normal stays zero
    double d = a[0] * p[0] + a[1] * p[1] + a[2] * p[2];
    if (std::fabs(d) > 1e-3 * la) {
      double s = d > 0 ? 1.0 : -1.0;
      a[0] = s * p[0], a[1] = s * p[1], a[2] = s * p[2];
    } else {
      a[0] /= la, a[1] /= la, a[2] /= la;
    }
  }
  return acc;
}

// The normals by vertex number, acc, by input index, duplicates given the
// normal of the point they repeat.
std::vector<double> normals_by_input(const std::vector<double> &acc,
                                     const Filtered &f, size_t n) {
  std::vector<double> normals(3 * n, 0.0);
  for (size_t k = 0; k < f.to_input.size(); ++k)
    std::memcpy(&normals[3 * size_t(f.to_input[k])], &acc[3 * k],
                3 * sizeof(double));
  for (auto &d : f.dups)
    for (int j = 0; j < 3; ++j)
      normals[3 * size_t(d.first) + j] = normals[3 * size_t(d.second) + j];
  return normals;
}

// Four points in general position make a single Delaunay cell, and the
// only surface they support is its boundary, the four facets of the hull.
// The candidate tests may pass them, but pruning cannot keep them: the
// facets meet at edges sharper than a right angle, which is what pruning
// removes (section 7), and a job of four points would come back empty. So
// a single cell is its own surface, in every mode; describe() orients it
// outward.
void single_cell_surface(const double *lxyz, Progress &progress, Surface &surf,
                         sc_diag_t &diag) {
  std::vector<uint32_t> tris = {0, 1, 2, 0, 3, 1, 0, 2, 3, 1, 3, 2};
  describe(lxyz, 4, tris, progress, surf, diag);
}

// The mesh handed back to C, in malloc'ed arrays.
sc_mesh_t *mesh_out(const Surface &surf, const std::vector<double> &normals,
                    size_t n, const sc_diag_t &diag) {
  sc_mesh_t *out = static_cast<sc_mesh_t *>(std::calloc(1, sizeof *out));
  if (!out)
    throw std::bad_alloc();
  try {
    out->triangles = copy_out(surf.tris.data(), surf.tris.size());
    out->triangle_count = surf.tris.size() / 3;
    out->normals = copy_out(normals.data(), normals.size());
    out->point_count = n;
    out->component_genus =
        copy_out(surf.component_genus.data(), surf.component_genus.size());
    out->component_count = surf.component_genus.size();
    out->diag = diag;
  } catch (...) {
    sc_mesh_free(out);
    throw;
  }
  return out;
}

// The exponent of the lowest set bit of x (x finite and not zero): x is a
// multiple of 2 to that power.
int lowest_bit(double x) {
  int e;
  const double m = std::frexp(std::fabs(x), &e); // in [0.5, 1)
  const uint64_t bits = uint64_t(std::ldexp(m, 53));
  return e - 53 + __builtin_ctzll(bits);
}

} // namespace

bool recentre(const double *xyz, size_t n, double shift[3]) {
  bool any = false;
  for (int a = 0; a < 3; ++a) {
    shift[a] = 0;
    if (n == 0)
      continue;
    double lo = xyz[a], hi = xyz[a];
    int low = INT_MAX;
    for (size_t i = 0; i < n; ++i) {
      const double c = xyz[3 * i + a];
      lo = std::min(lo, c);
      hi = std::max(hi, c);
      if (c != 0)
        low = std::min(low, lowest_bit(c));
    }
    // Every coordinate and lo are multiples of 2^low, so each difference
    // is one too; below 2^(low + 53) it is exact. (hi - lo is rounded: one
    // bit of margin.)
    if (lo == 0 || low == INT_MAX || !(hi - lo < std::ldexp(1.0, low + 52)))
      continue;
    shift[a] = lo;
    any = true;
  }
  return any;
}

// The stages after insertion, in order: the triangulation's (duplicates,
// poles, boundary detection, candidates: Triangulator::filter()), pruning,
// extraction (the walk, small holes, description), then for scans dropping
// bubbles, closing (watertight mode) and attaching samples; last the
// normals and the mesh in input indices.
sc_mesh_t *Recon::finish() {
  // However the reconstruction ends, the scratch it kept goes.
  struct ScratchRelease {
    ~ScratchRelease() { release_scratch(); }
  } scratch_release;
  Progress &progress = progress_;
  sc_diag_t diag;
  std::memset(&diag, 0, sizeof diag);
  diag.points_in = n_;

  // The noise estimate, in every job, and the smoothing (section 16), if
  // borrow() did not make them; as part of the insertion when points
  // were inserted as they came.
  if (!prepared_) {
    (void)tile_count(); // a job that cannot fit fails before it allocates
    if (!dt_)
      progress.stage(SC_STAGE_INPUT);
    prepare(progress);
  }
  const double *work = work_;
  diag.spacing = noise_.spacing;
  diag.noise = noise_.noise;
  diag.curvature = noise_.curvature;
  diag.denoised = !smoothed_.empty();
  diag.denoise_scale = smoothing_.scale;
  diag.denoise_shift = smoothing_.shift;
  diag.seconds_denoise = seconds_denoise_;
  Filtered f;
  if (params_.tile_count > 0)
    return finish_tile(work, progress, diag);
  // The tiles of a job that ran apart, unless one of them found that the
  // job cannot be tiled: then it runs here on one triangulation.
  bool merged = merge_ != nullptr;
  for (size_t i = 0; i < merge_count_; ++i)
    merged = merged && merge_[i]->diag.tiles >= 2;
  if (merged)
    dt::merge_tiles(work, n_, merge_, merge_count_, checks(params_), f, diag);
  // Tiles that gave up hand over the triangulation they had begun.
  std::unique_ptr<Triangulator> begun;
  const bool tiled =
      merged ||
      (!dt_ && tile_count() &&
       dt::tiled_filter(work, n_, tile_count(), thread_count(),
                        params_.memory_limit > 0, tile_margin(), params_,
                        progress, f, diag, seconds_, &begun));
  if (!tiled) {
    f = Filtered();
    if (!dt_)
      dt_ = std::move(begun);
    if (!dt_)
      insert_range(work, 0, n_, progress);
    check_spread(n_, dt_.get());
    // Points inserted as they came are in the caller's frame: moved with
    // the rest, exactly.
    if (dt_raw_ && !shifted_.empty())
      dt_->translate(shift_);
    // Watertight mode's labelling (section 11.4) labels the cells of this
    // triangulation with --labels. By default the labelling runs only
    // where the patches leave doubt (close_surface()), and the
    // triangulation goes, so that the peak memory stays that of the
    // patches where they suffice, and so that the stages after it reuse
    // its pages; it is built again when the labelling runs. But where it is
    // small (kKeepForLabels) and boundary samples were found, it is kept:
    // building it again cost as much as the first time (the knot's vertex
    // set, 6% of them boundary samples: 3.9 times CGAL's construction
    // instead of 3.0), where keeping it for nothing costs the stages after
    // it fresh pages (the bear: 1.77 instead of 1.69). A larger one is kept
    // where the boundary samples are many (kKeepBoundaryShare), unless the
    // patches come first (--patches). Auto mode closes as watertight mode
    // does where the sample looks closed (section 11.6), and keeps it where
    // it is small, by the same rule (its samples with many boundary samples
    // are mostly open scans, which it leaves open); it goes once the
    // surface is extracted, closed or not.
    const bool closing = params_.mode == SC_MODE_WATERTIGHT;
    const bool small = n_ <= kKeepForLabels;
    dt_->keep = closing && params_.watertight_labels;
    dt_->keep_from_boundary =
        (closing || params_.mode == SC_MODE_AUTO) && small ? 1
        : closing && !params_.watertight_patches
            ? (n_ + kKeepBoundaryShare - 1) / kKeepBoundaryShare
            : SIZE_MAX;
    // On more threads, wherever a boundary sample is found, and always
    // where it is small: the labelling then runs beside the extraction
    // (LabelTask), on it, and stops where the patches settle the closure.
    // (The small ones without a boundary sample that the patches leave in
    // doubt, such as the cheese, no longer wait for it to be built again:
    // 4.36 to 2.96-3.40 times CGAL's construction on two threads.)
    if (labels_beside() && !params_.watertight_labels)
      dt_->keep_from_boundary = 1;
    if (labels_beside() && small)
      dt_->keep = true;
    dt_->filter(work, n_, params_, progress, f, diag, seconds_);
    if (dt_->keep)
      kept_ = std::move(dt_);
    dt_.reset();
  }
  const bool watertight = params_.mode == SC_MODE_WATERTIGHT;
  diag.path = params_.mode == SC_MODE_SHORTCRUST ? SC_PATH_SHORTCRUST
              : params_.mode == SC_MODE_COCONE   ? SC_PATH_COCONE
                                                 : SC_PATH_BOUNDARY;
  // Auto mode is boundary mode, which is the cocone test exactly where no
  // boundary sample is found. (Measured alternatives: treating samples
  // whose poles merely disagree as interior, so that only cells that open
  // sideways count as boundary, broke the raw bunny scans into 6 and 63
  // components instead of 1 and 4.)
  if (params_.mode == SC_MODE_AUTO && diag.boundary_samples == 0)
    diag.path = SC_PATH_COCONE;

  Stopwatch sw;
  progress.stage(SC_STAGE_PRUNE);
  // The points in vertex order, for locality (see Filtered).
  const size_t m = f.to_input.size();
  std::vector<double> lxyz(3 * m);
  for (size_t k = 0; k < m; ++k)
    std::memcpy(&lxyz[3 * k], work + 3 * size_t(f.to_input[k]),
                3 * sizeof(double));
  // The labelling, where it is likely to be needed (boundary samples were
  // found, or --labels), starts now on a thread of its own; it reads lxyz,
  // and stops before lxyz goes, whatever happens.
  struct StopLabelling {
    std::unique_ptr<LabelTask> &task;
    ~StopLabelling() { task.reset(); }
  } stop_labelling{labelling_};
  // Auto mode, on more threads, labels beside the extraction too where it
  // kept the triangulation for a closing (small, a tenth of the samples
  // or more boundary samples): it stops once no closing is needed.
  if ((labels_beside() &&
       (params_.watertight_labels || !f.boundary.empty() || kept_)) ||
      (params_.mode == SC_MODE_AUTO && thread_count() > 1 && kept_))
    labelling_.reset(
        new LabelTask(std::move(kept_), lxyz.data(), m, label_theta()));
  const sc_diag_t before_prune = diag;
  std::vector<uint8_t> alive;
  EdgeTablePtr table;
  prune(lxyz.data(), m, f.tris, params_.paper_pruning != 0, f.boundary, alive,
        table, progress, diag, thread_count());
  seconds_[SC_STAGE_PRUNE] += sw.lap();

  progress.stage(SC_STAGE_EXTRACT);
  // (Forgotten once the surface is closed, whatever happens.)
  struct ForgetPoles {
    const double *&poles;
    ~ForgetPoles() { poles = nullptr; }
  } forget_poles{closing_poles_};
  closing_poles_ = f.poles.data();
  closing_everywhere_ = !f.boundary.empty();
  Surface surf;
  // Watertight mode cuts the handles that closed round holes of the scan
  // and then closes every hole, so nothing is filled before that. Where
  // the sample was found to look closed (no boundary detection: see
  // classify()), a hole is a few missing triangles, not a part of the
  // surface the scan missed: the small ones are filled as in the other
  // modes, and no handle is cut.
  const bool scan_holes = watertight && !f.boundary.empty();
  // Auto mode, where it found boundary samples, keeps the surface as
  // extracted too, before its small holes were filled: for
  // auto_closes_unfilled().
  std::vector<uint32_t> unfilled;
  const bool auto_unfilled =
      params_.mode == SC_MODE_AUTO && !f.boundary.empty();
  const sc_diag_t extracting = diag;
  // Watertight mode describes an open surface again once it is closed,
  // and checks its vertices then (fix_fans_in() leaves one fan at each).
  {
    // (Watertight mode's closing may take as long as the extraction.)
    Progress::Span span(progress, 0, watertight ? 0.5 : 0.9);
    extract(lxyz.data(), m, f.tris, alive, std::move(table),
            scan_holes ? 0 : size_t(params_.max_hole_edges), f.boundary,
            progress, surf, diag, !watertight,
            auto_unfilled ? &unfilled : nullptr);
  }
  Progress::Span closing(progress, watertight ? 0.5 : 0.9, 1);
  if (detects_boundary(params_.mode)) {
    // Real scans: overlapping layers leave bubbles, small closed components
    // between them, and samples the walk passed by. Drop the bubbles;
    // watertight mode closes the surface while every triangle is still a
    // Delaunay facet (the labelling needs that); then every sample near the
    // surface is inserted into it.
    auto drop_bubbles = [&](Surface &s, sc_diag_t &d) {
      const uint64_t closed_before = d.closed_components;
      drop_small_closed(lxyz.data(), m, s,
                        std::max<size_t>(kMinBubble, s.tris.size() / 3 / 1000),
                        false, progress, d);
      d.bubbles_dropped =
          closed_before - std::min(closed_before, d.closed_components);
    };
    drop_bubbles(surf, diag);
    // Auto mode: the surface as extracted, before its small holes were
    // filled, its bubbles dropped.
    auto as_extracted = [&](Surface &open, sc_diag_t &open_diag) {
      open_diag = extracting;
      open_diag.walk_rejected = diag.walk_rejected;
      describe(lxyz.data(), m, unfilled, progress, open, open_diag);
      drop_bubbles(open, open_diag);
    };
    if (watertight) {
      close_surface(lxyz.data(), m, scan_holes, progress, surf, diag);
    } else if (auto_closes(lxyz.data(), m, surf, diag, progress)) {
      // As watertight mode closes it: where boundary samples were found,
      // from the surface before its small holes were filled, cutting the
      // handles that closed round a hole first (section 11.6).
      if (auto_unfilled) {
        Surface open;
        sc_diag_t open_diag;
        as_extracted(open, open_diag);
        close_surface(lxyz.data(), m, true, progress, open, open_diag);
        surf = std::move(open);
        diag = open_diag;
      } else {
        // The holes that extraction filled count too.
        const uint64_t holes = diag.holes_filled, added = diag.hole_triangles;
        close_surface(lxyz.data(), m, false, progress, surf, diag);
        diag.holes_filled += holes;
        diag.hole_triangles += added;
      }
    } else if (auto_unfilled && diag.closed && diag.components == 1 &&
               diag.holes_filled > 0) {
      Surface open;
      sc_diag_t open_diag;
      as_extracted(open, open_diag);
      if (auto_closes_unfilled(lxyz.data(), m, diag.genus, progress, open,
                               open_diag)) {
        surf = std::move(open);
        diag = open_diag;
      }
    }
    unfilled = std::vector<uint32_t>();
    kept_.reset();
    labelling_.reset();
    diag.samples_attached =
        attach_samples(lxyz.data(), m, surf, progress, diag);
  }

  if (diag.delaunay_cells == 1 && m == 4)
    single_cell_surface(lxyz.data(), progress, surf, diag);
  else if (params_.mode == SC_MODE_SHORTCRUST && !f.check.cocone.empty())
    check_topology(lxyz.data(), m, f, before_prune, progress, surf, diag);

  std::vector<double> acc = vertex_normals(lxyz, m, surf.tris, f.poles);
  // Back to input indices.
  lxyz = std::vector<double>();
  const std::vector<double> normals = normals_by_input(acc, f, n_);
  for (uint32_t &v : surf.tris)
    v = f.to_input[v];
  canonical_order(surf.tris, true);
  seconds_[SC_STAGE_EXTRACT] += sw.lap();

  // An empty mesh, or one that leaves most samples out, is a result the
  // caller must not take for an ordinary success: the points do not look
  // like a surface this mode can reconstruct (PROTOCOL.md 6.9).
  diag.mostly_unused = 2 * diag.samples_unused > diag.delaunay_vertices;
  return result(surf, normals, diag, progress);
}

std::vector<uint32_t> Checks::at(int k) const {
  std::vector<uint32_t> tris;
  for (int j = 0; j <= k; ++j)
    tris.insert(tris.end(), near[j].begin(), near[j].end());
  canonical_order(tris, false);
  return tris;
}

void Checks::append(Checks &&other) {
  cocone.insert(cocone.end(), other.cocone.begin(), other.cocone.end());
  other.cocone = {};
  for (int k = 0; k < kNearR; ++k) {
    near[k].insert(near[k].end(), other.near[k].begin(), other.near[k].end());
    other.near[k] = {};
  }
}

void Checks::canonical() {
  canonical_order(cocone, false);
  for (int k = 0; k < kNearR; ++k)
    canonical_order(near[k], false);
}

void Recon::surface_of(const double *lxyz, size_t m,
                       const std::vector<uint32_t> &cand,
                       const std::vector<uint8_t> &boundary, Progress &progress,
                       Surface &s, sc_diag_t &d) const {
  std::vector<uint8_t> alive;
  EdgeTablePtr table;
  d.candidates = cand.size() / 3;
  prune(lxyz, m, cand, params_.paper_pruning != 0, boundary, alive, table,
        progress, d, thread_count());
  extract(lxyz, m, cand, alive, std::move(table),
          size_t(params_.max_hole_edges), boundary, progress, s, d);
}

// Shortcrust mode's check (section 6.5): the surface that the cocone test
// gives on the same triangulation, through the same pruning and walk, and
// whether its topology is the same; where it is not, the surfaces of the
// nearest values of r, nearest first and the larger first, until one is
// the cocone test's closed surface.
void Recon::check_topology(const double *lxyz, size_t m, Filtered &f,
                           const sc_diag_t &before, Progress &progress,
                           Surface &surf, sc_diag_t &diag) const {
  sc_diag_t cd = before;
  Surface cs;
  surface_of(lxyz, m, f.check.cocone, f.boundary, progress, cs, cd);
  f.check.cocone = {};
  auto same = [&](const sc_diag_t &d) {
    return d.components == cd.components &&
           d.closed_components == cd.closed_components && d.genus == cd.genus;
  };
  // What the check says of a surface d given by the criteria at r.
  auto report = [&](sc_diag_t &d, double r) {
    d.checked = 1;
    d.r_used = r;
    d.check_components = cd.components;
    d.check_closed_components = cd.closed_components;
    d.check_genus = cd.genus;
    d.topology_doubt = !same(d);
  };
  report(diag, params_.r);
  // Only a closed surface of the cocone test is worth looking for: where
  // it is open, it is in doubt itself.
  if (diag.topology_doubt && cd.closed) {
    const int mid = kNearR / 2;
    for (int step = 1; step <= mid; ++step)
      for (int k : {mid + step, mid - step}) {
        const double r = Checks::r_at(params_.r, k);
        if (!(r > 0))
          continue;
        sc_diag_t d = before;
        Surface s;
        surface_of(lxyz, m, f.check.at(k), f.boundary, progress, s, d);
        if (!same(d) || !d.closed)
          continue;
        report(d, r);
        diag = d;
        surf = std::move(s);
        f.check = Checks();
        return;
      }
  }
  f.check = Checks();
}

// With smoothed_vertices, every point's smoothed position goes with the
// mesh; a duplicate was smoothed as its first occurrence was (the same
// neighbours).
sc_mesh_t *Recon::result(const Surface &surf,
                         const std::vector<double> &normals, sc_diag_t &diag,
                         Progress &progress) const {
  for (int s = 0; s < SC_STAGE_COUNT; ++s) {
    diag.seconds[s] = seconds_[s];
    diag.seconds_total += seconds_[s];
  }
  progress.report(1.0);
  sc_mesh_t *out = mesh_out(surf, normals, n_, diag);
  if (!params_.smoothed_vertices || !diag.denoised)
    return out;
  out->smoothed = static_cast<double *>(
      std::malloc(std::max<size_t>(1, smoothed_.size()) * sizeof(double)));
  if (!out->smoothed) {
    sc_mesh_free(out);
    throw std::bad_alloc();
  }
  for (size_t i = 0; i < smoothed_.size(); ++i)
    out->smoothed[i] = smoothed_[i] + shift_[i % 3];
  return out;
}

sc_mesh_t *Recon::finish_tile(const double *work, Progress &progress,
                              sc_diag_t &diag) {
  Filtered f;
  Surface surf;
  std::vector<double> normals(3 * n_, 0.0);
  if (dt::tile_job(work, n_, size_t(params_.tile_count),
                   size_t(params_.tile_index), tile_margin(), params_, progress,
                   f, diag, seconds_)) {
    // Triangles by input index, each run in canonical order (PROTOCOL.md
    // section 6.3, tile jobs).
    auto add = [&](const std::vector<uint32_t> &tris) {
      std::vector<uint32_t> in(tris.size());
      for (size_t k = 0; k < tris.size(); ++k)
        in[k] = f.to_input[tris[k]];
      canonical_order(in, false);
      surf.tris.insert(surf.tris.end(), in.begin(), in.end());
    };
    if (checks(params_)) {
      // The candidates, by their least passing r, then the cocone test's.
      uint64_t *runs[kNearR] = {&diag.tile_near_0, &diag.tile_near_1,
                                &diag.tile_near_2, &diag.tile_near_3,
                                &diag.tile_near_4};
      for (int k = 0; k < kNearR; ++k) {
        add(f.check.near[k]);
        *runs[k] = f.check.near[k].size() / 3;
      }
      add(f.check.cocone);
      diag.checked = 1;
    } else {
      add(f.tris);
    }
    normals = normals_by_input(f.poles, f, n_);
  } else {
    diag.tiles = 0; // the merge runs the job on one triangulation
  }
  diag.triangles = surf.tris.size() / 3;
  return result(surf, normals, diag, progress);
}

} // namespace sc
