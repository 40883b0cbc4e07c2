/*
 * Shortcrust mode's check of its topology (docs/algorithm.md section 6.5):
 * where the paper's criteria at a too large r give a wrong surface, the
 * cocone test's surface on the same triangulation has the true topology;
 * then either the nearest r that gives that surface within 0.02 is taken
 * (R_USED), or none does and the reconstruction says that the topology is
 * in doubt. The same with the points in tiles; cocone mode makes no check.
 *
 *   test_core_check FILE GENUS R [R_USED]
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <stdio.h>
#include <stdlib.h>

#include "diag.h"
#include "shortcrust.h"
#include "shortcrust_files.h"
#include "synth.h"

static sc_mesh_t *run(const scf_points_t *pts, sc_mode_t mode, double r,
                      int tiles) {
  sc_params_t p;
  sc_params_init(&p);
  p.mode = mode;
  p.r = r;
  p.tiles = tiles;
  char msg[512];
  sc_mesh_t *m = NULL;
  int rc = sc_reconstruct(pts->xyz, pts->count, &p, &m, msg, sizeof msg);
  EXPECT_EQ(rc, 0);
  if (rc != 0)
    fprintf(stderr, "%s\n", msg);
  return m;
}

int main(int argc, char **argv) {
  if (argc != 4 && argc != 5) {
    fprintf(stderr, "usage: %s FILE GENUS R [R_USED]\n", argv[0]);
    return 2;
  }
  const long long genus = atoll(argv[2]);
  const double r = atof(argv[3]);
  const double r_used = argc == 5 ? atof(argv[4]) : r;
  char msg[512];
  scf_points_t pts;
  if (scf_points_read(argv[1], &pts, msg, sizeof msg) != 0) {
    fprintf(stderr, "FAIL: %s\n", msg);
    return 1;
  }

  sc_mesh_t *one = run(&pts, SC_MODE_SHORTCRUST, r, 1);
  sc_mesh_t *tiled = run(&pts, SC_MODE_SHORTCRUST, r, 3);
  sc_mesh_t *cocone = run(&pts, SC_MODE_COCONE, r, 1);
  if (one && tiled && cocone) {
    const sc_diag_t *d = &one->diag;
    printf("%s r = %g: r used %g, %llu components (%llu closed), genus "
           "%lld; check %llu (%llu closed), genus %lld, doubt %d\n",
           argv[1], r, d->r_used, (unsigned long long)d->components,
           (unsigned long long)d->closed_components, (long long)d->genus,
           (unsigned long long)d->check_components,
           (unsigned long long)d->check_closed_components,
           (long long)d->check_genus, d->topology_doubt);
    /* The check's surface is right. */
    EXPECT_EQ(d->checked, 1);
    EXPECT_EQ(d->check_components, 1);
    EXPECT_EQ(d->check_closed_components, 1);
    EXPECT_EQ(d->check_genus, genus);
    EXPECT_NEAR(d->r_used, r_used, 1e-12);
    const int right = d->closed && d->components == 1 && d->genus == genus;
    if (argc == 5) {
      /* Another r gave it, and the mesh is that surface. */
      EXPECT(right);
      EXPECT_EQ(d->topology_doubt, 0);
    } else {
      /* No r near gave it: the mesh is wrong, and the doubt is said. */
      EXPECT(!right);
      EXPECT_EQ(d->topology_doubt, 1);
    }
    /* It agrees with cocone mode, which makes no check of its own. */
    EXPECT_EQ(cocone->diag.components, d->check_components);
    EXPECT_EQ(cocone->diag.genus, d->check_genus);
    EXPECT_EQ(cocone->diag.checked, 0);
    EXPECT_EQ(cocone->diag.topology_doubt, 0);
    /* Tiles give the same mesh and the same check (a tile takes at least
     * 2000 points: the knot is one). */
    if (pts.count >= 6000)
      EXPECT_EQ(tiled->diag.tiles, 3);
    EXPECT_EQ(tiled->triangle_count, one->triangle_count);
    EXPECT_EQ(tiled->diag.genus, d->genus);
    EXPECT_EQ(tiled->diag.checked, 1);
    EXPECT_EQ(tiled->diag.check_components, d->check_components);
    EXPECT_EQ(tiled->diag.check_genus, d->check_genus);
    EXPECT_EQ(tiled->diag.topology_doubt, d->topology_doubt);
    EXPECT_NEAR(tiled->diag.r_used, d->r_used, 1e-12);
  }
  sc_mesh_free(one);
  sc_mesh_free(tiled);
  sc_mesh_free(cocone);
  scf_points_free(&pts);
  return sct_finish("core_check");
}
