/*
 * Samples of every surface at every density: exactly n points, each on the
 * surface, inside its box, and the same bytes for the same seed; a
 * different seed gives different points. Also the proportions an
 * area-uniform sample must show, and the names.
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

enum { N = 1500 };

/* A guard value after the n points shows a sampler writing past them. */
static const double guard = -12345.678;

static double *sample(scs_surface_t s, int d, size_t n, uint64_t seed) {
  double *xyz = malloc((3 * n + 3) * sizeof *xyz);
  if (!xyz)
    abort();
  for (int k = 0; k < 3; k++)
    xyz[3 * n + k] = guard;
  int rc = scs_sample_surface(s, d, n, seed, xyz);
  EXPECT_EQ(rc, SCS_OK);
  for (int k = 0; k < 3; k++)
    EXPECT_MSG(xyz[3 * n + k] == guard, "%s/%s wrote past %zu points",
               scs_surface_name(s), scs_density_name(d), n);
  return xyz;
}

static void test_on_surface(void) {
  for (int s = 0; s < SCS_SURF_COUNT; s++)
    for (int d = 0; d < SCS_DENSITY_COUNT; d++) {
      const scs_surface_info_t *info = scs_surface_info((scs_surface_t)s);
      double *a = sample((scs_surface_t)s, d, N, 42);
      double *b = sample((scs_surface_t)s, d, N, 42);
      double *c = sample((scs_surface_t)s, d, N, 43);
      EXPECT_MSG(memcmp(a, b, 3 * N * sizeof *a) == 0,
                 "%s/%s: the same seed gave different points", info->name,
                 scs_density_name(d));
      size_t same = 0;
      for (size_t i = 0; i < N; i++)
        same += memcmp(a + 3 * i, c + 3 * i, 3 * sizeof *a) == 0;
      EXPECT_EQ(same, 0);
      double worst = 0;
      size_t outside = 0;
      for (size_t i = 0; i < N; i++) {
        const double *p = a + 3 * i;
        double dist = scs_surface_distance((scs_surface_t)s, p);
        if (!(dist <= worst))
          worst = dist;
        for (int k = 0; k < 3; k++)
          outside += !(p[k] >= info->bbox_min[k] - 1e-12 &&
                       p[k] <= info->bbox_max[k] + 1e-12);
      }
      EXPECT_MSG(worst <= 1e-9, "%s/%s: a point %.3g from the surface",
                 info->name, scs_density_name(d), worst);
      EXPECT_EQ(outside, 0);
      free(a);
      free(b);
      free(c);
    }
}

/* The number asked for, at the edges too. */
static void test_counts(void) {
  static const size_t counts[] = {1, 2, 3, 10, 257};
  for (int d = 0; d < SCS_DENSITY_COUNT; d++)
    for (size_t i = 0; i < sizeof counts / sizeof counts[0]; i++) {
      double *a = sample(SCS_SURF_TORUS, d, counts[i], 7);
      free(a);
    }
  EXPECT_EQ(
      scs_sample_surface(SCS_SURF_SPHERE, SCS_DENSITY_UNIFORM, 0, 1, NULL),
      SCS_OK);
  double p[3];
  EXPECT_EQ(scs_sample_surface(SCS_SURF_COUNT, 0, 1, 1, p), SCS_EINVAL);
  EXPECT_EQ(scs_sample_surface((scs_surface_t)-1, 0, 1, 1, p), SCS_EINVAL);
  EXPECT_EQ(scs_sample_surface(SCS_SURF_SPHERE, SCS_DENSITY_COUNT, 1, 1, p),
            SCS_EINVAL);
  EXPECT_EQ(scs_sample_surface(SCS_SURF_SPHERE, -1, 1, 1, p), SCS_EINVAL);
  EXPECT_EQ(scs_sample_surface(SCS_SURF_SPHERE, 0, 1, 1, NULL), SCS_EINVAL);
  EXPECT_EQ(scs_sample_surface(SCS_SURF_SPHERE, SCS_DENSITY_UNIFORM,
                               (size_t)600000000, 1, p),
            SCS_EINVAL);
}

/*
 * Where the points land, against the exact area fractions (each count
 * binomial, allowed five standard deviations): each sphere of two-spheres
 * half, the inner of nested-spheres r^2 / (1 + r^2) = 1/5, the upper half
 * of the sphere half, and on the torus the outer half of the tube (rho >
 * R) (1 + 2r / (pi R)) / 2, which non-uniform angles would miss.
 */
