/*
 * shortcrust-read-bench: how fast the point readers go, and what carrying
 * the per-point properties costs. Writes N points (default 2 000 000) of a
 * random cloud as binary PLY (x, y, z doubles), the same with normals and
 * colours (floats and uchars), LAS 1.4 formats 2 and 7 (with colours) and
 * text, then reads each with scf_points_read() and with
 * scf_points_read_attrs(), best of 3, checking that each gives every
 * point and property, and prints MB/s, points/s and the bytes the
 * properties take.
 *
 *   shortcrust-read-bench [N] [DIR]
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "lasbuf.h"
#include "shortcrust_files.h"

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + (double)t.tv_nsec * 1e-9;
}

static uint64_t rng = 88172645463325252ull;
static double uniform(void) {
  rng ^= rng << 13;
  rng ^= rng >> 7;
  rng ^= rng << 17;
  return (double)(rng >> 11) / 9007199254740992.0;
}

/* LAS 1.4 of the points, scale 0.001, offset 500000 4000000 100. */
static void write_las(const char *path, const double *xyz, size_t n,
                      unsigned format) {
  int32_t *q = malloc(3 * n * sizeof *q);
  if (q == NULL)
    ASSERT_FAIL("out of memory");
  for (size_t i = 0; i < 3 * n; i++)
    q[i] = (int32_t)(xyz[i] * 1000);
  las_spec_t spec = {
      4, format, 0, 0, 0, {0.001, 0.001, 0.001}, {500000, 4000000, 100}, n, q};
  buf_t b;
  las_build(&b, &spec);
  buf_write(&b, path);
  buf_free(&b);
  free(q);
}

static int write_xyz(const char *path, const double *xyz, size_t n) {
  FILE *f = fopen(path, "w");
  if (f == NULL)
    return -1;
  for (size_t i = 0; i < n; i++)
    fprintf(f, "%.17g %.17g %.17g\n", xyz[3 * i], xyz[3 * i + 1],
            xyz[3 * i + 2]);
  return fclose(f);
}

/* Times both reads of path, and checks that they give all n points and
 * want_props properties. */
static void measure(const char *label, const char *path, size_t n,
                    size_t want_props) {
  struct stat st;
  if (stat(path, &st) != 0)
    return;
  const double mb = (double)st.st_size / 1e6;
  double best[2] = {1e30, 1e30};
  size_t points = 0, prop_bytes = 0, props = 0;
  for (int round = 0; round < 3; round++)
    for (int with = 0; with < 2; with++) {
      scf_points_t p;
      scf_attrs_t a;
      char msg[256];
      double t0 = now();
      int rc = with ? scf_points_read_attrs(path, &p, &a, msg, sizeof msg)
                    : scf_points_read(path, &p, msg, sizeof msg);
      double t = now() - t0;
      if (rc != 0) {
        fprintf(stderr, "%s: %s\n", path, msg);
        exit(1);
      }
      if (t < best[with])
        best[with] = t;
      points = p.count;
      if (with) {
        props = a.count;
        prop_bytes = a.stride * a.points;
        scf_attrs_free(&a);
      }
      scf_points_free(&p);
    }
  if (points != n || props != want_props) {
    fprintf(stderr, "%s: %zu points and %zu properties, expected %zu and %zu\n",
            path, points, props, n, want_props);
    exit(1);
  }
  printf("%-28s %8.1f MB  x,y,z only %6.3f s %7.0f MB/s %5.1f Mpt/s   "
         "with %zu properties %6.3f s (%.2fx), +%.0f B/point\n",
         label, mb, best[0], mb / best[0], (double)points / best[0] / 1e6,
         props, best[1], best[1] / best[0],
         points ? (double)prop_bytes / (double)points : 0.0);
}

int main(int argc, char **argv) {
  size_t n = argc > 1 ? (size_t)atol(argv[1]) : 2000000;
  const char *dir = argc > 2 ? argv[2] : NULL;
  char tmpl[] = "/tmp/sc-read-bench-XXXXXX";
  if (dir == NULL && (dir = mkdtemp(tmpl)) == NULL)
    return 1;
  if (n == 0)
    return 2;
  double *xyz = malloc(3 * n * sizeof *xyz);
  float *props = malloc(4 * n * sizeof *props); /* nx ny nz, then rgb */
  if (xyz == NULL || props == NULL)
    return 1;
  for (size_t i = 0; i < 3 * n; i++)
    xyz[i] = 100 * uniform();
  /* Properties as a PLY scan has them: float normals and uchar colours. */
  scf_prop_t pr[6] = {
      {"nx", SCF_TYPE_FLOAT32, 0},   {"ny", SCF_TYPE_FLOAT32, 4},
      {"nz", SCF_TYPE_FLOAT32, 8},   {"red", SCF_TYPE_UINT8, 12},
      {"green", SCF_TYPE_UINT8, 13}, {"blue", SCF_TYPE_UINT8, 14}};
  scf_attrs_t a = {pr, 6, 15, (unsigned char *)props, n};
  for (size_t i = 0; i < n; i++) {
    unsigned char *r = a.data + 15 * i;
    float v = (float)uniform();
    memcpy(r, &v, 4);
    memcpy(r + 4, &v, 4);
    memcpy(r + 8, &v, 4);
    r[12] = (unsigned char)i;
    r[13] = (unsigned char)(i >> 8);
    r[14] = 7;
  }
  char p1[512], p2[512], p3[512], p4[512], p5[512], msg[256];
  snprintf(p1, sizeof p1, "%s/plain.ply", dir);
  snprintf(p2, sizeof p2, "%s/coloured.ply", dir);
  snprintf(p3, sizeof p3, "%s/format2.las", dir);
  snprintf(p4, sizeof p4, "%s/format7.las", dir);
  snprintf(p5, sizeof p5, "%s/points.xyz", dir);
  printf("writing %zu points to %s\n", n, dir);
  if (scf_mesh_write(p1, SCF_MESH_FMT_PLY_BINARY, xyz, n, NULL, 0, NULL, msg,
                     sizeof msg) != 0 ||
      scf_mesh_write_attrs(p2, SCF_MESH_FMT_PLY_BINARY, xyz, n, NULL, 0, NULL,
                           &a, msg, sizeof msg) != 0 ||
      write_xyz(p5, xyz, n) != 0) {
    fprintf(stderr, "writing failed: %s\n", msg);
    return 1;
  }
  write_las(p3, xyz, n, 2);
  write_las(p4, xyz, n, 7);
  measure("binary PLY x,y,z", p1, n, 0);
  measure("binary PLY + normals, rgb", p2, n, 6);
  measure("LAS 1.4 format 2 (rgb)", p3, n, 7);
  measure("LAS 1.4 format 7 (gps, rgb)", p4, n, 8);
  measure("text x y z", p5, n, 0);
  if (argc <= 2) {
    unlink(p1);
    unlink(p2);
    unlink(p3);
    unlink(p4);
    unlink(p5);
    rmdir(dir);
  }
  free(xyz);
  free(props);
  return 0;
}
