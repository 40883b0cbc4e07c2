/*
 * Open surfaces with known boundaries: a hemisphere, a wavy disc (a height
 * field over the unit disc), a cylinder open at both ends, a sphere with
 * a cap cut off, and a torus with a hole (a true handle beside a hole).
 *
 *   test_core_open SURFACE MODE N [SEED]
 *
 * In boundary and auto mode the output must be a consistently oriented
 * 2-manifold whose boundary loops are the true ones: as many, and every loop
 * vertex within three spacings of the true boundary curve; almost every
 * sample a vertex. In
 * watertight mode it must be one closed manifold of the surface's genus
 * (0, and 1 for the torus).
 *
 * The samples are well spaced: area-uniform random candidates thinned by
 * dart throwing (a candidate is kept when no kept sample lies within 0.7
 * times the spacing), with a seeded generator.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "diag.h"
#include "shortcrust.h"
#include "synth.h"
#include "testsupport.h"


enum {
  HEMISPHERE,
  WAVY_DISC,
  OPEN_CYLINDER,
  CUT_SPHERE,
  HOLED_TORUS,
  OPEN_COUNT
};
static const char *const open_names[OPEN_COUNT] = {
    "hemisphere", "wavy-disc", "open-cylinder", "cut-sphere", "holed-torus"};
/* Boundary loops of each surface, the genus once closed, and its area (for
 * the spacing). */
static const int open_loops[OPEN_COUNT] = {1, 1, 2, 1, 1};
static const int closed_genus[OPEN_COUNT] = {0, 0, 0, 0, 1};
/* The cut sphere keeps z <= CUT_Z of the unit sphere. */
#define CUT_Z 0.7
#define CYL_R 0.5
#define CYL_H 1.0
/* The torus (radii TOR_R about the z axis, TOR_r of the tube) loses what
 * lies within HOLE_R of HOLE_C, a point on top of the tube: a hole across
 * most of the tube, which must not cost the torus its handle. */
#define TOR_R 1.0
#define TOR_r 0.4
#define HOLE_R 0.6
static double HOLE_C[3] = {0, 0, 0};

static double wavy(double x, double y) {
  return 0.15 * sin(3 * x) * cos(2 * y);
}

static double open_area(int s) {
  switch (s) {
  case HEMISPHERE:
    return 2 * SC_PI;
  case WAVY_DISC:
    return SC_PI * 1.06; /* the waves add a few per cent; only the spacing
                         depends on it */
  case OPEN_CYLINDER:
    return 2 * SC_PI * CYL_R * 2 * CYL_H;
  case HOLED_TORUS:
    /* less the hole, about a disc of its radius */
    return 4 * SC_PI * SC_PI * TOR_R * TOR_r - SC_PI * HOLE_R * HOLE_R;
  default:
    return 2 * SC_PI * (1 + CUT_Z);
  }
}