static void test_proportions(void) {
  enum { M = 40000 };
  static const double pi = 3.14159265358979323846;
  for (int d = 0; d < SCS_DENSITY_COUNT; d++) {
    if (d == SCS_DENSITY_ADAPTIVE)
      continue; /* not area-uniform by design */
    struct {
      scs_surface_t s;
      double expect;
    } cases[] = {{SCS_SURF_TWO_SPHERES, 0.5},
                 {SCS_SURF_NESTED_SPHERES, 0.2},
                 {SCS_SURF_SPHERE, 0.5},
                 {SCS_SURF_TORUS, (1 + 2 * 0.35 / pi) / 2}};
    for (int c = 0; c < 4; c++) {
      double *a = sample(cases[c].s, d, M, 99);
      size_t hits = 0;
      for (size_t i = 0; i < M; i++) {
        const double *p = a + 3 * i;
        double rho2 = p[0] * p[0] + p[1] * p[1];
        switch (cases[c].s) {
        case SCS_SURF_TWO_SPHERES:
          hits += p[0] < 0;
          break;
        case SCS_SURF_NESTED_SPHERES:
          hits += rho2 + p[2] * p[2] < 0.5;
          break;
        case SCS_SURF_SPHERE:
          hits += p[2] > 0;
          break;
        default:
          hits += rho2 > 1;
          break;
        }
      }
      double q = cases[c].expect, sd = sqrt(M * q * (1 - q));
      EXPECT_NEAR((double)hits, M * q, 5 * sd);
      free(a);
    }
  }
  /* ADAPTIVE puts more points where the curvature is high: near the tips
   * of the ellipsoid's long axis (curvature 11) over twice what an
   * area-uniform sample has there (3.3 times, measured), and fewer at its
   * flat poles (curvature 0.8; 0.8 times, measured). */
  double *u = sample(SCS_SURF_ELLIPSOID, SCS_DENSITY_UNIFORM, M, 99);
  double *a = sample(SCS_SURF_ELLIPSOID, SCS_DENSITY_ADAPTIVE, M, 99);
  size_t tips_u = 0, tips_a = 0, flat_u = 0, flat_a = 0;
  for (size_t i = 0; i < M; i++) {
    tips_u += fabs(u[3 * i]) > 0.97;
    tips_a += fabs(a[3 * i]) > 0.97;
    flat_u += fabs(u[3 * i + 2]) > 0.29;
    flat_a += fabs(a[3 * i + 2]) > 0.29;
  }
  EXPECT_LT(2.5 * (double)tips_u, (double)tips_a);
  EXPECT_LT((double)flat_a, 0.9 * (double)flat_u);
  free(u);
  free(a);
}

static void test_names(void) {
  for (int s = 0; s < SCS_SURF_COUNT; s++) {
    const char *name = scs_surface_name((scs_surface_t)s);
    EXPECT_EQ(scs_surface_from_name(name), s);
    EXPECT_MSG(strcmp(name, scs_surface_info((scs_surface_t)s)->name) == 0,
               "%s", name);
  }
  EXPECT_MSG(strcmp(scs_surface_name(SCS_SURF_COUNT), "?") == 0, "bad name");
  EXPECT_MSG(scs_surface_info(SCS_SURF_COUNT) == NULL, "info out of range");
  EXPECT_EQ(scs_surface_from_name("cube"), -1);
  EXPECT_EQ(scs_surface_from_name(NULL), -1);
  for (int d = 0; d < SCS_DENSITY_COUNT; d++)
    EXPECT_EQ(scs_density_from_name(scs_density_name(d)), d);
  EXPECT_MSG(strcmp(scs_density_name(SCS_DENSITY_COUNT), "?") == 0, "bad name");
  EXPECT_EQ(scs_density_from_name("dense"), -1);
  EXPECT_EQ(scs_density_from_name(NULL), -1);
  EXPECT_NEAR(scs_surface_spacing(SCS_SURF_SPHERE, 100),
              sqrt(4 * 3.14159265358979323846 / 100), 1e-15);
  EXPECT_NEAR(scs_surface_spacing(SCS_SURF_SPHERE, 0), 0, 0);
}

/* Samples of a mesh: a square of side 1 (two triangles) beside a
 * triangle of area 2 at z = 1. Every point lies on one of them, each gets
 * its share by area, the same seed gives the same points, and bad meshes
 * are refused. */
static void test_mesh(void) {
  const double v[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1,
                      0, 0, 0, 1, 2, 0, 1, 0, 2, 1};
  const uint32_t tri[] = {0, 1, 2, 0, 2, 3, 4, 5, 6};
  enum { M = 30000 };
  double *a = malloc(3 * M * sizeof *a), *b = malloc(3 * M * sizeof *b);
  EXPECT(a != NULL && b != NULL);
  if (!a || !b) {
    free(a);
    free(b);
    return;
  }
  EXPECT_NEAR(scs_mesh_area(v, tri, 3), 3, 1e-12);
  EXPECT_EQ(scs_sample_mesh(v, 7, tri, 3, M, 9, a), SCS_OK);
  EXPECT_EQ(scs_sample_mesh(v, 7, tri, 3, M, 9, b), SCS_OK);
  EXPECT_MSG(memcmp(a, b, 3 * M * sizeof *a) == 0, "same seed, other points");
  size_t square = 0, off = 0;
  for (size_t i = 0; i < M; i++) {
    const double *p = a + 3 * i;
    if (p[2] == 0)
      square += p[0] >= 0 && p[0] <= 1 && p[1] >= 0 && p[1] <= 1 ? 1 : 0;
    else if (!(fabs(p[2] - 1) <= 1e-12 && p[0] >= 0 && p[1] >= 0 &&
               p[0] + p[1] <= 2 + 1e-12))
      off++;
  }
  EXPECT_EQ(off, 0);
  /* A third of the area: binomial, within 5 standard deviations. */
  EXPECT_NEAR((double)square, M / 3.0, 5 * sqrt(M * (1 / 3.0) * (2 / 3.0)));
  const uint32_t bad[] = {0, 1, 7};
  EXPECT_EQ(scs_sample_mesh(v, 7, bad, 1, 10, 1, a), SCS_EINVAL);
  EXPECT_EQ(scs_sample_mesh(v, 7, tri, 0, 10, 1, a), SCS_EINVAL);
  const uint32_t flat[] = {0, 1, 1};
  EXPECT_EQ(scs_sample_mesh(v, 7, flat, 1, 10, 1, a), SCS_EINVAL);
  EXPECT_EQ(scs_sample_mesh(v, 7, tri, 3, 10, 1, NULL), SCS_EINVAL);
  free(a);
  free(b);
}

int main(void) {
  test_mesh();
  test_on_surface();
  test_counts();
  test_proportions();
  test_names();
  return sct_finish("synth_sample");
}
