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

/* Candidate selection (ALGORITHM.md section 3, and section 6 for the rest). */
typedef enum sc_mode {
  /* The paper's two criteria (normal and small ball) with parameter r. */
  SC_MODE_SHORTCRUST = 0,
  /* The cocone test: the dual Voronoi edge meets the cocone of all three
   * vertices. */
  SC_MODE_COCONE = 1,
  /* For scans with a boundary (ALGORITHM.md section 6): samples are sorted
   * into interior and boundary ones (Dey and Giesen's ratio and normal
   * tests, parameters boundary_rho and boundary_alpha); the cocone test is
   * made only at interior vertices, and no edge at a boundary sample is
   * pruned, so the output is a 2-manifold with boundary. */
  SC_MODE_BOUNDARY = 2,
  /* Boundary mode, then every hole is closed: handles that closed round a
   * hole are cut, each boundary loop gets a least-area patch, and where
   * the patches cannot close the surface the Delaunay cells are labelled
   * inside or outside across it and the boundary of the inside cells is
   * taken. The output is a closed 2-manifold. When most samples are
   * found not interior (too sparse to tell a boundary from
   * undersampling), the input is taken as closed, as in auto mode: the
   * cocone test everywhere, and no handle cut. */
  SC_MODE_WATERTIGHT = 3,
  /* For input not known to be closed: the cocone test where the samples
   * look like a closed surface, boundary mode where they do not (diag.path
   * says which was taken). */
  SC_MODE_AUTO = 4,
  /* Count of modes; not a mode. */
  SC_MODE_COUNT_
} sc_mode_t;

/* The stages of a reconstruction, in the order they run. */
typedef enum sc_stage {
  SC_STAGE_INPUT = 0,      /* validation, duplicate detection */
  SC_STAGE_DELAUNAY = 1,   /* the 3D Delaunay triangulation */
  SC_STAGE_POLES = 2,      /* Voronoi vertices and poles */
  SC_STAGE_CANDIDATES = 3, /* one pass over the Delaunay facets */
  SC_STAGE_PRUNE = 4,      /* sharp-edge pruning */
  SC_STAGE_EXTRACT = 5,    /* manifold extraction and orientation */
  SC_STAGE_COUNT = 6
} sc_stage_t;

/* Short lower-case name of a stage ("delaunay", ...); "?" when out of range. */
const char *sc_stage_name(int stage);

/*
 * Progress callback: called from the thread running the reconstruction with
 * the current stage and the fraction of that stage done, in [0, 1]. Return 0
 * to go on, non-zero to cancel: the call then returns SC_ECANCELLED at the
 * next check (at most a few milliseconds of work later) and frees everything
 * it held.
 */
typedef int (*sc_progress_fn)(void *user, sc_stage_t stage, double fraction);

typedef struct sc_params {
  /* Candidate test. Default SC_MODE_COCONE. */
  sc_mode_t mode;
  /* Sampling parameter of the shortcrust criteria, in (0, 0.5). The paper
   * proves its guarantees for r < 1/7; larger values accept more triangles
   * on sparser or less even samples, and from about 0.2 on bridge nearby
   * parts of a surface. Default 0.18 (see the README for the measurements
   * behind it). Ignored by the cocone test. */
  double r;
  /* Half-width of the cocone around the plane normal to the pole, radians,
   * in (0, pi/2). Default pi/8: the cocone is |cos angle(y - s, pole)| <=
   * cos(pi/2 - theta). */
  double cocone_theta;
  /* Edges with a single candidate triangle. 0 (default): such an edge is
   * sharp only when its triangle hangs by it alone (two or more of its edges
   * have no other candidate), so fins go but a hole left by a missing
   * triangle stays small. 1: every such edge is sharp, exactly as in the
   * paper; one missing triangle then erodes the whole surface. */
  int paper_pruning;
  /* Holes whose boundary loop has at most this many edges are closed after
   * extraction by a least-area triangulation of the loop; 0 disables. In
   * [0, 100000]. Default 100. */
  int max_hole_edges;
  /* Threads for the Delaunay triangulation; 0 means one per core.
   * Default 1. */
  int threads;
  /* Optional progress and cancellation; NULL for none. */
  sc_progress_fn progress;
  void *progress_user;
  /* Boundary detection (boundary, watertight and auto modes). A sample
   * passes the ratio test when the farthest Voronoi vertex of its cell
   * inside its cocone is at most boundary_rho times the distance to its
   * negative pole; in (0, 10], default 1.3; 0 means the default (so that a
   * caller written before this field existed keeps working). */
  double boundary_rho;
  /* Poles of neighbouring interior samples agree when the angle between
   * them (unoriented) is at most this, radians, in (0, pi/2]; default
   * pi/9 (20 degrees); 0 means the default. */
  double boundary_alpha;
  /* Watertight mode: 0 (default) closes the holes with least-area patches
   * and labels the Delaunay cells only where the patches cannot close the
   * surface; 1 labels the cells first (inside or outside across the
   * surface; the output is the boundary of the inside cells) and patches
   * only when no cell comes out inside. */
  int watertight_labels;
} sc_params_t;

