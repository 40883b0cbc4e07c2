/*
 * The reconstruction's parameters on the command line and in the report,
 * made from the core's parameter and diagnostic tables (SC_PARAM_MAP and
 * SC_DIAG_MAP in shortcrust.h): the options, their --help lines, their
 * parsing, and the report's "params" and diagnostics. A parameter added to
 * the table is an option of every mesh-producing subcommand with nothing
 * written here.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <getopt.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "scproto.h"

/* The options about the output, after the parameters. */
static const struct option output_options[] = {
    {"output", required_argument, NULL, 'o'},
    {"report", required_argument, NULL, SC_CLI_OPT_REPORT},
    {"ascii", no_argument, NULL, SC_CLI_OPT_ASCII},
    {"no-normals", no_argument, NULL, SC_CLI_OPT_NO_NORMALS},
    {"mesh-normals", no_argument, NULL, SC_CLI_OPT_MESH_NORMALS},
    {"quiet", no_argument, NULL, 'q'},
};
enum { NOUTPUT = sizeof output_options / sizeof output_options[0] };

typedef sc_param_info_t param_row_t;

static int offered(const param_row_t *r, int local) {
  return r->long_opt && (local || r->wire != SC_PARAM_LOCAL);
}

int sc_cli_job_getopt(sc_cli_getopt_t *g, int local,
                      const struct option *own, const char *own_short) {
  size_t nrows;
  const param_row_t *rows = sc_param_table(&nrows);
  size_t n = 0;
  if (SC_CLI_OPT_PARAM + (int)nrows > SC_CLI_OPT_OWN)
    return -1;
  for (size_t i = 0; i < nrows; ++i) {
    if (!offered(&rows[i], local))
      continue;
    g->long_options[n++] = (struct option){
        rows[i].long_opt,
        rows[i].kind == SC_PARAM_FLAG ? no_argument : required_argument, NULL,
        SC_CLI_OPT_PARAM + (int)i};
  }
  for (size_t i = 0; i < NOUTPUT; ++i)
    g->long_options[n++] = output_options[i];
  for (; own && own->name; ++own) {
    if (n + 1 >= SC_CLI_MAX_OPTIONS)
      return -1;
    g->long_options[n++] = *own;
  }
  g->long_options[n] = (struct option){NULL, 0, NULL, 0};

  /* ':' first, so that a missing value is told from an unknown option. */
  size_t k = 0;
  g->short_options[k++] = ':';
  g->short_options[k++] = 'o';
  g->short_options[k++] = ':';
  g->short_options[k++] = 'q';
  for (size_t i = 0; i < nrows; ++i) {
    if (!offered(&rows[i], local) || !rows[i].short_opt)
      continue;
    g->short_options[k++] = (char)rows[i].short_opt;
    if (rows[i].kind != SC_PARAM_FLAG)
      g->short_options[k++] = ':';
  }
  size_t own_len = own_short ? strlen(own_short) : 0;
  if (k + own_len + 1 > sizeof g->short_options)
    return -1;
  memcpy(g->short_options + k, own_short, own_len);
  g->short_options[k + own_len] = '\0';
  return 0;
}

/* The range of an angle as the command line takes it, in degrees. */
static void degrees_range(char *buf, size_t len, const param_row_t *r) {
  snprintf(buf, len, "%c%g,\1%g%c", (r->range & SC_RANGE_LO_OPEN) ? '(' : '[',
           r->lo * 180 / SC_PI, r->hi * 180 / SC_PI,
           (r->range & SC_RANGE_HI_OPEN) ? ')' : ']');
}

/* Writes words to f from column col, breaking lines before column 79 and
 * indenting the next ones to column 24; a \1 is a space that does not
 * break. Returns the column reached. */
static int wrap(FILE *f, int col, const char *words) {
  const char *p = words;
  while (*p) {
    const char *end = strchr(p, ' ');
    size_t n = end ? (size_t)(end - p) : strlen(p);
    if (col > 24 && col + 1 + (int)n > 79) {
      fprintf(f, "\n%24s", "");
      col = 24;
    } else if (col > 24) {
      fputc(' ', f);
      col++;
    }
    for (size_t i = 0; i < n; ++i)
      fputc(p[i] == '\1' ? ' ' : p[i], f);
    col += (int)n;
    p += n;
    while (*p == ' ')
      p++;
  }
  return col;
}

