/*
 * Pieces shared by the subcommands of the `shortcrust` command: option
 * values, progress on a terminal, the closing summary and the JSON report.
 * Every subcommand that produces a mesh (local or through the daemon) prints
 * the same summary and writes the same report, so scripts need not care
 * which path made the mesh.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SC_CLI_H
#define SC_CLI_H

#include <getopt.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "shortcrust.h"
#include "shortcrust_files.h"

/* Exit codes of every subcommand. */
enum {
  SC_EXIT_OK = 0,      /* the job was done */
  SC_EXIT_FAILURE = 1, /* a file, the reconstruction or the daemon failed */
  SC_EXIT_USAGE = 2    /* the command line was wrong; nothing was done */
};

/* Prints "shortcrust: " and the formatted message to stderr. */
void sc_cli_error(const char *fmt, ...)
    __attribute__((format(printf, 1, 2)));

/* Option values; each returns 0 or prints what is wrong and returns -1. */
int sc_cli_parse_mode(const char *opt, const char *arg, sc_mode_t *out);
int sc_cli_parse_double(const char *opt, const char *arg, double *out);
int sc_cli_parse_int(const char *opt, const char *arg, long min, long max,
                     long *out);

/*
 * The options every mesh-producing subcommand takes: -o, one per parameter
 * of the core's table (SC_PARAM_MAP in shortcrust.h; those the daemon does
 * not take only where local is 1), --report, --ascii, --no-normals,
 * --mesh-normals, -q.
 * A subcommand builds its getopt_long tables with sc_cli_job_getopt(),
 * adding its own options (numbered from SC_CLI_OPT_OWN, or short letters),
 * and passes each getopt_long result to sc_cli_job_option() first.
 */
typedef struct sc_cli_job_opts {
  sc_params_t params;
  const char *in_path, *out_path, *report;
  int quiet, ascii, normals, mesh_normals;
} sc_cli_job_opts_t;

enum {
  SC_CLI_OPT_REPORT = 256,
  SC_CLI_OPT_ASCII,
  SC_CLI_OPT_NO_NORMALS,
  SC_CLI_OPT_MESH_NORMALS,
  SC_CLI_OPT_PARAM, /* + the row of the parameter table */
  SC_CLI_OPT_OWN = SC_CLI_OPT_PARAM + 64
};

#define SC_CLI_MAX_OPTIONS 96
typedef struct sc_cli_getopt {
  struct option long_options[SC_CLI_MAX_OPTIONS];
  char short_options[64];
} sc_cli_getopt_t;

/* Fills g: the shared options, then own (ending with a NULL name; may be
 * NULL) and own_short (getopt's letters; may be NULL). -1 when they do not
 * fit. */
int sc_cli_job_getopt(sc_cli_getopt_t *g, int local,
                      const struct option *own, const char *own_short);
/* The help lines of the options that choose the job: -o and the
 * parameters, with their ranges and defaults (local as above). A
 * subcommand prints its own options, then sc_cli_job_usage_output()'s. */
void sc_cli_job_usage_params(FILE *f, int local);
void sc_cli_job_usage_output(FILE *f);
/* The defaults: the core's parameters, normals on. */
void sc_cli_job_init(sc_cli_job_opts_t *o);
/* Takes one getopt_long result: 1 when it was a shared option, 0 when it
 * is not one, -1 (after a message) when its value is bad. */
int sc_cli_job_option(sc_cli_job_opts_t *o, int c, const char *arg);
/* Reports a getopt_long error (':' for a missing value, anything else an
 * unknown option) for subcommand cmd; returns SC_EXIT_USAGE. */
int sc_cli_bad_option(const char *cmd, int c, char **argv);
/* After the options: exactly one input file, and -o, and the parameters
 * within the core's ranges. Returns 0, or prints what is wrong and
 * returns -1. */
int sc_cli_job_files(const char *cmd, sc_cli_job_opts_t *o, int argc,
                     char **argv);


/*
 * Progress on stderr, redrawn in place, when stderr is a terminal and the
 * user did not ask for quiet; otherwise silent. Usable as an sc_progress_fn
 * with a pointer to the struct as user data. Never cancels.
 */
typedef struct sc_cli_progress {
  int enabled;
  int last_stage;
  double last_time;
  int dirty; /* a line is on screen and must be cleared before other output */
} sc_cli_progress_t;

void sc_cli_progress_init(sc_cli_progress_t *p, int quiet);
int sc_cli_progress_fn(void *user, sc_stage_t stage, double fraction);
/* Shows an arbitrary step ("reading", "writing", "upload" ...). */
void sc_cli_progress_step(sc_cli_progress_t *p, const char *what,
                          double fraction);
/* Clears the progress line, if any. */
void sc_cli_progress_done(sc_cli_progress_t *p);

/* Monotonic seconds. */
double sc_cli_now(void);

/* What a mesh-producing subcommand did, for the summary and the report. */
typedef struct sc_cli_result {
  const char *command; /* "reconstruct", "submit" */
  const char *input;
  const char *output;
  sc_params_t params;
  const sc_diag_t *diag;
  const int32_t *component_genus; /* may be NULL */
  size_t component_count;
  double seconds_read;
  double seconds_write;
  double seconds_transfer; /* time on the wire for submit; 0 otherwise */
  int tile_jobs; /* submit --tiles: the tiles ran as jobs of the daemons */
} sc_cli_result_t;

/* The closing paragraph: points, duplicates, triangles, closed or not,
 * components, genus, time per stage. */
void sc_cli_summary(FILE *f, const sc_cli_result_t *r);

/* The report's "params" line and its diagnostics but the seconds, made
 * from the core's tables. */
void sc_cli_report_params(FILE *f, const sc_params_t *p);
void sc_cli_report_diag(FILE *f, const sc_diag_t *d);

/* The diagnostics as one JSON object; malloc'd, NULL when out of memory. */
char *sc_cli_report_json(const sc_cli_result_t *r);

/* Writes the JSON report to path atomically; prints an error on failure. */
int sc_cli_write_report(const char *path, const sc_cli_result_t *r);

/*
 * The two ends of a mesh-producing job. sc_cli_job_read() checks that -o
 * names a mesh format (SC_EXIT_USAGE otherwise), starts the progress line
 * and reads the input with its per-point properties (SC_EXIT_FAILURE, after
 * the message, when it cannot); on SC_EXIT_OK the caller frees pts and
 * attrs. sc_cli_job_write() writes the mesh to
 * -o, fills r->seconds_write, clears the progress line, then writes the
 * report and prints the summary; it returns the exit status.
 */
int sc_cli_job_read(const sc_cli_job_opts_t *o, sc_cli_progress_t *progress,
                    scf_mesh_format_t *fmt, scf_points_t *pts,
                    scf_attrs_t *attrs, double *seconds_read);
/* The input's properties go on the vertices (attrs is changed: with
 * --mesh-normals its nx, ny, nz are dropped for the computed normals). */
int sc_cli_job_write(const sc_cli_job_opts_t *o, sc_cli_progress_t *progress,
                     scf_mesh_format_t fmt, const scf_points_t *pts,
                     scf_attrs_t *attrs, const uint32_t *tris, size_t ntri,
                     const double *normals, sc_cli_result_t *r);

#endif /* SC_CLI_H */
