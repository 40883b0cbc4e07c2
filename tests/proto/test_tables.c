/*
 * The library's tables agree with PROTOCOL.md: frame types and who sends
 * them (section 3.2), modes, stages and formats (section 4), wire error
 * codes (section 9); and the library's own error codes are distinct, named,
 * and mapped to wire codes with the fatality section 8 gives them.
 *
 * Usage: test_proto_tables path/to/PROTOCOL.md
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <ctype.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mdtable.h"
#include "sct_assert.h"
#include "scproto.h"

typedef struct section_rows {
  int types, errors, modes, stages, formats;
} section_rows_t;

static void check_row(const char *section, char **c, int n,
                      section_rows_t *seen) {
  char *end;
  if (strncmp(section, "### 3.2", 7) == 0 && n >= 3 &&
      strncmp(c[0], "0x", 2) == 0) {
    unsigned long type = strtoul(c[0], &end, 16);
    ASSERT_EQ(*end, '\0');
    ASSERT_STR_EQ(scp_type_name((uint16_t)type), c[1]);
    int want = 0;
    if (strchr(c[2], 'C'))
      want |= SCP_FROM_CLIENT;
    if (strchr(c[2], 'S'))
      want |= SCP_FROM_SERVER;
    ASSERT_EQ(scp_type_senders((uint16_t)type), want);
    seen->types++;
  } else if (strncmp(section, "## 9.", 5) == 0 && n >= 2 &&
             isdigit((unsigned char)c[0][0])) {
    unsigned long code = strtoul(c[0], &end, 10);
    ASSERT_EQ(*end, '\0');
    ASSERT_STR_EQ(scp_wire_name((uint32_t)code), c[1]);
    ASSERT_STR_NE(scp_wire_strerror((uint32_t)code), "unknown error");
    seen->errors++;
  } else if (strncmp(section, "## 4.", 5) == 0 && n >= 2 &&
             isdigit((unsigned char)c[0][0])) {
    unsigned long v = strtoul(c[0], &end, 10);
    ASSERT_EQ(*end, '\0');
    /* Section 4 holds three tables of value/name; tell them apart by the
     * name, which each table's library function knows. */
    if (strcmp(scp_mode_name((uint32_t)v), c[1]) == 0 &&
        seen->stages == 0 && seen->formats == 0) {
      seen->modes++;
    } else if (strcmp(scp_stage_name((uint32_t)v), c[1]) == 0 &&
               seen->formats == 0) {
      seen->stages++;
    } else {
      /* value | name | element | size */
      ASSERT_GE(n, 4);
      ASSERT_GT(scp_format_size((uint32_t)v), 0);
      ASSERT_EQ(scp_format_size((uint32_t)v), strtoul(c[3], NULL, 10));
      static const char *const fmt[] = {NULL, "F32_XYZ", "F64_XYZ",
                                        "U32_TRIANGLE", "I32"};
      ASSERT(v >= 1 && v <= 4);
      ASSERT_STR_EQ(c[1], fmt[v]);
      seen->formats++;
    }
  }
}

static void check_document(const char *path) {
  FILE *fp = fopen(path, "r");
  if (!fp)
    ASSERT_FAIL("cannot open %s", path);
  char line[512], section[sizeof line] = "";
  section_rows_t seen = {0, 0, 0, 0, 0};
  while (fgets(line, sizeof line, fp)) {
    if (line[0] == '#') {
      snprintf(section, sizeof section, "%s", line);
      continue;
    }
    char *cells[8];
    int n = row_cells(line, cells, 8);
    if (n > 0)
      check_row(section, cells, n, &seen);
  }
  fclose(fp);
  ASSERT_EQ(seen.types, 19);
  ASSERT_EQ(seen.errors, 18);
  ASSERT_EQ(seen.modes, SCP_MODE_COUNT);
  ASSERT_EQ(seen.stages, SCP_STAGE_COUNT);
  ASSERT_EQ(seen.formats, 4);
}

