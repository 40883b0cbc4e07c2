/*
 * shortcrustd-bench, the measurements of whole commands: what a station
 * sees when it runs `shortcrust submit` instead of `shortcrust reconstruct`,
 * and what the daemon saves when the points stream in.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _DEFAULT_SOURCE /* wait4(), M_PI */
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include "bench.h"
#include "shortcrust.h"
#include "shortcrust_files.h"
#include "synth.h"

/* A finished process: wall and CPU seconds, and whether it exited 0. */
typedef struct run {
  double wall, cpu;
  int ok;
} run_t;

/* Runs argv (NULL-terminated) with its output thrown away. */
static run_t run(char *const *argv) {
  run_t r = {0, 0, 0};
  double t0 = bench_seconds();
  pid_t pid = fork();
  if (pid < 0)
    return r;
  if (pid == 0) {
    int null = open("/dev/null", O_WRONLY);
    if (null >= 0) {
      dup2(null, 1);
      dup2(null, 2);
    }
    execv(argv[0], argv);
    _exit(127);
  }
  int status = 0;
  struct rusage ru;
  if (wait4(pid, &status, 0, &ru) != pid)
    return r;
  r.wall = bench_seconds() - t0;
  r.cpu = (double)ru.ru_utime.tv_sec + ru.ru_utime.tv_usec / 1e6 +
          (double)ru.ru_stime.tv_sec + ru.ru_stime.tv_usec / 1e6;
  r.ok = WIFEXITED(status) && WEXITSTATUS(status) == 0;
  if (!r.ok)
    fprintf(stderr, "%s %s exited with status %d\n", argv[0], argv[1], status);
  return r;
}

/* 1 when the two files hold the same bytes. */
static int same_file(const char *a, const char *b) {
  FILE *fa = fopen(a, "rb"), *fb = fopen(b, "rb");
  int same = fa && fb;
  while (same) {
    int x = fgetc(fa), y = fgetc(fb);
    if (x != y)
      same = 0;
    if (x == EOF || y == EOF)
      break;
  }
  if (fa)
    fclose(fa);
  if (fb)
    fclose(fb);
  return same;
}

static int write_points(const char *path, const double *xyz, size_t n) {
  char msg[256];
  if (scf_mesh_write(path, SCF_MESH_FMT_PLY_BINARY, xyz, n, NULL, 0, NULL, msg,
                     sizeof msg) != 0) {
    fprintf(stderr, "%s\n", msg);
    return -1;
  }
  return 0;
}

static run_t reconstruct(const char *shortcrust, const char *in,
                         const char *out) {
  char *argv[] = {(char *)shortcrust, "reconstruct", (char *)in, "-o",
                  (char *)out,        NULL};
  return run(argv);
}

