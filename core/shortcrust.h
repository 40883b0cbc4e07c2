/*
 * shortcrust: surface reconstruction from unorganized 3D points by one-pass
 * Delaunay filtering (Amenta & Choi, "the short crust").
 *
 * This header is the whole public face of the core. It is plain C; the
 * implementation is C++ over CGAL and never lets an exception cross it.
 *
 * Points go in as an array of double x,y,z triples. Triangles come out as
 * index triples into that same array, so the caller keeps its coordinates.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SHORTCRUST_H
#define SHORTCRUST_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/*
 * Error codes. Every function that can fail returns 0 or one of these
 * negative values; sc_strerror() and sc_err_name() describe them.
 */
#define SC_ERRNO_MAP(X)                                                        \
  X(INVALID_ARGUMENT, -1, "invalid argument")                                  \
  X(DEGENERATE_INPUT, -2,                                                      \
    "degenerate input: fewer than 4 distinct points, or all coplanar")         \
  X(NONFINITE, -3, "non-finite coordinate (NaN or Inf) in the input")          \
  X(NO_MEMORY, -4, "out of memory")                                            \
  X(CANCELLED, -5, "cancelled")                                                \
  X(TOO_MANY_POINTS, -6, "too many points (at most 2^32 - 2)")                 \
  X(INTERNAL, -7, "internal error")                                            \
  X(BAD_STATE, -8, "call not allowed in the current state")

typedef enum sc_err {
  SC_OK = 0,
#define SC_ERR_ENUM_(name, value, msg) SC_E##name = (value),
  SC_ERRNO_MAP(SC_ERR_ENUM_)
#undef SC_ERR_ENUM_
} sc_err_t;

/* A fixed English message for a code; "unknown error" for other values. */
const char *sc_strerror(int code);
/* The code's name without the prefix, e.g. "NONFINITE"; "UNKNOWN" otherwise. */
const char *sc_err_name(int code);

/* Candidate selection (docs/algorithm.md section 6; sections 5 and 11 for
 * the modes for scans).
 * One row per mode: X(NAME, value, name): the numbering is the wire
 * protocol's too (proto/PROTOCOL.md section 4), and the name is how the
 * command line, reports and logs spell the mode.
 *  - SHORTCRUST: the paper's two criteria (normal and small ball) with
 *    parameter r.
 *  - COCONE: the cocone test: the dual Voronoi edge meets the cocone of all
 *    three vertices.
 *  - BOUNDARY: for scans with a boundary (docs/algorithm.md sections 5 and
 *    11): samples are sorted into interior and boundary ones (Dey and
 *    Giesen's ratio and normal tests, parameters boundary_rho and
 *    boundary_alpha); the cocone test is made only at interior vertices,
 *    and no edge at a boundary sample is pruned, so the output is a
 *    2-manifold with boundary.
 *  - WATERTIGHT: boundary mode, then every hole is closed: handles that
 *    closed round a hole are cut, each boundary loop gets a least-area
 *    patch, and where the patches cannot close the surface the Delaunay
 *    cells are labelled inside or outside across it and the boundary of the
 *    inside cells is taken. The output is a closed 2-manifold. When most
 *    samples are found not interior (too sparse to tell a boundary from
 *    undersampling), the input is taken as closed, as in auto mode: the
 *    cocone test everywhere, and no handle cut.
 *  - AUTO: for input not known to be closed: the cocone test where the
 *    samples look like a closed surface, boundary mode where they do not;
 *    and where what is left open is narrow (no loop wider than 3 of its
 *    edges) or in pieces, closed as in WATERTIGHT (diag.path says which
 *    was taken). */
#define SC_MODE_MAP(X)                                                         \
  X(SHORTCRUST, 0, "shortcrust")                                               \
  X(COCONE, 1, "cocone")                                                       \
  X(BOUNDARY, 2, "boundary")                                                   \
  X(WATERTIGHT, 3, "watertight")                                               \
  X(AUTO, 4, "auto")

typedef enum sc_mode {
#define SC_MODE_ENUM_(name, value, str) SC_MODE_##name = (value),
  SC_MODE_MAP(SC_MODE_ENUM_)
#undef SC_MODE_ENUM_
  /* Count of modes; not a mode. */
  SC_MODE_COUNT_
} sc_mode_t;

/* The name of a mode ("cocone", ...); "?" when out of range. */
const char *sc_mode_name(int mode);

/* The stages of a reconstruction, in the order they run:
 * X(NAME, value, name, what runs). Numbered as on the wire. */
#define SC_STAGE_MAP(X)                                                        \
  X(INPUT, 0, "input", "validation, duplicate detection")                      \
  X(DELAUNAY, 1, "delaunay", "the 3D Delaunay triangulation")                  \
  X(POLES, 2, "poles", "Voronoi vertices and poles")                           \
  X(CANDIDATES, 3, "candidates", "one pass over the Delaunay facets")          \
  X(PRUNE, 4, "prune", "sharp-edge pruning")                                   \
  X(EXTRACT, 5, "extract", "manifold extraction and orientation")

