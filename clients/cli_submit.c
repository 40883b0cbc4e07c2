/*
 * `shortcrust submit`: read a point file, have the daemon reconstruct it,
 * write the mesh. Options, formats, summary and report are those of
 * `shortcrust reconstruct`, and so are the triangles: the points travel as
 * exact values (floats when every coordinate is one, doubles otherwise)
 * and the daemon runs the same core with the same defaults.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cli.h"
#include "cli_commands.h"
#include "shortcrust_client.h"
#include "shortcrust_files.h"

/* A job is a pure function of its points and options: the command runs it
 * again, by default, when its connection is lost. */
#define SC_CLI_RETRIES 3
#define SC_CLI_RETRY_BACKOFF_MS 200
/* With --tiles, tile jobs at once, each on a connection of its own. */
#define SC_CLI_TILE_CONNECTIONS 16

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
          "                        before each next one (default %d)\n"
          "      --tiles N         split the job into N tiles (2 to 4096), "
          "send each as a\n"
          "                        job of its own, on a connection of its own "
          "(through a\n"
          "                        balancer, to many daemons), and finish "
          "the mesh here:\n"
          "                        the same triangles as one job (cocone and "
          "shortcrust\n"
          "                        modes; every tile job carries all the "
          "points); 1, the\n"
          "                        default, sends one job\n"
          "      --connections N   with --tiles, tile jobs under way at once "
          "(default: one\n"
          "                        per tile, at most %d)\n",
          sc_client_default_socket(sock, sizeof sock), SC_CLI_RETRIES,
          SC_CLI_RETRY_BACKOFF_MS, SC_CLI_TILE_CONNECTIONS);
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
  OPT_RETRY_BACKOFF,
  OPT_TILES,
  OPT_CONNECTIONS
};

