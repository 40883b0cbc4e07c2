/*
 * Samples of the boundary of a union of axis-aligned boxes: closed
 * surfaces with sharp edges and corners, thin parts and handles whose
 * topology is known by construction (see scs_sample_boxes() in synth.h).
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Whether p lies in box b (6 doubles: the low corner, then the high one),
 * its boundary included. */
static int in_box(const double *b, const double p[3]) {
  for (int a = 0; a < 3; a++)
    if (p[a] < b[a] || p[a] > b[3 + a])
      return 0;
  return 1;
}

/* Each face of each box, and its area: face f of box i has axis f / 2 and
 * lies at the low (f even) or high (f odd) side. */
static double face_area(const double *b, int f) {
  const int a = f / 2, u = (a + 1) % 3, v = (a + 2) % 3;
  return (b[3 + u] - b[u]) * (b[3 + v] - b[v]);
}

int scs_sample_boxes(const double *boxes, size_t nboxes, size_t n,
                     uint64_t seed, double *xyz) {
  if (!boxes || nboxes == 0 || (n > 0 && !xyz))
    return SCS_EINVAL;
  double total = 0;
  for (size_t i = 0; i < nboxes; i++)
    for (int a = 0; a < 3; a++)
      if (!(boxes[6 * i + 3 + a] > boxes[6 * i + a]))
        return SCS_EINVAL;
  double *cum = malloc(6 * nboxes * sizeof *cum);
  if (!cum)
    return SCS_ENOMEM;
  for (size_t k = 0; k < 6 * nboxes; k++) {
    total += face_area(boxes + 6 * (k / 6), (int)(k % 6));
    cum[k] = total;
  }
  scs_rng_t rng;
  scs_rng_seed(&rng, seed);
  /* A point of a face, uniform by area, is kept unless the union goes on
   * beyond it: just outside the face (a step along its outward normal far
   * below the boxes' sizes), some box holds it. That drops the parts of
   * faces inside other boxes and the faces two boxes share. */
  size_t got = 0, tries = 0;
  const size_t max_tries = 1000 * (n + 1);
  while (got < n) {
    if (++tries > max_tries) {
      free(cum); /* the union has (almost) no surface left */
      return SCS_EINVAL;
    }
    const size_t lo = scs_rng_pick(&rng, cum, 6 * nboxes);
    const double *b = boxes + 6 * (lo / 6);
    const int f = (int)(lo % 6), a = f / 2, side = f % 2;
    double p[3];
    for (int k = 0; k < 3; k++)
      p[k] = b[k] + scs_rng_uniform(&rng) * (b[3 + k] - b[k]);
    p[a] = side ? b[3 + a] : b[a];
    double q[3] = {p[0], p[1], p[2]};
    const double step = 1e-9 * (b[3 + a] - b[a]);
    q[a] += side ? step : -step;
    int outside = 1;
    for (size_t j = 0; j < nboxes && outside; j++)
      outside = !in_box(boxes + 6 * j, q);
    if (!outside)
      continue;
    for (int k = 0; k < 3; k++)
      xyz[3 * got + k] = p[k];
    got++;
  }
  free(cum);
  return 0;
}

/* The thin parts are two spacings thick, the spacing taken from the
 * shape's area (about that of its large faces) and n. */
size_t scs_box_shape(const char *name, size_t n,
                     double boxes[6 * SCS_MAX_BOXES], int *genus) {
  *genus = 0;
  if (!name || n == 0)
    return 0;
  if (strcmp(name, "cube") == 0) {
    const double b[6] = {0, 0, 0, 1, 1, 1};
    memcpy(boxes, b, sizeof b);
    return 1;
  }
  if (strcmp(name, "plate") == 0) {
    const double t = 2 * sqrt(2.0 / (double)n);
    const double b[6] = {0, 0, 0, 1, 1, t};
    memcpy(boxes, b, sizeof b);
    return 1;
  }
  if (strcmp(name, "fin") == 0) {
    const double t = 2 * sqrt((6 + 2 * 0.6 * 0.6) / (double)n);
    const double b[12] = {0, 0,   0,           1,   1,   1,
                          1, 0.2, 0.5 - t / 2, 1.6, 0.8, 0.5 + t / 2};
    memcpy(boxes, b, sizeof b);
    return 2;
  }
  if (strcmp(name, "frame") == 0) {
    const double b[24] = {0,   0,   0, 1,   0.3, 0.2, /* four bars */
                          0,   0.7, 0, 1,   1,   0.2, /* round a */
                          0,   0.3, 0, 0.3, 0.7, 0.2, /* square */
                          0.7, 0.3, 0, 1,   0.7, 0.2};
    memcpy(boxes, b, sizeof b);
    *genus = 1;
    return 4;
  }
  return 0;
}
