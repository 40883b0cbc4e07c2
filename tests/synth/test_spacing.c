/*
 * How the samples are spaced, against what synth.h promises and what
 * theory says, measured by each point's nearest-neighbour distance in units
 * of scs_surface_spacing() (sqrt(area / n)):
 *
 *  - UNIFORM is well spaced on every surface: no two points closer than
 *    0.63 units, the median 0.76 to 0.80, none above 1.45. (Measured: at
 *    least 0.667, medians 0.779 to 0.785, at most 1.33.) The median is the
 *    same on every surface only if the stated areas are right (a 5% error
 *    in an area moves it out of the band), so this checks those too.
 *  - UNIFORM_RANDOM is a Poisson sample: its median nearest-neighbour
 *    distance is sqrt(ln 2 / pi) = 0.470 units (measured 0.466 to 0.470),
 *    and it has near-collisions.
 *  - ADAPTIVE is UNIFORM on surfaces of constant curvature; elsewhere the
 *    spacing follows the curvature: on the nested spheres (curvatures 2
 *    and 1, densities 4 : 1) half the points are on the inner sphere and
 *    their spacing is half that of the outer one.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "sct_assert.h"
#include "synth.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/*
 * Nearest-neighbour distances by a uniform grid of cell size h: rings of
 * cells around a point's own are searched until no unsearched cell can
 * hold anything closer.
 */
typedef struct grid {
  double lo[3], h;
  long dim[3];
  size_t *start; /* per cell, into order; dim product + 1 entries */
  size_t *order;
} grid_t;

static long clampl(long v, long lo, long hi) {
  return v < lo ? lo : v > hi ? hi : v;
}

static long cell_coord(const grid_t *g, const double *p, int k) {
  return clampl((long)((p[k] - g->lo[k]) / g->h), 0, g->dim[k] - 1);
}

static size_t cell_index(const grid_t *g, long x, long y, long z) {
  return ((size_t)z * (size_t)g->dim[1] + (size_t)y) * (size_t)g->dim[0] +
         (size_t)x;
}

static double *nearest(const double *xyz, size_t n, double h) {
  grid_t g;
  double hi[3];
  for (int k = 0; k < 3; k++)
    g.lo[k] = hi[k] = xyz[k];
  for (size_t i = 0; i < n; i++)
    for (int k = 0; k < 3; k++) {
      double v = xyz[3 * i + k];
      g.lo[k] = v < g.lo[k] ? v : g.lo[k];
      hi[k] = v > hi[k] ? v : hi[k];
    }
  g.h = h;
  size_t cells = 1;
  for (int k = 0; k < 3; k++) {
    g.dim[k] = (long)((hi[k] - g.lo[k]) / h) + 1;
    cells *= (size_t)g.dim[k];
  }
  g.start = calloc(cells + 1, sizeof *g.start);
  g.order = malloc(n * sizeof *g.order);
  size_t *cell = malloc(n * sizeof *cell);
  double *nn = malloc(n * sizeof *nn);
  if (!g.start || !g.order || !cell || !nn)
    abort();
  for (size_t i = 0; i < n; i++) {
    const double *p = xyz + 3 * i;
    cell[i] = cell_index(&g, cell_coord(&g, p, 0), cell_coord(&g, p, 1),
                         cell_coord(&g, p, 2));
    g.start[cell[i] + 1]++;
  }
  for (size_t c = 0; c < cells; c++)
    g.start[c + 1] += g.start[c];
  size_t *fill = malloc((cells + 1) * sizeof *fill);
  if (!fill)
    abort();
  memcpy(fill, g.start, (cells + 1) * sizeof *fill);
  for (size_t i = 0; i < n; i++)
    g.order[fill[cell[i]]++] = i;
  free(fill);

  for (size_t i = 0; i < n; i++) {
    const double *p = xyz + 3 * i;
    long c[3] = {cell_coord(&g, p, 0), cell_coord(&g, p, 1),
                 cell_coord(&g, p, 2)};
    double best = HUGE_VAL;
    /* Ring r covers cells at Chebyshev distance r; anything beyond it is
     * at least r * h away. */
    for (long r = 0; r <= g.dim[0] + g.dim[1] + g.dim[2]; r++) {
      if (best <= (double)(r - 1) * h * (double)(r - 1) * h)
        break;
      long a[3], b[3];
      for (int k = 0; k < 3; k++) {
        a[k] = clampl(c[k] - r, 0, g.dim[k] - 1);
        b[k] = clampl(c[k] + r, 0, g.dim[k] - 1);
      }
      for (long z = a[2]; z <= b[2]; z++)
        for (long y = a[1]; y <= b[1]; y++)
          for (long x = a[0]; x <= b[0]; x++) {
            if (labs(x - c[0]) != r && labs(y - c[1]) != r &&
                labs(z - c[2]) != r)
              continue;
            size_t ci = cell_index(&g, x, y, z);
            for (size_t k = g.start[ci]; k < g.start[ci + 1]; k++) {
              size_t j = g.order[k];
              if (j == i)
                continue;
              const double *q = xyz + 3 * j;
              double dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2];
              double d2 = dx * dx + dy * dy + dz * dz;
              best = d2 < best ? d2 : best;
            }
          }
    }
    nn[i] = sqrt(best);
  }
  free(g.start);
  free(g.order);
  free(cell);
  return nn;
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

