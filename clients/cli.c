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

void sc_cli_job_init(sc_cli_job_opts_t *o) {
  memset(o, 0, sizeof *o);
  sc_params_init(&o->params);
  o->normals = 1;
}

void sc_cli_job_usage_output(FILE *f) {
  fputs(
      "      --report FILE     write the diagnostics as JSON to FILE\n"
      "      --ascii           write ascii PLY or STL instead of binary\n"
      "      --no-normals      do not write the computed per-vertex normals\n"
      "      --mesh-normals    write the computed normals even where the\n"
      "                        input has its own (nx, ny, nz), in their place\n"
      "  -q, --quiet           no progress and no summary; errors only\n"
      "  -h, --help            this text\n\n",
      f);
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
  /* Before any file is read: a parameter out of range is the command
   * line's fault, whatever the input. */
  char msg[256];
  if (sc_params_check(&o->params, msg, sizeof msg) != SC_OK) {
    sc_cli_error("%s: %s", cmd, msg);
    return -1;
  }
  return 0;
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

/* A path as the summary and the warnings name it. */
static const char *shown(const char *path, const char *stdio_name) {
  return strcmp(path, "-") == 0 ? stdio_name : path;
}

void sc_cli_summary(FILE *f, const sc_cli_result_t *r) {
  const sc_diag_t *d = r->diag;
  fprintf(f, "%s: %llu points", shown(r->input, "standard input"),
          (unsigned long long)d->points_in);
  if (d->duplicates_merged)
    fprintf(f, " (%llu duplicates merged)",
            (unsigned long long)d->duplicates_merged);
  fprintf(f, " -> %llu triangles in %s, mode %s",
          (unsigned long long)d->triangles, shown(r->output, "standard output"),
          sc_mode_name(r->params.mode));
  if (r->params.mode == SC_MODE_SHORTCRUST && d->checked &&
      d->r_used != r->params.r)
    fprintf(f, " (r = %g: at %g the topology was not the cocone test's)",
            d->r_used, r->params.r);
  else if (r->params.mode == SC_MODE_SHORTCRUST)
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
  if (d->small_handles_cut)
    fprintf(f, ", %llu small handle%s cut",
            (unsigned long long)d->small_handles_cut,
            d->small_handles_cut == 1 ? "" : "s");
  fprintf(f, ".\n");
  fprintf(f, "Path %s: %llu boundary sample%s, longest loop %llu edges",
          sc_path_name(d->path), (unsigned long long)d->boundary_samples,
          d->boundary_samples == 1 ? "" : "s",
          (unsigned long long)d->longest_loop);
  if (d->labelled)
    fprintf(f, "; cells labelled, %s",
            d->path == SC_PATH_WATERTIGHT_FILL ? "the patches' closure kept"
            : d->path == SC_PATH_COCONE
                ? "the cocone test's surface at every sample kept"
                : "their closure kept");
  fprintf(f, ".\n");
  if (d->checked) {
    fprintf(f,
            "Check: the cocone test's surface on the same triangulation "
            "has %llu component%s (%llu closed), genus %lld",
            (unsigned long long)d->check_components,
            d->check_components == 1 ? "" : "s",
            (unsigned long long)d->check_closed_components,
            (long long)d->check_genus);
    fprintf(f, "%s.\n",
            d->topology_doubt ? ": the topology is in doubt" : ", the same");
  }
  fprintf(f, "Noise: %.2f spacings (spacing %.3g)", d->noise, d->spacing);
  if (d->denoised)
    fprintf(f, "; denoised%s at scale %.3g, samples moved %.2f spacings "
               "(RMS)",
            r->params.denoise ? "" : " by auto mode", d->denoise_scale,
            d->denoise_shift);
  else if (r->params.denoise && d->noise < SC_NOISE_FLOOR)
    fprintf(f, "; below %.2f, not smoothed", SC_NOISE_FLOOR);
  else if (r->params.denoise)
    fprintf(f, "; not smoothed: the sample is too coarse to tell noise from "
               "shape (curvature %.2f), give --denoise-scale to smooth",
            d->curvature);
  fprintf(f, ".\n");
  if (d->tiles)
    fprintf(f,
            "Tiles: %llu; %llu points triangulated in a second tile "
            "(%.1f%%)%s.\n",
            (unsigned long long)d->tiles,
            (unsigned long long)d->tile_points_foreign,
            d->delaunay_vertices ? 100.0 * (double)d->tile_points_foreign /
                                       (double)d->delaunay_vertices
                                 : 0.0,
            r->tile_jobs ? "; each a job of the daemons, merged here"
            : r->params.memory_limit > 0
                ? "; within the memory limit, a few at a time, each twice"
                : "");
  else if (r->params.memory_limit > 0 || r->params.tiles != 1)
    fprintf(f, "Tiles: none, one triangulation: %s.\n",
            !sc_params_can_tile(&r->params)
                ? "watertight mode's labelling alone labels one "
                  "triangulation"
            : r->params.memory_limit > 0 ? "it fits the memory limit"
            : r->params.tiles == 0 && r->params.threads == 1
                ? "one tile per thread, and one thread"
            : r->params.tiles == 0 && r->params.mode == SC_MODE_WATERTIGHT &&
                    !r->params.watertight_patches
                ? "watertight mode labels its cells beside the extraction"
            : d->tile_points_foreign
                ? "the tiles' Delaunay balls reach far across each other "
                  "(as inside a closed surface's sample), so one "
                  "triangulation is faster"
                : "too few points to split (2000 a tile)");
  fprintf(f, "Time: read %.3f s", r->seconds_read);
  if (r->seconds_transfer > 0)
    fprintf(f, ", transfer %.3f s", r->seconds_transfer);
  for (int s = 0; s < SC_STAGE_COUNT; ++s)
    fprintf(f, ", %s %.3f s", sc_stage_name(s), d->seconds[s]);
  fprintf(f, ", write %.3f s; reconstruction %.3f s.\n", r->seconds_write,
          d->seconds_total);
}

char *sc_cli_report_json(const sc_cli_result_t *r) {
  char *buf = NULL;
  size_t len = 0;
  FILE *f = open_memstream(&buf, &len);
  if (!f)
    return NULL;
  const sc_diag_t *d = r->diag;
  fputs("{\n  \"command\": ", f);
  scf_json_string(f, r->command);
  fputs(",\n  \"input\": ", f);
  scf_json_string(f, r->input);
  fputs(",\n  \"output\": ", f);
  scf_json_string(f, r->output);
  fputs(",\n", f);
  sc_cli_report_params(f, &r->params);
  sc_cli_report_diag(f, d);
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
                    scf_attrs_t *attrs, double *seconds_read) {
  memset(attrs, 0, sizeof *attrs);
  char msg[1024];
  if (scf_mesh_format_from_path(o->out_path, o->ascii, fmt, msg, sizeof msg) <
      0) {
    sc_cli_error("%s", msg);
    return SC_EXIT_USAGE;
  }
  sc_cli_progress_init(progress, o->quiet);
  double t0 = sc_cli_now();
  sc_cli_progress_step(progress, "reading", 0);
  if (scf_points_read_attrs(o->in_path, pts, attrs, msg, sizeof msg) < 0) {
    sc_cli_progress_done(progress);
    sc_cli_error("%s", msg);
    return SC_EXIT_FAILURE;
  }
  *seconds_read = sc_cli_now() - t0;
  return SC_EXIT_OK;
}

/* "2 components, 1 closed" or "1 closed component of genus 2". */
static void topology_text(char *buf, size_t len, uint64_t components,
                          uint64_t closed, int64_t genus) {
  if (closed == components)
    snprintf(buf, len, "%llu closed component%s of genus %lld",
             (unsigned long long)components, components == 1 ? "" : "s",
             (long long)genus);
  else
    snprintf(buf, len, "%llu component%s, %llu closed",
             (unsigned long long)components, components == 1 ? "" : "s",
             (unsigned long long)closed);
}

/* An empty mesh, or one that leaves most samples in no triangle, is
 * written like any other but must not pass for an ordinary result
 * (PROTOCOL.md 6.9): one warning line on stderr, even with --quiet. The
 * counts decide too, for a daemon that does not send mostly_unused. */
static void warn_sparse(const sc_cli_result_t *r) {
  const sc_diag_t *d = r->diag;
  fflush(stdout); /* after the summary, when both go to one place */
  if (d->triangles == 0)
    sc_cli_error("warning: %s: the mesh is empty: the points support no "
                 "surface that mode %s accepts",
                 shown(r->output, "standard output"),
                 sc_mode_name(r->params.mode));
  else if (d->mostly_unused || 2 * d->samples_unused > d->delaunay_vertices)
    sc_cli_error("warning: %s: %llu of %llu distinct samples are in no "
                 "triangle",
                 shown(r->output, "standard output"),
                 (unsigned long long)d->samples_unused,
                 (unsigned long long)d->delaunay_vertices);
  /* Shortcrust mode's check (docs/algorithm.md section 6.5). */
  if (d->topology_doubt) {
    char ours[128], theirs[128];
    topology_text(ours, sizeof ours, d->components, d->closed_components,
                  d->genus);
    topology_text(theirs, sizeof theirs, d->check_components,
                  d->check_closed_components, d->check_genus);
    sc_cli_error("warning: %s: the topology is in doubt: the criteria with "
                 "r = %g give %s where the cocone test, on the same "
                 "triangulation, gives %s%s; the sample may be too sparse "
                 "for the criteria: compare --mode cocone",
                 shown(r->output, "standard output"), r->params.r, ours, theirs,
                 d->check_closed_components == d->check_components
                     ? ", and no r within 0.02 of it gives that surface"
                     : "");
  }
}

int sc_cli_job_write(const sc_cli_job_opts_t *o, sc_cli_progress_t *progress,
                     scf_mesh_format_t fmt, const scf_points_t *pts,
                     scf_attrs_t *attrs, const uint32_t *tris, size_t ntri,
                     const double *normals, sc_cli_result_t *r) {
  char msg[1024];
  sc_cli_progress_step(progress, "writing", 0);
  double t0 = sc_cli_now();
  /* The input's own normals stay unless --mesh-normals asks for ours. */
  if (o->mesh_normals && o->normals && normals != NULL) {
    scf_attrs_remove(attrs, "nx");
    scf_attrs_remove(attrs, "ny");
    scf_attrs_remove(attrs, "nz");
  }
  int rc =
      scf_mesh_write_attrs(o->out_path, fmt, pts->xyz, pts->count, tris, ntri,
                           o->normals ? normals : NULL, attrs, msg, sizeof msg);
  r->seconds_write = sc_cli_now() - t0;
  sc_cli_progress_done(progress);
  if (rc < 0) {
    sc_cli_error("%s", msg);
    return SC_EXIT_FAILURE;
  }
  int status = SC_EXIT_OK;
  if (o->report && sc_cli_write_report(o->report, r) < 0)
    status = SC_EXIT_FAILURE;
  /* With the mesh on standard output, the summary goes beside it. */
  if (!o->quiet)
    sc_cli_summary(strcmp(o->out_path, "-") == 0 ? stderr : stdout, r);
  warn_sparse(r);
  return status;
}
