/*
 * Real scans shipped in tests/data: closed 2-manifolds of the known genus,
 * consistently oriented outward, with (almost) every sample a vertex.
 *
 *   test_core_realdata FILE GENUS
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <stdlib.h>

#include "check.h"
#include "files.h"
#include "shortcrust.h"
#include "testsupport.h"

int main(int argc, char **argv) {
  if (argc != 3) {
    fprintf(stderr, "usage: %s FILE GENUS\n", argv[0]);
    return 2;
  }
  int genus = atoi(argv[2]);
  char msg[512];
  sc_points_t pts;
  if (sc_points_read(argv[1], &pts, msg, sizeof msg) != 0) {
    fprintf(stderr, "FAIL: %s\n", msg);
    return 1;
  }
  sc_params_t p;
  sc_params_init(&p);
  sc_mesh_t *m = NULL;
  int rc = sc_reconstruct(pts.xyz, pts.count, &p, &m, msg, sizeof msg);
  CHECK_EQ_INT(rc, 0);
  if (rc != 0) {
    fprintf(stderr, "%s\n", msg);
    return CHECK_DONE();
  }
  sc_meshcheck_t c;
  CHECK_EQ_INT(sc_meshcheck(pts.count, pts.xyz, m->triangles,
                            m->triangle_count, NULL, &c),
               0);
  char line[512];
  printf("%s: %s\n", argv[1], sc_meshcheck_summary(&c, line, sizeof line));
  CHECK(c.manifold);
  CHECK(c.closed);
  CHECK(c.oriented);
  CHECK_EQ_INT(c.components, 1);
  CHECK_EQ_INT(c.genus_total, genus);
  CHECK(c.volume > 0);
  /* A stray sample or two far from the surface may stay out. */
  CHECK(c.samples_unused * 1000 <= pts.count);
  CHECK_EQ_INT(m->diag.genus, genus);
  CHECK(m->diag.closed);
  sc_meshcheck_free(&c);
  sc_mesh_free(m);
  sc_points_free(&pts);
  return CHECK_DONE();
}