int bench_round_trip(const char *shortcrust, size_t n, int repeat) {
  printf("round trip: `shortcrust submit` to a one-worker daemon against "
         "`shortcrust reconstruct`,\n  %zu points of a torus, whole "
         "processes, alternated\n",
         n);
  scdt_daemon_t d;
  if (bench_start(&d, 1) != 0) {
    fprintf(stderr, "daemon did not start\n");
    exit(1);
  }
  char in[256], local_out[256], daemon_out[256];
  snprintf(in, sizeof in, "%s/torus.ply", d.dir);
  snprintf(local_out, sizeof local_out, "%s/local.ply", d.dir);
  snprintf(daemon_out, sizeof daemon_out, "%s/daemon.ply", d.dir);
  double *xyz = scdt_sample_random(SCS_SURF_TORUS, n, 3);
  if (!xyz || write_points(in, xyz, n) != 0)
    exit(1);
  free(xyz);
  char *submit[] = {(char *)shortcrust, "submit",   in,     "-o",
                    daemon_out,         "--socket", d.sock, NULL};
  double *local = calloc((size_t)repeat, sizeof *local);
  double *remote = calloc((size_t)repeat, sizeof *remote);
  double *pair = calloc((size_t)repeat, sizeof *pair);
  double *lcpu = calloc((size_t)repeat, sizeof *lcpu);
  double *rcpu = calloc((size_t)repeat, sizeof *rcpu);
  int identical = 1, failed = 0;
  for (int r = 0; r < repeat; r++) {
    run_t a = reconstruct(shortcrust, in, local_out);
    double c0 = bench_cpu_of(d.pid);
    run_t b = run(submit);
    rcpu[r] = b.cpu + bench_cpu_of(d.pid) - c0;
    local[r] = a.wall;
    lcpu[r] = a.cpu;
    remote[r] = b.wall;
    pair[r] = b.wall / a.wall;
    failed |= !a.ok || !b.ok;
    identical &= same_file(local_out, daemon_out);
  }
  scdt_daemon_stop(&d);
  double pm = bench_median(pair, repeat);
  printf("  reconstruct            %8.3f s\n", bench_median(local, repeat));
  printf("  submit                 %8.3f s  (output %s)\n",
         bench_median(remote, repeat),
         failed      ? "MISSING: a command failed"
         : identical ? "byte-identical"
                     : "DIFFERENT");
  printf("  ratio submit/reconstruct  %.3f  (median of %d paired ratios)\n", pm,
         repeat);
  printf("  CPU: reconstruct %.3f s, submit and daemon %.3f s (ratio "
         "%.3f)\n",
         bench_median(lcpu, repeat), bench_median(rcpu, repeat),
         bench_median(rcpu, repeat) / bench_median(lcpu, repeat));
  free(local);
  free(remote);
  free(pair);
  free(lcpu);
  free(rcpu);
  return failed || !identical;
}

/* Point orders of a streamed upload. */
enum { ORDER_RANDOM, ORDER_SCAN };

typedef struct keyed {
  double key;
  size_t i;
} keyed_t;

static int cmp_keyed(const void *a, const void *b) {
  double x = ((const keyed_t *)a)->key, y = ((const keyed_t *)b)->key;
  return x < y ? -1 : x > y;
}

/* The points reordered: shuffled, or as a range scanner at a corner of
 * the scene would send them, row by row (elevation bands from the bottom
 * up, each swept in azimuth). */
static void reorder(double *xyz, size_t n, int order) {
  keyed_t *k = malloc(n * sizeof *k);
  scs_rng_t rng;
  scs_rng_seed(&rng, 77);
  const double eye[3] = {-4, -3, 1.5};
  const size_t rows = (size_t)sqrt((double)n);
  for (size_t i = 0; i < n; i++) {
    const double *p = &xyz[3 * i];
    if (order == ORDER_RANDOM) {
      k[i].key = scs_rng_uniform(&rng);
    } else {
      double dx = p[0] - eye[0], dy = p[1] - eye[1], dz = p[2] - eye[2];
      double elev = atan2(dz, hypot(dx, dy)), azim = atan2(dy, dx);
      /* elev and azim both lie in (-pi/2, pi/2) seen from this corner. */
      double row = floor((elev / M_PI + 0.5) * (double)rows);
      k[i].key = row * 4 + (azim / M_PI + 0.5);
    }
    k[i].i = i;
  }
  qsort(k, n, sizeof *k, cmp_keyed);
  double *copy = malloc(3 * n * sizeof *copy);
  for (size_t i = 0; i < n; i++)
    memcpy(&copy[3 * i], &xyz[3 * k[i].i], 3 * sizeof(double));
  memcpy(xyz, copy, 3 * n * sizeof *copy);
  free(copy);
  free(k);
}

/* One paced job: seconds from JOB_END to JOB_DONE, or -1. The triangles
 * are compared with those of the local run's output. */
