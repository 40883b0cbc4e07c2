/*
 * synthgen: writes a seeded sample of an analytic test surface, with
 * Gaussian noise of a given multiple of the sample spacing, as an .xyz
 * file, for the shell tests of the commands.
 *
 *   synthgen SURFACE N SIGMA SEED OUT.xyz [DENSITY]
 *
 * DENSITY is uniform (well spaced, the default), uniform-random or
 * adaptive (denser where the surface curves more). SURFACE may also be a
 * shape of boxes with sharp edges (cube, plate, fin, frame:
 * scs_box_shape()), sampled uniformly at random, without noise (SIGMA 0)
 * or density.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <stdio.h>
#include <stdlib.h>

#include "synth.h"

int main(int argc, char **argv) {
  if (argc != 6 && argc != 7) {
    fprintf(stderr, "usage: %s SURFACE N SIGMA SEED OUT.xyz [DENSITY]\n",
            argv[0]);
    return 2;
  }
  const int s = scs_surface_from_name(argv[1]);
  const int d =
      argc == 7 ? scs_density_from_name(argv[6]) : SCS_DENSITY_UNIFORM;
  const size_t n = strtoul(argv[2], NULL, 10);
  const double sigma = atof(argv[3]);
  const uint64_t seed = strtoull(argv[4], NULL, 10);
  double *xyz = malloc(3 * n * sizeof *xyz);
  double boxes[6 * SCS_MAX_BOXES];
  int genus;
  const size_t nboxes = scs_box_shape(argv[1], n, boxes, &genus);
  int bad = n < 4 || !xyz;
  if (!bad && nboxes > 0) /* no noise on those: their spacing is not kept */
    bad = sigma != 0 || argc == 7 ||
          scs_sample_boxes(boxes, nboxes, n, seed, xyz) != 0;
  else if (!bad)
    bad = s < 0 || d < 0 ||
          scs_sample_surface((scs_surface_t)s, (scs_density_t)d, n, seed,
                             xyz) != 0;
  if (bad) {
    fprintf(stderr,
            "%s: bad surface, density or count (box shapes: no noise, no "
            "density), or sampling failed\n",
            argv[0]);
    return 1;
  }
  if (nboxes == 0)
    scs_add_noise(xyz, n, sigma * scs_surface_spacing((scs_surface_t)s, n),
                  seed + 1000);
  FILE *f = fopen(argv[5], "w");
  if (!f) {
    perror(argv[5]);
    return 1;
  }
  for (size_t i = 0; i < n; ++i)
    fprintf(f, "%.17g %.17g %.17g\n", xyz[3 * i], xyz[3 * i + 1],
            xyz[3 * i + 2]);
  free(xyz);
  return fclose(f) == 0 ? 0 : 1;
}