static void usage_row(FILE *f, const param_row_t *r) {
  char left[64], text[512], range[64];
  if (r->short_opt)
    snprintf(left, sizeof left, "  -%c, --%s%s%s", r->short_opt, r->long_opt,
             r->metavar ? " " : "", r->metavar ? r->metavar : "");
  else
    snprintf(left, sizeof left, "      --%s%s%s", r->long_opt,
             r->metavar ? " " : "", r->metavar ? r->metavar : "");
  switch (r->kind) {
  case SC_PARAM_MODE:
    snprintf(text, sizeof text, "%s (default\1%s)", r->help,
             sc_mode_name((int)r->dflt));
    break;
  case SC_PARAM_ANGLE:
    degrees_range(range, sizeof range, r);
    snprintf(text, sizeof text, "%s, in\1%s\1degrees (default\1%g)", r->help,
             range, r->dflt * 180 / SC_PI);
    break;
  case SC_PARAM_FLAG:
    snprintf(text, sizeof text, "%s", r->help);
    break;
  default:
    /* "in (0, 10]" stays on one line. */
    snprintf(range, sizeof range, "%s", r->range_text);
    for (char *c = range; *c; ++c)
      if (*c == ' ')
        *c = '\1';
    /* A default of 0 that stands for "estimated" is said in the help. */
    if ((r->range & SC_RANGE_ZERO_DEFAULT) && r->dflt == 0)
      snprintf(text, sizeof text, "%s, %s", r->help, range);
    else
      snprintf(text, sizeof text, "%s, %s (default\1%g)", r->help, range,
               r->dflt);
    break;
  }
  int col = fprintf(f, "%-23s", left);
  if (col > 23) {
    fprintf(f, "\n%24s", "");
    col = 24;
  } else {
    fputc(' ', f);
    col = 24;
  }
  wrap(f, col, text);
  fputc('\n', f);
}

void sc_cli_job_usage_params(FILE *f, int local) {
  size_t nrows;
  const param_row_t *rows = sc_param_table(&nrows);
  fputs("  -o, --output OUT      the mesh to write (required)\n", f);
  for (size_t i = 0; i < nrows; ++i)
    if (offered(&rows[i], local))
      usage_row(f, &rows[i]);
}

/* Takes the value of option row r from arg into o->params. */
static int parse_row(sc_cli_job_opts_t *o, const param_row_t *r,
                     const char *arg) {
  char opt[64];
  snprintf(opt, sizeof opt, "--%s", r->long_opt);
  void *field = (char *)&o->params + r->offset;
  double v;
  long l;
  switch (r->kind) {
  case SC_PARAM_MODE:
    return sc_cli_parse_mode(opt, arg, (sc_mode_t *)field);
  case SC_PARAM_FLAG:
    *(int *)field = 1;
    return 0;
  case SC_PARAM_INT:
    if (sc_cli_parse_int(opt, arg, (long)r->lo, (long)r->hi, &l) < 0)
      return -1;
    *(int *)field = (int)l;
    return 0;
  case SC_PARAM_BYTES: {
    uint64_t b;
    if (scp_bytes_parse(arg, &b) != 0) {
      sc_cli_error("%s: expected a size in bytes such as 400000000, 512M or "
                   "2G, got '%s'",
                   opt, arg);
      return -1;
    }
    *(double *)field = (double)b;
    return 0;
  }
  default:
    if (sc_cli_parse_double(opt, arg, &v) < 0)
      return -1;
    /* 0 stands for the default in the core, not on the command line. */
    if ((r->range & SC_RANGE_ZERO_DEFAULT) && !(v > 0)) {
      sc_cli_error("%s: must be positive, got %s", opt, arg);
      return -1;
    }
    *(double *)field = r->kind == SC_PARAM_ANGLE ? v * SC_PI / 180 : v;
    return 0;
  }
}

