// Internals of the core, shared by its translation units. Nothing here is
// visible outside core/. Sections cited are those of docs/algorithm.md.
//
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef SC_CORE_INTERNAL_HPP
#define SC_CORE_INTERNAL_HPP

#include "shortcrust.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace sc {

// Measured peak bytes per input point of a whole reconstruction (the
// triangulation dominates); used for admission control by the daemon.
constexpr uint64_t kBytesPerPoint = 1100;

// The defaults of the parameter table in shortcrust.h, in its order.
constexpr sc_params_t kDefaultParams = {
#define SC_PARAM_DEFAULT_(field, type, kind, dflt, ...) type(dflt),
    SC_PARAM_MAP(SC_PARAM_DEFAULT_)
#undef SC_PARAM_DEFAULT_
        nullptr,
    nullptr};

// Defaults of the boundary detection (see the README for the measurements
// behind them); a parameter of 0 stands for these.
constexpr double kDefaultRho = kDefaultParams.boundary_rho;
constexpr double kDefaultAlpha = kDefaultParams.boundary_alpha;

// An error with a code from the public table, thrown inside the core and
// turned into a return value at the C boundary.
struct Error : std::runtime_error {
  int code;
  Error(int c, const std::string &what) : std::runtime_error(what), code(c) {}
};

