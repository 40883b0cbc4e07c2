/*
 * A georeferenced LAS file reconstructs as the same points from a PLY:
 * samples of a torus, moved to UTM-like coordinates and stored as LAS
 * integers (scale 0.1 mm, offsets 500 000, 4 000 000, 100), in every point
 * data record format (1.2 for 0 to 5, 1.4 for 6 to 10). Each reads back as
 * exactly the points of a binary PLY written from the values LAS defines,
 * and gives the same triangles: a closed torus.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "sct_assert.h"
#include "shortcrust.h"
#include "shortcrust_files.h"
#include "synth.h"

enum { N = 4000 };
static const unsigned min_len[11] = {20, 28, 26, 34, 57, 63,
                                     30, 36, 38, 59, 67};
static const double kScale = 1e-4, kOffset[3] = {500000, 4000000, 100};

static void put(unsigned char *b, uint64_t v, int n) {
  for (int i = 0; i < n; i++)
    b[i] = (unsigned char)(v >> (8 * i));
}

static void put_f64(unsigned char *b, double d) {
  uint64_t w;
  memcpy(&w, &d, sizeof w);
  put(b, w, 8);
}

static void write_las(const char *path, const int32_t *q, unsigned format) {
  const unsigned minor = format >= 6 ? 4 : 2, len = min_len[format];
  const unsigned hsize = minor == 4 ? 375 : 227;
  unsigned char h[375];
  memset(h, 0, sizeof h);
  memcpy(h, "LASF", 4);
  h[24] = 1;
  h[25] = (unsigned char)minor;
  put(h + 94, hsize, 2);
  put(h + 96, hsize, 4);
  h[104] = (unsigned char)format;
  put(h + 105, len, 2);
  if (format < 6)
    put(h + 107, N, 4);
  if (minor == 4)
    put(h + 247, N, 8);
  for (int a = 0; a < 3; a++) {
    put_f64(h + 131 + 8 * a, kScale);
    put_f64(h + 155 + 8 * a, kOffset[a]);
  }
  FILE *f = fopen(path, "wb");
  ASSERT(f != NULL);
  ASSERT(fwrite(h, 1, hsize, f) == hsize);
  unsigned char rec[80];
  for (size_t i = 0; i < N; i++) {
    for (unsigned j = 0; j < len; j++)
      rec[j] = (unsigned char)(i * 31 + j);
    for (int a = 0; a < 3; a++)
      put(rec + 4 * a, (uint32_t)q[3 * i + a], 4);
    ASSERT(fwrite(rec, 1, len, f) == len);
  }
  ASSERT(fclose(f) == 0);
}

int main(void) {
  double *xyz = malloc(3 * N * sizeof *xyz), *geo = malloc(3 * N * sizeof *geo);
  int32_t *q = malloc(3 * N * sizeof *q);
  ASSERT(xyz && geo && q);
  ASSERT_EQ(scs_sample_surface(SCS_SURF_TORUS, SCS_DENSITY_UNIFORM, N, 8, xyz),
            SCS_OK);
  /* The torus, a few metres across, at its georeferenced place; then the
   * values LAS defines for its integers (two statements: no fma). */
  for (size_t i = 0; i < 3 * N; i++) {
    q[i] = (int32_t)lround(3 * xyz[i] / kScale + 1000 * (double)(i % 3));
    double scaled = q[i] * kScale;
    geo[i] = scaled + kOffset[i % 3];
  }
  char dir[] = "/tmp/sc-las-recon-XXXXXX", ply[64], las[64], msg[256];
  ASSERT(mkdtemp(dir) != NULL);
  snprintf(ply, sizeof ply, "%s/torus.ply", dir);
  snprintf(las, sizeof las, "%s/torus.las", dir);
  ASSERT_MSG(scf_mesh_write(ply, SCF_MESH_FMT_PLY_BINARY, geo, N, NULL, 0, NULL,
                            msg, sizeof msg) == 0,
             "%s", msg);
  scf_points_t from_ply;
  ASSERT(scf_points_read(ply, &from_ply, msg, sizeof msg) == 0);
  sc_params_t p;
  sc_params_init(&p);
  sc_mesh_t *ref = NULL;
  ASSERT_MSG(sc_reconstruct(from_ply.xyz, N, &p, &ref, msg, sizeof msg) == 0,
             "%s", msg);
  EXPECT_MSG(ref->diag.closed && ref->diag.components == 1 &&
                 ref->diag.genus == 1,
             "the torus from PLY: closed %d, %llu components, genus %lld",
             (int)ref->diag.closed, (unsigned long long)ref->diag.components,
             (long long)ref->diag.genus);
  for (unsigned format = 0; format <= 10; format++) {
    write_las(las, q, format);
    scf_points_t from_las;
    ASSERT_MSG(scf_points_read(las, &from_las, msg, sizeof msg) == 0,
               "format %u: %s", format, msg);
    EXPECT_MSG(from_las.count == N && memcmp(from_las.xyz, from_ply.xyz,
                                             3 * N * sizeof *from_las.xyz) == 0,
               "format %u: the points differ from the PLY's", format);
    sc_mesh_t *m = NULL;
    EXPECT_EQ(
        sc_reconstruct(from_las.xyz, from_las.count, &p, &m, msg, sizeof msg),
        0);
    EXPECT_MSG(m && m->triangle_count == ref->triangle_count &&
                   memcmp(m->triangles, ref->triangles,
                          3 * m->triangle_count * sizeof *m->triangles) == 0,
               "format %u: other triangles", format);
    sc_mesh_free(m);
    scf_points_free(&from_las);
  }
  sc_mesh_free(ref);
  scf_points_free(&from_ply);
  unlink(ply);
  unlink(las);
  rmdir(dir);
  free(xyz);
  free(geo);
  free(q);
  return sct_finish("core_las_recon");
}
