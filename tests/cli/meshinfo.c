/*
 * Prints what the mesh checker finds in a mesh file, as key=value words on
 * one line, for the command-line tests:
 *
 *   meshinfo FILE  ->  points=... triangles=... closed=1 oriented=1 ...
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <stdio.h>
#include <stdlib.h>

#include "shortcrust_files.h"
#include "synth.h"

int main(int argc, char **argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: meshinfo FILE\n");
    return 2;
  }
  scf_points_t pts;
  uint32_t *tri;
  size_t ntri;
  char msg[512];
  if (scf_mesh_read(argv[1], &pts, &tri, &ntri, msg, sizeof msg) != 0) {
    fprintf(stderr, "meshinfo: %s\n", msg);
    return 1;
  }
  scs_meshcheck_t c;
  if (scs_meshcheck(pts.count, pts.xyz, tri, ntri, NULL, &c) != 0) {
    fprintf(stderr, "meshinfo: checker failed\n");
    return 1;
  }
  /* genus: of the closed components; genus_all: of every component, open
   * ones included (-1 when one is not a surface). */
  long long all = 0;
  for (size_t i = 0; i < c.components && all >= 0; ++i)
    all = c.comp[i].genus < 0 ? -1 : all + c.comp[i].genus;
  printf("points=%zu triangles=%zu manifold=%d closed=%d oriented=%d "
         "components=%llu genus=%lld unused=%llu outward=%d genus_all=%lld\n",
         pts.count, ntri, c.manifold, c.closed, c.oriented,
         (unsigned long long)c.components, (long long)c.genus_total,
         (unsigned long long)c.samples_unused, c.volume > 0, all);
  scs_meshcheck_free(&c);
  free(tri);
  scf_points_free(&pts);
  return 0;
}
