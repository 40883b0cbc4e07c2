/*
 * The core's tables agree with PROTOCOL.md, so that the spec cannot drift
 * from the code that is made from them: the job options of section 6.3
 * (name, kind, range, default) are the parameters whose wire role is
 * OPTION, the diagnostics of section 6.12 are the rows of SC_DIAG_MAP with
 * their wire names and kinds, in the order JOB_DONE carries them, and the
 * modes and stages of section 4 are numbered and named as in the core.
 *
 * Usage: test_proto_core_tables path/to/PROTOCOL.md
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mdtable.h"
#include "scproto.h"
#include "sct_assert.h"
#include "shortcrust.h"

/* A default as the spec writes it: a number, or "pi/N". */
static double spec_number(const char *s) {
  if (strncmp(s, "pi/", 3) == 0)
    return SC_PI / strtod(s + 3, NULL);
  return strtod(s, NULL);
}

static const char *option_kind(sc_param_kind_t k) {
  return k == SC_PARAM_REAL || k == SC_PARAM_ANGLE ? "f64" : "u64";
}

/* A row of a name | kind | ... table, not its header. */
static int named_row(char **c, int n) {
  return n >= 3 && islower((unsigned char)c[0][0]) &&
         (strcmp(c[1], "u64") == 0 || strcmp(c[1], "i64") == 0 ||
          strcmp(c[1], "f64") == 0);
}

/* Section 6.3's option rows: name | kind | range | meaning (default). */
static int check_option(char **c, int n) {
  size_t count;
  const sc_param_info_t *rows = sc_param_table(&count);
  if (n < 4 || !named_row(c, n))
    return 0;
  const sc_param_info_t *row = NULL;
  for (size_t i = 0; i < count; ++i)
    if (strcmp(rows[i].name, c[0]) == 0)
      row = &rows[i];
  if (!row)
    ASSERT_FAIL("PROTOCOL.md 6.3: option %s is not in SC_PARAM_MAP", c[0]);
  EXPECT_EQ(row->wire, SC_PARAM_OPTION);
  EXPECT_STR_EQ(c[1], option_kind(row->kind));
  /* The table words a range for messages ("in (0, 10]", "0 or 1"). */
  const char *text = row->range_text;
  if (strncmp(text, "in ", 3) == 0)
    text += 3;
  EXPECT_STR_EQ(c[2], text);
  const char *open = strrchr(c[3], '(');
  ASSERT_NOT_NULL(open);
  EXPECT_NEAR(spec_number(open + 1), row->dflt, 1e-12 * fabs(row->dflt));
  return 1;
}

/* Section 6.12's rows, name | kind | meaning, against the names the core's
 * table gives on the wire, in order; at the end, the server's own. */
typedef struct wire_names {
  char name[96][64];
  const char *kind[96];
  size_t count;
} wire_names_t;

static const char *diag_kind(sc_diag_kind_t k) {
  switch (k) {
  case SC_DIAG_INT:
    return "i64";
  case SC_DIAG_REAL:
  case SC_DIAG_SECONDS:
  case SC_DIAG_STAGE_SECONDS:
    return "f64";
  default:
    return "u64";
  }
}

static void expected_diagnostics(wire_names_t *w) {
  size_t count;
  const sc_diag_info_t *rows = sc_diag_table(&count);
  w->count = 0;
  for (size_t r = 0; r < count; ++r) {
    for (size_t i = 0; i < rows[r].count; ++i) {
      ASSERT_LT(w->count, 94);
      const char *suffix = sc_diag_element_name(&rows[r], i);
      if (suffix)
        snprintf(w->name[w->count], sizeof w->name[0], "%s.%s", rows[r].wire,
                 suffix);
      else
        snprintf(w->name[w->count], sizeof w->name[0], "%s", rows[r].wire);
      w->kind[w->count++] = diag_kind(rows[r].kind);
    }
  }
  /* The daemon's own, about the job rather than the reconstruction. */
  snprintf(w->name[w->count], sizeof w->name[0], "seconds.upload");
  w->kind[w->count++] = "f64";
  snprintf(w->name[w->count], sizeof w->name[0], "seconds.server");
  w->kind[w->count++] = "f64";
}

static void check_document(const char *path) {
  FILE *fp = fopen(path, "r");
  if (!fp)
    ASSERT_FAIL("cannot open %s", path);
  wire_names_t want;
  expected_diagnostics(&want);
  char line[512], section[sizeof line] = "";
  int options = 0, modes = 0, stages = 0;
  size_t diags = 0;
  while (fgets(line, sizeof line, fp)) {
    if (line[0] == '#') {
      snprintf(section, sizeof section, "%s", line);
      continue;
    }
    char *c[8];
    int n = row_cells(line, c, 8);
    if (n == 0)
      continue;
    if (strncmp(section, "### 6.3", 7) == 0) {
      options += check_option(c, n);
    } else if (strncmp(section, "### 6.12", 8) == 0 && named_row(c, n)) {
      ASSERT_LT(diags, want.count);
      EXPECT_STR_EQ(c[0], want.name[diags]);
      EXPECT_STR_EQ(c[1], want.kind[diags]);
      diags++;
    } else if (strncmp(section, "## 4.", 5) == 0 && n >= 2 &&
               isdigit((unsigned char)c[0][0])) {
      int v = atoi(c[0]);
      /* Modes come first, then stages, then formats (another test's). */
      if (stages == 0 && strcmp(sc_mode_name(v), c[1]) == 0)
        modes++;
      else if (strcmp(sc_stage_name(v), c[1]) == 0)
        stages++;
    }
  }
  fclose(fp);
  size_t count, want_options = 0;
  const sc_param_info_t *rows = sc_param_table(&count);
  for (size_t i = 0; i < count; ++i)
    want_options += rows[i].wire == SC_PARAM_OPTION;
  EXPECT_EQ(options, want_options);
  EXPECT_EQ(diags, want.count);
  EXPECT_EQ(modes, SC_MODE_COUNT_);
  EXPECT_EQ(stages, SC_STAGE_COUNT);
}

int main(int argc, char **argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: %s PROTOCOL.md\n", argv[0]);
    return 2;
  }
  check_document(argv[1]);
  return sct_finish("proto_core_tables");
}
