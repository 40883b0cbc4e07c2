/*
 * XYZ-like text (.xyz, .txt, .pts, .csv): one point per line.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "scf_internal.h"

#include <stdio.h>

/*
 * XYZ-like text. The first line of a .pts file may be the point count and
 * the first line of a .csv file may name the columns; both are skipped.
 */
int scf__read_xyz(scf__rd_t *r, enum scf__kind kind, scf__vbuf_t *v) {
  char *line;
  int rc, first = 1;
  while ((rc = scf__rd_line(r, &line)) == 1) {
    scf__strip_comment(line);
    char *cur = line + strspn(line, SCF__XYZ_SEPS);
    if (*cur == '\0')
      continue;
    if (first) {
      first = 0;
      char copy[64], *c = copy, *tok;
      snprintf(copy, sizeof copy, "%s", cur);
      uint64_t n;
      double d;
      if (kind == SCF__K_PTS &&
          (tok = scf__next_tok(&c, SCF__XYZ_SEPS)) != NULL &&
          scf__parse_u64(tok, &n) == 0 &&
          scf__next_tok(&c, SCF__XYZ_SEPS) == NULL && strlen(cur) < sizeof copy)
        continue;
      if (kind == SCF__K_CSV) {
        int numeric = 0;
        for (int i = 0;
             i < 3 && (tok = scf__next_tok(&c, SCF__XYZ_SEPS)) != NULL; i++)
          numeric |= scf__parse_double(tok, &d) == 0;
        if (!numeric)
          continue;
      }
    }
    double xyz[3];
    const char *bad;
    int ntok;
    if (scf__three_numbers(&cur, SCF__XYZ_SEPS, xyz, &bad, &ntok) < 0)
      return scf__bad_numbers(r, "", bad, ntok);
    if ((rc = scf__vbuf_push(r, v, xyz[0], xyz[1], xyz[2])) < 0)
      return rc;
  }
  return rc;
}
