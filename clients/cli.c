/*
 * Shared pieces of the `shortcrust` command; see cli.h.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "cli.h"

#include <errno.h>
#include <getopt.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "shortcrust_files.h"

void sc_cli_error(const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  fputs("shortcrust: ", stderr);
  vfprintf(stderr, fmt, ap);
  fputc('\n', stderr);
  va_end(ap);
}

static const char *const mode_names[SC_MODE_COUNT_] = {
    [SC_MODE_SHORTCRUST] = "shortcrust",
    [SC_MODE_COCONE] = "cocone",
    [SC_MODE_BOUNDARY] = "boundary",
    [SC_MODE_WATERTIGHT] = "watertight",
    [SC_MODE_AUTO] = "auto",
};

void sc_cli_job_init(sc_cli_job_opts_t *o) {
  memset(o, 0, sizeof *o);
  sc_params_init(&o->params);
  o->normals = 1;
}

void sc_cli_job_usage_params(FILE *f) {
  sc_params_t d;
  sc_params_init(&d);
  fprintf(f,
          "  -o, --output OUT      the mesh to write (required)\n"
          "  -m, --mode MODE       cocone, shortcrust, boundary (scans with a "
          "boundary),\n"
          "                        watertight (close every hole) or auto "
          "(default %s)\n"
          "      --r R             shortcrust sampling parameter, in (0, 0.5) "
          "(default %g)\n"
          "      --theta DEG       cocone half-width in degrees, in (0, 90) "
          "(default %g)\n"
          "      --max-hole N      close holes of at most N edges, 0 = never "
          "(default %d)\n"
          "      --paper-pruning   prune every edge with a single candidate, "
          "as in the paper\n"
          "      --labels          watertight mode: close the surface by "
          "labelling Delaunay\n"
          "                        cells inside or outside first (default: "
          "least-area\n"
          "                        patches first, labelling where they "
          "cannot close it)\n"
          "      --rho RHO         boundary detection: ratio of cocone extent "
          "to pole height,\n"
          "                        in (0, 10] (default %g)\n"
          "      --alpha DEG       boundary detection: largest angle between "
          "neighbouring\n"
          "                        poles, in (0, 90] degrees (default %g)\n",
          sc_cli_mode_name(d.mode), d.r, d.cocone_theta * 180 / SC_PI,
          d.max_hole_edges, d.boundary_rho, d.boundary_alpha * 180 / SC_PI);
}

void sc_cli_job_usage_output(FILE *f) {
  fputs("      --report FILE     write the diagnostics as JSON to FILE\n"
        "      --ascii           write ascii PLY or STL instead of binary\n"
        "      --no-normals      do not write per-vertex normals\n"
        "  -q, --quiet           no progress and no summary; errors only\n"
        "  -h, --help            this text\n\n",
        f);
}

int sc_cli_job_option(sc_cli_job_opts_t *o, int c, const char *arg) {
  double v;
  long l;
  switch (c) {
  case SC_CLI_OPT_MAX_HOLE:
    if (sc_cli_parse_int("--max-hole", arg, 0, 100000, &l) < 0)
      return -1;
    o->params.max_hole_edges = (int)l;
    return 1;
  case SC_CLI_OPT_PAPER:
    o->params.paper_pruning = 1;
    return 1;
  case SC_CLI_OPT_LABELS:
    o->params.watertight_labels = 1;
    return 1;
  case SC_CLI_OPT_RHO:
    if (sc_cli_parse_double("--rho", arg, &o->params.boundary_rho) < 0)
      return -1;
    if (!(o->params.boundary_rho > 0)) {
      sc_cli_error("--rho: must be positive, got %s", arg);
      return -1;
    }
    return 1;
  case SC_CLI_OPT_ALPHA:
    if (sc_cli_parse_double("--alpha", arg, &v) < 0)
      return -1;
    if (!(v > 0)) {
      sc_cli_error("--alpha: must be positive, got %s", arg);
      return -1;
    }
    o->params.boundary_alpha = v * SC_PI / 180;
    return 1;
  case 'o':
    o->out_path = arg;
    return 1;
  case 'm':
    return sc_cli_parse_mode("--mode", arg, &o->params.mode) < 0 ? -1 : 1;
  case SC_CLI_OPT_R:
    return sc_cli_parse_double("--r", arg, &o->params.r) < 0 ? -1 : 1;
  case SC_CLI_OPT_THETA:
    if (sc_cli_parse_double("--theta", arg, &v) < 0)
      return -1;
    o->params.cocone_theta = v * SC_PI / 180;
    return 1;
  case SC_CLI_OPT_REPORT:
    o->report = arg;
    return 1;
  case SC_CLI_OPT_ASCII:
    o->ascii = 1;
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

int sc_cli_bad_option(const char *cmd, int c, char **argv) {
  if (c == ':')
    sc_cli_error("%s: %s needs a value", cmd, argv[optind - 1]);
  else
    sc_cli_error("%s: unknown option '%s' (see shortcrust %s --help)", cmd,
                 argv[optind - 1], cmd);
  return SC_EXIT_USAGE;
}

int sc_cli_job_files(const char *cmd, sc_cli_job_opts_t *o, int argc,
                     char **argv) {
  if (optind >= argc) {
    sc_cli_error("%s: no input file (see shortcrust %s --help)", cmd, cmd);
    return -1;
  }
  if (optind + 1 < argc) {
    sc_cli_error("%s: one input file expected, got '%s' too", cmd,
                 argv[optind + 1]);
    return -1;
  }
  o->in_path = argv[optind];
  if (!o->out_path) {
    sc_cli_error("%s: no output file: give -o OUT", cmd);
    return -1;
  }
  return 0;
}

const char *sc_cli_mode_name(sc_mode_t mode) {
  if ((int)mode < 0 || mode >= SC_MODE_COUNT_ || !mode_names[mode])
    return "?";
  return mode_names[mode];
}

int sc_cli_parse_mode(const char *opt, const char *arg, sc_mode_t *out) {
  for (int m = 0; m < SC_MODE_COUNT_; ++m) {
    if (mode_names[m] && strcmp(arg, mode_names[m]) == 0) {
      *out = (sc_mode_t)m;
      return 0;
    }
  }
  char list[256] = "";
  for (int m = 0; m < SC_MODE_COUNT_; ++m) {
    if (!mode_names[m])
      continue;
    if (list[0])
      strncat(list, ", ", sizeof list - strlen(list) - 1);
    strncat(list, mode_names[m], sizeof list - strlen(list) - 1);
  }
  sc_cli_error("%s: unknown mode '%s' (expected one of: %s)", opt, arg, list);
  return -1;
}

int sc_cli_parse_double(const char *opt, const char *arg, double *out) {
  char *end;
  errno = 0;
  double v = strtod(arg, &end);
  if (end == arg || *end != '\0' || errno == ERANGE || !isfinite(v)) {
    sc_cli_error("%s: '%s' is not a finite number", opt, arg);
    return -1;
  }
  *out = v;
  return 0;
}

int sc_cli_parse_int(const char *opt, const char *arg, long min, long max,
                     long *out) {
  char *end;
  errno = 0;
  long v = strtol(arg, &end, 10);
  if (end == arg || *end != '\0' || errno == ERANGE) {
    sc_cli_error("%s: '%s' is not an integer", opt, arg);
    return -1;
  }
  if (v < min || v > max) {
    sc_cli_error("%s: %ld is out of range [%ld, %ld]", opt, v, min, max);
    return -1;
  }
  *out = v;
  return 0;
}

double sc_cli_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void sc_cli_progress_init(sc_cli_progress_t *p, int quiet) {
  memset(p, 0, sizeof *p);
  p->enabled = !quiet && isatty(STDERR_FILENO);
  p->last_stage = -1;
}

void sc_cli_progress_step(sc_cli_progress_t *p, const char *what,
                          double fraction) {
  if (!p->enabled)
    return;
  /* A terminal redrawn more than ten times a second only costs time. */
  double now = sc_cli_now();
  if (p->dirty && now - p->last_time < 0.1 && fraction < 1.0)
    return;
  p->last_time = now;
  if (fraction < 0)
    fraction = 0;
  if (fraction > 1)
    fraction = 1;
  int width = 30, filled = (int)(fraction * width + 0.5);
  char bar[64];
  for (int i = 0; i < width; ++i)
    bar[i] = i < filled ? '#' : '.';
  bar[width] = '\0';
  fprintf(stderr, "\r\033[K%-11s [%s] %3d%%", what, bar,
          (int)(fraction * 100 + 0.5));
  fflush(stderr);
  p->dirty = 1;
}

