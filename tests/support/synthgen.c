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
 * or density. SURFACE may also be a triangle mesh file (.ply, .off, .obj,
 * .stl: any name with a dot), sampled uniformly at random by area
 * (scs_sample_mesh()), with noise of SIGMA times the mean spacing of N
 * samples on its area, and no density.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "shortcrust_files.h"
#include "synth.h"

/* Samples the mesh in path into xyz; 0, or 1 with a message. */
static int sample_mesh_file(const char *path, size_t n, double sigma,
                            uint64_t seed, double *xyz) {
  scf_points_t v = {0};
  uint32_t *tri = NULL;
  size_t ntri = 0;
  char msg[256];
  if (scf_mesh_read(path, &v, &tri, &ntri, msg, sizeof msg) != 0) {
    fprintf(stderr, "synthgen: %s\n", msg);
    return 1;
  }
  int rc = scs_sample_mesh(v.xyz, v.count, tri, ntri, n, seed, xyz);
  if (rc != 0) {
    fprintf(stderr, "synthgen: %s: %s\n", path,
            ntri == 0 ? "no triangles" : "a bad or empty mesh");
  } else if (sigma != 0) {
    const double area = scs_mesh_area(v.xyz, tri, ntri);
    scs_add_noise(xyz, n, sigma * sqrt(area / (double)n), seed + 1000);
  }
  free(tri);
  scf_points_free(&v);
  return rc != 0;
}

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
  const int mesh = nboxes == 0 && strchr(argv[1], '.') != NULL;
  if (mesh) {
    if (bad || argc == 7 || sample_mesh_file(argv[1], n, sigma, seed, xyz)) {
      fprintf(stderr, "%s: bad mesh, count or density (meshes: none)\n",
              argv[0]);
      free(xyz);
      return 1;
    }
  } else if (!bad && nboxes > 0) /* no noise: their spacing is not kept */
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
  if (nboxes == 0 && !mesh)
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