static const struct option own_options[] = {
    {"socket", required_argument, NULL, OPT_SOCKET},
    {"connect", required_argument, NULL, OPT_CONNECT},
    {"token-file", required_argument, NULL, OPT_TOKEN_FILE},
    {"retries", required_argument, NULL, OPT_RETRIES},
    {"retry-backoff", required_argument, NULL, OPT_RETRY_BACKOFF},
    {"tiles", required_argument, NULL, OPT_TILES},
    {"connections", required_argument, NULL, OPT_CONNECTIONS},
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

/* A job split into tiles (--tiles): the tile jobs, `connections` at a
 * time, each thread on a connection of its own taking the next tile when
 * its job is done. Each result is copied out of its job as the core's
 * merge takes it, so that a connection lost between two jobs can be
 * replaced. */
typedef struct tile_run {
  const sc_client_options_t *opts;
  const sc_client_params_t *cp;
  const double *xyz;
  uint64_t n;
  int count;
  pthread_mutex_t mu;
  pthread_cond_t cv;
  int next, done, failed;
  unsigned retries;
  char msg[1100];
  sc_mesh_t *parts; /* per tile */
} tile_run_t;

typedef struct tile_worker {
  tile_run_t *run;
  pthread_t thread;
} tile_worker_t;

/* Ends the run with its first error. */
static void tile_fail(tile_run_t *r, int tile, const char *what) {
  pthread_mutex_lock(&r->mu);
  if (!r->failed) {
    r->failed = 1;
    if (tile >= 0)
      snprintf(r->msg, sizeof r->msg, "tile %d: %s", tile, what);
    else
      snprintf(r->msg, sizeof r->msg, "%s", what);
  }
  pthread_cond_broadcast(&r->cv);
  pthread_mutex_unlock(&r->mu);
}

static int tile_stopped(tile_run_t *r) {
  pthread_mutex_lock(&r->mu);
  const int stop = r->failed;
  pthread_mutex_unlock(&r->mu);
  return stop;
}

/* A finished tile job's result, copied into *out; -1 without memory. */
static int tile_copy(sc_client_job_t *job, sc_mesh_t *out) {
  sc_client_mesh_t m;
  sc_client_job_mesh(job, &m);
  size_t nt = 3 * (size_t)m.triangle_count, nn = 3 * (size_t)m.normal_count;
  out->triangles = malloc((nt ? nt : 1) * sizeof *out->triangles);
  out->normals = nn ? malloc(nn * sizeof *out->normals) : NULL;
  if (!out->triangles || (nn && !out->normals))
    return -1;
  if (nt)
    memcpy(out->triangles, m.triangles, nt * sizeof *out->triangles);
  if (nn)
    memcpy(out->normals, m.normals, nn * sizeof *out->normals);
  out->triangle_count = (size_t)m.triangle_count;
  out->point_count = (size_t)m.point_count;
  diag_from_values(&m, &out->diag);
  return 0;
}

/* Whether a job or a connection that ended with code may be run again on
 * a new connection: it was lost, or its daemon shut down. */
static int tile_may_retry(int code) {
  return code == SC_CLIENT_ELOST || code == SC_CLIENT_ESHUTDOWN ||
         code == SC_CLIENT_ENODAEMON || code == SC_CLIENT_ECONNECT ||
         code == SC_CLIENT_ETIMEOUT;
}

static void *tile_worker(void *arg) {
  tile_worker_t *w = arg;
  tile_run_t *r = w->run;
  char msg[1024];
  sc_client_t *c = NULL;
  int tile = -1, attempts = 0;
  for (;;) {
    if (tile < 0) {
      pthread_mutex_lock(&r->mu);
      tile = r->failed ? r->count : r->next++;
      pthread_mutex_unlock(&r->mu);
      attempts = 0;
      if (tile >= r->count)
        break;
    }
    /* A connection, new or again: the library retries a job whose
     * connection is lost while it runs; this covers one lost between two
     * jobs, or on connecting. */
    int rc = 0;
    if (!c || sc_client_status(c) < 0) {
      sc_client_free(c);
      c = NULL;
      rc = sc_client_connect(r->opts, &c, msg, sizeof msg);
    }
    sc_client_job_t *job = NULL;
    if (rc == 0) {
      sc_client_params_t cp = *r->cp;
      cp.tile_count = r->count;
      cp.tile_index = tile;
      rc = sc_client_submit(c, &cp, r->xyz, r->n, &job);
      if (rc < 0)
        snprintf(msg, sizeof msg, "%s", sc_client_last_error(c));
    }
    if (rc == 0) {
      /* A failure elsewhere cancels this one. */
      while ((rc = sc_client_wait(c, job, 200)) == SC_CLIENT_ETIMEOUT)
        if (tile_stopped(r))
          (void)sc_client_cancel(c, job);
      if (rc < 0)
        snprintf(msg, sizeof msg, "%s", sc_client_job_message(job));
    }
    const unsigned used = job ? sc_client_job_retries(job) : 0;
    if (rc == 0 && tile_copy(job, &r->parts[tile]) < 0) {
      snprintf(msg, sizeof msg, "out of memory");
      rc = SC_CLIENT_ENOMEM;
    }
    sc_client_job_free(job);
    pthread_mutex_lock(&r->mu);
    r->retries += used;
    pthread_mutex_unlock(&r->mu);
    attempts += (int)used;
    if (rc < 0 && tile_may_retry(rc) && attempts < r->cp->retries &&
        !tile_stopped(r)) {
      pthread_mutex_lock(&r->mu);
      r->retries++;
      pthread_mutex_unlock(&r->mu);
      attempts++;
      struct timespec pause = {r->cp->retry_backoff_ms / 1000,
                               (r->cp->retry_backoff_ms % 1000) * 1000000L};
      nanosleep(&pause, NULL);
      continue;
    }
    if (rc < 0) {
      tile_fail(r, tile, msg);
      break;
    }
    pthread_mutex_lock(&r->mu);
    r->done++;
    pthread_cond_broadcast(&r->cv);
    pthread_mutex_unlock(&r->mu);
    tile = -1;
  }
  sc_client_free(c);
  return NULL;
}

/* Runs the tile jobs, then merges them here into *mesh (sc_mesh_free()).
 * Returns 0, or -1 after a message. */
static int run_tiles(const sc_client_options_t *opts,
                     const sc_client_params_t *cp, const sc_params_t *params,
                     const scf_points_t *pts, int count, int connections,
                     sc_cli_progress_t *progress, sc_mesh_t **mesh,
                     double *seconds) {
  double t0 = sc_cli_now();
  tile_run_t r;
  memset(&r, 0, sizeof r);
  r.opts = opts;
  r.cp = cp;
  r.xyz = pts->xyz;
  r.n = pts->count;
  r.count = count;
  pthread_mutex_init(&r.mu, NULL);
  pthread_cond_init(&r.cv, NULL);
  r.parts = calloc((size_t)count, sizeof *r.parts);
  const sc_mesh_t **views = calloc((size_t)count, sizeof *views);
  tile_worker_t *w = calloc((size_t)connections, sizeof *w);
  int started = 0, status = 0;
  if (!r.parts || !views || !w) {
    sc_cli_error("submit: out of memory");
    status = -1;
  }
  for (; status == 0 && started < connections; ++started) {
    w[started].run = &r;
    if (pthread_create(&w[started].thread, NULL, tile_worker, &w[started])) {
      tile_fail(&r, -1, "cannot start a thread");
      break;
    }
  }
  /* Progress: the tiles done of all. */
  pthread_mutex_lock(&r.mu);
  while (started > 0 && r.done < count && !r.failed) {
    struct timespec until;
    clock_gettime(CLOCK_REALTIME, &until);
    until.tv_nsec += 200000000;
    if (until.tv_nsec >= 1000000000)
      until.tv_sec++, until.tv_nsec -= 1000000000;
    pthread_cond_timedwait(&r.cv, &r.mu, &until);
    const double f = (double)r.done / count;
    pthread_mutex_unlock(&r.mu);
    sc_cli_progress_step(progress, "tiles", f);
    pthread_mutex_lock(&r.mu);
  }
  pthread_mutex_unlock(&r.mu);
  for (int i = 0; i < started; ++i)
    pthread_join(w[i].thread, NULL);
  if (status == 0 && r.failed) {
    sc_cli_progress_done(progress);
    sc_cli_error("submit: %s", r.msg);
    status = -1;
  }
  *seconds = sc_cli_now() - t0;
  if (status == 0) {
    if (r.retries)
      fprintf(stderr,
              "shortcrust: %u tile job%s submitted again after losing "
              "the connection\n",
              r.retries, r.retries == 1 ? "" : "s");
    for (int i = 0; i < count; ++i)
      views[i] = &r.parts[i];
    char msg[1024];
    sc_params_t p = *params;
    p.progress = sc_cli_progress_fn;
    p.progress_user = progress;
    int rc = sc_reconstruct_merge(pts->xyz, pts->count, &p, views,
                                  (size_t)count, mesh, msg, sizeof msg);
    if (rc != 0) {
      sc_cli_progress_done(progress);
      sc_cli_error("submit: merging the tiles: %s", msg);
      status = -1;
    }
  }
  for (int i = 0; r.parts && i < count; ++i) {
    free(r.parts[i].triangles);
    free(r.parts[i].normals);
  }
  free(r.parts);
  free(views);
  free(w);
  pthread_cond_destroy(&r.cv);
  pthread_mutex_destroy(&r.mu);
  return status;
}

int sc_cmd_submit(int argc, char **argv) {
  sc_cli_job_opts_t o;
  sc_cli_job_init(&o);
  sc_params_t params;
  /* The daemon's reconstruction runs on one thread. */
  o.params.threads = 1;
  const char *socket_path = NULL, *token_file = NULL;
  long retries = SC_CLI_RETRIES, backoff = SC_CLI_RETRY_BACKOFF_MS;
  long tiles = 1, connections = 0;

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
    case OPT_TILES:
      if (sc_cli_parse_int("--tiles", optarg, 1, 4096, &tiles) < 0)
        return SC_EXIT_USAGE;
      break;
    case OPT_CONNECTIONS:
      if (sc_cli_parse_int("--connections", optarg, 1, 256, &connections) < 0)
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
  if (tiles > 1) {
    /* The tile jobs' parameters, checked here before anything is read. */
    sc_params_t tp = params;
    tp.tile_count = (int)tiles;
    char why[256];
    if (tp.mode != SC_MODE_COCONE && tp.mode != SC_MODE_SHORTCRUST) {
      sc_cli_error("submit: --tiles works in the cocone and shortcrust modes "
                   "only (the %s mode needs one triangulation of all the "
                   "points)",
                   sc_mode_name(tp.mode));
      return SC_EXIT_USAGE;
    }
    if (sc_params_check(&tp, why, sizeof why) != 0) {
      sc_cli_error("submit: --tiles: %s", why);
      return SC_EXIT_USAGE;
    }
    if (connections == 0)
      connections =
          tiles < SC_CLI_TILE_CONNECTIONS ? tiles : SC_CLI_TILE_CONNECTIONS;
    if (connections > tiles)
      connections = tiles;
  } else if (connections) {
    sc_cli_error("submit: --connections goes with --tiles");
    return SC_EXIT_USAGE;
  }

  sc_cli_progress_t progress;
  scf_mesh_format_t fmt;
  scf_points_t pts;
  scf_attrs_t attrs;
  double t_read;
  int status = sc_cli_job_read(&o, &progress, &fmt, &pts, &attrs, &t_read);
  if (status != SC_EXIT_OK)
    return status;

  sc_client_options_t opts;
  sc_client_options_init(&opts);
  opts.socket_path = socket_path;
  opts.token_file = token_file;
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
  if (tiles > 1) {
    /* The tile jobs send no progress of their own: the line shows the
     * tiles done, then the merge's stages. */
    cp.progress = NULL;
    /* The merge smooths the points as the tile jobs did: their smoothed
     * positions need not travel back. */
    cp.smoothed_vertices = 0;
    sc_mesh_t *merged = NULL;
    double seconds = 0;
    status = SC_EXIT_FAILURE;
    if (run_tiles(&opts, &cp, &params, &pts, (int)tiles, (int)connections,
                  &progress, &merged, &seconds) == 0) {
      params.tiles = (int)tiles;
      sc_cli_result_t res = {
          .command = "submit",
          .input = in_path,
          .output = out_path,
          .params = params,
          .diag = &merged->diag,
          .component_genus = merged->component_genus,
          .component_count = merged->component_count,
          .seconds_read = t_read,
          .seconds_transfer = seconds - merged->diag.seconds_total,
          .tile_jobs = 1,
      };
      if (merged->smoothed)
        memcpy(pts.xyz, merged->smoothed, 3 * pts.count * sizeof *pts.xyz);
      status =
          sc_cli_job_write(&o, &progress, fmt, &pts, &attrs, merged->triangles,
                           merged->triangle_count, merged->normals, &res);
    }
    sc_mesh_free(merged);
    scf_points_free(&pts);
    scf_attrs_free(&attrs);
    return status;
  }
  char msg[1024];
  sc_client_t *client = NULL;
  int rc = sc_client_connect(&opts, &client, msg, sizeof msg);
  if (rc < 0) {
    sc_cli_progress_done(&progress);
    scf_points_free(&pts);
    scf_attrs_free(&attrs);
    sc_cli_error("%s", msg);
    return SC_EXIT_FAILURE;
  }
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
