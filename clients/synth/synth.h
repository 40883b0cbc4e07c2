/*
 * Synthetic input and a yardstick for shortcrust: seeded samples of analytic
 * closed surfaces whose topology is known, and a mesh checker that measures
 * reconstruction output without trusting anything the core reports about
 * itself. The tests, the benchmarks and the load generator all use it, so
 * it is a module of its own (prefix scs_) rather than part of the tests.
 *
 * Nothing here depends on core/ or any other module, so a bug in the core
 * cannot hide itself by also breaking the yardstick.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SCS_SYNTH_H
#define SCS_SYNTH_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Return codes of the functions below that can fail. */
#define SCS_OK 0
#define SCS_EINVAL (-1) /* an argument is out of range or NULL */
#define SCS_ENOMEM (-2) /* an allocation failed; nothing is left held */

/*
 * Random numbers: xoshiro256** seeded through splitmix64. Only integer
 * arithmetic, so a seed gives the same stream on every machine, which
 * rand() does not.
 */
typedef struct scs_rng {
  uint64_t s[4];
} scs_rng_t;

void scs_rng_seed(scs_rng_t *rng, uint64_t seed);
uint64_t scs_rng_next(scs_rng_t *rng);
/* Uniform in [0, 1), 53 random bits. */
double scs_rng_uniform(scs_rng_t *rng);
/* A standard normal deviate (Box-Muller). */
double scs_rng_gauss(scs_rng_t *rng);
/* Moves every coordinate of n points by a Gaussian of standard deviation
 * sigma (isotropic noise), drawn from the stream of seed. */
void scs_add_noise(double *xyz, size_t n, double sigma, uint64_t seed);

/*
 * The test surfaces. All are smooth and closed; units are chosen so each
 * fits in a box of a few units.
 *
 *   SPHERE          unit sphere at the origin.
 *   ELLIPSOID       semi-axes 1, 0.6, 0.3 along x, y, z.
 *   TORUS           axis z, R = 1, r = 0.35.
 *   GENUS2          a thickened figure eight, 1.5 * {q : F(q) = 0} with
 *                   F(x,y,z) = (x^4 - x^2 + y^2)^2 + (1.25 z)^2 - 0.15^2:
 *                   the band |x^4 - x^2 + y^2| <= 0.15 around a figure-eight
 *                   curve in the plane z = 0, with two holes around
 *                   (+-0.707, 0), swollen into z. It is smooth because F has
 *                   no critical point on its zero set (the critical values of
 *                   x^4 - x^2 + y^2 are 0 and -1/4, never +-0.15). Extent
 *                   about 3.2 x 1.9 x 0.36.
 *   TWO_SPHERES     radius 1 at (-1.6, 0, 0) and (1.6, 0, 0).
 *   NESTED_SPHERES  radii 1 and 0.5 at the origin.
 */
typedef enum scs_surface {
  SCS_SURF_SPHERE = 0,
  SCS_SURF_ELLIPSOID,
  SCS_SURF_TORUS,
  SCS_SURF_GENUS2,
  SCS_SURF_TWO_SPHERES,
  SCS_SURF_NESTED_SPHERES,
  SCS_SURF_COUNT
} scs_surface_t;

#define SCS_SURF_MAX_COMPONENTS 2

/*
 * What a correct reconstruction of a dense sample must reproduce. (The
 * struct has no tag: one named like scs_surface_info() would be hidden by
 * the function in C++, which -Wshadow reports.)
 */
typedef struct {
  const char *name;       /* "sphere", "ellipsoid", "torus", "genus2", ... */
  int components;         /* connected components */
  int genus[SCS_SURF_MAX_COMPONENTS]; /* genus of each component */
  int genus_total;
  double area;            /* total area; the genus-2 value is numerical */
  /* Volume enclosed by each component on its own (always positive). */
  double volume[SCS_SURF_MAX_COMPONENTS];
  double bbox_min[3], bbox_max[3];
  double max_curvature;   /* largest |principal curvature| anywhere */
} scs_surface_info_t;

/* NULL when s is out of range. */
const scs_surface_info_t *scs_surface_info(scs_surface_t s);
/* The name, or "?" when s is out of range. */
const char *scs_surface_name(scs_surface_t s);
/* The surface with that name, or -1. */
int scs_surface_from_name(const char *name);