int sc_cli_progress_fn(void *user, sc_stage_t stage, double fraction) {
  sc_cli_progress_t *p = user;
  if (p->enabled && (int)stage != p->last_stage) {
    p->last_stage = (int)stage;
    p->last_time = 0; /* a new stage is always shown */
  }
  sc_cli_progress_step(p, sc_stage_name(stage), fraction);
  return 0;
}

void sc_cli_progress_done(sc_cli_progress_t *p) {
  if (p->enabled && p->dirty) {
    fputs("\r\033[K", stderr);
    fflush(stderr);
  }
  p->dirty = 0;
}

static void genus_list(FILE *f, const sc_cli_result_t *r) {
  const sc_diag_t *d = r->diag;
  /* An open surface: the genus of the whole, from its Euler characteristic
   * and its loops (2 c - 2 g - b = chi; the output is a manifold, so no two
   * loops share a vertex). */
  if (!d->closed) {
    long long g = (2 * (long long)d->components - (long long)d->euler -
                   (long long)d->boundary_loops) /
                  2;
    fprintf(f, "genus %lld", g);
    return;
  }
  /* "genus 1" for one closed component; "genera 0, 0, 1" for several. */
  size_t closed = 0;
  for (size_t i = 0; i < r->component_count; ++i)
    closed += r->component_genus && r->component_genus[i] >= 0;
  if (!r->component_genus || closed == 0) {
    fprintf(f, "genus %lld", (long long)r->diag->genus);
    return;
  }
  fputs(closed == 1 ? "genus " : "genera ", f);
  const char *sep = "";
  for (size_t i = 0; i < r->component_count; ++i) {
    if (r->component_genus[i] < 0)
      continue;
    fprintf(f, "%s%d", sep, r->component_genus[i]);
    sep = ", ";
  }
}