typedef enum sc_stage {
#define SC_STAGE_ENUM_(name, value, str, what) SC_STAGE_##name = (value),
  SC_STAGE_MAP(SC_STAGE_ENUM_)
#undef SC_STAGE_ENUM_
  SC_STAGE_COUNT = 6
} sc_stage_t;

/* Short lower-case name of a stage ("delaunay", ...); "?" when out of range. */
const char *sc_stage_name(int stage);

/*
 * Progress callback: called from the thread running the reconstruction with
 * the current stage and the fraction of that stage done, in [0, 1]. Within
 * a stage the fraction never goes back, on any number of threads and tiles;
 * a stage may come again after a later one (the input stage, where the
 * points are smoothed once the triangulation has begun), and each chunk of
 * sc_recon_add() counts its insertion from 0. Return 0 to go on, non-zero
 * to cancel: the call then returns SC_ECANCELLED at the next check (at most
 * a few milliseconds of work later) and frees everything it held.
 */
typedef int (*sc_progress_fn)(void *user, sc_stage_t stage, double fraction);

/* pi, for the angles below and for every module that converts them. */
#define SC_PI 3.14159265358979323846

/*
 * The parameters of a reconstruction, one row each; sc_params_t, its
 * defaults (sc_params_init) and checks (sc_params_check), the command
 * line's options and --help lines, the report, the daemon's decoding of job
 * options and the client library's checks are all made from this table.
 *
 *   X(field, type, kind, default, lo, hi, range, range_text, wire,
 *     short_opt, long_opt, metavar, help)
 *
 * kind: MODE (an sc_mode_t), REAL, ANGLE (radians; degrees on the command
 * line), INT, FLAG (0 or 1; an option without a value).
 * lo, hi, range: the valid values; range is a mask of SC_RANGE_* below,
 * and range_text says the same in words for messages (angles in radians).
 * wire: FIXED (a field of JOB_BEGIN, proto/PROTOCOL.md section 6.3),
 * OPTION (a job option of that name and of kind u64 for INT and FLAG, f64
 * for REAL and ANGLE), or LOCAL (not sent to the daemon).
 * short_opt, long_opt, metavar: the command line's spelling (0 or NULL for
 * none); help: the meaning, in one sentence without the default.
 *
 * Why the defaults are what they are: the README, "Parameters".
 *  - mode: the candidate test (sc_mode_t above).
 *  - r: sampling parameter of the shortcrust criteria. The paper proves its
 *    guarantees for r < 1/7; larger values accept more triangles on sparser
 *    or less even samples, and from about 0.2 on bridge nearby parts of a
 *    surface. Ignored by the cocone test.
 *  - cocone_theta: half-width of the cocone around the plane normal to the
 *    pole: the cocone is |cos angle(y - s, pole)| <= cos(pi/2 - theta).
 *  - unchecked: shortcrust mode checks its surface against the one the
 *    cocone test gives on the same triangulation and, where their
 *    topologies differ, takes the nearest r within 0.02 that gives the
 *    cocone test's closed surface, or says that the topology is in doubt
 *    (diag.topology_doubt; docs/algorithm.md section 6.5). 1 skips that.
 *  - paper_pruning: edges with a single candidate triangle. 0: such an edge
 *    is sharp only when its triangle hangs by it alone (two or more of its
 *    edges have no other candidate), so fins go but a hole left by a
 *    missing triangle stays small. 1: every such edge is sharp, exactly as
 *    in the paper; one missing triangle then erodes the whole surface.
 *  - max_hole_edges: holes whose boundary loop has at most this many edges
 *    are closed after extraction by a least-area triangulation of the loop,
 *    and so are slits, loops narrower than their edges are long, whatever
 *    their length (docs/algorithm.md section 9); 0 disables both.
 *  - threads: threads of the reconstruction; 0 means one per core. With
 *    several tiles, the tiles run on them; one triangulation runs on one
 *    thread (CGAL's parallel triangulation measured no faster: README,
 *    "Benchmark"). Denoising's smoothing runs on them too, with the same
 *    result on any number, and so does watertight mode's labelling of the
 *    Delaunay cells, beside the extraction, where boundary samples are
 *    found (docs/algorithm.md section 11.5).
 *  - tiles (every mode; watertight mode with watertight_labels runs one
 *    triangulation): the points are split into this many tiles whose
 *    triangulations are certified against each other, so that the mesh is
 *    the one a single triangulation gives, triangle for triangle
 *    (docs/algorithm.md section 17). 1, the default, never tiles; 0 means
 *    one per thread, given up for one triangulation where the tiles would
 *    cost more (diag.tiles 0, diag.tile_points_foreign not: section 17.4),
 *    and none in watertight mode on more than one thread unless
 *    watertight_patches (its labelling runs on the one triangulation,
 *    beside the extraction: section 11.5).
 *  - boundary_rho (boundary, watertight and auto modes): a sample passes
 *    the ratio test when the farthest Voronoi vertex of its cell inside its
 *    cocone is at most boundary_rho times the distance to its negative
 *    pole. 0 means the default, so that a caller written before this field
 *    existed keeps working; so for boundary_alpha.
 *  - boundary_alpha: poles of neighbouring interior samples agree when the
 *    angle between them (unoriented) is at most this.
 *  - denoise (every mode; docs/algorithm.md section 16): the noise is
 *    estimated in every job; with denoise, when it is at least
 *    SC_NOISE_FLOOR spacings, a copy of the points is smoothed toward the
 *    surface (scale-space projection onto local quadrics) and the Delaunay
 *    filtering runs on the copy; the triangles index the original points,
 *    as always. denoise_scale: the smoothing radius (0: estimated);
 *    smoothed_vertices: the mesh also carries the smoothed positions
 *    (sc_mesh_t.smoothed). Auto mode denoises by itself above the floor.
 *  - memory_limit (cocone and shortcrust modes; 0 = none): the points are
 *    split into as many tiles as it takes for `threads` of them at a time,
 *    and what a reconstruction keeps besides, to stay near this many bytes
 *    (the caller's copy of the points included); each tile is
 *    triangulated twice, once for its poles and once for its candidates.
 *    A job that cannot fit fails with SC_ENO_MEMORY before it allocates
 *    (docs/algorithm.md section 17.5).
 *  - tile_count, tile_index (cocone and shortcrust modes; no command-line
 *    option): a tile job, one part of a job whose tiles run apart, on
 *    other machines perhaps (docs/algorithm.md section 17.6). With
 *    tile_count k >= 2 the points are split into k tiles as `tiles` splits
 *    them, and only tile tile_index is computed; the result is not a mesh
 *    but what sc_reconstruct_merge() needs of that tile: see there.
 *    tile_count 0, the default, is the whole job.
 *  - watertight_labels, watertight_patches: by default watertight mode
 *    closes the surface by least-area patches over the holes of the
 *    extracted surface and, where those leave doubt (not one closed piece,
 *    a handle cut, more than 0.1% of the samples left out), also by
 *    labelling the Delaunay cells inside or outside by their empty balls
 *    (the boundary of the inside cells), and keeps the better closure
 *    (docs/modes.md). watertight_labels 1 takes
 *    the labelling alone (the patches only when no cell comes out inside);
 *    watertight_patches 1 (with watertight_labels 0) patches first and
 *    labels only where the patches leave the surface open.
 */