typedef struct stats {
  double min, median, max;
} stats_t;

/* Order statistics of v[0..n), in place, scaled by 1 / unit. */
static stats_t stats_of(double *v, size_t n, double unit) {
  qsort(v, n, sizeof *v, cmp_double);
  return (stats_t){v[0] / unit, v[n / 2] / unit, v[n - 1] / unit};
}

static double *sample(scs_surface_t s, int d, size_t n, uint64_t seed) {
  double *xyz = malloc(3 * n * sizeof *xyz);
  if (!xyz)
    abort();
  EXPECT_EQ(scs_sample_surface(s, d, n, seed, xyz), SCS_OK);
  return xyz;
}

/* The well-spaced band of UNIFORM, and of ADAPTIVE where it is uniform. */
static void check_spaced(scs_surface_t s, int d, size_t n, uint64_t seed) {
  double *xyz = sample(s, d, n, seed);
  double unit = scs_surface_spacing(s, n);
  double *nn = nearest(xyz, n, unit);
  stats_t st = stats_of(nn, n, unit);
  EXPECT_MSG(st.min >= 0.63 && st.median >= 0.76 && st.median <= 0.80 &&
                 st.max <= 1.45,
             "%s/%s n=%zu: nearest neighbours min %.3f median %.3f max %.3f",
             scs_surface_name(s), scs_density_name(d), n, st.min, st.median,
             st.max);
  free(nn);
  free(xyz);
}

static void test_uniform(void) {
  for (int s = 0; s < SCS_SURF_COUNT; s++)
    check_spaced((scs_surface_t)s, SCS_DENSITY_UNIFORM, 4000, 5);
  /* Small and larger samples alike. */
  check_spaced(SCS_SURF_SPHERE, SCS_DENSITY_UNIFORM, 300, 6);
  check_spaced(SCS_SURF_TORUS, SCS_DENSITY_UNIFORM, 30000, 7);
  /* Constant curvature: ADAPTIVE has nothing to adapt to. */
  check_spaced(SCS_SURF_SPHERE, SCS_DENSITY_ADAPTIVE, 4000, 5);
  check_spaced(SCS_SURF_TWO_SPHERES, SCS_DENSITY_ADAPTIVE, 4000, 5);
  check_spaced(SCS_SURF_TORUS, SCS_DENSITY_ADAPTIVE, 4000, 5);
}

/* A Poisson sample of density n / A: P(nn > r) = exp(-pi r^2 n / A). */
static void test_random(void) {
  const double median = 0.46971863934982566; /* sqrt(ln 2 / pi) */
  for (int s = 0; s < SCS_SURF_COUNT; s++) {
    size_t n = 20000;
    double *xyz = sample((scs_surface_t)s, SCS_DENSITY_UNIFORM_RANDOM, n, 8);
    double unit = scs_surface_spacing((scs_surface_t)s, n);
    double *nn = nearest(xyz, n, unit);
    stats_t st = stats_of(nn, n, unit);
    EXPECT_NEAR(st.median, median, 0.012);
    EXPECT_LT(st.min, 0.1);
    free(nn);
    free(xyz);
  }
}

