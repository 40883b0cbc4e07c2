/*
 * meshcmp A B: whether two mesh files hold the same mesh: the same
 * vertices, bit for bit and in the same order, and the same triangles as
 * a multiset, each with its orientation (a triangle may start at any of
 * its three corners). Prints "same: V vertices, T triangles" and exits 0,
 * or prints the first difference and exits 1; 2 when a file cannot be
 * read.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "shortcrust_files.h"

/* Rotates a triangle so that its smallest index comes first, which keeps
 * its orientation. */
static void canonical(uint32_t *t) {
  while (t[0] > t[1] || t[0] > t[2]) {
    uint32_t a = t[0];
    t[0] = t[1];
    t[1] = t[2];
    t[2] = a;
  }
}

static int cmp_tri(const void *pa, const void *pb) {
  const uint32_t *a = pa, *b = pb;
  for (int k = 0; k < 3; k++)
    if (a[k] != b[k])
      return a[k] < b[k] ? -1 : 1;
  return 0;
}

int main(int argc, char **argv) {
  if (argc != 3) {
    fprintf(stderr, "usage: meshcmp A B\n");
    return 2;
  }
  scf_points_t p[2];
  uint32_t *t[2];
  size_t nt[2];
  char msg[1024];
  for (int i = 0; i < 2; i++) {
    if (scf_mesh_read(argv[1 + i], &p[i], &t[i], &nt[i], msg, sizeof msg)) {
      fprintf(stderr, "meshcmp: %s\n", msg);
      return 2;
    }
  }
  if (p[0].count != p[1].count) {
    printf("differ: %zu vertices against %zu\n", p[0].count, p[1].count);
    return 1;
  }
  for (size_t i = 0; i < 3 * p[0].count; i++) {
    if (memcmp(&p[0].xyz[i], &p[1].xyz[i], sizeof(double)) != 0) {
      printf("differ: vertex %zu: %.17g against %.17g\n", i / 3, p[0].xyz[i],
             p[1].xyz[i]);
      return 1;
    }
  }
  if (nt[0] != nt[1]) {
    printf("differ: %zu triangles against %zu\n", nt[0], nt[1]);
    return 1;
  }
  for (int i = 0; i < 2; i++) {
    for (size_t k = 0; k < nt[i]; k++)
      canonical(t[i] + 3 * k);
    qsort(t[i], nt[i], 3 * sizeof(uint32_t), cmp_tri);
  }
  for (size_t k = 0; k < nt[0]; k++) {
    if (cmp_tri(t[0] + 3 * k, t[1] + 3 * k) != 0) {
      printf("differ: triangle (%u %u %u) against (%u %u %u) in sorted "
             "order\n",
             t[0][3 * k], t[0][3 * k + 1], t[0][3 * k + 2], t[1][3 * k],
             t[1][3 * k + 1], t[1][3 * k + 2]);
      return 1;
    }
  }
  printf("same: %zu vertices, %zu triangles\n", p[0].count, nt[0]);
  for (int i = 0; i < 2; i++) {
    scf_points_free(&p[i]);
    free(t[i]);
  }
  return 0;
}
