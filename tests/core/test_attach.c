/*
 * Samples beyond the end of a part too thin for its sampling: a chain of
 * samples standing out of a cube's top face, each one a little under a
 * sample spacing past the last, as the samples of a horn's tip stand past
 * the surface that closes below them. Attaching samples (docs/algorithm.md
 * section 12) must take in the whole chain whatever the order the samples
 * come in: nearest first, farthest first, or the cube's samples after the
 * chain. Each order must give one closed, oriented 2-manifold of genus 0
 * with every sample a vertex, in the mode named.
 *
 *   test_core_attach MODE N SEED
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

enum { kChain = 4 };

int main(int argc, char **argv) {
  if (argc != 4) {
    fprintf(stderr, "usage: %s MODE N SEED\n", argv[0]);
    return 2;
  }
  sc_params_t p;
  sc_params_init(&p);
  p.mode = sct_mode_from_name(argv[1]);
  const size_t n = strtoul(argv[2], NULL, 10);
  const uint64_t seed = strtoull(argv[3], NULL, 10);
  double boxes[6 * SCS_MAX_BOXES];
  int genus;
  if (p.mode == SC_MODE_COUNT_ || n < 1000 ||
      scs_box_shape("cube", n, boxes, &genus) != 1) {
    fprintf(stderr, "unknown mode, or too few points\n");
    return 2;
  }
  const size_t total = n + kChain;
  double *cube = malloc(3 * n * sizeof *cube);
  double *xyz = malloc(3 * total * sizeof *xyz);
  EXPECT(cube != NULL && xyz != NULL);
  if (!cube || !xyz) {
    free(cube);
    free(xyz);
    return sct_finish("core_attach");
  }
  EXPECT_EQ(scs_sample_boxes(boxes, 1, n, seed, cube), 0);
  // The cube's faces are 1 wide: its samples are about sqrt(6 / n) apart.
  const double step = 0.8 * sqrt(6.0 / (double)n);
  static const char *const kOrders[] = {"nearest first", "farthest first",
                                        "chain before the cube"};
  for (int order = 0; order < 3; ++order) {
    double *chain = order == 2 ? xyz : xyz + 3 * n;
    memcpy(order == 2 ? xyz + 3 * kChain : xyz, cube, 3 * n * sizeof *cube);
    for (int k = 0; k < kChain; ++k) {
      const int out = order == 0 ? k + 1 : kChain - k;
      chain[3 * k] = 0.5;
      chain[3 * k + 1] = 0.5;
      chain[3 * k + 2] = 1 + out * step;
    }
    // Every sample, the chain's too.
    char what[128];
    snprintf(what, sizeof what, "%s, %s", argv[1], kOrders[order]);
    sc_mesh_free(sct_expect_closed(xyz, total, &p, genus, 1, what));
  }
  free(cube);
  free(xyz);
  return sct_finish("core_attach");
}
