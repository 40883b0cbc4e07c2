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

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "shortcrust.h"
#include "shortcrust_files.h"

#define SC_PI 3.14159265358979323846

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
 * The options every mesh-producing subcommand takes: -o, -m, --r, --theta,
 * --max-hole, --paper-pruning, --labels, --rho, --alpha, --report, --ascii,
 * --no-normals, -q. A subcommand lists
 * SC_CLI_JOB_LONG_OPTIONS in its getopt_long table (and "o:m:q" in its short
 * options), numbers its own long options from SC_CLI_OPT_OWN, and passes
 * each getopt_long result to sc_cli_job_option() first.
 */
typedef struct sc_cli_job_opts {
  sc_params_t params;
  const char *in_path, *out_path, *report;
  int quiet, ascii, normals;
} sc_cli_job_opts_t;

enum {
  SC_CLI_OPT_R = 256,
  SC_CLI_OPT_THETA,
  SC_CLI_OPT_REPORT,
  SC_CLI_OPT_ASCII,
  SC_CLI_OPT_NO_NORMALS,
  SC_CLI_OPT_MAX_HOLE,
  SC_CLI_OPT_PAPER,
  SC_CLI_OPT_LABELS,
  SC_CLI_OPT_RHO,
  SC_CLI_OPT_ALPHA,
  SC_CLI_OPT_OWN
};

#define SC_CLI_JOB_LONG_OPTIONS                                              \
  {"output", required_argument, NULL, 'o'},                                  \
      {"mode", required_argument, NULL, 'm'},                                \
      {"r", required_argument, NULL, SC_CLI_OPT_R},                          \
      {"theta", required_argument, NULL, SC_CLI_OPT_THETA},                  \
      {"report", required_argument, NULL, SC_CLI_OPT_REPORT},                \
      {"ascii", no_argument, NULL, SC_CLI_OPT_ASCII},                        \
      {"no-normals", no_argument, NULL, SC_CLI_OPT_NO_NORMALS},              \
      {"max-hole", required_argument, NULL, SC_CLI_OPT_MAX_HOLE},            \
      {"paper-pruning", no_argument, NULL, SC_CLI_OPT_PAPER},                \
      {"labels", no_argument, NULL, SC_CLI_OPT_LABELS},                      \
      {"rho", required_argument, NULL, SC_CLI_OPT_RHO},                      \
      {"alpha", required_argument, NULL, SC_CLI_OPT_ALPHA},                  \
      {"quiet", no_argument, NULL, 'q'}

/* The help lines of the shared options: those that choose the job (-o,
 * -m, --r, --theta to --alpha, with their defaults), and those about the output
 * (--report to --help). A subcommand prints its own options between. */
void sc_cli_job_usage_params(FILE *f);
void sc_cli_job_usage_output(FILE *f);
/* The defaults: the core's parameters, normals on. */
void sc_cli_job_init(sc_cli_job_opts_t *o);
/* Takes one getopt_long result: 1 when it was a shared option, 0 when it
 * is not one, -1 (after a message) when its value is bad. */
int sc_cli_job_option(sc_cli_job_opts_t *o, int c, const char *arg);
/* Reports a getopt_long error (':' for a missing value, anything else an
 * unknown option) for subcommand cmd; returns SC_EXIT_USAGE. */
int sc_cli_bad_option(const char *cmd, int c, char **argv);
/* After the options: exactly one input file, and -o. Returns 0, or prints
 * what is missing and returns -1. */
int sc_cli_job_files(const char *cmd, sc_cli_job_opts_t *o, int argc,
                     char **argv);

/* The name of a mode as the --mode option spells it. */
const char *sc_cli_mode_name(sc_mode_t mode);

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
} sc_cli_result_t;

/* The closing paragraph: points, duplicates, triangles, closed or not,
 * components, genus, time per stage. */
void sc_cli_summary(FILE *f, const sc_cli_result_t *r);

/* The diagnostics as one JSON object; malloc'd, NULL when out of memory. */
char *sc_cli_report_json(const sc_cli_result_t *r);

/* Writes the JSON report to path atomically; prints an error on failure. */
int sc_cli_write_report(const char *path, const sc_cli_result_t *r);

/*
 * The two ends of a mesh-producing job. sc_cli_job_read() checks that -o
 * names a mesh format (SC_EXIT_USAGE otherwise), starts the progress line
 * and reads the input (SC_EXIT_FAILURE, after the message, when it cannot);
 * on SC_EXIT_OK the caller frees pts. sc_cli_job_write() writes the mesh to
 * -o, fills r->seconds_write, clears the progress line, then writes the
 * report and prints the summary; it returns the exit status.
 */
int sc_cli_job_read(const sc_cli_job_opts_t *o, sc_cli_progress_t *progress,
                    scf_mesh_format_t *fmt, scf_points_t *pts,
                    double *seconds_read);
int sc_cli_job_write(const sc_cli_job_opts_t *o, sc_cli_progress_t *progress,
                     scf_mesh_format_t fmt, const scf_points_t *pts,
                     const uint32_t *tris, size_t ntri, const double *normals,
                     sc_cli_result_t *r);

#endif /* SC_CLI_H */