int sc_cli_job_option(sc_cli_job_opts_t *o, int c, const char *arg) {
  size_t nrows;
  const param_row_t *rows = sc_param_table(&nrows);
  for (size_t i = 0; i < nrows; ++i)
    if (c == SC_CLI_OPT_PARAM + (int)i ||
        (rows[i].short_opt && c == rows[i].short_opt))
      return parse_row(o, &rows[i], arg) < 0 ? -1 : 1;
  switch (c) {
  case 'o':
    o->out_path = arg;
    return 1;
  case SC_CLI_OPT_REPORT:
    o->report = arg;
    return 1;
  case SC_CLI_OPT_ASCII:
    o->ascii = 1;
    return 1;
  case SC_CLI_OPT_MESH_NORMALS:
    o->mesh_normals = 1;
    return 1;
  case SC_CLI_OPT_NO_NORMALS:
    o->normals = 0;
    return 1;
  case 'q':
    o->quiet = 1;
    return 1;
  default:
    return 0;
  }
}

int sc_cli_parse_mode(const char *opt, const char *arg, sc_mode_t *out) {
  static const char *const names[] = {
#define SC_CLI_MODE_NAME_(name, value, str) str,
      SC_MODE_MAP(SC_CLI_MODE_NAME_)
#undef SC_CLI_MODE_NAME_
  };
  char list[256] = "";
  for (int m = 0; m < SC_MODE_COUNT_; ++m) {
    if (strcmp(arg, names[m]) == 0) {
      *out = (sc_mode_t)m;
      return 0;
    }
    if (list[0])
      strncat(list, ", ", sizeof list - strlen(list) - 1);
    strncat(list, names[m], sizeof list - strlen(list) - 1);
  }
  sc_cli_error("%s: unknown mode '%s' (expected one of: %s)", opt, arg, list);
  return -1;
}

void sc_cli_report_params(FILE *f, const sc_params_t *p) {
  size_t nrows;
  const param_row_t *rows = sc_param_table(&nrows);
  const char *sep = "";
  fputs("  \"params\": {", f);
  for (size_t i = 0; i < nrows; ++i) {
    const void *field = (const char *)p + rows[i].offset;
    fprintf(f, "%s\"%s\": ", sep, rows[i].name);
    sep = ", ";
    switch (rows[i].kind) {
    case SC_PARAM_MODE:
      scf_json_string(f, sc_mode_name(*(const int *)field));
      break;
    case SC_PARAM_INT:
    case SC_PARAM_FLAG:
      fprintf(f, "%d", *(const int *)field);
      break;
    default:
      fprintf(f, "%.17g", *(const double *)field);
      break;
    }
  }
  fputs("},\n", f);
}

/* The report's diagnostics: the counts first, then the path, the loops,
 * closed and the signed values, each kind in the table's order (the
 * seconds go with the command's own, in sc_cli_report_json()). */
static void report_row(FILE *f, const sc_diag_info_t *row, const void *v) {
  switch (row->kind) {
  case SC_DIAG_COUNT:
    fprintf(f, "  \"%s\": %llu,\n", row->name,
            (unsigned long long)*(const uint64_t *)v);
    break;
  case SC_DIAG_PATH:
    fprintf(f, "  \"%s\": ", row->name);
    scf_json_string(f, sc_path_name(*(const int *)v));
    fputs(",\n", f);
    break;
  case SC_DIAG_LOOPS:
    fprintf(f, "  \"%s\": [", row->name);
    for (size_t i = 0; i < row->count; ++i)
      fprintf(f, "%s%llu", i ? ", " : "",
              (unsigned long long)((const uint64_t *)v)[i]);
    fputs("],\n", f);
    break;
  case SC_DIAG_BOOL:
    fprintf(f, "  \"%s\": %s,\n", row->name,
            *(const int *)v ? "true" : "false");
    break;
  case SC_DIAG_INT:
    fprintf(f, "  \"%s\": %lld,\n", row->name,
            (long long)*(const int64_t *)v);
    break;
  case SC_DIAG_REAL:
    fprintf(f, "  \"%s\": %.6g,\n", row->name, *(const double *)v);
    break;
  default:
    break;
  }
}

void sc_cli_report_diag(FILE *f, const sc_diag_t *d) {
  static const sc_diag_kind_t order[] = {SC_DIAG_COUNT, SC_DIAG_PATH,
                                         SC_DIAG_LOOPS, SC_DIAG_BOOL,
                                         SC_DIAG_INT, SC_DIAG_REAL};
  size_t n;
  const sc_diag_info_t *rows = sc_diag_table(&n);
  for (size_t k = 0; k < sizeof order / sizeof order[0]; ++k)
    for (size_t i = 0; i < n; ++i)
      if (rows[i].kind == order[k])
        report_row(f, &rows[i], (const char *)d + rows[i].offset);
}