static double dist3(const double *a, const double *b) {
  double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
  return sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

/* One area-uniform random point of surface s (the wavy disc is uniform in
 * the plane, which its gentle slope makes nearly uniform in area). */
static void open_point(int s, scs_rng_t *rng, double p[3]) {
  double u = scs_rng_uniform(rng), v = scs_rng_uniform(rng);
  switch (s) {
  case HOLED_TORUS:
    /* The tube angle by rejection against the area element, then outside
     * the hole. */
    for (;;) {
      double t = 2 * SC_PI * u, f = 2 * SC_PI * v;
      double w = TOR_R + TOR_r * cos(f);
      p[0] = w * cos(t), p[1] = w * sin(t), p[2] = TOR_r * sin(f);
      if (scs_rng_uniform(rng) * (TOR_R + TOR_r) <= w &&
          dist3(p, HOLE_C) > HOLE_R)
        return;
      u = scs_rng_uniform(rng), v = scs_rng_uniform(rng);
    }
  case HEMISPHERE:
  case CUT_SPHERE: {
    /* Archimedes: z uniform gives area-uniform points on the sphere. */
    double z = s == HEMISPHERE ? u : -1 + u * (1 + CUT_Z);
    double r = sqrt(1 - z * z), t = 2 * SC_PI * v;
    p[0] = r * cos(t), p[1] = r * sin(t), p[2] = z;
    break;
  }
  case WAVY_DISC: {
    double r = sqrt(u), t = 2 * SC_PI * v;
    p[0] = r * cos(t), p[1] = r * sin(t), p[2] = wavy(p[0], p[1]);
    break;
  }
  default: {
    double t = 2 * SC_PI * u;
    p[0] = CYL_R * cos(t), p[1] = CYL_R * sin(t), p[2] = CYL_H * (2 * v - 1);
    break;
  }
  }
}

/* Distance from a sample to the nearest true boundary curve. */
static double boundary_distance(int s, const double p[3]) {
  double rho = sqrt(p[0] * p[0] + p[1] * p[1]);
  switch (s) {
  case HEMISPHERE:
    return sqrt((rho - 1) * (rho - 1) + p[2] * p[2]);
  case WAVY_DISC:
    /* Close to the curve the surface is nearly flat: the distance in the
     * plane is within a few per cent of the true one. */
    return fabs(rho - 1);
  case OPEN_CYLINDER:
    return CYL_H - fabs(p[2]);
  case HOLED_TORUS:
    /* The distance to the sphere that cut the hole: near the curve, close
     * to the distance to it. */
    return fabs(dist3(p, HOLE_C) - HOLE_R);
  default: {
    double r0 = sqrt(1 - CUT_Z * CUT_Z);
    return sqrt((rho - r0) * (rho - r0) + (p[2] - CUT_Z) * (p[2] - CUT_Z));
  }
  }
}

/* Dart throwing over a uniform grid of cells of the exclusion radius. */
static size_t sample_open(int s, size_t n, uint64_t seed, double spacing,
                          double **out) {
  const double rmin = 0.7 * spacing, r2 = rmin * rmin;
  const double lo = -1.6, span = 3.2;
  const int g = (int)(span / rmin) + 1;
  size_t cap = 2 * n + 16, count = 0;
  double *xyz = malloc(3 * cap * sizeof *xyz);
  int32_t *head = malloc((size_t)g * g * g * sizeof *head);
  int32_t *next = malloc(cap * sizeof *next);
  if (!xyz || !head || !next) {
    free(xyz), free(head), free(next);
    return 0;
  }
  for (size_t i = 0; i < (size_t)g * g * g; ++i)
    head[i] = -1;
  scs_rng_t rng;
  scs_rng_seed(&rng, seed);
  for (size_t tries = 0; tries < 40 * n && count < cap; ++tries) {
    double p[3];
    open_point(s, &rng, p);
    int c[3];
    for (int k = 0; k < 3; ++k)
      c[k] = (int)((p[k] - lo) / rmin);
    int ok = 1;
    for (int dx = -1; dx <= 1 && ok; ++dx)
      for (int dy = -1; dy <= 1 && ok; ++dy)
        for (int dz = -1; dz <= 1 && ok; ++dz) {
          int x = c[0] + dx, y = c[1] + dy, z = c[2] + dz;
          if (x < 0 || y < 0 || z < 0 || x >= g || y >= g || z >= g)
            continue;
          for (int32_t j = head[((size_t)x * g + y) * g + z]; j >= 0 && ok;
               j = next[j]) {
            double d[3] = {xyz[3 * j] - p[0], xyz[3 * j + 1] - p[1],
                           xyz[3 * j + 2] - p[2]};
            ok = d[0] * d[0] + d[1] * d[1] + d[2] * d[2] >= r2;
          }
        }
    if (!ok)
      continue;
    memcpy(xyz + 3 * count, p, sizeof p);
    size_t cell = ((size_t)c[0] * g + c[1]) * g + c[2];
    next[count] = head[cell];
    head[cell] = (int32_t)count;
    ++count;
  }
  free(head);
  free(next);
  *out = xyz;
  return count;
}

static int cmp_u64(const void *a, const void *b) {
  uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return x < y ? -1 : x > y;
}

/* The vertices of boundary edges (edges of one triangle): marks them in
 * on_boundary (n bytes) and returns their count. */
static size_t boundary_vertices(const uint32_t *tri, size_t nt, size_t n,
                                unsigned char *on_boundary) {
  uint64_t *keys = malloc(3 * nt * sizeof *keys + 1);
  if (!keys)
    return 0;
  for (size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      uint64_t a = tri[3 * t + k], b = tri[3 * t + (k + 1) % 3];
      keys[3 * t + k] = a < b ? (a << 32) | b : (b << 32) | a;
    }
  qsort(keys, 3 * nt, sizeof *keys, cmp_u64);
  memset(on_boundary, 0, n);
  size_t count = 0;
  for (size_t i = 0; i < 3 * nt;) {
    size_t j = i;
    while (j < 3 * nt && keys[j] == keys[i])
      ++j;
    if (j - i == 1) {
      uint32_t a = (uint32_t)(keys[i] >> 32), b = (uint32_t)keys[i];
      count += !on_boundary[a] + !on_boundary[b];
      on_boundary[a] = on_boundary[b] = 1;
    }
    i = j;
  }
  free(keys);
  return count;
}

int main(int argc, char **argv) {
  if (argc < 4) {
    fprintf(stderr, "usage: %s SURFACE MODE N [SEED [HOLE_ANGLE]]\n",
            argv[0]);
    return 2;
  }
  /* Where the torus's hole is: on top of the tube, at this angle about the
   * z axis. */
  const double hole_angle = argc > 5 ? strtod(argv[5], NULL) : 0;
  HOLE_C[0] = TOR_R * cos(hole_angle);
  HOLE_C[1] = TOR_R * sin(hole_angle);
  HOLE_C[2] = TOR_r;
  int s = -1;
  for (int i = 0; i < OPEN_COUNT; ++i)
    if (strcmp(argv[1], open_names[i]) == 0)
      s = i;
  /* "labels": watertight mode that labels cells before it patches. */
  const int labels = strcmp(argv[2], "labels") == 0;
  int mode = strcmp(argv[2], "boundary") == 0     ? SC_MODE_BOUNDARY
             : strcmp(argv[2], "watertight") == 0 ? SC_MODE_WATERTIGHT
             : labels                             ? SC_MODE_WATERTIGHT
             : strcmp(argv[2], "auto") == 0       ? SC_MODE_AUTO
                                                  : -1;
  size_t want = strtoul(argv[3], NULL, 10);
  uint64_t seed = argc > 4 ? strtoull(argv[4], NULL, 10) : 1;
  if (s < 0 || mode < 0 || want < 100) {
    fprintf(stderr, "bad arguments\n");
    return 2;
  }
  const double spacing = sqrt(open_area(s) / (double)want);
  double *xyz = NULL;
  size_t n = sample_open(s, want, seed, spacing, &xyz);
  if (n < want / 2) {
    fprintf(stderr, "FAIL: sampling gave %zu of %zu points\n", n, want);
    return 1;
  }

  sc_params_t p;
  sc_params_init(&p);
  p.mode = (sc_mode_t)mode;
  p.watertight_labels = labels;
  sc_mesh_t *m = NULL;
  char msg[256] = "";
  double t0 = sct_seconds();
  int rc = sc_reconstruct(xyz, n, &p, &m, msg, sizeof msg);
  double t1 = sct_seconds();
  EXPECT_EQ(rc, 0);
  if (rc != 0) {
    fprintf(stderr, "%s\n", msg);
    free(xyz);
    return sct_finish("core_open");
  }
  scs_meshcheck_t c;
  EXPECT_EQ(scs_meshcheck(n, xyz, m->triangles, m->triangle_count, NULL, &c),
            0);
  char line[512];
  printf("%s %s n=%zu: %s path=%s boundary_samples=%llu holes=%llu/%llu "
         "handles_cut=%llu (%.2f s)\n",
         argv[1], argv[2], n, scs_meshcheck_summary(&c, line, sizeof line),
         sc_path_name(m->diag.path),
         (unsigned long long)m->diag.boundary_samples,
         (unsigned long long)m->diag.holes_filled,
         (unsigned long long)m->diag.hole_triangles,
         (unsigned long long)m->diag.handles_cut, t1 - t0);
  EXPECT(c.manifold);
  EXPECT(c.oriented);
  EXPECT_EQ(c.nonmanifold_edges, 0);
  EXPECT_EQ(c.nonmanifold_vertices, 0);
  EXPECT_EQ(c.components, 1);
  EXPECT_EQ(m->diag.nonmanifold_edges, 0);
  EXPECT_EQ(m->diag.nonmanifold_vertices, 0);
  EXPECT_EQ(m->diag.boundary_loops, c.boundary_loops);
  EXPECT_DIAG_COUNTS(m->diag, c);

  if (mode == SC_MODE_WATERTIGHT) {
    EXPECT(c.closed);
    EXPECT_EQ(c.genus_total, closed_genus[s]);
    EXPECT_GT(c.volume, 0);
    EXPECT(m->diag.closed);
    EXPECT(m->diag.path == SC_PATH_WATERTIGHT ||
           m->diag.path == SC_PATH_WATERTIGHT_FILL);
    if (labels)
      EXPECT_EQ(m->diag.path, SC_PATH_WATERTIGHT);
    /* Closing may bury a sample or two of the rim inside. */
    EXPECT_LE(c.samples_unused * 100, n);
  } else {
    EXPECT_EQ(c.boundary_loops, open_loops[s]);
    EXPECT_EQ(m->diag.path, SC_PATH_BOUNDARY);
    EXPECT_GT(m->diag.boundary_samples, 0);
    EXPECT_LE(c.samples_unused * 200, n);
    /* Every vertex of a boundary edge lies near the true boundary; and the
     * longest loop is at least as long as the shortest true curve needs. */
    unsigned char *on = malloc(n);
    if (on) {
      boundary_vertices(m->triangles, m->triangle_count, n, on);
      double worst = 0;
      size_t far = 0;
      for (size_t i = 0; i < n; ++i) {
        if (!on[i])
          continue;
        double d = boundary_distance(s, xyz + 3 * i);
        worst = d > worst ? d : worst;
        far += d > 3 * spacing;
      }
      printf("boundary vertices: worst %.3g spacings from the true curve\n",
             worst / spacing);
      EXPECT_EQ(far, 0);
      free(on);
    }
    /* The loops follow the boundary samples, which may be a few spacings
     * apart along the curve; but they are loops, not slivers. */
    EXPECT_GE(m->diag.longest_loop, 8);
  }
  scs_meshcheck_free(&c);
  sc_mesh_free(m);
  free(xyz);
  return sct_finish("core_open");
}
