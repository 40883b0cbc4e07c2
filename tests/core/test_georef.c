/*
 * Georeferenced coordinates: the same scan moved to UTM-like eastings and
 * northings (500 000, 4 000 000, 100) must give the same triangles as the
 * scan where it was, in every mode, at once or in chunks; and denoising's
 * smoothed positions must come back in the caller's frame. (Without the
 * re-centring of docs/algorithm.md 3.4, the moved bunny fell into 77
 * pieces.)
 *
 *   test_core_georef FILE...
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

static const double kOffset[3] = {500000, 4000000, 100};

static int same_triangles(const sc_mesh_t *a, const sc_mesh_t *b) {
  return a && b && a->triangle_count == b->triangle_count &&
         memcmp(a->triangles, b->triangles,
                3 * a->triangle_count * sizeof *a->triangles) == 0;
}

/* The points moved by kOffset, then back: those that the move rounded
 * (coordinates much smaller than the offset's unit in the last place)
 * come back as the points the moved copy holds. */
static void offset_copy(const double *xyz, size_t n, double *moved,
                        double *back) {
  for (size_t i = 0; i < 3 * n; i++) {
    moved[i] = xyz[i] + kOffset[i % 3];
    back[i] = moved[i] - kOffset[i % 3];
  }
}

static sc_mesh_t *run(const double *xyz, size_t n, const sc_params_t *p,
                      size_t chunk) {
  char msg[256] = "";
  sc_mesh_t *m = NULL;
  if (chunk == 0) {
    EXPECT_MSG(sc_reconstruct(xyz, n, p, &m, msg, sizeof msg) == 0, "%s", msg);
    return m;
  }
  sc_recon_t *r = NULL;
  EXPECT_EQ(sc_recon_new(p, &r), 0);
  for (size_t at = 0; r && at < n; at += chunk)
    EXPECT_EQ(sc_recon_add(r, xyz + 3 * at, n - at < chunk ? n - at : chunk,
                           msg, sizeof msg),
              0);
  EXPECT_MSG(r && sc_recon_finish(r, &m, msg, sizeof msg) == 0, "%s", msg);
  sc_recon_free(r);
  return m;
}

static void check_scan(const char *path) {
  char msg[256];
  scf_points_t pts;
  ASSERT_MSG(scf_points_read(path, &pts, msg, sizeof msg) == 0, "%s", msg);
  const size_t n = pts.count;
  double *moved = malloc(3 * n * sizeof *moved);
  double *back = malloc(3 * n * sizeof *back);
  ASSERT(moved && back);
  offset_copy(pts.xyz, n, moved, back);
  const sc_mode_t modes[] = {SC_MODE_COCONE, SC_MODE_BOUNDARY,
                             SC_MODE_WATERTIGHT, SC_MODE_AUTO};
  for (size_t k = 0; k < sizeof modes / sizeof *modes; k++) {
    sc_params_t p;
    sc_params_init(&p);
    p.mode = modes[k];
    sc_mesh_t *here = run(back, n, &p, 0);
    sc_mesh_t *there = run(moved, n, &p, 0);
    sc_mesh_t *chunked = run(moved, n, &p, 7000);
    EXPECT_MSG(same_triangles(here, there),
               "%s, mode %d: %zu triangles where it was, %zu moved", path,
               (int)modes[k], here ? here->triangle_count : 0,
               there ? there->triangle_count : 0);
    EXPECT_MSG(same_triangles(there, chunked), "%s, mode %d, in chunks", path,
               (int)modes[k]);
    EXPECT_MSG(there && there->diag.components == here->diag.components,
               "%s, mode %d: components", path, (int)modes[k]);
    sc_mesh_free(here);
    sc_mesh_free(there);
    sc_mesh_free(chunked);
  }
  free(moved);
  free(back);
  scf_points_free(&pts);
}

/* A noisy torus, denoised: the same triangles moved, and the smoothed
 * positions of the moved copy are those of the points where they were,
 * moved (to the rounding of the move). */
static void check_denoised(void) {
  enum { N = 20000 };
  double *xyz = malloc(3 * N * sizeof *xyz);
  double *moved = malloc(3 * N * sizeof *moved);
  double *back = malloc(3 * N * sizeof *back);
  ASSERT(xyz && moved && back);
  ASSERT_EQ(scs_sample_surface(SCS_SURF_TORUS, SCS_DENSITY_UNIFORM, N, 4, xyz),
            SCS_OK);
  scs_add_noise(xyz, N, 0.3 * scs_surface_spacing(SCS_SURF_TORUS, N), 5);
  offset_copy(xyz, N, moved, back);
  sc_params_t p;
  sc_params_init(&p);
  p.mode = SC_MODE_WATERTIGHT;
  p.denoise = 1;
  p.smoothed_vertices = 1;
  sc_mesh_t *here = run(back, N, &p, 0), *there = run(moved, N, &p, 0);
  EXPECT(here && here->diag.denoised && here->smoothed);
  EXPECT_MSG(same_triangles(here, there), "denoised torus: %zu vs %zu",
             here ? here->triangle_count : 0,
             there ? there->triangle_count : 0);
  double worst = 0;
  for (size_t i = 0;
       here && there && here->smoothed && there->smoothed && i < 3 * (size_t)N;
       i++)
    worst = fmax(worst,
                 fabs(there->smoothed[i] - kOffset[i % 3] - here->smoothed[i]));
  /* The move rounds to the offsets' units in the last place, 1e-9 here. */
  EXPECT_MSG(worst < 1e-8, "smoothed positions differ by %g", worst);
  sc_mesh_free(here);
  sc_mesh_free(there);
  free(xyz);
  free(moved);
  free(back);
}

int main(int argc, char **argv) {
  /* The shared data set may be absent: then the test is skipped. */
  for (int i = 1; i < argc; i++)
    if (access(argv[i], R_OK) != 0) {
      printf("skipped: %s is not there\n", argv[i]);
      return 77;
    }
  for (int i = 1; i < argc; i++)
    check_scan(argv[i]);
  check_denoised();
  return sct_finish("core_georef");
}
