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

static void usage(FILE *f) {
  char sock[256];
  fputs("usage: shortcrust submit IN -o OUT [options]\n\n"
        "Sends the points of IN to the shortcrust daemon (shortcrustd), which\n"
        "reconstructs the mesh, and writes the mesh to OUT. Formats, summary\n"
        "and report are those of `shortcrust reconstruct`, and so are the\n"
        "triangles for the same input and options. IN may be .ply (ascii or\n"
        "binary), .xyz/.txt/.pts/.csv, .off or .obj; OUT's extension picks the\n"
        "format: .ply (binary unless --ascii), .off, .obj or .stl. The daemon\n"
        "reconstructs on one thread; options that leave their default are not\n"
        "sent, and a daemon too old to take the others refuses the job.\n\n"
        "options:\n",
        f);
  sc_cli_job_usage_params(f);
  fprintf(f, "      --socket PATH     the daemon's socket (default %s)\n",
          sc_client_default_socket(sock, sizeof sock));
  sc_cli_job_usage_output(f);
  fputs("Progress (upload, each stage on the daemon, download) goes to stderr\n"
        "when it is a terminal; the summary goes to stdout. Exit status: 0\n"
        "done, 1 failed (the message says why), 2 bad command line.\n",
        f);
}

enum { OPT_SOCKET = SC_CLI_OPT_OWN };

static const struct option long_options[] = {
    SC_CLI_JOB_LONG_OPTIONS,
    {"socket", required_argument, NULL, OPT_SOCKET},
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

/* The daemon's diagnostics (PROTOCOL.md 6.12) as the core reports them. */
static void diag_from_values(const sc_client_mesh_t *m, sc_diag_t *d) {
  memset(d, 0, sizeof *d);
#define U_(field) d->field = value_u64(m, #field)
  U_(points_in);
  U_(duplicates_merged);
  U_(delaunay_vertices);
  U_(delaunay_cells);
  U_(delaunay_facets);
  U_(hull_vertices);
  U_(degenerate_cells);
  U_(candidates);
  U_(pruned);
  U_(triangles);
  U_(walk_rejected);
  U_(holes_filled);
  U_(hole_triangles);
  U_(samples_unused);
  U_(boundary_edges);
  U_(boundary_loops);
  U_(nonmanifold_edges);
  U_(nonmanifold_vertices);
  U_(components);
  U_(closed_components);
  U_(boundary_samples);
  U_(longest_loop);
  U_(cells_relabelled);
  U_(bubbles_dropped);
  U_(samples_attached);
  U_(handles_cut);
#undef U_
  d->path = (int)value_u64(m, "path");
  d->loops_by_length[0] = value_u64(m, "loops.3_10");
  d->loops_by_length[1] = value_u64(m, "loops.11_100");
  d->loops_by_length[2] = value_u64(m, "loops.101_1000");
  d->loops_by_length[3] = value_u64(m, "loops.over_1000");
  d->closed = value_u64(m, "closed") != 0;
  d->euler = value_i64(m, "euler");
  d->genus = value_i64(m, "genus");
  char name[64];
  for (int s = 0; s < SC_STAGE_COUNT; ++s) {
    snprintf(name, sizeof name, "seconds.%s", sc_stage_name(s));
    d->seconds[s] = sc_client_value_get(m->values, m->value_count, name, 0);
  }
  d->seconds_total =
      sc_client_value_get(m->values, m->value_count, "seconds.total", 0);
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
  const char *socket_path = NULL;

  opterr = 0;
  int c;
  while ((c = getopt_long(argc, argv, ":o:m:qh", long_options, NULL)) != -1) {
    int shared = sc_cli_job_option(&o, c, optarg);
    if (shared < 0)
      return SC_EXIT_USAGE;
    if (shared > 0)
      continue;
    switch (c) {
    case OPT_SOCKET:
      socket_path = optarg;
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
  /* Checked here, before any file or the daemon is touched, and worded as
   * `reconstruct` words them. */
  if (!(params.r > 0 && params.r < 0.5)) {
    sc_cli_error("submit: r must be in (0, 0.5), got %g", params.r);
    return SC_EXIT_USAGE;
  }
  if (!(params.cocone_theta > 0 && params.cocone_theta < SC_PI / 2)) {
    sc_cli_error("submit: cocone_theta must be in (0, pi/2), got %g",
                 params.cocone_theta);
    return SC_EXIT_USAGE;
  }

  sc_cli_progress_t progress;
  scf_mesh_format_t fmt;
  scf_points_t pts;
  double t_read;
  int status = sc_cli_job_read(&o, &progress, &fmt, &pts, &t_read);
  if (status != SC_EXIT_OK)
    return status;

  char msg[1024];
  sc_client_options_t opts;
  sc_client_options_init(&opts);
  opts.socket_path = socket_path;
  sc_client_t *client = NULL;
  int rc = sc_client_connect(&opts, &client, msg, sizeof msg);
  if (rc < 0) {
    sc_cli_progress_done(&progress);
    scf_points_free(&pts);
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
  if (params.max_hole_edges != dflt.max_hole_edges)
    cp.max_hole_edges = params.max_hole_edges;
  if (params.boundary_rho != dflt.boundary_rho)
    cp.boundary_rho = params.boundary_rho;
  if (params.boundary_alpha != dflt.boundary_alpha)
    cp.boundary_alpha = params.boundary_alpha;
  cp.paper_pruning = params.paper_pruning;
  cp.watertight_labels = params.watertight_labels;
  /* As doubles, so that the file gets what the local command writes. */
  cp.normals = o.normals;
  cp.progress = show_progress;
  cp.progress_user = &progress;
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
  status = sc_cli_job_write(&o, &progress, fmt, &pts, mesh.triangles,
                            (size_t)mesh.triangle_count, mesh.normals, &res);
  sc_client_job_free(job);
  sc_client_free(client);
  scf_points_free(&pts);
  return status;
}