#define SC_RANGE_CLOSED 0      /* lo <= v <= hi */
#define SC_RANGE_LO_OPEN 1     /* lo < v */
#define SC_RANGE_HI_OPEN 2     /* v < hi */
#define SC_RANGE_ZERO_DEFAULT 4 /* 0 is valid too, and means the default */
#define SC_RANGE_OPEN (SC_RANGE_LO_OPEN | SC_RANGE_HI_OPEN)

#define SC_PARAM_MAP(X)                                                        \
  X(mode, sc_mode_t, MODE, SC_MODE_COCONE, 0, SC_MODE_COUNT_ - 1,              \
    SC_RANGE_CLOSED, "a mode", FIXED, 'm', "mode", "MODE",                     \
    "cocone, shortcrust, boundary (scans with a boundary), watertight "        \
    "(close every hole) or auto")                                              \
  X(r, double, REAL, 0.14, 0, 0.5, SC_RANGE_OPEN, "in (0, 0.5)", FIXED, 0,     \
    "r", "R", "shortcrust sampling parameter")                                 \
  X(cocone_theta, double, ANGLE, SC_PI / 8, 0, SC_PI / 2, SC_RANGE_OPEN,       \
    "in (0, pi/2)", FIXED, 0, "theta", "DEG", "cocone half-width")             \
  X(unchecked, int, FLAG, 0, 0, 1, SC_RANGE_CLOSED, "0 or 1", OPTION, 0,       \
    "unchecked", NULL,                                                         \
    "shortcrust mode: skip the check of the topology against the cocone "      \
    "test's surface, and the search of a nearby r (a tenth less time)")        \
  X(paper_pruning, int, FLAG, 0, 0, 1, SC_RANGE_CLOSED, "0 or 1", OPTION, 0,   \
    "paper-pruning", NULL,                                                     \
    "prune every edge with a single candidate, as in the paper")               \
  X(max_hole_edges, int, INT, 100, 0, 100000, SC_RANGE_CLOSED,                 \
    "in [0, 100000]", OPTION, 0, "max-hole", "N",                              \
    "close holes of at most N edges, and narrow slits of any length, "         \
    "0 = never")                                                               \
  X(threads, int, INT, 1, 0, 1024, SC_RANGE_CLOSED, "in [0, 1024]", LOCAL,     \
    'j', "threads", "N",                                                       \
    "threads for the tiles, the smoothing, watertight mode's labelling, the "  \
    "noise estimate and the candidates (a single triangulation is built on "   \
    "one), 0 = one per core")                                                  \
  X(tiles, int, INT, 1, 0, 4096, SC_RANGE_CLOSED, "in [0, 4096]", LOCAL, 0,    \
    "tiles", "N",                                                              \
    "split the points into N tiles triangulated apart, on the threads; the "   \
    "same mesh whatever N; 0 = one per thread, while tiles pay (in "           \
    "watertight mode only with --patches)")                                    \
  X(memory_limit, double, BYTES, 0, 0, 1e300,                                  \
    SC_RANGE_LO_OPEN | SC_RANGE_ZERO_DEFAULT, "positive", LOCAL, 0,            \
    "memory-limit", "BYTES",                                                   \
    "keep the peak memory near BYTES (a number, or with K, M, G or T: powers " \
    "of 1024, 1.5G too) by triangulating tiles a few at a time, each twice; "  \
    "the same mesh (cocone and shortcrust modes)")                             \
  X(tile_count, int, INT, 0, 2, 4096, SC_RANGE_CLOSED | SC_RANGE_ZERO_DEFAULT, \
    "in [2, 4096]", OPTION, 0, NULL, NULL,                                     \
    "a tile job: reconstruct only tile tile_index of the job split into this " \
    "many tiles, for sc_reconstruct_merge() (cocone and shortcrust modes)")    \
  X(tile_index, int, INT, 0, 0, 4095, SC_RANGE_CLOSED, "in [0, 4095]", OPTION, \
    0, NULL, NULL, "a tile job: which tile, from 0")                           \
  X(boundary_rho, double, REAL, 1.3, 0, 10,                                    \
    SC_RANGE_LO_OPEN | SC_RANGE_ZERO_DEFAULT, "in (0, 10]", OPTION, 0, "rho",  \
    "RHO", "boundary detection: ratio of cocone extent to pole height")        \
  X(boundary_alpha, double, ANGLE, SC_PI / 9, 0, SC_PI / 2,                    \
    SC_RANGE_LO_OPEN | SC_RANGE_ZERO_DEFAULT, "in (0, pi/2]", OPTION, 0,       \
    "alpha", "DEG",                                                            \
    "boundary detection: largest angle between neighbouring poles")            \
  X(watertight_labels, int, FLAG, 0, 0, 1, SC_RANGE_CLOSED, "0 or 1", OPTION,  \
    0, "labels", NULL,                                                         \
    "watertight mode: close the surface by labelling the Delaunay cells "      \
    "inside or outside alone (default: patches and labelling, the better "     \
    "kept; overrides --patches)")                                              \
  X(watertight_patches, int, FLAG, 0, 0, 1, SC_RANGE_CLOSED, "0 or 1", OPTION, \
    0, "patches", NULL,                                                        \
    "watertight mode: close the holes of the extracted surface with "          \
    "least-area patches first, labelling cells only where they cannot")        \
  X(denoise, int, FLAG, 0, 0, 1, SC_RANGE_CLOSED, "0 or 1", OPTION, 0,         \
    "denoise", NULL,                                                           \
    "smooth a copy of the points toward the surface and reconstruct on it; "   \
    "the triangles still join the original samples")                           \
  X(denoise_scale, double, REAL, 0, 0, 1e300,                                  \
    SC_RANGE_LO_OPEN | SC_RANGE_ZERO_DEFAULT, "positive", OPTION, 0,           \
    "denoise-scale", "S",                                                      \
    "denoising: radius of the smoothing neighbourhood, in the input's units "  \
    "(default: estimated); given, it smooths whatever the noise")              \
  X(smoothed_vertices, int, FLAG, 0, 0, 1, SC_RANGE_CLOSED, "0 or 1", OPTION,  \
    0, "smoothed-vertices", NULL,                                              \
    "denoising: give the mesh the smoothed positions of the samples instead "  \
    "of the original ones")

