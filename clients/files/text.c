/*
 * XYZ-like text (.xyz, .txt, .pts, .csv): one point per line.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "scf_internal.h"

#include <stdio.h>
#include <stdlib.h>

/* Columns after x, y, z carried as per-point properties, at most. */
#define TEXT_MAX_COLS 64

/*
 * Columns after x, y, z, when the caller wants them: the first data line
 * decides. If all its further columns are numbers, each becomes a double
 * property, named by the .csv header when it names every column, else
 * f0, f1, ...; every later line must then have as many. Otherwise (a text
 * label, say) they are ignored, as they are when not wanted.
 */
typedef struct text_cols {
  int n; /* -1 until the first data line */
  char names[TEXT_MAX_COLS][32];
  int named;
} text_cols_t;

/* The numbers after x, y, z on a line: their count (TEXT_MAX_COLS + 1 for
 * more), or -1 when one is not a number. */
static int extra_numbers(char *cur, double *out) {
  int n = 0;
  char *tok;
  while ((tok = scf__next_tok(&cur, SCF__XYZ_SEPS)) != NULL) {
    if (n == TEXT_MAX_COLS)
      return TEXT_MAX_COLS + 1;
    if (scf__parse_double(tok, &out[n]) < 0)
      return -1;
    n++;
  }
  return n;
}

/* The .csv header's names for the columns after the third. */
static void header_names(const char *line, text_cols_t *tc) {
  char *copy = strdup(line), *c = copy, *tok;
  int i = 0;
  tc->named = 0;
  while (copy != NULL && (tok = scf__next_tok(&c, SCF__XYZ_SEPS)) != NULL) {
    if (i >= 3 && i - 3 < TEXT_MAX_COLS)
      snprintf(tc->names[i - 3], sizeof tc->names[0], "%s", tok);
    i++;
  }
  free(copy);
  tc->named = i - 3;
}

static int extra_columns(scf__rd_t *r, scf__vbuf_t *v, text_cols_t *tc,
                         char *cur) {
  double val[TEXT_MAX_COLS + 1];
  int n = extra_numbers(cur, val);
  int rc;
  if (tc->n < 0) {
    tc->n = n > 0 && n <= TEXT_MAX_COLS ? n : 0;
    for (int k = 0; k < tc->n; k++) {
      char name[32];
      if (tc->named == tc->n)
        snprintf(name, sizeof name, "%s", tc->names[k]);
      else
        snprintf(name, sizeof name, "f%d", k);
      if ((rc = scf__attrs_add(r, v->attrs, name, SCF_TYPE_FLOAT64)) < 0)
        return rc;
    }
  }
  if (tc->n == 0)
    return 0;
  if (n != tc->n)
    return scf__rd_fail_line(
        r, r->line, SCF_EFORMAT,
        n < 0 ? "a column after x, y, z is not a number, but the first point's "
                "%d further columns were"
              : "%d columns after x, y, z, but the first point had %d",
        n < 0 ? tc->n : n, tc->n);
  unsigned char rec[8 * TEXT_MAX_COLS];
  for (int k = 0; k < n; k++)
    scf__put_f64le(rec + 8 * k, val[k]);
  return scf__attrs_push(r, v, rec);
}

/*
 * XYZ-like text. The first line of a .pts file may be the point count and
 * the first line of a .csv file may name the columns; both are skipped.
 */
int scf__read_xyz(scf__rd_t *r, enum scf__kind kind, scf__vbuf_t *v) {
  char *line;
  int rc, first = 1;
  text_cols_t tc;
  tc.n = -1;
  tc.named = 0;
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
        if (!numeric) {
          header_names(cur, &tc);
          continue;
        }
      }
    }
    double xyz[3];
    const char *bad;
    int ntok;
    if (scf__three_numbers(&cur, SCF__XYZ_SEPS, xyz, &bad, &ntok) < 0)
      return scf__bad_numbers(r, "", bad, ntok);
    if ((rc = scf__vbuf_push(r, v, xyz[0], xyz[1], xyz[2])) < 0)
      return rc;
    if (v->attrs != NULL && (rc = extra_columns(r, v, &tc, cur)) < 0)
      return rc;
  }
  return rc;
}
