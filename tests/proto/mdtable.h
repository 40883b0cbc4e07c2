/*
 * Reading the tables of PROTOCOL.md, for the tests that hold the code to
 * the document.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SC_TESTS_PROTO_MDTABLE_H
#define SC_TESTS_PROTO_MDTABLE_H

#include <ctype.h>
#include <string.h>

/* Splits a markdown table row into at most max trimmed cells; returns the
 * number of cells, or 0 for a line that is not a row. */
static inline int row_cells(char *line, char **cells, int max) {
  if (line[0] != '|')
    return 0;
  int n = 0;
  char *p = line + 1;
  while (n < max) {
    char *bar = strchr(p, '|');
    if (!bar)
      break;
    *bar = '\0';
    while (isspace((unsigned char)*p) || *p == '`')
      p++;
    char *end = bar;
    while (end > p && (isspace((unsigned char)end[-1]) || end[-1] == '`'))
      *--end = '\0';
    cells[n++] = p;
    p = bar + 1;
  }
  return n;
}

#endif /* SC_TESTS_PROTO_MDTABLE_H */