/*
 * Densities of a sample.
 *
 *   UNIFORM_RANDOM  independent, area-uniform points. Such a sample has gaps
 *                   and clumps at every scale; it is the realistic worst case,
 *                   not something a reconstruction can be expected to get
 *                   right everywhere.
 *   UNIFORM         area-uniform and well spaced: k times more area-uniform
 *                   random candidates than asked for (k = 4 up to 200,000
 *                   points, then falling towards 2 at a few million), thinned
 *                   to exactly n by weighted sample elimination (Yuksel 2015:
 *                   repeatedly drop the candidate most crowded by its
 *                   neighbours within twice the ideal Poisson-disk radius).
 *                   Nearest-neighbour distances then lie in a narrow band
 *                   around the spacing, instead of reaching down to almost 0.
 *   ADAPTIVE        candidates drawn with area density proportional to k^2,
 *                   k the largest |principal curvature| (so the spacing
 *                   follows the radius of curvature, a stand-in for the local
 *                   feature size), clamped so the densest place is at most 6
 *                   times as dense as the sparsest; then thinned like UNIFORM
 *                   with the elimination radius scaled by the local spacing.
 *                   Constant-curvature surfaces (sphere, two spheres) come out
 *                   uniform; the torus almost so.
 */
typedef enum scs_density {
  SCS_DENSITY_UNIFORM_RANDOM = 0,
  SCS_DENSITY_UNIFORM = 1,
  SCS_DENSITY_ADAPTIVE = 2,
  SCS_DENSITY_COUNT
} scs_density_t;

/* "uniform-random", "uniform", "adaptive"; "?" when out of range. */
const char *scs_density_name(int density);
/* The density with that name, or -1. */
int scs_density_from_name(const char *name);

/*
 * Writes exactly n points (3n doubles, x y z) of surface s at the given
 * density into xyz. The same arguments give bit-identical points on every
 * machine with IEEE doubles: only + - * / and sqrt are used (no libm
 * transcendental functions) and the library is built without contraction
 * into fused multiply-adds. Every point lies on the surface to rounding
 * error (a few 1e-16 relative). The points come out in random order.
 *
 * Returns 0, SCS_EINVAL (bad surface or density, xyz NULL with n > 0, or n
 * too large for the well-spaced modes, over 500 million), or SCS_ENOMEM.
 * The well-spaced modes hold about 200 bytes per point while they run.
 */
int scs_sample_surface(scs_surface_t s, int density, size_t n, uint64_t seed,
                       double *xyz);

/*
 * Writes n points (3n doubles) spread uniformly at random over the
 * boundary of the union of nboxes axis-aligned boxes, each 6 doubles
 * (the low corner, then the high one): closed surfaces with sharp edges
 * and corners, thin parts and handles, whose topology follows from the
 * boxes. Parts of faces inside other boxes, and faces that two boxes
 * share, get no points. Bit-identical on every machine, as above.
 * Returns 0, SCS_EINVAL (a box empty or inverted, boxes or xyz NULL, or a
 * union whose faces are almost all inside it), or SCS_ENOMEM.
 */
int scs_sample_boxes(const double *boxes, size_t nboxes, size_t n,
                     uint64_t seed, double *xyz);

/*
 * Writes n points (3n doubles) spread uniformly at random over the ntri
 * triangles of a mesh (3 vertex indices each into the nv vertices, 3
 * doubles each): other samplings of a model than its vertex set.
 * Bit-identical on every machine, as above. Returns 0, SCS_EINVAL (an
 * index out of range, no triangle, a mesh of no area, or a NULL array),
 * or SCS_ENOMEM.
 */
int scs_sample_mesh(const double *vertices, size_t nv, const uint32_t *tri,
                    size_t ntri, size_t n, uint64_t seed, double *xyz);

/* The area of the ntri triangles of a mesh, as for scs_sample_mesh(). */
double scs_mesh_area(const double *vertices, const uint32_t *tri, size_t ntri);