void sc_cli_summary(FILE *f, const sc_cli_result_t *r) {
  const sc_diag_t *d = r->diag;
  fprintf(f, "%s: %llu points", r->input, (unsigned long long)d->points_in);
  if (d->duplicates_merged)
    fprintf(f, " (%llu duplicates merged)",
            (unsigned long long)d->duplicates_merged);
  fprintf(f, " -> %llu triangles in %s, mode %s", (unsigned long long)d->triangles,
          r->output, sc_cli_mode_name(r->params.mode));
  if (r->params.mode == SC_MODE_SHORTCRUST)
    fprintf(f, " (r = %g)", r->params.r);
  fprintf(f, ".\n");
  if (d->closed)
    fprintf(f, "Closed 2-manifold, %llu component%s, ",
            (unsigned long long)d->components, d->components == 1 ? "" : "s");
  else
    fprintf(f,
            "Open 2-manifold: %llu boundary edge%s in %llu loop%s, "
            "%llu component%s (%llu closed), ",
            (unsigned long long)d->boundary_edges,
            d->boundary_edges == 1 ? "" : "s",
            (unsigned long long)d->boundary_loops,
            d->boundary_loops == 1 ? "" : "s",
            (unsigned long long)d->components, d->components == 1 ? "" : "s",
            (unsigned long long)d->closed_components);
  genus_list(f, r);
  fprintf(f, "; %llu sample%s unused",
          (unsigned long long)d->samples_unused,
          d->samples_unused == 1 ? "" : "s");
  if (d->holes_filled)
    fprintf(f, ", %llu small hole%s filled",
            (unsigned long long)d->holes_filled,
            d->holes_filled == 1 ? "" : "s");
  if (d->handles_cut)
    fprintf(f, ", %llu handle%s cut", (unsigned long long)d->handles_cut,
            d->handles_cut == 1 ? "" : "s");
  fprintf(f, ".\n");
  fprintf(f, "Path %s: %llu boundary sample%s, longest loop %llu edges.\n",
          sc_path_name(d->path), (unsigned long long)d->boundary_samples,
          d->boundary_samples == 1 ? "" : "s",
          (unsigned long long)d->longest_loop);
  fprintf(f, "Time: read %.3f s", r->seconds_read);
  if (r->seconds_transfer > 0)
    fprintf(f, ", transfer %.3f s", r->seconds_transfer);
  for (int s = 0; s < SC_STAGE_COUNT; ++s)
    fprintf(f, ", %s %.3f s", sc_stage_name(s), d->seconds[s]);
  fprintf(f, ", write %.3f s; reconstruction %.3f s.\n", r->seconds_write,
          d->seconds_total);
}