static double paced_job(const char *sock, const double *xyz, size_t n,
                        double upload_s, const char *local_out, int *identical,
                        double *upload_took) {
  scdt_conn_t *c;
  if (scdt_open(sock, 1u << 20, &c) != 0)
    return -1;
  scdt_job_t j;
  scdt_job_init(&j, 1, xyz, n);
  sc_params_t def; /* the command's defaults */
  sc_params_init(&def);
  j.r = def.r;
  const uint64_t chunk = 4096;
  double t0 = bench_seconds();
  int rc = scdt_job_begin(c, &j);
  for (uint64_t k = 0; rc == 0 && j.sent < n; k++) {
    double due = t0 + upload_s * (double)((k + 1) * chunk) / (double)n;
    double now = bench_seconds();
    if (due > now)
      scdt_sleep_ms((unsigned)((due - now) * 1e3));
    uint64_t left = n - j.sent;
    rc = scdt_job_points(c, &j, left < chunk ? left : chunk);
  }
  double t_end = bench_seconds();
  *upload_took = t_end - t0;
  if (rc == 0)
    rc = scdt_job_end(c, &j);
  scdt_job_t *pj = &j;
  char why[512] = "";
  if (rc == 0)
    rc = scdt_collect(c, &pj, 1, BENCH_T_MS, why, sizeof why);
  double t = bench_seconds() - t_end;
  if (rc != 0 || !j.done) {
    fprintf(stderr, "streamed job failed: %s %s\n", why, j.error_msg);
    t = -1;
  }
  scf_points_t pts = {0};
  uint32_t *tri = NULL;
  size_t ntri = 0;
  *identical = t >= 0 &&
               scf_mesh_read(local_out, &pts, &tri, &ntri, NULL, 0) == 0 &&
               ntri == j.ntri &&
               (ntri == 0 || memcmp(tri, j.tri, 3 * ntri * sizeof *tri) == 0);
  free(tri);
  scf_points_free(&pts);
  scdt_job_reset(&j);
  scdt_close(c);
  return t;
}

int bench_streaming(const char *shortcrust, size_t n, double upload_s,
                    int repeat) {
  printf("streaming: %zu points of a torus uploaded over %.1f s, then "
         "JOB_END;\n  JOB_END to JOB_DONE against the whole `shortcrust "
         "reconstruct` of the same points\n",
         n, upload_s);
  scdt_daemon_t d;
  if (bench_start(&d, 1) != 0) {
    fprintf(stderr, "daemon did not start\n");
    exit(1);
  }
  char in[256], local_out[256];
  snprintf(in, sizeof in, "%s/stream.ply", d.dir);
  snprintf(local_out, sizeof local_out, "%s/stream_local.ply", d.dir);
  double *xyz = scdt_sample_random(SCS_SURF_TORUS, n, 5);
  if (!xyz)
    exit(1);
  double *local = calloc((size_t)repeat, sizeof *local);
  double *tail = calloc((size_t)repeat, sizeof *tail);
  double *pair = calloc((size_t)repeat, sizeof *pair);
  double *took = calloc((size_t)repeat, sizeof *took);
  int bad = 0;
  for (int order = ORDER_RANDOM; order <= ORDER_SCAN; order++) {
    reorder(xyz, n, order);
    if (write_points(in, xyz, n) != 0)
      exit(1);
    int identical = 1, failed = 0;
    for (int r = 0; r < repeat; r++) {
      run_t a = reconstruct(shortcrust, in, local_out);
      int same = 0;
      tail[r] = paced_job(d.sock, xyz, n, upload_s, local_out, &same, &took[r]);
      local[r] = a.wall;
      pair[r] = tail[r] / a.wall;
      failed |= !a.ok || tail[r] < 0;
      identical &= same;
    }
    printf("  %s order: upload %.2f s, JOB_END to JOB_DONE %.3f s, local "
           "%.3f s:\n    ratio %.3f (median of %d paired ratios; "
           "triangles %s)\n",
           order == ORDER_RANDOM ? "random" : "scan  ",
           bench_median(took, repeat), bench_median(tail, repeat),
           bench_median(local, repeat), bench_median(pair, repeat), repeat,
           failed      ? "MISSING: a run failed"
           : identical ? "identical"
                       : "DIFFERENT");
    bad |= failed || !identical;
  }
  scdt_daemon_stop(&d);
  free(xyz);
  free(local);
  free(tail);
  free(pair);
  free(took);
  return bad;
}
