/*
 * The modes for scans on small, sparse and awkward inputs: a tetrahedron,
 * a cube's corners, a few points on a sphere, a noisy flat slab, a cloud
 * filling a cube, two planes crossing. Each must give a consistently
 * oriented 2-manifold (possibly empty) with diagnostics that agree with the
 * checker, never a crash. Also the validation of rho and alpha.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "diag.h"
#include "shortcrust.h"
#include "synth.h"

static void run(const char *what, const double *xyz, size_t n, int mode) {
  sc_params_t p;
  sc_params_init(&p);
  p.mode = (sc_mode_t)mode;
  sc_mesh_t *m = NULL;
  char msg[256] = "";
  int rc = sc_reconstruct(xyz, n, &p, &m, msg, sizeof msg);
  if (rc != 0) {
    EXPECT_FAIL("%s, mode %d: %s (%s)", what, mode, sc_err_name(rc), msg);
    return;
  }
  scs_meshcheck_t c;
  EXPECT_EQ(scs_meshcheck(n, xyz, m->triangles, m->triangle_count, NULL, &c),
            0);
  char line[512];
  printf("%s, mode %d, path %s: %s\n", what, mode, sc_path_name(m->diag.path),
         scs_meshcheck_summary(&c, line, sizeof line));
  EXPECT(c.manifold);
  EXPECT(c.oriented);
  EXPECT_EQ(m->diag.nonmanifold_edges, 0);
  EXPECT_EQ(m->diag.nonmanifold_vertices, 0);
  EXPECT_DIAG_COUNTS(m->diag, c);
  if (mode == SC_MODE_WATERTIGHT && m->diag.path == SC_PATH_WATERTIGHT)
    EXPECT(c.closed || c.faces == 0);
  /* Auto mode falls back to the cocone test when the detection finds too
   * few interior samples to tell: the cube's corners come out as a closed
   * box instead of nothing. */
  if (mode == SC_MODE_AUTO && n <= 8) {
    EXPECT_EQ(m->diag.path, SC_PATH_COCONE);
    EXPECT(c.closed);
    if (n == 8)
      EXPECT_EQ(c.faces, 12);
  }
  scs_meshcheck_free(&c);
  sc_mesh_free(m);
}

int main(void) {
  const int modes[] = {SC_MODE_BOUNDARY, SC_MODE_WATERTIGHT, SC_MODE_AUTO};
  scs_rng_t rng;
  double *xyz = malloc(3 * 2000 * sizeof *xyz);
  if (!xyz)
    return 1;

  for (int mi = 0; mi < 3; ++mi) {
    int mode = modes[mi];
    double tet[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    run("tetrahedron", tet, 4, mode);

    double cube[24];
    for (int i = 0; i < 8; ++i)
      for (int k = 0; k < 3; ++k)
        cube[3 * i + k] = (i >> k) & 1;
    run("cube corners", cube, 8, mode);

    scs_rng_seed(&rng, 11);
    for (int i = 0; i < 30; ++i) {
      double z = 2 * scs_rng_uniform(&rng) - 1,
             t = 6.283185307 * scs_rng_uniform(&rng);
      double r = sqrt(1 - z * z);
      xyz[3 * i] = r * cos(t), xyz[3 * i + 1] = r * sin(t), xyz[3 * i + 2] = z;
    }
    run("30 points on a sphere", xyz, 30, mode);

    for (int i = 0; i < 500; ++i) {
      xyz[3 * i] = scs_rng_uniform(&rng);
      xyz[3 * i + 1] = scs_rng_uniform(&rng);
      xyz[3 * i + 2] = 0.01 * scs_rng_uniform(&rng);
    }
    run("noisy flat slab", xyz, 500, mode);

    for (int i = 0; i < 1000; ++i)
      for (int k = 0; k < 3; ++k)
        xyz[3 * i + k] = scs_rng_uniform(&rng);
    run("cloud filling a cube", xyz, 1000, mode);

    /* Two unit squares crossing at right angles along the x axis. */
    for (int i = 0; i < 1000; ++i) {
      double u = 2 * scs_rng_uniform(&rng) - 1,
             v = 2 * scs_rng_uniform(&rng) - 1;
      xyz[3 * i] = u;
      xyz[3 * i + 1] = i % 2 ? v : 0.001 * v;
      xyz[3 * i + 2] = i % 2 ? 0.001 * v : v;
    }
    run("two crossing planes", xyz, 1000, mode);
  }

  /* rho and alpha: out of range is an error, 0 is the default. */
  sc_params_t p;
  sc_params_init(&p);
  EXPECT_LT(fabs(p.boundary_rho - 1.3), 1e-12);
  EXPECT_LT(fabs(p.boundary_alpha - SC_PI / 9), 1e-12);
  double tet[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  sc_mesh_t *m = NULL;
  char msg[256] = "";
  p.mode = SC_MODE_BOUNDARY;
  p.boundary_rho = -1;
  EXPECT_EQ(sc_reconstruct(tet, 4, &p, &m, msg, sizeof msg),
            SC_EINVALID_ARGUMENT);
  EXPECT_NULL(m);
  p.boundary_rho = 0;
  p.boundary_alpha = 2;
  EXPECT_EQ(sc_reconstruct(tet, 4, &p, &m, msg, sizeof msg),
            SC_EINVALID_ARGUMENT);
  p.boundary_alpha = 0;
  EXPECT_EQ(sc_reconstruct(tet, 4, &p, &m, msg, sizeof msg), 0);
  sc_mesh_free(m);
  EXPECT_STR_EQ(sc_path_name(SC_PATH_WATERTIGHT_FILL), "watertight-fill");
  EXPECT_STR_EQ(sc_path_name(SC_PATH_COUNT_), "?");

  free(xyz);
  return sct_finish("core_modes_small");
}
