/*
 * Timings at full size: a million samples, and the checker on two million
 * triangles. The times are printed for the log, not asserted (machines
 * differ); what is asserted is that the results are still right at this
 * size, where index widths and sort passes would show their limits.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "sct_assert.h"
#include "synth.h"
#include "testsupport.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static void time_sampling(scs_surface_t s, int d, size_t n) {
  double *xyz = malloc(3 * n * sizeof *xyz);
  if (!xyz)
    abort();
  double t0 = sct_seconds();
  int rc = scs_sample_surface(s, d, n, 1, xyz);
  double t1 = sct_seconds();
  EXPECT_EQ(rc, SCS_OK);
  double worst = 0;
  for (size_t i = 0; i < n; i++) {
    double dist = scs_surface_distance(s, xyz + 3 * i);
    worst = dist > worst || dist != dist ? dist : worst;
  }
  EXPECT_LE(worst, 1e-9);
  printf("sample %s/%s, %zu points: %.3f s\n", scs_surface_name(s),
         scs_density_name(d), n, t1 - t0);
  free(xyz);
}

/* A torus as a U x V grid of quads, two triangles each, outward. */
static void time_meshcheck(void) {
  enum { U = 1000, V = 1000 };
  const double pi = 3.14159265358979323846, R = 1, r = 0.35;
  size_t n = (size_t)U * V, ntri = 2 * n;
  double *xyz = malloc(3 * n * sizeof *xyz);
  uint32_t *tri = malloc(3 * ntri * sizeof *tri);
  if (!xyz || !tri)
    abort();
  for (uint32_t i = 0; i < U; i++)
    for (uint32_t j = 0; j < V; j++) {
      double u = 2 * pi * i / U, v = 2 * pi * j / V, rho = R + r * cos(v);
      double *p = xyz + 3 * ((size_t)V * i + j);
      p[0] = rho * cos(u);
      p[1] = rho * sin(u);
      p[2] = r * sin(v);
    }
  uint32_t *t = tri;
  for (uint32_t i = 0; i < U; i++)
    for (uint32_t j = 0; j < V; j++) {
      uint32_t a = V * i + j, b = V * ((i + 1) % U) + j;
      uint32_t c = V * ((i + 1) % U) + (j + 1) % V, d = V * i + (j + 1) % V;
      uint32_t q[6] = {a, b, c, a, c, d};
      for (int k = 0; k < 6; k++)
        *t++ = q[k];
    }
  scs_meshcheck_t c;
  double t0 = sct_seconds();
  int rc = scs_meshcheck(n, xyz, tri, ntri, NULL, &c);
  double t1 = sct_seconds();
  EXPECT_EQ(rc, SCS_OK);
  EXPECT_EQ(c.faces, ntri);
  EXPECT_EQ(c.edges, 3 * n);
  EXPECT_EQ(c.vertices_used, n);
  EXPECT_EQ(c.components, 1);
  EXPECT_EQ(c.genus_total, 1);
  EXPECT_MSG(c.closed && c.oriented, "closed %d oriented %d", c.closed,
             c.oriented);
  char why[256];
  EXPECT_MSG(scs_meshcheck_expect(&c, SCS_SURF_TORUS,
                                  SCS_EXPECT_ALL_USED | SCS_EXPECT_OUTWARD, why,
                                  sizeof why),
             "%s", why);
  /* The inscribed polyhedron falls short of the torus by O(h^2). */
  const scs_surface_info_t *info = scs_surface_info(SCS_SURF_TORUS);
  EXPECT_NEAR(c.volume / info->volume[0], 1, 1e-4);
  EXPECT_NEAR(c.area / info->area, 1, 1e-4);
  char line[512];
  printf("meshcheck, %zu triangles: %.3f s\n  %s\n", ntri, t1 - t0,
         scs_meshcheck_summary(&c, line, sizeof line));
  scs_meshcheck_free(&c);
  free(xyz);
  free(tri);
}

int main(void) {
  time_sampling(SCS_SURF_SPHERE, SCS_DENSITY_UNIFORM_RANDOM, 1000000);
  time_sampling(SCS_SURF_SPHERE, SCS_DENSITY_UNIFORM, 1000000);
  time_sampling(SCS_SURF_TORUS, SCS_DENSITY_ADAPTIVE, 1000000);
  time_meshcheck();
  return sct_finish("synth_speed");
}
