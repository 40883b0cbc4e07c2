/*
 * `shortcrust submit`: read a point file, have the daemon reconstruct it,
 * write the mesh. Options, formats, summary and report are those of
 * `shortcrust reconstruct`, and so are the triangles: the points travel as
 * exact doubles and the daemon runs the same core with the same defaults.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "cli_commands.h"
#include "shortcrust_client.h"
#include "shortcrust_files.h"

/* A job is a pure function of its points and options: the command runs it
 * again, by default, when its connection is lost. */
#define SC_CLI_RETRIES 3
#define SC_CLI_RETRY_BACKOFF_MS 200

static void usage(FILE *f) {
  char sock[256];
  fputs(
      "usage: shortcrust submit IN -o OUT [options]\n\n"
      "Sends the points of IN to the shortcrust daemon (shortcrustd), which\n"
      "reconstructs the mesh, and writes the mesh to OUT. Formats, summary\n"
      "and report are those of `shortcrust reconstruct`, and so are the\n"
      "triangles for the same input and options. IN may be .ply (ascii or\n"
      "binary), .xyz/.txt/.pts/.csv, .off, .obj or .las (not .laz); OUT's\n"
      "extension picks the format: .ply (binary unless --ascii), .off, .obj\n"
      "or .stl; - is standard input or output, as for reconstruct. The\n"
      "daemon reconstructs on one thread; options that leave their default\n"
      "are not sent, and a daemon too old to take the others refuses the\n"
      "job.\n\n"
      "options:\n",
      f);
  sc_cli_job_usage_params(f, 0);
  fprintf(f,
          "      --connect ADDR    the daemon: tcp://HOST:PORT, unix://PATH "
          "or a socket\n"
          "                        path (default %s)\n"
          "      --socket PATH     the same as --connect unix://PATH\n"
          "      --token-file FILE the token of a daemon on TCP (default: "
          "the variable\n"
          "                        SHORTCRUST_TOKEN)\n"
          "      --retries N       submit the job again up to N times when "
          "the connection\n"
          "                        is lost or the daemon shuts down "
          "(default %d)\n"
          "      --retry-backoff MS  wait MS ms before the first retry, twice "
          "as long\n"
          "                        before each next one (default %d)\n",
          sc_client_default_socket(sock, sizeof sock), SC_CLI_RETRIES,
          SC_CLI_RETRY_BACKOFF_MS);
  sc_cli_job_usage_output(f);
  fputs(
      "Progress (upload, each stage on the daemon, download) goes to stderr\n"
      "when it is a terminal; the summary goes to stdout (stderr with -o -).\n"
      "Exit status: 0\n"
      "done, 1 failed (the message says why), 2 bad command line. A mesh\n"
      "that is empty or leaves most samples in no triangle is written with\n"
      "status 0 and a warning line on stderr.\n",
      f);
}

enum {
  OPT_SOCKET = SC_CLI_OPT_OWN,
  OPT_CONNECT,
  OPT_TOKEN_FILE,
  OPT_RETRIES,
  OPT_RETRY_BACKOFF
};

static const struct option own_options[] = {
    {"socket", required_argument, NULL, OPT_SOCKET},
    {"connect", required_argument, NULL, OPT_CONNECT},
    {"token-file", required_argument, NULL, OPT_TOKEN_FILE},
    {"retries", required_argument, NULL, OPT_RETRIES},
    {"retry-backoff", required_argument, NULL, OPT_RETRY_BACKOFF},
    {"help", no_argument, NULL, 'h'},
    {NULL, 0, NULL, 0},
};

/* The library's progress, on the command's progress line. */
static int show_progress(void *user, sc_client_job_t *job, uint32_t stage,
                         double fraction) {
  sc_cli_progress_t *p = user;
  if (stage == SC_CLIENT_STAGE_UPLOAD || stage == SC_CLIENT_STAGE_DOWNLOAD) {
    if (p->enabled && (int)stage != p->last_stage) {
      p->last_stage = (int)stage;
      p->last_time = 0; /* a new step is always shown */
    }
    sc_cli_progress_step(p, sc_client_stage_name(stage), fraction);
  } else if (stage < SC_STAGE_COUNT) {
    sc_cli_progress_fn(p, (sc_stage_t)stage, fraction);
  }
  return 0;
}