/* Nested spheres: densities 4 : 1 on areas 1 : 4 put half the points on
 * the inner sphere, at half the spacing. */
static void test_adaptive(void) {
  size_t n = 8000;
  double *xyz = sample(SCS_SURF_NESTED_SPHERES, SCS_DENSITY_ADAPTIVE, n, 9);
  double *nn = nearest(xyz, n, scs_surface_spacing(SCS_SURF_NESTED_SPHERES, n));
  double *in = malloc(n * sizeof *in), *out = malloc(n * sizeof *out);
  if (!in || !out)
    abort();
  size_t n_in = 0, n_out = 0;
  for (size_t i = 0; i < n; i++) {
    const double *p = xyz + 3 * i;
    if (p[0] * p[0] + p[1] * p[1] + p[2] * p[2] < 0.75 * 0.75)
      in[n_in++] = nn[i];
    else
      out[n_out++] = nn[i];
  }
  EXPECT_NEAR((double)n_in / (double)n, 0.5, 0.02);
  stats_t si = stats_of(in, n_in, 1), so = stats_of(out, n_out, 1);
  EXPECT_NEAR(so.median / si.median, 2.0, 0.15);
  /* Each sphere on its own is well spaced at its own density. */
  double unit_in = sqrt(3.14159265358979323846 * 0.25 * 4 / (double)n_in);
  EXPECT_MSG(si.min / unit_in >= 0.55, "inner sphere: min %.3f units",
             si.min / unit_in);
  free(in);
  free(out);
  free(nn);
  free(xyz);

  /* The ellipsoid: closer points at the curved tips of its long axis than
   * at its flat poles, by up to sqrt(6) (measured 2.12). */
  n = 6000;
  xyz = sample(SCS_SURF_ELLIPSOID, SCS_DENSITY_ADAPTIVE, n, 5);
  nn = nearest(xyz, n, scs_surface_spacing(SCS_SURF_ELLIPSOID, n));
  double *tip = malloc(n * sizeof *tip), *flat = malloc(n * sizeof *flat);
  if (!tip || !flat)
    abort();
  size_t n_tip = 0, n_flat = 0;
  for (size_t i = 0; i < n; i++) {
    if (fabs(xyz[3 * i]) > 0.97)
      tip[n_tip++] = nn[i];
    if (fabs(xyz[3 * i + 2]) > 0.29)
      flat[n_flat++] = nn[i];
  }
  EXPECT_MSG(n_tip > 100 && n_flat > 100, "%zu tip and %zu flat points", n_tip,
             n_flat);
  double ratio =
      stats_of(flat, n_flat, 1).median / stats_of(tip, n_tip, 1).median;
  EXPECT_MSG(ratio > 1.8 && ratio < 2.6, "flat / tip spacing %.3f", ratio);
  free(tip);
  free(flat);
  free(nn);
  free(xyz);
}

/* The grid search against brute force, on a sample with clumps. */
static void test_nearest(void) {
  size_t n = 700;
  double *xyz = sample(SCS_SURF_GENUS2, SCS_DENSITY_UNIFORM_RANDOM, n, 10);
  /* A far outlier, so that rings must grow well past the first. */
  xyz[0] = 5;
  double *nn = nearest(xyz, n, 0.05);
  for (size_t i = 0; i < n; i++) {
    double best = HUGE_VAL;
    for (size_t j = 0; j < n; j++) {
      if (j == i)
        continue;
      double d2 = 0;
      for (int k = 0; k < 3; k++)
        d2 += (xyz[3 * i + k] - xyz[3 * j + k]) *
              (xyz[3 * i + k] - xyz[3 * j + k]);
      best = d2 < best ? d2 : best;
    }
    EXPECT_NEAR(nn[i], sqrt(best), 0);
  }
  free(nn);
  free(xyz);
}

int main(void) {
  test_nearest();
  test_uniform();
  test_random();
  test_adaptive();
  return sct_finish("synth_spacing");
}
