/*
 * Real scans and the vertex sets of closed models shipped in tests/data:
 * closed 2-manifolds of the known genus, consistently oriented outward,
 * with (almost) every sample a vertex, in the default mode or the one
 * named.
 *
 *   test_core_realdata FILE GENUS [MODE]    (a name of sc_mode_name())
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "diag.h"
#include "shortcrust.h"
#include "shortcrust_files.h"
#include "synth.h"

int main(int argc, char **argv) {
  if (argc != 3 && argc != 4) {
    fprintf(stderr, "usage: %s FILE GENUS [MODE]\n", argv[0]);
    return 2;
  }
  sc_params_t p;
  sc_params_init(&p);
  if (argc == 4) {
    p.mode = sct_mode_from_name(argv[3]);
    if (p.mode == SC_MODE_COUNT_) {
      fprintf(stderr, "unknown mode '%s'\n", argv[3]);
      return 2;
    }
  }
  int genus = atoi(argv[2]);
  char msg[512];
  scf_points_t pts;
  if (scf_points_read(argv[1], &pts, msg, sizeof msg) != 0) {
    fprintf(stderr, "FAIL: %s\n", msg);
    return 1;
  }
  char what[512];
  snprintf(what, sizeof what, "%s %s", argv[1], argc == 4 ? argv[3] : "");
  sc_mesh_t *m = sct_expect_closed(pts.xyz, pts.count, &p, genus, 0, what);
  if (!m) {
    scf_points_free(&pts);
    return sct_finish("core_realdata");
  }
  /* Right, so shortcrust mode's check finds no doubt (docs/algorithm.md
   * section 6.5); the other modes make none. */
  EXPECT_EQ(m->diag.checked, p.mode == SC_MODE_SHORTCRUST);
  EXPECT_EQ(m->diag.topology_doubt, 0);
  sc_mesh_free(m);
  scf_points_free(&pts);
  return sct_finish("core_realdata");
}