typedef struct sc_params {
#define SC_PARAM_FIELD_(field, type, ...) type field;
  SC_PARAM_MAP(SC_PARAM_FIELD_)
#undef SC_PARAM_FIELD_
  /* Optional progress and cancellation; NULL for none. */
  sc_progress_fn progress;
  void *progress_user;
} sc_params_t;

/* Whether v lies in a row's range (lo, hi and the SC_RANGE_ mask). */
#define SC_IN_RANGE(v, lo, hi, range)                                          \
  ((((range)&SC_RANGE_ZERO_DEFAULT) && (v) == 0) ||                            \
   ((((range)&SC_RANGE_LO_OPEN) ? (v) > (lo) : (v) >= (lo)) &&                 \
    (((range)&SC_RANGE_HI_OPEN) ? (v) < (hi) : (v) <= (hi))))

/* The parameter table as data, for programs that walk it (the command
 * line, the daemon, reports): sc_param_table() returns its rows in order and
 * sets *count. */
typedef enum sc_param_kind {
  SC_PARAM_MODE,
  SC_PARAM_REAL,
  SC_PARAM_ANGLE,
  SC_PARAM_INT,
  SC_PARAM_FLAG,
  SC_PARAM_BYTES /* a double, in bytes; K, M, G, T on the command line */
} sc_param_kind_t;
typedef enum sc_param_wire {
  SC_PARAM_FIXED,
  SC_PARAM_OPTION,
  SC_PARAM_LOCAL
} sc_param_wire_t;
typedef struct sc_param_info {
  const char *name;       /* the field's name, and the job option's */
  sc_param_kind_t kind;
  size_t offset;          /* of the field in sc_params_t */
  double dflt, lo, hi;    /* as numbers (a mode's value) */
  int range;              /* SC_RANGE_ mask */
  const char *range_text; /* "in (0, 0.5)" */
  sc_param_wire_t wire;
  int short_opt;          /* 0 for none */
  const char *long_opt;   /* NULL for none */
  const char *metavar;    /* NULL for an option without a value */
  const char *help;
} sc_param_info_t;
const sc_param_info_t *sc_param_table(size_t *count);

