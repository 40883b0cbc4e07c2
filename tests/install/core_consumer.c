/*
 * Built against the installed core only (shortcrust.pc or
 * find_package(shortcrust)): reconstructs an evenly sampled sphere and
 * checks that the mesh is a closed, consistently oriented surface of genus
 * 0 through every point.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <shortcrust.h>

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#define N 2000

static int fail(const char *what) {
  fprintf(stderr, "core_consumer: FAIL: %s\n", what);
  return 1;
}

static int cmp_u64(const void *a, const void *b) {
  uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return (x > y) - (x < y);
}

/* Each directed edge once, and its reverse too: closed and oriented. */
static int closed_and_oriented(const uint32_t *tri, size_t count) {
  size_t e = 3 * count;
  uint64_t *edges = malloc(e * sizeof *edges);
  if (!edges)
    return 0;
  for (size_t t = 0; t < count; t++)
    for (int k = 0; k < 3; k++) {
      uint64_t a = tri[3 * t + k], b = tri[3 * t + (k + 1) % 3];
      edges[3 * t + k] = a << 32 | b;
    }
  qsort(edges, e, sizeof *edges, cmp_u64);
  int ok = 1;
  for (size_t i = 0; ok && i < e; i++) {
    if (i > 0 && edges[i] == edges[i - 1])
      ok = 0;
    uint64_t rev = edges[i] << 32 | edges[i] >> 32;
    if (!bsearch(&rev, edges, e, sizeof *edges, cmp_u64))
      ok = 0;
  }
  free(edges);
  return ok;
}

int main(void) {
  /* A Fibonacci lattice on the unit sphere. */
  static double xyz[3 * N];
  const double golden = 3.0 - sqrt(5.0), pi = 3.14159265358979323846;
  for (int i = 0; i < N; i++) {
    double z = 1.0 - (2.0 * i + 1.0) / N, r = sqrt(1.0 - z * z);
    double phi = pi * golden * i;
    xyz[3 * i] = r * cos(phi);
    xyz[3 * i + 1] = r * sin(phi);
    xyz[3 * i + 2] = z;
  }

  sc_params_t p;
  sc_params_init(&p);
  char msg[256] = "";
  if (sc_params_check(&p, msg, sizeof msg) != SC_OK)
    return fail(msg);

  sc_mesh_t *m = NULL;
  int rc = sc_reconstruct(xyz, N, &p, &m, msg, sizeof msg);
  if (rc != SC_OK) {
    fprintf(stderr, "core_consumer: sc_reconstruct: %s (%s): %s\n",
            sc_err_name(rc), sc_strerror(rc), msg);
    return 1;
  }
  printf("core_consumer: %zu triangles, closed %d, genus %lld, path %s\n",
         m->triangle_count, m->diag.closed, (long long)m->diag.genus,
         sc_path_name(m->diag.path));
  int bad = 0;
  if (!m->diag.closed || m->diag.genus != 0 || m->diag.components != 1)
    bad = fail("not one closed surface of genus 0");
  else if (m->triangle_count != 2 * N - 4 || m->diag.samples_unused != 0)
    bad = fail("not every point in the mesh");
  else if (!closed_and_oriented(m->triangles, m->triangle_count))
    bad = fail("edges not paired with opposite orientations");
  sc_mesh_free(m);

  /* An error comes back as a code with a name. */
  double flat[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  rc = sc_reconstruct(flat, 4, &p, &m, msg, sizeof msg);
  if (rc != SC_EDEGENERATE_INPUT || m != NULL)
    bad = fail("four coplanar points were not DEGENERATE_INPUT");
  return bad;
}