/* Fills *p with the documented defaults. */
void sc_params_init(sc_params_t *p);
/* Checks every field of *p against the ranges documented above, as
 * sc_reconstruct() does: SC_OK, or SC_EINVALID_ARGUMENT with the reason
 * in msg (when msg is not NULL). */
int sc_params_check(const sc_params_t *p, char *msg, size_t msg_len);

/* Diagnostics of one reconstruction (ALGORITHM.md section 7). */
typedef struct sc_diag {
  uint64_t points_in;          /* points given */
  uint64_t duplicates_merged;  /* exact duplicates of an earlier point */
  uint64_t delaunay_vertices;  /* distinct points in the triangulation */
  uint64_t delaunay_cells;     /* finite tetrahedra */
  uint64_t delaunay_facets;    /* finite triangles */
  uint64_t hull_vertices;      /* samples on the convex hull */
  uint64_t degenerate_cells;   /* flat cells whose circumcentre was guarded */
  uint64_t candidates;         /* triangles passing the candidate test */
  uint64_t pruned;             /* candidates removed for a sharp edge */
  uint64_t triangles;          /* triangles in the output */
  uint64_t walk_rejected;      /* survivors of pruning left out by the walk */
  uint64_t holes_filled;       /* small holes closed after the walk */
  uint64_t hole_triangles;     /* triangles added to close them */
  uint64_t samples_unused;     /* distinct samples in no output triangle */
  uint64_t boundary_edges;     /* output edges with a single triangle */
  uint64_t boundary_loops;     /* closed loops of boundary edges */
  uint64_t nonmanifold_edges;  /* always 0 on success; kept as a check */
  uint64_t nonmanifold_vertices; /* always 0 on success; kept as a check */
  uint64_t components;         /* edge-connected components of the output */
  uint64_t closed_components;  /* components without boundary */
  int closed;                  /* 1 when the whole output has no boundary */
  int64_t euler;               /* V - E + F over the used vertices */
  int64_t genus;               /* sum of the genera of closed components */
  double seconds[SC_STAGE_COUNT]; /* wall time per stage */
  double seconds_total;
  /* The path taken, one of the SC_PATH_ values below: what auto mode chose,
   * and whether watertight mode closed the surface with patches or had to
   * label cells. */
  int path;
  uint64_t boundary_samples;  /* samples found not interior (0 in the
                                 shortcrust and cocone modes) */
  uint64_t longest_loop;      /* edges in the longest boundary loop */
  /* Boundary loops by length in edges: 3-10, 11-100, 101-1000, > 1000. */
  uint64_t loops_by_length[4];
  uint64_t cells_relabelled;  /* watertight: cells moved to the other label
                                 to make the surface a manifold */
  uint64_t bubbles_dropped;   /* small closed components removed (boundary,
                                 watertight and auto modes) */
  uint64_t samples_attached;  /* samples left out by extraction and then
                                 inserted into the nearest triangle */
  uint64_t handles_cut;       /* watertight: handles that closed round a
                                 hole, cut before the holes were closed */
} sc_diag_t;

/* Values of sc_diag_t.path. */
typedef enum sc_path {
  SC_PATH_SHORTCRUST = 0,      /* the paper's criteria */
  SC_PATH_COCONE = 1,          /* the cocone test everywhere */
  SC_PATH_BOUNDARY = 2,        /* the cocone test at interior samples only */
  SC_PATH_WATERTIGHT = 3,      /* closed by labelling cells (or nothing
                                  was open) */
  SC_PATH_WATERTIGHT_FILL = 4, /* closed by patches over the holes */
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

#ifdef __cplusplus
}
#endif

#endif /* SHORTCRUST_H */