/* Fills *p with the defaults of the table above. */
void sc_params_init(sc_params_t *p);
/* Checks every field of *p against the ranges of the table above, as
 * sc_reconstruct() does: SC_OK, or SC_EINVALID_ARGUMENT with the reason
 * in msg (when msg is not NULL). */
int sc_params_check(const sc_params_t *p, char *msg, size_t msg_len);
/* Whether a job with these parameters can run in tiles on one machine
 * (tiles other than 1, a memory limit, the daemon's --tile-points): 1 in
 * every mode but watertight mode's labelling alone (watertight_labels),
 * which labels the cells of one triangulation, and the boundary modes
 * within a memory limit (which sc_params_check() refuses). */
int sc_params_can_tile(const sc_params_t *p);

/* Boundary loops are counted by length in edges, in these bins:
 * X(index, wire suffix, least, most); most 0 for no upper bound. */
#define SC_LOOP_BIN_MAP(X)                                                     \
  X(0, "3_10", 3, 10)                                                          \
  X(1, "11_100", 11, 100)                                                      \
  X(2, "101_1000", 101, 1000)                                                  \
  X(3, "over_1000", 1001, 0)
#define SC_LOOP_BINS 4

/*
 * Diagnostics of one reconstruction (docs/algorithm.md section 15), one row
 * each: sc_diag_t, the report (`--report`), the daemon's JOB_DONE values
 * (proto/PROTOCOL.md section 6.12) and the command's reading of them are
 * made from this table.
 *
 *   X(field, type, dim, kind, wire, help)
 *
 * kind: COUNT (uint64_t), BOOL (int, 0 or 1; u64 on the wire), INT
 * (int64_t), REAL (double; f64 on the wire), PATH (int, an sc_path_t; u64
 * on the wire, its name in the report), STAGE_SECONDS (double per stage; on the wire "wire.STAGE", with
 * the names of sc_stage_name()), SECONDS (double), LOOPS (uint64_t per bin
 * of SC_LOOP_BIN_MAP; on the wire "wire.SUFFIX"). wire: the name in JOB_DONE
 * (the prefix, for the two arrays). The report names each field as the
 * struct does; its seconds make an object of their own.
 */
