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

#include "lasbuf.h"
#include "sct_assert.h"
#include "shortcrust.h"
#include "shortcrust_files.h"
#include "synth.h"

enum { N = 4000 };
static const double kScale = 1e-4, kOffset[3] = {500000, 4000000, 100};

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
    geo[i] = las_value(q[i], kScale, kOffset[i % 3]);
  }
  tmp_init();
  const char *ply = tmp_path("torus.ply"), *las = tmp_path("torus.las");
  char msg[256];
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
    las_spec_t spec = {format >= 6 ? 4 : 2,
                       format,
                       0,
                       0,
                       0,
                       {kScale, kScale, kScale},
                       {kOffset[0], kOffset[1], kOffset[2]},
                       N,
                       q};
    buf_t b;
    las_build(&b, &spec);
    buf_write(&b, las);
    buf_free(&b);
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
  free(xyz);
  free(geo);
  free(q);
  return sct_finish("core_las_recon");
}
