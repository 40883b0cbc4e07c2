/*
 * Reconstruction of dense samples of the analytic test surfaces: the output
 * must be a closed, consistently oriented 2-manifold, outward, with the
 * surface's components and genus, every sample a vertex and every vertex on
 * the surface.
 *
 *   test_core_surfaces SURFACE DENSITY MODE N [SEED [R]]
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "diag.h"
#include "sct_assert.h"
#include "shortcrust.h"
#include "synth.h"
#include "testsupport.h"

int main(int argc, char **argv) {
  if (argc < 5) {
    fprintf(stderr, "usage: %s SURFACE DENSITY MODE N [SEED [R]]\n", argv[0]);
    return 2;
  }
  int surf = scs_surface_from_name(argv[1]);
  int dens = scs_density_from_name(argv[2]);
  int mode = sct_mode_from_name(argv[3]);
  size_t n = strtoul(argv[4], NULL, 10);
  uint64_t seed = argc > 5 ? strtoull(argv[5], NULL, 10) : 1;
  if (surf < 0 || dens < 0 || mode == SC_MODE_COUNT_ || n < 4) {
    fprintf(stderr, "bad arguments\n");
    return 2;
  }

  double *xyz = malloc(3 * n * sizeof *xyz);
  if (!xyz || scs_sample_surface(surf, dens, n, seed, xyz) != 0) {
    fprintf(stderr, "sampling failed\n");
    return 1;
  }
  sc_params_t params;
  sc_params_init(&params);
  params.mode = (sc_mode_t)mode;
  if (argc > 6)
    params.r = strtod(argv[6], NULL);
  sc_mesh_t *mesh = NULL;
  char msg[256] = "";
  double t0 = sct_seconds();
  int rc = sc_reconstruct(xyz, n, &params, &mesh, msg, sizeof msg);
  double t1 = sct_seconds();
  if (rc != 0) {
    EXPECT_FAIL("sc_reconstruct returned %d (%s): %s", rc, sc_err_name(rc),
                msg);
    return 1;
  }

  scs_meshcheck_t c;
  if (scs_meshcheck(n, xyz, mesh->triangles, mesh->triangle_count, NULL, &c)) {
    fprintf(stderr, "meshcheck failed\n");
    return 1;
  }
  char line[512];
  printf("%s %s %s n=%zu: %s noise=%.3f%s (%.2f s)\n", argv[1], argv[2],
         argv[3], n, scs_meshcheck_summary(&c, line, sizeof line),
         mesh->diag.noise, mesh->diag.denoised ? " denoised" : "", t1 - t0);
  char why[256];
  /* The modes for scans may leave out a sample or two where the boundary
   * detection sees undersampling (at most one in a thousand). */
  const int scan_mode = mode == SC_MODE_BOUNDARY ||
                        mode == SC_MODE_WATERTIGHT || mode == SC_MODE_AUTO;
  if (!scs_meshcheck_expect(
          &c, surf, (scan_mode ? 0u : SCS_EXPECT_ALL_USED) | SCS_EXPECT_OUTWARD,
          why, sizeof why)) {
    EXPECT_FAIL("%s", why);
  }
  if (scan_mode && c.samples_unused * 1000 > n) {
    EXPECT_FAIL("%llu of %zu samples unused",
                (unsigned long long)c.samples_unused, n);
  }

  /* The core's own diagnostics must agree with the independent checker. */
  const sc_diag_t *d = &mesh->diag;
  if (d->triangles != c.faces || d->components != c.components ||
      d->closed != c.closed || d->genus != c.genus_total ||
      d->samples_unused != c.samples_unused ||
      d->boundary_edges != c.boundary_edges ||
      d->nonmanifold_edges != c.nonmanifold_edges ||
      d->nonmanifold_vertices != c.nonmanifold_vertices) {
    EXPECT_FAIL("diagnostics disagree with the checker: triangles %llu/%llu "
                "components %llu/%llu closed %d/%d genus %lld/%lld unused "
                "%llu/%llu boundary %llu/%llu",
                (unsigned long long)d->triangles, (unsigned long long)c.faces,
                (unsigned long long)d->components,
                (unsigned long long)c.components, d->closed, c.closed,
                (long long)d->genus, (long long)c.genus_total,
                (unsigned long long)d->samples_unused,
                (unsigned long long)c.samples_unused,
                (unsigned long long)d->boundary_edges,
                (unsigned long long)c.boundary_edges);
  }

  /* Shortcrust mode checks its topology against the cocone test's surface
   * (docs/algorithm.md section 6.5): on these right results, no doubt. */
  EXPECT_EQ(d->checked, mode == SC_MODE_SHORTCRUST);
  EXPECT_EQ(d->topology_doubt, 0);
  if (mode == SC_MODE_SHORTCRUST) {
    EXPECT_EQ(d->check_components, d->components);
    EXPECT_EQ(d->check_genus, d->genus);
  }

  /* Vertices are samples, so they lie on the surface to rounding error. */
  scs_distcheck_t dc;
  if (scs_mesh_distance_check(surf, n, xyz, mesh->triangles,
                              mesh->triangle_count, 1e-9, &dc) != 0 ||
      dc.beyond != 0) {
    EXPECT_FAIL("%llu vertices off the surface (max %g)",
                (unsigned long long)dc.beyond, dc.max_distance);
  }

  /* Normals: unit length, and pointing outward like the true normal. */
  size_t bad_normals = 0;
  for (size_t i = 0; i < n; ++i) {
    const double *nv = mesh->normals + 3 * i;
    double len = sqrt(nv[0] * nv[0] + nv[1] * nv[1] + nv[2] * nv[2]);
    double truth[3];
    scs_surface_normal(surf, xyz + 3 * i, truth);
    double dot = nv[0] * truth[0] + nv[1] * truth[1] + nv[2] * truth[2];
    if (fabs(len - 1) > 1e-9 || dot < 0.5)
      ++bad_normals;
  }
  if (bad_normals > n / 1000) {
    EXPECT_FAIL("%zu of %zu normals not unit or not outward", bad_normals, n);
  }

  /* Every component's genus as reported per component. */
  int64_t sum = 0;
  for (size_t i = 0; i < mesh->component_count; ++i)
    sum += mesh->component_genus[i];
  if (mesh->component_count != c.components || sum != c.genus_total) {
    EXPECT_FAIL("component_genus lists %zu components, sum %lld",
                mesh->component_count, (long long)sum);
  }

  scs_meshcheck_free(&c);
  sc_mesh_free(mesh);
  free(xyz);
  return sct_finish("core_surfaces");
}