#define SC_DIAG_MAP(X)                                                         \
  X(points_in, uint64_t, , COUNT, "points_in", "points given")                 \
  X(duplicates_merged, uint64_t, , COUNT, "duplicates_merged",                 \
    "exact duplicates of an earlier point")                                    \
  X(delaunay_vertices, uint64_t, , COUNT, "delaunay_vertices",                 \
    "distinct points in the triangulation")                                    \
  X(delaunay_cells, uint64_t, , COUNT, "delaunay_cells", "finite tetrahedra")  \
  X(delaunay_facets, uint64_t, , COUNT, "delaunay_facets", "finite triangles") \
  X(hull_vertices, uint64_t, , COUNT, "hull_vertices",                         \
    "samples on the convex hull")                                              \
  X(degenerate_cells, uint64_t, , COUNT, "degenerate_cells",                   \
    "flat cells whose circumcentre was guarded")                               \
  X(candidates, uint64_t, , COUNT, "candidates",                               \
    "triangles passing the candidate test")                                    \
  X(pruned, uint64_t, , COUNT, "pruned",                                       \
    "candidates removed for a sharp edge")                                     \
  X(triangles, uint64_t, , COUNT, "triangles", "triangles in the output")      \
  X(walk_rejected, uint64_t, , COUNT, "walk_rejected",                         \
    "survivors of pruning left out by the walk")                               \
  X(holes_filled, uint64_t, , COUNT, "holes_filled",                           \
    "small holes closed after the walk")                                       \
  X(hole_triangles, uint64_t, , COUNT, "hole_triangles",                       \
    "triangles added to close them")                                           \
  X(samples_unused, uint64_t, , COUNT, "samples_unused",                       \
    "distinct samples in no output triangle")                                  \
  X(mostly_unused, int, , BOOL, "mostly_unused",                               \
    "1 when more than half of the distinct samples are in no output "          \
    "triangle (so always when the output is empty), else 0")                   \
  X(boundary_edges, uint64_t, , COUNT, "boundary_edges",                       \
    "output edges with a single triangle")                                     \
  X(boundary_loops, uint64_t, , COUNT, "boundary_loops",                       \
    "closed loops of boundary edges")                                          \
  X(nonmanifold_edges, uint64_t, , COUNT, "nonmanifold_edges",                 \
    "always 0 on success; kept as a check")                                    \
  X(nonmanifold_vertices, uint64_t, , COUNT, "nonmanifold_vertices",           \
    "always 0 on success; kept as a check")                                    \
  X(components, uint64_t, , COUNT, "components",                               \
    "edge-connected components of the output")                                 \
  X(closed_components, uint64_t, , COUNT, "closed_components",                 \
    "components without boundary")                                             \
  X(closed, int, , BOOL, "closed",                                             \
    "1 when the whole output has no boundary, else 0")                         \
  X(euler, int64_t, , INT, "euler", "V - E + F over the used vertices")        \
  X(genus, int64_t, , INT, "genus",                                            \
    "sum of the genera of the closed components")                              \
  X(seconds, double, [SC_STAGE_COUNT], STAGE_SECONDS, "seconds",               \
    "wall time of each stage, in seconds")                                     \
  X(seconds_total, double, , SECONDS, "seconds.total",                         \
    "wall time of the whole reconstruction, in seconds")                       \
  X(path, int, , PATH, "path",                                                 \
    "the path taken: what auto mode chose, and how watertight mode (or auto "  \
    "mode) closed the surface (the SC_PATH_ values)")                          \
  X(boundary_samples, uint64_t, , COUNT, "boundary_samples",                   \
    "samples found not interior (0 in the shortcrust and cocone modes)")       \
  X(longest_loop, uint64_t, , COUNT, "longest_loop",                           \
    "edges in the longest boundary loop")                                      \
  X(loops_by_length, uint64_t, [SC_LOOP_BINS], LOOPS, "loops",                 \
    "boundary loops by length in edges")                                       \
  X(cells_relabelled, uint64_t, , COUNT, "cells_relabelled",                   \
    "watertight: cells moved to the other label to keep a manifold")           \
  X(bubbles_dropped, uint64_t, , COUNT, "bubbles_dropped",                     \
    "small closed components removed (boundary, watertight and auto modes)")   \
  X(samples_attached, uint64_t, , COUNT, "samples_attached",                   \
    "samples left out by extraction, then inserted into the nearest "          \
    "triangle")                                                                \
  X(handles_cut, uint64_t, , COUNT, "handles_cut",                             \
    "watertight: handles that closed round a hole, cut before closing")        \
  X(small_handles_cut, uint64_t, , COUNT, "small_handles_cut",                 \
    "watertight: small handles cut from the closure by labels, beyond the "    \
    "extracted surface's genus")                                               \
  X(hull_facets, uint64_t, , COUNT, "hull_facets",                             \
    "triangles of the convex hull")                                            \
  X(spacing, double, , REAL, "spacing",                                        \
    "estimated sample spacing, in the input's units")                          \
  X(noise, double, , REAL, "noise",                                            \
    "estimated noise: RMS distance of the samples to their local surface, in " \
    "spacings")                                                                \
  X(curvature, double, , REAL, "curvature",                                    \
    "median of the local surface's larger curvature times the spacing; above " \
    "0.15 + noise / 2 the sample is too coarse to tell noise, and denoising "  \
    "does not smooth")                                                         \
  X(denoised, int, , BOOL, "denoised",                                         \
    "1 when the surface was reconstructed on a smoothed copy of the points")   \
  X(denoise_scale, double, , REAL, "denoise_scale",                            \
    "the smoothing neighbourhood's radius, in the input's units (0 without "   \
    "denoising)")                                                              \
  X(denoise_shift, double, , REAL, "denoise_shift",                            \
    "RMS distance the smoothing moved the samples, in spacings")               \
  X(seconds_denoise, double, , SECONDS, "seconds.denoise",                     \
    "wall time of the noise estimate and the smoothing, in seconds (part of "  \
    "the input stage)")                                                        \
  X(tiles, uint64_t, , COUNT, "tiles",                                         \
    "tiles the points were split into (0: one triangulation of all)")          \
  X(tile_points_foreign, uint64_t, , COUNT, "tile_points_foreign",             \
    "points triangulated in a tile besides its own: the tiles' overhead; "     \
    "with tiles 0, those a tile had taken in, or had found it must, when it "  \
    "gave up")                                                                 \
  X(labelled, int, , BOOL, "labelled",                                         \
    "watertight: 1 when the Delaunay cells were labelled inside or outside "   \
    "for a closure (the patches left doubt, or watertight_labels); path "      \
    "watertight-fill then means that the patches' closure was kept, cocone "   \
    "that the cocone test's surface at every sample was")                      \
  X(checked, int, , BOOL, "checked",                                           \
    "shortcrust: 1 when the surface was checked against the one the cocone "   \
    "test gives on the same triangulation, else 0 (other modes); in a tile "   \
    "job's result, 1 when its triangles carry what the check needs")           \
  X(r_used, double, , REAL, "r_used",                                          \
    "shortcrust: the r of the surface given: r, or the nearest value within "  \
    "0.02 whose surface is the cocone test's closed one where r's is not")     \
  X(check_components, uint64_t, , COUNT, "check_components",                   \
    "shortcrust: components of the cocone test's surface")                     \
  X(check_closed_components, uint64_t, , COUNT, "check_closed_components",     \
    "shortcrust: its components without boundary")                             \
  X(check_genus, int64_t, , INT, "check_genus",                                \
    "shortcrust: the sum of the genera of its closed components")              \
  X(topology_doubt, int, , BOOL, "topology_doubt",                             \
    "shortcrust: 1 when the two surfaces differ in components, closed "        \
    "components or genus: the sample is too sparse for r, or for one of "      \
    "the tests, to be sure of the topology")                                   \
  X(tile_near_0, uint64_t, , COUNT, "tile_near_0",                             \
    "shortcrust tile job with its check: of its triangles, the first this "    \
    "many pass the criteria at r - 0.02")                                      \
  X(tile_near_1, uint64_t, , COUNT, "tile_near_1",                             \
    "the next this many pass them first at r - 0.01")                          \
  X(tile_near_2, uint64_t, , COUNT, "tile_near_2",                             \
    "the next this many first at r")                                           \
  X(tile_near_3, uint64_t, , COUNT, "tile_near_3",                             \
    "the next this many first at r + 0.01")                                    \
  X(tile_near_4, uint64_t, , COUNT, "tile_near_4",                             \
    "the next this many first at r + 0.02; the rest pass the cocone test")