/* Writes s to f as a JSON string: quoted, with the quote and the backslash
 * escaped and control characters as \u00XX; NULL is written as "". */
static void json_string(FILE *f, const char *s) {
  fputc('"', f);
  for (const unsigned char *p = (const unsigned char *)s; p && *p; ++p) {
    if (*p == '"' || *p == '\\')
      fprintf(f, "\\%c", *p);
    else if (*p < 0x20)
      fprintf(f, "\\u%04x", *p);
    else
      fputc(*p, f);
  }
  fputc('"', f);
}

char *sc_cli_report_json(const sc_cli_result_t *r) {
  char *buf = NULL;
  size_t len = 0;
  FILE *f = open_memstream(&buf, &len);
  if (!f)
    return NULL;
  const sc_diag_t *d = r->diag;
  fputs("{\n  \"command\": ", f);
  json_string(f, r->command);
  fputs(",\n  \"input\": ", f);
  json_string(f, r->input);
  fputs(",\n  \"output\": ", f);
  json_string(f, r->output);
  fputs(",\n  \"params\": {\"mode\": ", f);
  json_string(f, sc_cli_mode_name(r->params.mode));
  fprintf(f,
          ", \"r\": %.17g, \"cocone_theta\": %.17g, \"paper_pruning\": %d, "
          "\"max_hole_edges\": %d, \"threads\": %d, \"boundary_rho\": %.17g, "
          "\"boundary_alpha\": %.17g, \"watertight_labels\": %d},\n",
          r->params.r, r->params.cocone_theta, r->params.paper_pruning,
          r->params.max_hole_edges, r->params.threads, r->params.boundary_rho,
          r->params.boundary_alpha, r->params.watertight_labels);
#define U64_(field) fprintf(f, "  \"" #field "\": %llu,\n", (unsigned long long)d->field)
  U64_(points_in);
  U64_(duplicates_merged);
  U64_(delaunay_vertices);
  U64_(delaunay_cells);
  U64_(delaunay_facets);
  U64_(hull_vertices);
  U64_(degenerate_cells);
  U64_(candidates);
  U64_(pruned);
  U64_(triangles);
  U64_(walk_rejected);
  U64_(holes_filled);
  U64_(hole_triangles);
  U64_(samples_unused);
  U64_(boundary_edges);
  U64_(boundary_loops);
  U64_(nonmanifold_edges);
  U64_(nonmanifold_vertices);
  U64_(components);
  U64_(closed_components);
  U64_(boundary_samples);
  U64_(longest_loop);
  U64_(cells_relabelled);
  U64_(bubbles_dropped);
  U64_(samples_attached);
  U64_(handles_cut);
#undef U64_
  fputs("  \"path\": ", f);
  json_string(f, sc_path_name(d->path));
  fprintf(f, ",\n  \"loops_by_length\": [%llu, %llu, %llu, %llu],\n",
          (unsigned long long)d->loops_by_length[0],
          (unsigned long long)d->loops_by_length[1],
          (unsigned long long)d->loops_by_length[2],
          (unsigned long long)d->loops_by_length[3]);
  fprintf(f, "  \"closed\": %s,\n", d->closed ? "true" : "false");
  fprintf(f, "  \"euler\": %lld,\n  \"genus\": %lld,\n", (long long)d->euler,
          (long long)d->genus);
  fputs("  \"component_genus\": [", f);
  for (size_t i = 0; r->component_genus && i < r->component_count; ++i)
    fprintf(f, "%s%d", i ? ", " : "", r->component_genus[i]);
  fputs("],\n  \"seconds\": {", f);
  fprintf(f, "\"read\": %.6f", r->seconds_read);
  if (r->seconds_transfer > 0)
    fprintf(f, ", \"transfer\": %.6f", r->seconds_transfer);
  for (int s = 0; s < SC_STAGE_COUNT; ++s)
    fprintf(f, ", \"%s\": %.6f", sc_stage_name(s), d->seconds[s]);
  fprintf(f, ", \"write\": %.6f, \"reconstruction\": %.6f}\n}\n",
          r->seconds_write, d->seconds_total);
  if (fclose(f) != 0) {
    free(buf);
    return NULL;
  }
  return buf;
}

