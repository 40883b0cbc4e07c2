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
  p.mode = SC_MODE_COUNT_;
  for (int k = 0; k < SC_MODE_COUNT_; ++k)
    if (strcmp(argv[1], sc_mode_name(k)) == 0)
      p.mode = (sc_mode_t)k;
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
    char msg[512];
    sc_mesh_t *m = NULL;
    const int rc = sc_reconstruct(xyz, total, &p, &m, msg, sizeof msg);
    EXPECT_EQ(rc, 0);
    if (rc != 0) {
      fprintf(stderr, "%s\n", msg);
      continue;
    }
    scs_meshcheck_t c;
    EXPECT_EQ(
        scs_meshcheck(total, xyz, m->triangles, m->triangle_count, NULL, &c),
        0);
    char line[512];
    printf("%s, %s: %s; %llu attached\n", argv[1], kOrders[order],
           scs_meshcheck_summary(&c, line, sizeof line),
           (unsigned long long)m->diag.samples_attached);
    EXPECT_CLOSED_PIECE(m->diag, c, genus, total);
    // Every sample, the chain's too.
    EXPECT_EQ(m->diag.samples_unused, 0);
    EXPECT_EQ(c.samples_unused, 0);
    scs_meshcheck_free(&c);
    sc_mesh_free(m);
  }
  free(cube);
  free(xyz);
  return sct_finish("core_attach");
}