typedef struct sc_diag {
#define SC_DIAG_FIELD_(field, type, dim, kind, wire, help) type field dim;
  SC_DIAG_MAP(SC_DIAG_FIELD_)
#undef SC_DIAG_FIELD_
} sc_diag_t;

/* The diagnostic table as data: sc_diag_table() returns its rows in order
 * and sets *count. Arrays (STAGE_SECONDS, LOOPS) have count elements, named
 * on the wire "wire.SUFFIX" with sc_diag_element_name()'s suffix. */
typedef enum sc_diag_kind {
  SC_DIAG_COUNT,
  SC_DIAG_BOOL,
  SC_DIAG_INT,
  SC_DIAG_REAL,
  SC_DIAG_PATH,
  SC_DIAG_STAGE_SECONDS,
  SC_DIAG_SECONDS,
  SC_DIAG_LOOPS
} sc_diag_kind_t;
typedef struct sc_diag_info {
  const char *name; /* the field's name, and the report's */
  sc_diag_kind_t kind;
  size_t offset;    /* of the field in sc_diag_t */
  size_t count;     /* elements: 1, or those of an array */
  const char *wire; /* the name in JOB_DONE, or the arrays' prefix */
  const char *help;
} sc_diag_info_t;
const sc_diag_info_t *sc_diag_table(size_t *count);
/* The wire suffix of element i of an array row ("delaunay", "3_10"); NULL
 * for a scalar row or i out of range. */
const char *sc_diag_element_name(const sc_diag_info_t *row, size_t i);

/* Denoising (params.denoise, and auto mode by itself) smooths the points
 * only when the estimated noise (sc_diag_t.noise) is at least this many
 * sample spacings, and the sample resolves its surface (sc_diag_t.curvature
 * at most 0.15 + noise / 2): below the floor the Delaunay filtering needs
 * no help, and on a coarse sample what the estimate takes for noise is the
 * shape, which smoothing would flatten. The estimate reads about 0.09 at a
 * noise of 0.1 spacings, where the filtering alone starts to fail. A
 * denoise_scale given by the caller smooths whatever the estimate.
 * (docs/algorithm.md section 16.) */
#define SC_NOISE_FLOOR 0.08

/* Values of sc_diag_t.path: X(NAME, value, name).
 *  - SHORTCRUST: the paper's criteria.
 *  - COCONE: the cocone test everywhere (in the watertight and auto modes,
 *    its surface kept over the closures: docs/algorithm.md section 11.5).
 *  - BOUNDARY: the cocone test at interior samples only.
 *  - WATERTIGHT: closed by labelling cells (or nothing was open).
 *  - WATERTIGHT_FILL: closed by patches over the holes. */
#define SC_PATH_MAP(X)                                                         \
  X(SHORTCRUST, 0, "shortcrust")                                               \
  X(COCONE, 1, "cocone")                                                       \
  X(BOUNDARY, 2, "boundary")                                                   \
  X(WATERTIGHT, 3, "watertight")                                               \
  X(WATERTIGHT_FILL, 4, "watertight-fill")

typedef enum sc_path {
#define SC_PATH_ENUM_(name, value, str) SC_PATH_##name = (value),
  SC_PATH_MAP(SC_PATH_ENUM_)
#undef SC_PATH_ENUM_
  SC_PATH_COUNT_
} sc_path_t;

/* Short name of a path ("cocone", "boundary", "watertight-fill", ...);
 * "?" when out of range. */
const char *sc_path_name(int path);