static uint64_t value_u64(const sc_client_mesh_t *m, const char *name) {
  const sc_client_value_t *v =
      sc_client_value_find(m->values, m->value_count, name);
  if (!v)
    return 0;
  return v->kind == SC_CLIENT_F64 ? (uint64_t)v->v.f : v->v.u;
}

static int64_t value_i64(const sc_client_mesh_t *m, const char *name) {
  const sc_client_value_t *v =
      sc_client_value_find(m->values, m->value_count, name);
  if (!v)
    return 0;
  return v->kind == SC_CLIENT_F64 ? (int64_t)v->v.f : v->v.i;
}

/* One element of a diagnostic, from the value of its wire name. */
static void diag_element(const sc_client_mesh_t *m, const sc_diag_info_t *row,
                         const char *name, void *field, size_t i) {
  switch (row->kind) {
  case SC_DIAG_COUNT:
  case SC_DIAG_LOOPS:
    ((uint64_t *)field)[i] = value_u64(m, name);
    break;
  case SC_DIAG_BOOL:
    *(int *)field = value_u64(m, name) != 0;
    break;
  case SC_DIAG_PATH:
    *(int *)field = (int)value_u64(m, name);
    break;
  case SC_DIAG_INT:
    *(int64_t *)field = value_i64(m, name);
    break;
  case SC_DIAG_REAL:
  case SC_DIAG_SECONDS:
  case SC_DIAG_STAGE_SECONDS:
    ((double *)field)[i] =
        sc_client_value_get(m->values, m->value_count, name, 0);
    break;
  }
}

/* The daemon's diagnostics (PROTOCOL.md 6.12) as the core reports them,
 * read by the names of the core's table. */
static void diag_from_values(const sc_client_mesh_t *m, sc_diag_t *d) {
  memset(d, 0, sizeof *d);
  size_t n;
  const sc_diag_info_t *rows = sc_diag_table(&n);
  for (size_t r = 0; r < n; ++r) {
    void *field = (char *)d + rows[r].offset;
    if (rows[r].kind != SC_DIAG_STAGE_SECONDS &&
        rows[r].kind != SC_DIAG_LOOPS) {
      diag_element(m, &rows[r], rows[r].wire, field, 0);
      continue;
    }
    for (size_t i = 0; i < rows[r].count; ++i) {
      char name[64];
      snprintf(name, sizeof name, "%s.%s", rows[r].wire,
               sc_diag_element_name(&rows[r], i));
      diag_element(m, &rows[r], name, field, i);
    }
  }
  /* What the counts must be whatever the daemon chose to send. */
  if (!sc_client_value_find(m->values, m->value_count, "points_in"))
    d->points_in = m->point_count;
  d->triangles = m->triangle_count;
}