void set_msg(char *msg, size_t len, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
int check_params(const sc_params_t *p, char *msg, size_t len);

// Reports progress of one stage and turns a cancel request into an Error.
// Within a stage the fraction never goes back: the steps of a stage each
// report their own share through a Span, and a step that counts again
// from 0 (a table built a second time) holds the bar where it is.
class Progress {
public:
  Progress(sc_progress_fn fn, void *user) : fn_(fn), user_(user) {}
  // Enters stage s at 0; the stage it is in already goes on where it was.
  void stage(sc_stage_t s) {
    if (s != stage_) {
      stage_ = s;
      last_ = 0;
    }
    ++entries_;
    lo_ = 0;
    hi_ = 1;
    send(last_);
  }
  void report(double fraction) {
    send(std::max(last_, lo_ + (hi_ - lo_) * fraction));
  }
  // While waiting for other threads: reports the last fraction again, so
  // that a cancel is taken.
  void poll() { send(last_); }
  // For loops: report every `every` iterations (a power of two); i of
  // about n, never more than the whole.
  void tick(size_t i, size_t n, size_t every = 1u << 15) {
    if (fn_ && (i & (every - 1)) == 0)
      report(n && i < n ? double(i) / double(n) : 1.0);
  }

  // While it lives, the fractions reported go to [from, to] of the part of
  // the stage reported to before. (A stage entered meanwhile has its own
  // parts: the span then ends with nothing to do.)
  class Span {
  public:
    Span(Progress &p, double from, double to)
        : p_(p), lo_(p.lo_), hi_(p.hi_), entries_(p.entries_) {
      p.lo_ = lo_ + (hi_ - lo_) * from;
      p.hi_ = lo_ + (hi_ - lo_) * to;
    }
    ~Span() {
      if (p_.entries_ != entries_)
        return;
      p_.lo_ = lo_;
      p_.hi_ = hi_;
    }
    Span(const Span &) = delete;
    Span &operator=(const Span &) = delete;

  private:
    Progress &p_;
    double lo_, hi_;
    unsigned entries_;
  };

private:
  void send(double f) {
    last_ = f;
    if (fn_ && fn_(user_, stage_, f))
      throw Error(SC_ECANCELLED, "cancelled during stage " +
                                     std::string(sc_stage_name(stage_)));
  }
  sc_progress_fn fn_;
  void *user_;
  sc_stage_t stage_ = SC_STAGE_INPUT;
  unsigned entries_ = 0; // stage() calls
  double last_ = 0;
  double lo_ = 0, hi_ = 1; // the part of the stage reported to
};

// Shortcrust mode's check (docs/algorithm.md section 6.5), from the same
// pass over the facets as the candidates: those that pass the cocone test,
// and those that pass the paper's criteria at the values of r next to the
// one asked for, r + (k - 2) kNearStep for k = 0 .. kNearR - 1: near[k]
// holds the facets whose least passing one is the k-th. Vertex numbers,
// each list in canonical order.
constexpr int kNearR = 5;
constexpr double kNearStep = 0.01;
struct Checks {
  std::vector<uint32_t> cocone;
  std::vector<uint32_t> near[kNearR];
  // The facets that pass the criteria at the k-th value, in canonical
  // order.
  std::vector<uint32_t> at(int k) const;
  void append(Checks &&other);
  void canonical();
  // The k-th value, r + (k - 2) kNearStep; 0 where that is outside
  // (0, 0.5), where the criteria pass nothing.
  static double r_at(double r, int k) {
    const double v = r + (k - kNearR / 2) * kNearStep;
    return v > 1e-9 && v < 0.5 ? v : 0;
  }
};
// Whether a job runs shortcrust mode's check, and so its candidates stage
// collects the lists above.
inline bool checks(const sc_params_t &p) {
  return p.mode == SC_MODE_SHORTCRUST && !p.unchecked;
}

// What the triangulation stages hand to the rest of the pipeline; the
// triangulation itself is gone by then.
// Vertices are numbered 0 .. m-1 in the triangulation's (spatially sorted)
// order; to_input maps them back to input indices.
struct Filtered {
  std::vector<uint32_t> tris;     // candidate triangles, 3 vertex numbers each
  std::vector<double> poles;      // 3 per vertex: unit pole direction
  std::vector<uint32_t> to_input; // vertex number -> input index
  std::vector<std::pair<uint32_t, uint32_t>> dups; // (duplicate, first), input
  // Per vertex: 0 for an interior sample, kBoundarySample or kOpenSample
  // for the others; empty when boundary detection did not run, or found
  // too few interior samples to tell (then taken as closed: section 5.5).
  std::vector<uint8_t> boundary;
  // Shortcrust mode: what its check needs (section 6.5); empty in the
  // other modes.
  Checks check;
};

// A boundary sample whose pole disagrees with its neighbours', and one
// whose Voronoi cell opens sideways (it failed the ratio test).
constexpr uint8_t kBoundarySample = 1;
constexpr uint8_t kOpenSample = 3;

// Whether a mode sorts samples into interior and boundary ones.
inline bool detects_boundary(int mode) {
  return mode == SC_MODE_BOUNDARY || mode == SC_MODE_WATERTIGHT ||
         mode == SC_MODE_AUTO;
}

// See sc_params_can_tile(). Boundary detection runs over tiles, but not
// within a memory limit (the tiles there never all hold their
// triangulations at once).
inline bool can_tile(const sc_params_t &p) {
  return !(p.mode == SC_MODE_WATERTIGHT && p.watertight_labels) &&
         !(detects_boundary(p.mode) && p.memory_limit > 0);
}

// The Delaunay-dependent stages, behind an interface that keeps CGAL's
// types out of the rest of the pipeline.
class Triangulator {
public:
  virtual ~Triangulator() = default;
  // Inserts points [first, first + n) of xyz (which holds every point so far).
  virtual void insert(const double *xyz, size_t first, size_t n,
                      Progress &progress) = 0;
  virtual int dimension() const = 0;
  // Resolves duplicates, then runs poles and candidates, filling diag.
  // Frees the triangulation at the end, unless keep is set (for close()).
  virtual void filter(const double *xyz, size_t n, const sc_params_t &params,
                      Progress &progress, Filtered &out, sc_diag_t &diag,
                      double seconds[SC_STAGE_COUNT]) = 0;
  // Watertight mode (section 11.4), on the triangulation that filter()
  // kept, or on one of the surface's (distinct) points inserted in the
  // order of its vertex numbers, without filter(): labels the cells inside
  // or outside and puts in tris (vertex numbers) the boundary of the inside
  // cells, repaired into a 2-manifold as far as relabelling goes (a few
  // pinched vertices may be left). Returns false, leaving tris as it was,
  // when no cell is inside. cocone_theta is the cocone test's, by which the
  // labels do not cross the facets it finds on the surface where the
  // balls reach through it (a coarse sample); 0 where the points are
  // noisy, for the test then finds facets between the layers of the noise.
  virtual bool close(std::vector<uint32_t> &tris, Progress &progress,
                     sc_diag_t &diag, double cocone_theta) = 0;
  // After close(): puts in tris the candidates of the cocone test at every
  // sample, with params' cocone_theta, in canonical order: those of cocone
  // mode on the same points (section 11.5).
  virtual void cocone_everywhere(const sc_params_t &params, Progress &progress,
                                 std::vector<uint32_t> &tris) = 0;
  // Moves every vertex by -shift; the caller makes sure each subtraction
  // is exact (recentre()), so the triangulation stays the Delaunay
  // triangulation of its points, cell for cell.
  virtual void translate(const double shift[3]) = 0;
  // filter() keeps the triangulation for close() instead of freeing it;
  // or where at least keep_from_boundary vertices are boundary samples
  // (SIZE_MAX: never), and then sets keep.
  bool keep = false;
  size_t keep_from_boundary = SIZE_MAX;
};

// Section 3.4: sets shift to the lower corner of the points' box on each
// axis where every coordinate minus it is exact, 0 on the others; returns
// whether any is not 0.
bool recentre(const double *xyz, size_t n, double shift[3]);

std::unique_ptr<Triangulator> make_triangulator();

// Pruning and manifold extraction over the candidates (prune.cpp,
// extract.cpp).
// Returns the oriented output triangles and fills the output diagnostics.
struct Surface {
  std::vector<uint32_t> tris;
  std::vector<int32_t> component_genus; // per component, -1 when open
  std::vector<int32_t> component;       // per triangle: its component
  // What describe() counted in each component, so that dropping whole
  // components or splitting triangles need not count again. The vertex
  // counts are per component only when no vertex is pinched.
  struct Part {
    int64_t faces = 0, edges = 0, vertices = 0;
    uint64_t boundary_edges = 0, loops = 0, nonmanifold_edges = 0;
    uint64_t longest_loop = 0, loops_by_length[4] = {0, 0, 0, 0};
  };
  std::vector<Part> parts;
  uint64_t pinched = 0;
  // The boundary loops (loops that touch at a vertex are one): each one's
  // component (-1 once dropped) and length in edges, and each boundary
  // vertex's loop (UINT32_MAX for the others).
  struct Loop {
    int32_t part;
    uint64_t length;
  };
  std::vector<Loop> loops;
  std::vector<uint32_t> loop_of;
  // Whether triangle t's component is closed.
  bool in_closed(size_t t) const {
    return parts[size_t(component[t])].boundary_edges == 0;
  }
};
// The candidates' edges with their triangles in order about each edge
// (edges.hpp): pruning builds it, extraction takes it over.
struct EdgeTable;
struct EdgeTableFree {
  void operator()(EdgeTable *et) const;
};
typedef std::unique_ptr<EdgeTable, EdgeTableFree> EdgeTablePtr;
// An empty table, for fill_holes() to leave the table of its result in.
EdgeTablePtr new_edge_table();
// Frees the arrays that this thread's edge tables and vertex stars keep
// for reuse (edges.cpp); called at the end of each reconstruction.
void release_scratch();
// Sharp-edge pruning (section 7). keep_vertex, when not empty, marks the
// vertices at which no edge is ever sharp (boundary samples). Leaves the
// candidates' edge table in `table`, built on `threads` threads.
void prune(const double *xyz, size_t n, const std::vector<uint32_t> &cand,
           bool erode_single, const std::vector<uint8_t> &keep_vertex,
           std::vector<uint8_t> &alive, EdgeTablePtr &table, Progress &progress,
           sc_diag_t &diag, unsigned threads = 1);
// The walk and small holes (sections 8 and 9). Takes the table prune()
// left for the same candidates and alive flags. Holes mostly rimmed by
// samples marked in boundary are left open. The walk takes the flattest
// continuation first (section 8).
// `check_vertices` as in describe(): pass false only when an open surface
// will be described again before it is output. `unfilled`, when given,
// receives the triangles before the holes were filled.
void extract(const double *xyz, size_t n, const std::vector<uint32_t> &cand,
             const std::vector<uint8_t> &alive, EdgeTablePtr table,
             size_t max_hole, const std::vector<uint8_t> &boundary,
             Progress &progress, Surface &out, sc_diag_t &diag,
             bool check_vertices = true,
             std::vector<uint32_t> *unfilled = nullptr);
// The topology of a finished surface (section 10): components, boundary loops,
// genus, manifold checks; closed components facing inward are flipped. Resets
// and fills the output fields of diag (triangles, boundary, components ...).
// `table`, when given, is the edge table of tris (it saves building one).
// Without check_vertices, the vertices of a surface with an open component are
// taken to be manifold, as extraction leaves them, instead of checked (a third
// of the time here); a closed surface is checked either way.
void describe(const double *xyz, size_t n, std::vector<uint32_t> &tris,
              Progress &progress, Surface &out, sc_diag_t &diag,
              const EdgeTable *table = nullptr, bool check_vertices = true);
// Fills those fields of diag, and s.component_genus, from s.parts.
void summarise(Surface &s, sc_diag_t &diag);
// Counts s.loops into s.parts (loops, the longest, loops by length).
void tally_loops(Surface &s);
// Puts the triangles in one order that depends only on the set (section 13):
// each rotated to start at its smallest vertex number (keep_orientation) or
// with its numbers ascending, then all sorted. Which Delaunay cell reports a
// facet depends on heap addresses; with this, two runs on the same points (a
// daemon job and a local run) list the same triangles in the same order.
void canonical_order(std::vector<uint32_t> &tris, bool keep_orientation);
// The triangles of parts, each part in canonical_order() without
// orientation and no triangle in two, in that order: what canonical_order()
// of them all gives, by merging pairs of parts (the parts are emptied).
void merge_canonical(std::vector<std::vector<uint32_t>> &parts,
                     std::vector<uint32_t> &out);
// Removes the closed components of fewer than min_triangles triangles (bubbles
// between the layers of overlapping scans, section 11.1), and the open ones too
// when open_too, from a surface that describe() filled; s and diag then
// describe what is left. Returns the triangles removed.
size_t drop_small_closed(const double *xyz, size_t n, Surface &s,
                         size_t min_triangles, bool open_too,
                         Progress &progress, sc_diag_t &diag);
// Inserts every sample that is in no triangle into the nearest triangle
// (section 12: splitting it in three, or the two triangles of the nearest edge
// in two each) when it is closer to it than the triangle's longest edge. Keeps
// the surface a consistently oriented manifold, with its components, genus and
// loops; s and diag, which describe() filled, describe the result. Returns the
// count.
size_t attach_samples(const double *xyz, size_t n, Surface &s,
                      Progress &progress, sc_diag_t &diag);
// Removes every triangle on an edge with more than two, then keeps the
// largest fan at each vertex: what is left is a 2-manifold (with boundary).
void drop_nonmanifold(const double *xyz, size_t n, std::vector<uint32_t> &tris,
                      Progress &progress);
// A vertex whose triangles (those with in[t] set) form several fans is
// pinched: keeps its largest fan. Removing triangles can pinch their other
// vertices, so repeats until every vertex has one fan. Clears in[t] for the
// triangles removed. With one_fan_before, the triangles were one fan at
// each vertex before in[] was cleared for some of them: only the vertices
// of those need looking at.
void fix_fans(size_t n, const std::vector<uint32_t> &tris,
              std::vector<uint8_t> &in, bool one_fan_before = false);
// twin[h] for half-edge h = 3 t + k (from corner k of triangle t to corner
// k + 1): the other half-edge of its edge when exactly two triangles share
// the edge, else UINT32_MAX; leaves the edge table of tris in et.
void pair_half_edges(size_t n, const std::vector<uint32_t> &tris,
                     Progress &progress, std::vector<uint32_t> &twin,
                     EdgeTable &et);
// The edge table of the triangles that keep marks, renumbered in order.
void keep_edges_of(EdgeTable &et, const std::vector<uint8_t> &keep);
// The edge table of tris, from that of tris up to triangle first_new.
void append_edges_of(EdgeTable &et, size_t n,
                     const std::vector<uint32_t> &tris, size_t first_new,
                     Progress &progress);
// Cuts the handles of an oriented, edge- and vertex-manifold surface that
// closed round a hole (section 11.2): grows a region over each component,
// nearest triangle first, refusing every triangle that would join two of its
// boundary loops (raise its genus), then takes out the refused triangles of
// each cut that runs mostly along holes and keeps the others. The result is a
// manifold again; returns the number of cuts. Leaves the edge table of the
// result (as fill_holes() builds it) in `table`.
size_t cut_handles(const double *xyz, size_t n, std::vector<uint32_t> &tris,
                   Progress &progress, EdgeTable &table);
// Small handles of a closed, oriented manifold surface (section 11.5):
// takes out the triangles within `rings` rings of a vertex wherever they
// hold a handle, or with `poles` (by vertex), a tunnel instead: an annulus
// that faces its axis, lies at an angle to its corners' poles, and whose
// cut leaves its two sides joined; the smallest in area first and at most
// max_sites places; returns how many. The vertices are probed on
// `threads` threads, for the same result.
// `cache`, when given, carries the probes from one round to the next with
// the same rings: only the vertices near triangles that changed since are
// probed again, for the same result.
struct ProbeCache {
  int rings = -1;
  std::vector<std::array<uint32_t, 3>> keys; // the last surface's triangles
  std::vector<uint8_t> holds, known; // by vertex: what a probe found, and
                                     // whether it was probed
};
size_t cut_small_handles(const double *xyz, size_t n,
                         std::vector<uint32_t> &tris, int rings,
                         size_t max_sites, const double *poles,
                         const std::vector<uint8_t> *only, unsigned threads,
                         Progress &progress, ProbeCache *cache = nullptr);
// Closes every hole of at most max_loop edges by a least-area patch (sections 9
// and 11.3; a loop of more than 16 edges is first cut by short chords into
// pieces), except the loops that boundary (which may be empty) marks as where
// the surface ends. The patches together take at most max_work steps of the
// dynamic programme (about L^3 / 6 for a loop of L edges); loops beyond it
// stay. `table`, when given, is the edge table of tris, or an empty table
// (new_edge_table()) to build it in; either way it is the table of the filled
// tris on return, for describe(), though no longer in angular order about each
// edge.
void fill_holes(const double *xyz, size_t n, std::vector<uint32_t> &tris,
                size_t max_loop, const std::vector<uint8_t> &boundary,
                Progress &progress, sc_diag_t &diag,
                uint64_t max_work = UINT64_MAX, EdgeTable *table = nullptr);
// The width of the widest boundary loop of tris, in the median length of
// its edges (twice its vector area over its length: the radius of a round
// hole, the width of a slit; section 9); 0 when tris is closed, infinity
// when a loop passes a pinched vertex.
double widest_loop(const double *xyz, size_t n,
                   const std::vector<uint32_t> &tris, Progress &progress);

// Noise (denoise.cpp; section 16).
struct NoiseEstimate {
  double spacing = 0;   // typical distance between neighbouring samples
  double noise = 0;     // RMS distance to the local surface, in spacings
  double curvature = 0; // the local surface's larger curvature x spacing
  // Whether the sample resolves its surface, so that what the estimate
  // calls noise is noise: noise bends the fitted surfaces too, by about
  // half the noise, and a coarse sample (the vertices of a decimated mesh,
  // a few hundred points on a handle) bends them much more.
  bool resolved() const { return curvature <= 0.15 + 0.5 * noise; }
  // Whether the points are noisy: denoising (and auto mode) smooths them
  // (section 16.2; SC_NOISE_FLOOR was measured with shortcrust-noise-table
  // and on the shared closed models, README "Noise").
  bool noisy() const { return noise >= SC_NOISE_FLOOR && resolved(); }
};
// The estimate from the neighbourhoods of a fixed subset of the points (the
// same whatever chunks the points arrived in).
NoiseEstimate estimate_noise(const double *xyz, size_t n, Progress &progress);
// The smoothing radius for an estimate.
double default_scale(const NoiseEstimate &e);
// What smooth() did, for the diagnostics.
struct Smoothing {
  double scale = 0; // the neighbourhood radius used
  double shift = 0; // RMS distance the points moved, in spacings
};
// Scale-space smoothing (after Digne et al. 2011): out receives a copy of
// the points, each moved a few times onto the weighted least-squares
// quadric of its neighbours within `scale`; on `threads` threads, with the
// same result on any number.
Smoothing smooth(const double *xyz, size_t n, double scale,
                 const NoiseEstimate &e, unsigned threads, Progress &progress,
                 std::vector<double> &out);

namespace dt {
// The triangulation stages over tiles (tiles.cpp, section 17): fills out
// and diag as Triangulator::filter() does, with the same candidates,
// poles and numbering, from `tiles` tiles of the n points run on `threads`
// threads, each holding the points within `margin` of
// its region from the start. Returns false, having done nothing that
// counts, where the points cannot be split (too few) or span no volume:
// the single triangulation then takes over. bounded: at most `threads`
// triangulations at a time (within a memory limit), each tile
// triangulated twice. Where tiles that may give up (tiles 0) do, it
// returns false too, and with fallback the triangulation of all the points,
// grown from the largest tile's (the time counts in seconds).
bool tiled_filter(const double *xyz, size_t n, size_t tiles, unsigned threads,
                  bool bounded, double margin, const sc_params_t &params,
                  Progress &progress, Filtered &out, sc_diag_t &diag,
                  double seconds[SC_STAGE_COUNT],
                  std::unique_ptr<Triangulator> *fallback = nullptr);

// One tile of a job split over several reconstructions (section 17.6): of
// the n points split into `tiles` tiles as tiled_filter() splits them, tile
// `index` alone, grown until it can compute the poles of its neighbours'
// vertices too. Fills out with the distinct points' numbering, the
// candidates the tile owns (by vertex number, in canonical order) and the
// poles of its own vertices (zero for the others), and diag with what it
// owns and diag.tiles. Returns false where the points cannot be split, or
// the tile spans no volume: the job then runs on one triangulation.
bool tile_job(const double *xyz, size_t n, size_t tiles, size_t index,
              double margin, const sc_params_t &params, Progress &progress,
              Filtered &out, sc_diag_t &diag, double seconds[SC_STAGE_COUNT]);

// The union of the results of every tile of such a job (tiles[i] by
// tile_job(), its candidates and poles by input index): fills out as
// tiled_filter() would. Throws SC_EINVALID_ARGUMENT for results that cannot
// be one job's tiles. check: shortcrust mode's check runs (checks()),
// and the tiles carry its lists.
void merge_tiles(const double *xyz, size_t n, const sc_mesh_t *const *tiles,
                 size_t count, bool check, Filtered &out, sc_diag_t &diag);
} // namespace dt

// Within a memory limit of `limit` bytes (section 17.5): the tiles n points
// need on `threads` threads, 1 where one triangulation of all fits. Throws
// Error SC_ENO_MEMORY, saying what would fit, where not even tiles of the
// least size fit.
size_t memory_tiles(size_t n, unsigned threads, double limit);

// Watertight mode on more than one thread: the labelling of the Delaunay
// cells (section 11.4) reads nothing of the extracted surface, so it runs
// on a thread of its own while the surface is pruned, extracted and
// patched (section 11.5). Over the triangulation that filter() kept, or
// over a triangulation of the m points lxyz (in vertex order) built first;
// lxyz must outlive the task. Destroying it stops and joins the thread.
class LabelTask {
public:
  LabelTask(std::unique_ptr<Triangulator> dt, const double *lxyz, size_t m,
            double cocone_theta);
  ~LabelTask();
  LabelTask(const LabelTask &) = delete;
  LabelTask &operator=(const LabelTask &) = delete;
  // Waits for the labelling, reporting progress (and so taking a cancel)
  // meanwhile; then as Triangulator::close(): the boundary of the inside
  // cells in tris and diag's cells_relabelled, false when no cell is
  // inside; where one is, the triangulation in dt when it has at most
  // 65 536 points (else dt is null). Rethrows what the thread threw.
  bool take(std::vector<uint32_t> &tris, Progress &progress, sc_diag_t &diag,
            std::unique_ptr<Triangulator> &dt);

private:
  struct State;
  std::unique_ptr<State> state_;
};

// One reconstruction, fed all at once or in chunks.
class Recon {
public:
  explicit Recon(const sc_params_t &p) : params_(p) {}
  void add(const double *xyz, size_t n);
  void borrow(const double *xyz, size_t n);
  // Before borrow(): finish() takes the candidates and poles from the
  // results of the job's tiles (sc_reconstruct_merge()).
  void merge_from(const sc_mesh_t *const *tiles, size_t count) {
    merge_ = tiles;
    merge_count_ = count;
  }
  sc_mesh_t *finish();

private:
  // A tile job's result (params.tile_count): its candidates and poles.
  sc_mesh_t *finish_tile(const double *work, Progress &progress,
                         sc_diag_t &diag);
  // The result handed back: the stage times in diag, the progress at its
  // end, and the smoothed points when asked for.
  sc_mesh_t *result(const Surface &surf, const std::vector<double> &normals,
                    sc_diag_t &diag, Progress &progress) const;
  // A tile job, or the merge of tile jobs' results: no tiles of its own
  // (tile_count() is 0), and every point before the work starts.
  bool apart() const { return params_.tile_count > 0 || merge_; }
  // How far each tile holds the points beyond its region from the start.
  double tile_margin() const { return 3 * noise_.spacing; }
  void insert_range(const double *xyz, size_t first, size_t n,
                    Progress &progress);
  // Auto mode: whether watertight mode's closing of surf, extracted with
  // no hole filled, is one closed piece of lower genus than `genus`, or
  // the cocone test's surface at every sample; then surf and diag take
  // that closure.
  bool auto_closes_unfilled(const double *lxyz, size_t m, int64_t genus,
                            Progress &progress, Surface &surf, sc_diag_t &diag);
  // Auto mode: whether surf, extracted, is of a closed surface and is to be
  // closed as in watertight mode.
  bool auto_closes(const double *lxyz, size_t m, const Surface &surf,
                   const sc_diag_t &diag, Progress &progress) const;
  // Watertight mode: closes surf, by labelling the Delaunay cells or by
  // least-area patches (or takes the cocone test's surface at every
  // sample, section 11.5); before the patches, cuts the handles that
  // closed round holes of the scan when `cut`.
  void close_surface(const double *lxyz, size_t m, bool cut,
                     Progress &progress, Surface &surf, sc_diag_t &diag);
  // The poles of the vertices, by vertex number, while finish() closes the
  // surface (close_surface() tells the labelling's tunnels by them); and
  // whether boundary detection left samples out of the candidates' test,
  // so that the cocone test at every sample gives other candidates.
  const double *closing_poles_ = nullptr;
  bool closing_everywhere_ = false;
  // Pruning and extraction (small holes filled) of the candidates cand,
  // with boundary samples marked in boundary (empty: none), into s and d.
  void surface_of(const double *lxyz, size_t m,
                  const std::vector<uint32_t> &cand,
                  const std::vector<uint8_t> &boundary, Progress &progress,
                  Surface &s, sc_diag_t &d) const;
  void patch_surface(const double *lxyz, size_t m, bool cut, Progress &progress,
                     Surface &surf, sc_diag_t &diag);
  // Shortcrust mode's check (section 6.5): the cocone test's surface,
  // compared with surf (whose counts are in diag); where they differ, surf
  // and diag become those of the nearest r that agrees, if one does.
  // before: diag as it was before the pruning. Frees f.check.
  void check_topology(const double *lxyz, size_t m, Filtered &f,
                      const sc_diag_t &before, Progress &progress,
                      Surface &surf, sc_diag_t &diag) const;
  // Denoising (section 16): whether insertion waits for finish(); the
  // estimate and the smoothing, which set work_ (xyz_, or smoothed_).
  bool defer_insertion() const;
  // The tiles the triangulation stages run over (section 17), 0 for one
  // triangulation of all.
  size_t tile_count() const;
  // The threads asked for, one per core for 0.
  unsigned thread_count() const;
  // Watertight mode: whether the labelling may run beside the extraction
  // (LabelTask): on more than one thread, unless the patches come first.
  bool labels_beside() const;
  void prepare(Progress &progress);
  void prepare_and_insert(Progress &progress);
  const double *recentred();
  bool smooths(const NoiseEstimate &e) const;
  double label_theta() const;
  void smooth_if_noisy(const double *base, Progress &progress);
  sc_params_t params_;
  // The caller's progress, from borrow() or the first add() to the end of
  // finish(): a stage that goes on there goes on where it was. (Chunks
  // that arrive count each on their own: their number is not known.)
  Progress progress_{params_.progress, params_.progress_user};
  std::vector<double> own_;
  const double *xyz_ = nullptr;
  size_t n_ = 0;
  bool prepared_ = false;
  const double *work_ = nullptr;
  std::vector<double> smoothed_;
  // The points re-centred (section 3.4) when shift_ is not 0 and they are
  // not smoothed; whether dt_ holds points in the caller's frame.
  std::vector<double> shifted_;
  double shift_[3] = {0, 0, 0};
  bool dt_raw_ = false;
  NoiseEstimate noise_;
  Smoothing smoothing_;
  double seconds_denoise_ = 0;
  std::unique_ptr<Triangulator> dt_;
  // Watertight mode: the triangulation filter() kept for the labelling,
  // or the labelling under way on a thread of its own.
  std::unique_ptr<Triangulator> kept_;
  std::unique_ptr<LabelTask> labelling_;
  double seconds_[SC_STAGE_COUNT] = {};
  const sc_mesh_t *const *merge_ = nullptr;
  size_t merge_count_ = 0;
};

class Stopwatch {
public:
  Stopwatch() : t0_(std::chrono::steady_clock::now()) {}
  double lap() {
    auto t = std::chrono::steady_clock::now();
    double s = std::chrono::duration<double>(t - t0_).count();
    t0_ = t;
    return s;
  }

private:
  std::chrono::steady_clock::time_point t0_;
};

} // namespace sc

#endif