/* The result of a reconstruction. Free with sc_mesh_free(). */
typedef struct sc_mesh {
  /* 3 * triangle_count indices into the caller's point array. Every closed
   * component is oriented outward (counter-clockwise seen from outside).
   * Each triangle starts at its smallest index, and the triangles come in
   * increasing order, index by index: the same surface gives the same
   * array, however the points were added. */
  uint32_t *triangles;
  size_t triangle_count;
  /* 3 * point_count unit normals, one per input point, oriented like the
   * triangles around it; zero for a point in no triangle. A duplicate gets
   * its first occurrence's normal. */
  double *normals;
  size_t point_count;
  /* Genus of each closed component, component_count entries in the order
   * the components were found; -1 for a component with boundary. */
  int32_t *component_genus;
  size_t component_count;
  sc_diag_t diag;
  /* With params.smoothed_vertices and denoising on: 3 * point_count
   * coordinates, the smoothed position of each input point (a duplicate's
   * is its first occurrence's); NULL otherwise. */
  double *smoothed;
} sc_mesh_t;

void sc_mesh_free(sc_mesh_t *mesh);

/*
 * One-call reconstruction of n points (xyz holds 3n doubles). On success
 * returns 0 and sets *out to a mesh the caller frees. On failure returns a
 * negative code, sets *out to NULL, and writes a one-line explanation (for
 * example the index of the first non-finite coordinate) to msg when msg is
 * not NULL.
 */
int sc_reconstruct(const double *xyz, size_t n, const sc_params_t *params,
                   sc_mesh_t **out, char *msg, size_t msg_len);

/*
 * A job whose tiles ran apart (params.tile_count, above), finished: tiles
 * holds the results of the count tile jobs of these same points and
 * parameters (tile_count = count, tile_index 0 to count - 1, in any order).
 * A tile job's result holds, in triangles, the candidate triangles the
 * tile decides (input indices, no orientation: not a mesh), in normals the
 * pole of each point it owns (zero for the others), no components, and in
 * diag what it owns, with diag.tiles the number of tiles (0 when the points
 * cannot be tiled: the merge then reconstructs on one triangulation).
 * params is the job's, tile_count and tile_index aside (they are ignored).
 * The mesh is the one sc_reconstruct() gives without tiles, triangle for
 * triangle; the normals too when every tile result carries its normals.
 * SC_EINVALID_ARGUMENT for results that cannot be those of this job's
 * tiles (another point count, an index out of range, a triangle twice).
 */
int sc_reconstruct_merge(const double *xyz, size_t n, const sc_params_t *params,
                         const sc_mesh_t *const *tiles, size_t count,
                         sc_mesh_t **out, char *msg, size_t msg_len);

/*
 * Streaming reconstruction, for points that arrive in chunks: the Delaunay
 * insertion of each chunk runs in sc_recon_add(), while later chunks are
 * still on their way.
 *
 *   sc_recon_t *r;  sc_recon_new(&params, &r);
 *   sc_recon_add(r, chunk, k, ...);   (any number of times)
 *   sc_recon_finish(r, &mesh, ...);
 *   sc_recon_free(r);
 *
 * Indices in the result count the points in the order they were added. A
 * failed sc_recon_add() leaves the reconstruction unusable except for
 * sc_recon_free(). Not thread-safe: one thread at a time per object.
 */
typedef struct sc_recon sc_recon_t;

int sc_recon_new(const sc_params_t *params, sc_recon_t **out);
int sc_recon_add(sc_recon_t *r, const double *xyz, size_t n, char *msg,
                 size_t msg_len);
int sc_recon_finish(sc_recon_t *r, sc_mesh_t **out, char *msg, size_t msg_len);
void sc_recon_free(sc_recon_t *r);

/* Approximate bytes a reconstruction of n points holds at its peak, for
 * admission control. Measured; see the README. */
uint64_t sc_estimate_bytes(uint64_t n);

/*
 * Asks the C library's allocator to keep the memory a reconstruction frees
 * for the next allocation instead of handing it back to the system: a
 * reconstruction allocates and frees buffers of tens of megabytes, and with
 * glibc's defaults each such buffer is a fresh mapping whose pages are
 * faulted in one by one (a sixth of the time on 362k points). Process-wide
 * (glibc's mallopt(): no mmap for large blocks, no trimming on free), so it
 * is for programs to call, once, before their first reconstruction. (A
 * program that reconstructs on several threads and must shrink when idle
 * should not: malloc_trim() does not shrink the heaps of threads' arenas.)
 * Returns 0, or SC_EINTERNAL when the allocator is not glibc's or refused.
 */
int sc_tune_allocator(void);

/*
 * Hands back to the system what the allocators keep of the memory that
 * finished reconstructions freed: the C library's free pages (glibc's
 * malloc_trim()) and the pools of TBB's allocator, in which CGAL's k-d
 * trees keep their nodes. For a long-running program, when it is idle.
 */
void sc_release_memory(void);

#ifdef __cplusplus
}
#endif

#endif /* SHORTCRUST_H */