/*
 * The boxes of a named shape for scs_sample_boxes(), for n samples, and
 * its genus (one component); returns how many boxes, or 0 for an unknown
 * name. Thin parts are two sample spacings thick.
 *   cube   the unit cube: sharp edges and corners;
 *   plate  a unit square plate: a thin part whose two sides are closer
 *          than the samples on each are apart, at random, in many places;
 *   fin    the unit cube with a fin standing out of one face: a thin part
 *          joined to a body along sharp edges;
 *   frame  a square frame (genus 1): a handle whose every edge is sharp.
 */
#define SCS_MAX_BOXES 4
size_t scs_box_shape(const char *name, size_t n,
                     double boxes[6 * SCS_MAX_BOXES], int *genus);

/*
 * Distance from p to the surface (to the nearest component). Exact up to
 * rounding for the spheres and the torus. For the ellipsoid and the genus-2
 * surface it is |p - q| for a surface point q found by Newton projection and
 * a foot-point iteration: never less than the true distance, and equal to it
 * within 1e-12 for points closer to the surface than about half the local
 * radius of curvature (which is where mesh vertices are). Far from those
 * two surfaces it is only an upper bound.
 */
double scs_surface_distance(scs_surface_t s, const double p[3]);

/*
 * Unit outward normal, at the surface point nearest p, of the component
 * nearest p; "outward" means away from the region that component encloses
 * on its own, so on the inner sphere of NESTED_SPHERES it points away from
 * the centre. Meant for points on or near the surface. Returns 0 or
 * SCS_EINVAL.
 */
int scs_surface_normal(scs_surface_t s, const double p[3], double n[3]);

/*
 * The typical spacing of n samples spread uniformly over s: sqrt(area / n).
 * In UNIFORM mode the nearest-neighbour distance is 0.67 to about 1.3
 * times this, with a median of 0.78 (UNIFORM_RANDOM: median 0.47, and
 * down to almost 0); in ADAPTIVE mode the spacing ranges over a factor of
 * up to sqrt(6) = 2.4 around it. Returns 0 for n == 0 or s out of range.
 */
double scs_surface_spacing(scs_surface_t s, size_t n);

/*
 * The mesh checker. It takes the point count n, the coordinates (3n
 * doubles; may be NULL, then areas and volumes are 0) and ntri triangles
 * as index triples, and measures everything a correct reconstruction must
 * satisfy. Definitions:
 *
 *  - A triangle with an index >= n is "out of range"; one that repeats an
 *    index is "degenerate". Both are counted and then left out of every
 *    other measurement. So is each extra copy of a triangle whose vertex
 *    set appeared before ("duplicate", whatever its orientation).
 *  - An edge is an unordered vertex pair of the remaining triangles. It is
 *    a boundary edge with one triangle and non-manifold with more than two.
 *  - An edge is an orientation error when some directed version of it is
 *    used by more than one triangle (two neighbours that disagree, or any
 *    non-manifold edge where that happens).
 *  - A vertex is non-manifold when its incident triangles, joined across
 *    the edges at that vertex, fall into more than one piece (two cones
 *    meeting at a point). A single closed or open fan is manifold; a vertex
 *    on a non-manifold edge is counted only through that edge.
 *  - Components are classes of triangles joined across shared edges. For
 *    each: V counts its distinct vertices, E its edges, F its triangles,
 *    chi = V - E + F, b its boundary loops (cycles of boundary edges, with a
 *    vertex where two fans touch kept apart), genus = (2 - chi - b) / 2, or
 *    -1 when that is not a non-negative integer.
 *  - The signed volume of a component is the sum over its triangles of
 *    det(a, b, c) / 6 (taken about the component's first vertex); positive
 *    means counter-clockwise seen from outside. It is meaningful only for a
 *    closed, consistently oriented component.
 */
typedef struct scs_meshcheck_component {
  uint64_t triangles;
  uint64_t edges;
  uint64_t vertices;
  uint64_t boundary_edges;
  uint64_t boundary_loops;
  int closed;         /* no boundary edge */
  int64_t euler;      /* V - E + F */
  int64_t genus;      /* see above; -1 when undefined */
  double area;
  double volume;      /* signed; see above */
} scs_meshcheck_component_t;

