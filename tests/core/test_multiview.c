/*
 * Registered range scans of one object from several views, concatenated:
 * layered, slightly misregistered sheets, with the regions no view saw
 * left open. With denoising, boundary mode makes them one sheet of genus
 * 0 with at most 10 boundary loops, and watertight mode one closed surface
 * of genus 0 (docs/algorithm.md section 16), at least 99% of the samples
 * vertices in both.
 *
 *   test_core_multiview FILE
 *
 * The ten Stanford bunny scans are 4 MB, too large for tests/data: the
 * test reads them where the shared data set is, and reports itself skipped
 * (exit status 77) where it is not.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <stdio.h>
#include <unistd.h>

#include "diag.h"
#include "shortcrust.h"
#include "shortcrust_files.h"
#include "synth.h"

static void check(const scf_points_t *pts, sc_mode_t mode) {
  sc_params_t p;
  sc_params_init(&p);
  p.mode = mode;
  p.denoise = 1;
  char msg[512];
  sc_mesh_t *m = NULL;
  int rc = sc_reconstruct(pts->xyz, pts->count, &p, &m, msg, sizeof msg);
  EXPECT_EQ(rc, 0);
  if (rc != 0) {
    fprintf(stderr, "%s\n", msg);
    return;
  }
  EXPECT_EQ(m->diag.denoised, 1);
  scs_meshcheck_t c;
  EXPECT_EQ(scs_meshcheck(pts->count, pts->xyz, m->triangles, m->triangle_count,
                          NULL, &c),
            0);
  char line[512];
  printf("%s --denoise: %s; noise %.2f spacings\n", sc_mode_name(mode),
         scs_meshcheck_summary(&c, line, sizeof line), m->diag.noise);
  EXPECT(c.manifold);
  EXPECT(c.oriented);
  EXPECT_EQ(c.components, 1);
  EXPECT_GE(c.vertices_used * 100, 99 * pts->count);
  if (c.component_count == 1)
    EXPECT_EQ(c.comp[0].genus, 0);
  if (mode == SC_MODE_WATERTIGHT) {
    EXPECT(c.closed);
    EXPECT_GT(c.volume, 0);
  } else {
    EXPECT_LE(c.boundary_loops, 10);
  }
  EXPECT_DIAG_COUNTS(m->diag, c);
  scs_meshcheck_free(&c);
  sc_mesh_free(m);
}

int main(int argc, char **argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: %s FILE\n", argv[0]);
    return 2;
  }
  if (access(argv[1], R_OK) != 0) {
    printf("SKIP: %s is not here\n", argv[1]);
    return 77;
  }
  char msg[512];
  scf_points_t pts;
  if (scf_points_read(argv[1], &pts, msg, sizeof msg) != 0) {
    fprintf(stderr, "FAIL: %s\n", msg);
    return 1;
  }
  check(&pts, SC_MODE_BOUNDARY);
  check(&pts, SC_MODE_WATERTIGHT);
  scf_points_free(&pts);
  return sct_finish("core_multiview");
}