int sc_cmd_submit(int argc, char **argv) {
  sc_cli_job_opts_t o;
  sc_cli_job_init(&o);
  sc_params_t params;
  /* The daemon's reconstruction runs on one thread. */
  o.params.threads = 1;
  const char *socket_path = NULL, *token_file = NULL;
  long retries = SC_CLI_RETRIES, backoff = SC_CLI_RETRY_BACKOFF_MS;

  sc_cli_getopt_t g;
  if (sc_cli_job_getopt(&g, 0, own_options, "h") < 0) {
    sc_cli_error("submit: too many options");
    return SC_EXIT_FAILURE;
  }

  opterr = 0;
  int c;
  while ((c = getopt_long(argc, argv, g.short_options, g.long_options,
                          NULL)) != -1) {
    int shared = sc_cli_job_option(&o, c, optarg);
    if (shared < 0)
      return SC_EXIT_USAGE;
    if (shared > 0)
      continue;
    switch (c) {
    case OPT_SOCKET:
    case OPT_CONNECT:
      socket_path = optarg;
      break;
    case OPT_TOKEN_FILE:
      token_file = optarg;
      break;
    case OPT_RETRIES:
      if (sc_cli_parse_int("--retries", optarg, 0, 1000, &retries) < 0)
        return SC_EXIT_USAGE;
      break;
    case OPT_RETRY_BACKOFF:
      if (sc_cli_parse_int("--retry-backoff", optarg, 0, 60000, &backoff) < 0)
        return SC_EXIT_USAGE;
      break;
    case 'h':
      usage(stdout);
      return SC_EXIT_OK;
    default:
      return sc_cli_bad_option("submit", c, argv);
    }
  }
  if (sc_cli_job_files("submit", &o, argc, argv) < 0)
    return SC_EXIT_USAGE;
  params = o.params;
  const char *in_path = o.in_path, *out_path = o.out_path;

  sc_cli_progress_t progress;
  scf_mesh_format_t fmt;
  scf_points_t pts;
  scf_attrs_t attrs;
  double t_read;
  int status = sc_cli_job_read(&o, &progress, &fmt, &pts, &attrs, &t_read);
  if (status != SC_EXIT_OK)
    return status;

  char msg[1024];
  sc_client_options_t opts;
  sc_client_options_init(&opts);
  opts.socket_path = socket_path;
  opts.token_file = token_file;
  sc_client_t *client = NULL;
  int rc = sc_client_connect(&opts, &client, msg, sizeof msg);
  if (rc < 0) {
    sc_cli_progress_done(&progress);
    scf_points_free(&pts);
    scf_attrs_free(&attrs);
    sc_cli_error("%s", msg);
    return SC_EXIT_FAILURE;
  }

  sc_client_params_t cp;
  sc_client_params_init(&cp);
  cp.mode = (int)params.mode;
  cp.r = params.r;
  cp.theta = params.cocone_theta;
  /* The job options that differ from the core's defaults, which are the
   * daemon's. */
  sc_params_t dflt;
  sc_params_init(&dflt);
#define SUBMIT_OPTION_OPTION(field)                                            \
  if (params.field != dflt.field)                                              \
    cp.field = params.field;
#define SUBMIT_OPTION_FIXED(field)
#define SUBMIT_OPTION_LOCAL(field)
#define SUBMIT_OPTION_(field, type, kind, dflt_, lo, hi, range, text, wire,    \
                       ...)                                                    \
  SUBMIT_OPTION_##wire(field)
  SC_PARAM_MAP(SUBMIT_OPTION_)
#undef SUBMIT_OPTION_
#undef SUBMIT_OPTION_LOCAL
#undef SUBMIT_OPTION_FIXED
#undef SUBMIT_OPTION_OPTION
  /* As doubles, so that the file gets what the local command writes. */
  cp.normals = o.normals;
  cp.progress = show_progress;
  cp.progress_user = &progress;
  cp.retries = (int)retries;
  cp.retry_backoff_ms = (int)backoff;
  sc_client_job_t *job = NULL;
  rc = sc_client_submit(client, &cp, pts.xyz, pts.count, &job);
  if (rc == 0)
    rc = sc_client_wait(client, job, -1);
  if (rc < 0) {
    sc_cli_progress_done(&progress);
    status = SC_EXIT_FAILURE;
    if (rc == SC_CLIENT_EINVAL) {
      sc_cli_error("submit: %s", sc_client_last_error(client));
      status = SC_EXIT_USAGE;
    } else if (job) {
      sc_cli_error("%s: %s", in_path, sc_client_job_message(job));
    } else {
      sc_cli_error("%s: %s", in_path, sc_client_last_error(client));
    }
    sc_client_job_free(job);
    sc_client_free(client);
    scf_points_free(&pts);
    scf_attrs_free(&attrs);
    return status;
  }

  sc_client_mesh_t mesh;
  sc_client_job_mesh(job, &mesh);
  sc_diag_t diag;
  diag_from_values(&mesh, &diag);

  sc_cli_result_t res = {
      .command = "submit",
      .input = in_path,
      .output = out_path,
      .params = params,
      .diag = &diag,
      .component_genus = mesh.genus,
      .component_count = (size_t)mesh.component_count,
      .seconds_read = t_read,
      .seconds_transfer = mesh.seconds_upload + mesh.seconds_download,
  };
  /* --smoothed-vertices: the mesh over the positions the daemon smoothed,
   * as `reconstruct` writes it; none came when nothing was smoothed. */
  if (mesh.vertices)
    memcpy(pts.xyz, mesh.vertices, 3 * pts.count * sizeof *pts.xyz);
  status = sc_cli_job_write(&o, &progress, fmt, &pts, &attrs, mesh.triangles,
                            (size_t)mesh.triangle_count, mesh.normals, &res);
  sc_client_job_free(job);
  sc_client_free(client);
  scf_points_free(&pts);
  scf_attrs_free(&attrs);
  return status;
}