/* Untagged for the same reason as scs_surface_info_t. */
typedef struct {
  uint64_t points;               /* n */
  uint64_t triangles;            /* ntri, as given */
  uint64_t out_of_range;         /* triangles with an index >= n */
  uint64_t degenerate;           /* triangles repeating an index */
  uint64_t duplicates;           /* extra copies of a vertex set */
  uint64_t faces;                /* triangles measured: the rest */
  uint64_t edges;
  uint64_t vertices_used;        /* distinct vertices of measured triangles */
  uint64_t samples_unused;       /* points in no triangle and not ignored */
  uint64_t boundary_edges;
  uint64_t boundary_loops;
  uint64_t nonmanifold_edges;
  uint64_t nonmanifold_vertices;
  uint64_t orientation_errors;   /* edges, see above */
  uint64_t components;
  uint64_t closed_components;
  int64_t euler;                 /* vertices_used - edges + faces */
  int64_t genus_total;           /* sum over closed components */
  double area;
  double volume;                 /* sum over closed components */
  /* 1 when out_of_range, degenerate, duplicates, non-manifold edges and
   * vertices are all 0. */
  int manifold;
  int closed;                    /* manifold and no boundary edge */
  int oriented;                  /* no orientation error */
  /* One entry per component, ordered by their smallest triangle index. */
  scs_meshcheck_component_t *comp;
  size_t component_count;
} scs_meshcheck_t;

/*
 * Fills *out (which the caller then releases with scs_meshcheck_free()).
 * ignore, when not NULL, has n bytes; a point with a non-zero byte (an
 * exact duplicate the reconstruction is allowed to skip) is not counted in
 * samples_unused. Runs in O(n + ntri) time with sorts (test_speed prints
 * the time for two million triangles). Returns 0, SCS_EINVAL (NULL
 * pointers with non-zero counts, n >= 2^32, or more than 1.4e9 triangles)
 * or SCS_ENOMEM; on failure *out is zeroed.
 */
int scs_meshcheck(size_t n, const double *xyz, const uint32_t *tri,
                  size_t ntri, const unsigned char *ignore,
                  scs_meshcheck_t *out);
/* Releases what scs_meshcheck() allocated; accepts NULL and zeroed structs. */
void scs_meshcheck_free(scs_meshcheck_t *c);

/*
 * A one-line summary for test logs, such as
 * "faces=960 V=482 E=1440 comps=1 closed=1/1 genus=[0] chi=2 bnd=0/0 nm=0/0
 *  orient=0 degen=0 dup=0 oor=0 unused=0 vol=4.12"
 * (one line, no newline). Returns buf; truncates to len - 1 characters.
 */
char *scs_meshcheck_summary(const scs_meshcheck_t *c, char *buf, size_t len);

/* Flags of scs_meshcheck_expect(). */
#define SCS_EXPECT_ALL_USED 1u /* every point not ignored is a vertex */
#define SCS_EXPECT_OUTWARD 2u  /* every component has positive volume */

/*
 * Whether the checked mesh is what a correct reconstruction of surface s
 * gives: manifold, closed, consistently oriented, with the surface's number
 * of components and the same genus for each (compared as multisets), plus
 * the checks the flags ask for. Returns 1 when it is; otherwise 0, with the
 * first disagreement written to why (when not NULL) as one line.
 */
int scs_meshcheck_expect(const scs_meshcheck_t *c, scs_surface_t s,
                         unsigned flags, char *why, size_t why_len);

/* What scs_mesh_distance_check() found. */
typedef struct scs_distcheck {
  uint64_t vertices;  /* distinct in-range vertices of the triangles */
  uint64_t beyond;    /* of those, farther than tol from the surface */
  double max_distance;
  uint32_t worst;     /* the vertex at max_distance */
} scs_distcheck_t;

/*
 * Measures scs_surface_distance() for every vertex referenced by tri (out of
 * range indices are skipped; the checker counts them). Returns 0,
 * SCS_EINVAL or SCS_ENOMEM.
 */
int scs_mesh_distance_check(scs_surface_t s, size_t n, const double *xyz,
                            const uint32_t *tri, size_t ntri, double tol,
                            scs_distcheck_t *out);

#ifdef __cplusplus
}
#endif

#endif /* SCS_SYNTH_H */
