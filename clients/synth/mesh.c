/*
 * Random samples of a triangle mesh: other samplings of a model than its
 * own vertex set, for measuring reconstruction against the mesh.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "internal.h"

#include <math.h>
#include <stdlib.h>

/* Twice the area of triangle abc. */
static double twice_area(const double *a, const double *b, const double *c) {
  double u[3], v[3];
  for (int k = 0; k < 3; k++)
    u[k] = b[k] - a[k], v[k] = c[k] - a[k];
  const double x = u[1] * v[2] - u[2] * v[1], y = u[2] * v[0] - u[0] * v[2],
               z = u[0] * v[1] - u[1] * v[0];
  return sqrt(x * x + y * y + z * z);
}

double scs_mesh_area(const double *vertices, const uint32_t *tri, size_t ntri) {
  double area = 0;
  for (size_t t = 0; t < ntri; t++) {
    const uint32_t *v = tri + 3 * t;
    area += twice_area(vertices + 3 * (size_t)v[0], vertices + 3 * (size_t)v[1],
                       vertices + 3 * (size_t)v[2]);
  }
  return area / 2;
}

int scs_sample_mesh(const double *vertices, size_t nv, const uint32_t *tri,
                    size_t ntri, size_t n, uint64_t seed, double *xyz) {
  if (!vertices || !tri || ntri == 0 || (n > 0 && !xyz))
    return SCS_EINVAL;
  for (size_t i = 0; i < 3 * ntri; i++)
    if (tri[i] >= nv)
      return SCS_EINVAL;
  double *cum = malloc(ntri * sizeof *cum);
  if (!cum)
    return SCS_ENOMEM;
  double total = 0;
  for (size_t t = 0; t < ntri; t++) {
    const uint32_t *v = tri + 3 * t;
    total +=
        twice_area(vertices + 3 * (size_t)v[0], vertices + 3 * (size_t)v[1],
                   vertices + 3 * (size_t)v[2]);
    cum[t] = total;
  }
  if (!(total > 0) || !isfinite(total)) {
    free(cum);
    return SCS_EINVAL;
  }
  scs_rng_t rng;
  scs_rng_seed(&rng, seed);
  for (size_t i = 0; i < n; i++) {
    /* A triangle by area, then a point uniform in it (the square root
     * spreads the first weight so that area, not the corner, is uniform). */
    const uint32_t *v = tri + 3 * scs_rng_pick(&rng, cum, ntri);
    const double *a = vertices + 3 * (size_t)v[0],
                 *b = vertices + 3 * (size_t)v[1],
                 *c = vertices + 3 * (size_t)v[2];
    const double s = sqrt(scs_rng_uniform(&rng)), w = scs_rng_uniform(&rng);
    for (int k = 0; k < 3; k++)
      xyz[3 * i + k] = (1 - s) * a[k] + s * (1 - w) * b[k] + s * w * c[k];
  }
  free(cum);
  return 0;
}
