/*
 * Closed shapes with sharp edges and thin parts, sampled at random over
 * unions of boxes (scs_sample_boxes()): each must come out a closed,
 * oriented 2-manifold of one component and the shape's genus, with (almost)
 * every sample a vertex, in the mode named.
 *
 *   test_core_shapes SHAPE N SEED MODE
 *
 * SHAPE is one of scs_box_shape()'s: cube (sharp edges and corners),
 * plate (a thin part), fin (a thin part on a body), frame (a handle with
 * sharp edges).
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "diag.h"
#include "shortcrust.h"
#include "synth.h"

int main(int argc, char **argv) {
  if (argc != 5) {
    fprintf(stderr, "usage: %s SHAPE N SEED MODE\n", argv[0]);
    return 2;
  }
  const size_t n = strtoul(argv[2], NULL, 10);
  const uint64_t seed = strtoull(argv[3], NULL, 10);
  sc_params_t p;
  sc_params_init(&p);
  p.mode = sct_mode_from_name(argv[4]);
  double boxes[6 * SCS_MAX_BOXES];
  int genus;
  const size_t nboxes = scs_box_shape(argv[1], n, boxes, &genus);
  if (p.mode == SC_MODE_COUNT_ || nboxes == 0 || n < 100) {
    fprintf(stderr, "unknown shape or mode, or too few points\n");
    return 2;
  }
  double *xyz = malloc(3 * n * sizeof *xyz);
  EXPECT(xyz != NULL);
  if (!xyz)
    return sct_finish("core_shapes");
  EXPECT_EQ(scs_sample_boxes(boxes, nboxes, n, seed, xyz), 0);
  char what[128];
  snprintf(what, sizeof what, "%s %zu %s", argv[1], n, argv[4]);
  sc_mesh_free(sct_expect_closed(xyz, n, &p, genus, 0, what));
  free(xyz);
  return sct_finish("core_shapes");
}