int sc_cli_write_report(const char *path, const sc_cli_result_t *r) {
  char *json = sc_cli_report_json(r);
  if (!json) {
    sc_cli_error("%s: out of memory while writing the report", path);
    return -1;
  }
  char msg[512];
  int rc = scf_write_atomic(path, json, strlen(json), msg, sizeof msg);
  free(json);
  if (rc < 0) {
    sc_cli_error("%s", msg);
    return -1;
  }
  return 0;
}

int sc_cli_job_read(const sc_cli_job_opts_t *o, sc_cli_progress_t *progress,
                    scf_mesh_format_t *fmt, scf_points_t *pts,
                    double *seconds_read) {
  char msg[1024];
  if (scf_mesh_format_from_path(o->out_path, o->ascii, fmt, msg, sizeof msg) <
      0) {
    sc_cli_error("%s", msg);
    return SC_EXIT_USAGE;
  }
  sc_cli_progress_init(progress, o->quiet);
  double t0 = sc_cli_now();
  sc_cli_progress_step(progress, "reading", 0);
  if (scf_points_read(o->in_path, pts, msg, sizeof msg) < 0) {
    sc_cli_progress_done(progress);
    sc_cli_error("%s", msg);
    return SC_EXIT_FAILURE;
  }
  *seconds_read = sc_cli_now() - t0;
  return SC_EXIT_OK;
}

int sc_cli_job_write(const sc_cli_job_opts_t *o, sc_cli_progress_t *progress,
                     scf_mesh_format_t fmt, const scf_points_t *pts,
                     const uint32_t *tris, size_t ntri, const double *normals,
                     sc_cli_result_t *r) {
  char msg[1024];
  sc_cli_progress_step(progress, "writing", 0);
  double t0 = sc_cli_now();
  int rc = scf_mesh_write(o->out_path, fmt, pts->xyz, pts->count, tris, ntri,
                          o->normals ? normals : NULL, msg, sizeof msg);
  r->seconds_write = sc_cli_now() - t0;
  sc_cli_progress_done(progress);
  if (rc < 0) {
    sc_cli_error("%s", msg);
    return SC_EXIT_FAILURE;
  }
  int status = SC_EXIT_OK;
  if (o->report && sc_cli_write_report(o->report, r) < 0)
    status = SC_EXIT_FAILURE;
  if (!o->quiet)
    sc_cli_summary(stdout, r);
  return status;
}