static void check_library_codes(void) {
  static const struct {
    int code;
    const char *name;
    uint32_t wire;
    int fatal;
  } want[] = {
      {SCP_EINVAL, "INVAL", SCP_WIRE_INTERNAL, 1},
      {SCP_ENOMEM, "NOMEM", SCP_WIRE_NO_MEMORY, 1},
      {SCP_ETOOBIG, "TOOBIG", SCP_WIRE_LIMIT, 1},
      {SCP_ERESERVED, "RESERVED", SCP_WIRE_PROTOCOL, 1},
      {SCP_EBADMAGIC, "BADMAGIC", SCP_WIRE_PROTOCOL, 1},
      {SCP_EHANDSHAKE, "HANDSHAKE", SCP_WIRE_PROTOCOL, 1},
      {SCP_EVERSION, "VERSION", SCP_WIRE_VERSION, 1},
      {SCP_ETRUNCATED, "TRUNCATED", SCP_WIRE_PROTOCOL, 1},
      {SCP_ESHORT, "SHORT", SCP_WIRE_PROTOCOL, 1},
      {SCP_ELENGTH, "LENGTH", SCP_WIRE_PROTOCOL, 1},
      {SCP_EUNKNOWN_TYPE, "UNKNOWN_TYPE", SCP_WIRE_UNKNOWN_TYPE, 0},
      {SCP_ERANGE, "RANGE", SCP_WIRE_INVALID, 0},
      {SCP_EFLAGS, "FLAGS", SCP_WIRE_INVALID, 0},
  };
  size_t n = sizeof want / sizeof want[0];
  for (size_t i = 0; i < n; i++) {
    ASSERT_LT(want[i].code, 0);
    ASSERT_STR_EQ(scp_err_name(want[i].code), want[i].name);
    ASSERT_STR_NE(scp_strerror(want[i].code), "unknown error");
    ASSERT_EQ(scp_err_to_wire(want[i].code), want[i].wire);
    ASSERT_EQ(scp_err_is_fatal(want[i].code), want[i].fatal);
    for (size_t j = 0; j < i; j++)
      ASSERT_NE(want[i].code, want[j].code);
  }
  /* Codes the table lacks: unknown, and fatal to be safe. */
  ASSERT_STR_EQ(scp_err_name(-1000), "UNKNOWN");
  ASSERT_STR_EQ(scp_strerror(-1000), "unknown error");
  ASSERT_EQ(scp_err_to_wire(-1000), SCP_WIRE_INTERNAL);
  ASSERT_EQ(scp_err_is_fatal(-1000), 1);
  ASSERT_STR_EQ(scp_err_name(0), "OK");
  ASSERT_EQ(scp_err_is_fatal(0), 0);

  /* Wire codes this version does not define must still be accepted and
   * shown (section 9). */
  ASSERT_STR_EQ(scp_wire_name(0), "UNKNOWN");
  ASSERT_STR_EQ(scp_wire_name(19), "UNKNOWN");
  ASSERT_STR_EQ(scp_wire_strerror(0xFFFFFFFFu), "unknown error");

  /* Names outside the tables. */
  ASSERT_STR_EQ(scp_type_name(0), "?");
  ASSERT_STR_EQ(scp_type_name(0x8000), "?");
  ASSERT_EQ(scp_type_senders(0x8000), 0);
  ASSERT_STR_EQ(scp_mode_name(SCP_MODE_COUNT), "?");
  ASSERT_STR_EQ(scp_stage_name(SCP_STAGE_COUNT), "?");
  ASSERT_STR_EQ(scp_stage_name(SCP_STAGE_UPLOAD), "upload");
  ASSERT_STR_EQ(scp_stage_name(SCP_STAGE_DOWNLOAD), "download");
  ASSERT_EQ(scp_format_size(0), 0);
  ASSERT_EQ(scp_format_size(5), 0);
}

int main(int argc, char **argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: %s PROTOCOL.md\n", argv[0]);
    return 2;
  }
  check_document(argv[1]);
  check_library_codes();
  return sct_finish("proto_tables");
}
