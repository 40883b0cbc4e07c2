/*
 * Degenerate and invalid input: each case gives its own error code and a
 * message, never a crash, a leak or a mesh.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sct_assert.h"
#include "shortcrust.h"
#include "synth.h"

/* Runs a reconstruction that must fail with `want`, leaving no mesh and a
 * message. */
static void expect_error(const char *what, const double *xyz, size_t n,
                         const sc_params_t *params, int want) {
  sc_mesh_t *mesh = (sc_mesh_t *)&mesh; /* must be reset to NULL */
  char msg[256] = "";
  int rc = sc_reconstruct(xyz, n, params, &mesh, msg, sizeof msg);
  if (rc != want) {
    EXPECT_FAIL("%s: got %d (%s: %s), expected %d (%s)", what, rc,
                sc_err_name(rc), msg, want, sc_err_name(want));
  } else {
    printf("ok: %s -> %s: %s\n", what, sc_err_name(rc), msg);
  }
  EXPECT_NULL(mesh);
  EXPECT_NE(msg[0], '\0');
  if (rc == 0)
    sc_mesh_free(mesh);
}

int main(void) {
  sc_params_t p;
  sc_params_init(&p);
  double pts[3 * 400];

  /* Fewer than four points. */
  expect_error("no points", NULL, 0, &p, SC_EDEGENERATE_INPUT);
  double four[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  for (size_t n = 1; n <= 3; ++n)
    expect_error("1-3 points", four, n, &p, SC_EDEGENERATE_INPUT);

  /* Collinear, coplanar and all-duplicate clouds. */
  for (int i = 0; i < 400; ++i) {
    pts[3 * i] = i * 0.01;
    pts[3 * i + 1] = 2 * i * 0.01;
    pts[3 * i + 2] = -i * 0.01;
  }
  expect_error("400 collinear points", pts, 400, &p, SC_EDEGENERATE_INPUT);
  for (int i = 0; i < 400; ++i) {
    /* Dyadic coordinates, so the tilted plane holds them exactly. */
    pts[3 * i] = (i % 20) * 0.125;
    pts[3 * i + 1] = (i / 20) * 0.125 + 0.0078125 * (i % 7);
    pts[3 * i + 2] = 0.5 * pts[3 * i] - 0.25 * pts[3 * i + 1] + 3;
  }
  expect_error("400 coplanar points", pts, 400, &p, SC_EDEGENERATE_INPUT);
  for (int i = 0; i < 400; ++i) {
    pts[3 * i] = 1.5;
    pts[3 * i + 1] = -2;
    pts[3 * i + 2] = 7;
  }
  expect_error("400 copies of one point", pts, 400, &p, SC_EDEGENERATE_INPUT);
  double dup4[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 0, 0};
  expect_error("4 points, 3 distinct", dup4, 4, &p, SC_EDEGENERATE_INPUT);

  /* Non-finite coordinates anywhere. */
  scs_sample_surface(SCS_SURF_SPHERE, SCS_DENSITY_UNIFORM_RANDOM, 400, 3, pts);
  const double bad[] = {NAN, INFINITY, -INFINITY};
  for (int b = 0; b < 3; ++b)
    for (int where = 0; where < 3; ++where) {
      size_t at = (size_t)(where == 0 ? 0 : where == 1 ? 601 : 1199);
      double keep = pts[at];
      pts[at] = bad[b];
      expect_error("non-finite coordinate", pts, 400, &p, SC_ENONFINITE);
      pts[at] = keep;
    }

  /* Invalid arguments and parameters. */
  expect_error("NULL points", NULL, 10, &p, SC_EINVALID_ARGUMENT);
  EXPECT_EQ(sc_reconstruct(pts, 400, &p, NULL, NULL, 0), SC_EINVALID_ARGUMENT);
  sc_params_t q;
  q = p, q.r = 0;
  expect_error("r = 0", pts, 400, &q, SC_EINVALID_ARGUMENT);
  q = p, q.r = 0.5;
  expect_error("r = 0.5", pts, 400, &q, SC_EINVALID_ARGUMENT);
  q = p, q.r = NAN;
  expect_error("r = NaN", pts, 400, &q, SC_EINVALID_ARGUMENT);
  q = p, q.mode = (sc_mode_t)99;
  expect_error("mode 99", pts, 400, &q, SC_EINVALID_ARGUMENT);
  q = p, q.cocone_theta = 0;
  expect_error("theta 0", pts, 400, &q, SC_EINVALID_ARGUMENT);
  q = p, q.cocone_theta = 2;
  expect_error("theta 2", pts, 400, &q, SC_EINVALID_ARGUMENT);
  q = p, q.threads = -1;
  expect_error("threads -1", pts, 400, &q, SC_EINVALID_ARGUMENT);
  q = p, q.max_hole_edges = -1;
  expect_error("max_hole_edges -1", pts, 400, &q, SC_EINVALID_ARGUMENT);
  q = p, q.paper_pruning = 2;
  expect_error("paper_pruning 2", pts, 400, &q, SC_EINVALID_ARGUMENT);
  q = p, q.watertight_labels = -1;
  expect_error("watertight_labels -1", pts, 400, &q, SC_EINVALID_ARGUMENT);

  /* The smallest valid inputs do not fail: a tetrahedron gives a closed
   * tetrahedron or nothing, never something non-manifold. */
  sc_mesh_t *mesh = NULL;
  char msg[256] = "";
  int rc = sc_reconstruct(four, 4, &p, &mesh, msg, sizeof msg);
  EXPECT_EQ(rc, 0);
  if (rc == 0) {
    scs_meshcheck_t c;
    EXPECT_EQ(
        scs_meshcheck(4, four, mesh->triangles, mesh->triangle_count, NULL, &c),
        0);
    EXPECT(c.manifold && c.oriented);
    EXPECT(mesh->triangle_count == 0 || (c.closed && c.volume > 0));
    scs_meshcheck_free(&c);
    sc_mesh_free(mesh);
  }

  /* Exact duplicates are merged, counted, and share their first copy's
   * normal; the rest of the sample is reconstructed as without them. */
  enum { N = 3000, D = 300 };
  double *xyz = malloc(3 * (N + D) * sizeof *xyz);
  scs_sample_surface(SCS_SURF_SPHERE, SCS_DENSITY_UNIFORM, N, 5, xyz);
  for (int i = 0; i < D; ++i)
    memcpy(xyz + 3 * (N + i), xyz + 3 * (size_t)(7 * i), 3 * sizeof *xyz);
  rc = sc_reconstruct(xyz, N + D, &p, &mesh, msg, sizeof msg);
  EXPECT_EQ(rc, 0);
  if (rc == 0) {
    EXPECT_EQ(mesh->diag.duplicates_merged, D);
    EXPECT_EQ(mesh->diag.delaunay_vertices, N);
    unsigned char *ignore = calloc(N + D, 1);
    memset(ignore + N, 1, D);
    scs_meshcheck_t c;
    scs_meshcheck(N + D, xyz, mesh->triangles, mesh->triangle_count, ignore,
                  &c);
    char why[256];
    EXPECT(scs_meshcheck_expect(&c, SCS_SURF_SPHERE,
                                SCS_EXPECT_ALL_USED | SCS_EXPECT_OUTWARD, why,
                                sizeof why));
    for (uint32_t t = 0; t < 3 * mesh->triangle_count; ++t)
      EXPECT_LT(mesh->triangles[t], N);
    for (int i = 0; i < D; ++i)
      EXPECT_EQ(memcmp(mesh->normals + 3 * (N + i),
                       mesh->normals + 3 * (size_t)(7 * i), 3 * sizeof(double)),
                0);
    scs_meshcheck_free(&c);
    free(ignore);
    sc_mesh_free(mesh);
  }
  free(xyz);
  return sct_finish("core_degenerate");
}
