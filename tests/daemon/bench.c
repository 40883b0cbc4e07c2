/*
 * shortcrustd-bench: what the daemon costs and what it gives.
 *
 *   1. Latency: one job of --points points (default 100000) through the
 *      daemon, from the first byte sent to the last byte of the mesh,
 *      against sc_reconstruct() on the same points in this process.
 *   2. Throughput: --jobs jobs of --job-points points over 4 connections at
 *      once, with 1 .. --workers-max workers.
 *   3. Memory: the daemon's resident size idle, at the peak of a burst,
 *      and once the burst is over.
 *   4. Round trip: `shortcrust submit` of a --points torus file to a
 *      one-worker daemon against `shortcrust reconstruct` of it, as whole
 *      processes (bench_cmd.c).
 *   5. Streaming: --stream-points points uploaded at a pace that spreads
 *      them over --stream-seconds, in random and in scan order, then
 *      JOB_END: the time to JOB_DONE against `shortcrust reconstruct` of
 *      the same points (bench_cmd.c).
 *
 * Every figure is the median of --repeat runs (alternated with the run it
 * is compared with). Meshes are checked (closed
 * sphere) so that a fast wrong answer does not count.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <pthread.h>
#include <sys/resource.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bench.h"
#include "harness.h"
#include "shortcrust.h"
#include "synth.h"

/* One job through a connection; seconds, or -1. */
static double one_job(const char *sock, const double *xyz, size_t n,
                      uint64_t *ntri) {
  scdt_conn_t *c;
  if (scdt_open(sock, 1u << 20, &c) != 0)
    return -1;
  scdt_job_t j;
  scdt_job_init(&j, 1, xyz, n);
  scdt_job_t *pj = &j;
  char why[512] = "";
  double t0 = bench_seconds();
  int rc = scdt_job_send(c, &j);
  if (rc == 0)
    rc = scdt_collect(c, &pj, 1, BENCH_T_MS, why, sizeof why);
  double t = bench_seconds() - t0;
  if (rc != 0 || !j.done) {
    fprintf(stderr, "job failed: %s %s\n", why, j.error_msg);
    t = -1;
  } else if (!scdt_mesh_ok(SCS_SURF_SPHERE, &j, why, sizeof why)) {
    fprintf(stderr, "wrong mesh: %s\n", why);
    t = -1;
  }
  *ntri = j.ntri;
  scdt_job_reset(&j);
  scdt_close(c);
  return t;
}

static void latency(size_t n, int repeat) {
  printf("latency: one job of %zu points\n", n);
  double *xyz = scdt_sample(SCS_SURF_SPHERE, n, 1);
  double *direct = calloc((size_t)repeat, sizeof *direct);
  double *daemon = calloc((size_t)repeat, sizeof *daemon);
  double *pair = calloc((size_t)repeat, sizeof *pair);
  double *dcpu = calloc((size_t)repeat, sizeof *dcpu);
  double *scpu = calloc((size_t)repeat, sizeof *scpu);
  uint64_t direct_tri = 0, daemon_tri = 0;
  sc_params_t p;
  sc_params_init(&p);
  scdt_daemon_t d;
  if (bench_start(&d, 1) != 0) {
    fprintf(stderr, "daemon did not start\n");
    exit(1);
  }
  /* Alternated, so that a change in the machine's load hits both alike. */
  for (int r = 0; r < repeat; r++) {
    sc_mesh_t *m = NULL;
    double c0 = bench_cpu_self();
    double t0 = bench_seconds();
    int rc = sc_reconstruct(xyz, n, &p, &m, NULL, 0);
    direct[r] = bench_seconds() - t0;
    dcpu[r] = bench_cpu_self() - c0;
    if (rc == 0)
      direct_tri = m->triangle_count;
    sc_mesh_free(m);
    c0 = bench_cpu_of(d.pid);
    daemon[r] = one_job(d.sock, xyz, n, &daemon_tri);
    scpu[r] = bench_cpu_of(d.pid) - c0;
    pair[r] = daemon[r] / direct[r];
  }
  scdt_daemon_stop(&d);
  double a = bench_median(direct, repeat), b = bench_median(daemon, repeat);
  printf("  direct sc_reconstruct  %8.3f s  (%llu triangles)\n", a,
         (unsigned long long)direct_tri);
  printf("  through the daemon     %8.3f s  (%llu triangles, upload and "
         "download included)\n",
         b, (unsigned long long)daemon_tri);
  printf("  ratio daemon/direct    %8.3f  (median of the %d paired ratios: "
         "%.3f)\n",
         b / a, repeat, bench_median(pair, repeat));
  printf("  CPU: direct %.3f s, daemon %.3f s (ratio %.3f)\n",
         bench_median(dcpu, repeat), bench_median(scpu, repeat),
         bench_median(scpu, repeat) / bench_median(dcpu, repeat));
  free(direct);
  free(daemon);
  free(pair);
  free(dcpu);
  free(scpu);
  free(xyz);
}

typedef struct burst {
  const char *sock;
  double **xyz;
  size_t n;
  int first, count;  /* jobs of this connection */
  atomic_int *failed;
  double end;        /* when its last job ended */
} burst_t;

static void *burst_client(void *arg) {
  burst_t *b = arg;
  scdt_conn_t *c;
  if (scdt_open(b->sock, 1u << 20, &c) != 0) {
    atomic_fetch_add(b->failed, b->count);
    return NULL;
  }
  scdt_job_t *j = calloc((size_t)b->count, sizeof *j);
  scdt_job_t **pj = calloc((size_t)b->count, sizeof *pj);
  for (int k = 0; k < b->count; k++) {
    scdt_job_init(&j[k], (uint32_t)k + 1, b->xyz[b->first + k], b->n);
    pj[k] = &j[k];
    if (scdt_job_send(c, &j[k]) != 0)
      atomic_fetch_add(b->failed, 1);
  }
  char why[512] = "";
  if (scdt_collect(c, pj, (size_t)b->count, BENCH_T_MS, why, sizeof why) != 0)
    fprintf(stderr, "burst: %s\n", why);
  b->end = bench_seconds();
  /* Checked after the clock stopped: the checks share the machine with the
   * daemon. */
  for (int k = 0; k < b->count; k++) {
    if (!j[k].done || !scdt_mesh_ok(SCS_SURF_SPHERE, &j[k], why, sizeof why))
      atomic_fetch_add(b->failed, 1);
    scdt_job_reset(&j[k]);
  }
  free(j);
  free(pj);
  scdt_close(c);
  return NULL;
}

/* All jobs at once over 4 connections; seconds. */
static double burst(const char *sock, double **xyz, size_t n, int jobs,
                    int *failed_out) {
  enum { NC = 4 };
  pthread_t th[NC];
  burst_t b[NC];
  atomic_int failed;
  atomic_init(&failed, 0);
  double t0 = bench_seconds();
  int at = 0;
  for (int i = 0; i < NC; i++) {
    int count = jobs / NC + (i < jobs % NC);
    b[i] = (burst_t){sock, xyz, n, at, count, &failed, 0};
    at += count;
    pthread_create(&th[i], NULL, burst_client, &b[i]);
  }
  double end = t0;
  for (int i = 0; i < NC; i++) {
    pthread_join(th[i], NULL);
    if (b[i].end > end)
      end = b[i].end;
  }
  *failed_out = atomic_load(&failed);
  return end - t0;
}

/* The same jobs in this process, on `threads` threads calling
 * sc_reconstruct(): how far the machine itself scales. */
typedef struct direct {
  double **xyz;
  size_t n;
  int jobs;
  atomic_int next;
} direct_t;

static void *direct_worker(void *arg) {
  direct_t *d = arg;
  sc_params_t p;
  sc_params_init(&p);
  for (;;) {
    int k = atomic_fetch_add(&d->next, 1);
    if (k >= d->jobs)
      return NULL;
    sc_mesh_t *m = NULL;
    sc_reconstruct(d->xyz[k], d->n, &p, &m, NULL, 0);
    sc_mesh_free(m);
  }
}

static double direct_burst(double **xyz, size_t n, int jobs,
                           unsigned threads) {
  direct_t d = {.xyz = xyz, .n = n, .jobs = jobs};
  atomic_init(&d.next, 0);
  pthread_t *th = calloc(threads, sizeof *th);
  double t0 = bench_seconds();
  for (unsigned i = 0; i < threads; i++)
    pthread_create(&th[i], NULL, direct_worker, &d);
  for (unsigned i = 0; i < threads; i++)
    pthread_join(th[i], NULL);
  free(th);
  return bench_seconds() - t0;
}

typedef struct sampler {
  pid_t pid;
  atomic_int stop;
  uint64_t peak;
} sampler_t;

static void *sample_rss(void *arg) {
  sampler_t *s = arg;
  while (!atomic_load(&s->stop)) {
    uint64_t r = scdt_rss(s->pid);
    if (r > s->peak)
      s->peak = r;
    scdt_sleep_ms(5);
  }
  return NULL;
}

static void throughput(size_t n, int jobs, unsigned wmax, int repeat) {
  printf("throughput: %d jobs of %zu points over 4 connections\n", jobs, n);
  double **xyz = calloc((size_t)jobs, sizeof *xyz);
  for (int k = 0; k < jobs; k++)
    xyz[k] = scdt_sample(SCS_SURF_SPHERE, n, (uint64_t)k + 10);
  double base = 0, direct_base = 0;
  double *t = calloc((size_t)repeat, sizeof *t);
  for (unsigned w = 1; w <= wmax; w++) {
    double c0 = bench_cpu_self();
    for (int r = 0; r < repeat; r++)
      t[r] = direct_burst(xyz, n, jobs, w);
    double direct_cpu = (bench_cpu_self() - c0) / repeat;
    double dm = bench_median(t, repeat);
    if (w == 1)
      direct_base = dm;
    scdt_daemon_t d;
    if (bench_start(&d, w) != 0) {
      fprintf(stderr, "daemon did not start\n");
      exit(1);
    }
    uint64_t cold = scdt_rss(d.pid);
    /* A few small jobs first, one per worker: what a daemon keeps after
     * its first jobs (each thread's stack and malloc arena, libraries'
     * one-time state) is not the burst's. */
    double *warm = scdt_sample(SCS_SURF_SPHERE, 2000, 9);
    double **warms = calloc(w, sizeof *warms);
    for (unsigned i = 0; i < w; i++)
      warms[i] = warm;
    int warm_failed;
    burst(d.sock, warms, 2000, (int)w, &warm_failed);
    free(warms);
    free(warm);
    scdt_stat_wait(d.sock, "jobs_active", 0, BENCH_T_MS);
    scdt_sleep_ms(1000);
    uint64_t idle = scdt_rss(d.pid);
    sampler_t s = {.pid = d.pid, .peak = idle};
    atomic_init(&s.stop, 0);
    pthread_t st;
    pthread_create(&st, NULL, sample_rss, &s);
    int failed = 0;
    double c1 = bench_cpu_of(d.pid);
    for (int r = 0; r < repeat; r++) {
      int f = 0;
      t[r] = burst(d.sock, xyz, n, jobs, &f);
      failed += f;
    }
    double daemon_cpu = (bench_cpu_of(d.pid) - c1) / repeat;
    atomic_store(&s.stop, 1);
    pthread_join(st, NULL);
    scdt_stat_wait(d.sock, "jobs_active", 0, BENCH_T_MS);
    scdt_sleep_ms(1000);
    uint64_t after = scdt_rss(d.pid);
    uint64_t held = scdt_stat_fresh(d.sock, "memory_jobs_bytes");
    scdt_daemon_stop(&d);
    double m = bench_median(t, repeat);
    if (w == 1)
      base = m;
    printf("  %u worker%s  %7.3f s  %6.2f jobs/s  speed-up %.2f%s   "
           "(in-process sc_reconstruct on %u thread%s: %.3f s, speed-up "
           "%.2f; daemon/direct %.3f)\n",
           w, w == 1 ? " " : "s", m, jobs / m, base / m,
           failed ? "  (FAILED JOBS)" : "", w, w == 1 ? "" : "s", dm,
           direct_base / dm, m / dm);
    printf("             CPU per job: daemon %.1f ms, in-process %.1f ms "
           "(ratio %.3f)\n",
           1e3 * daemon_cpu / jobs, 1e3 * direct_cpu / jobs,
           direct_cpu > 0 ? daemon_cpu / direct_cpu : 0);
    printf("             memory: started %.1f MiB, idle after warm-up %.1f "
           "MiB, burst peak %.1f MiB,\n"
           "             after the burst %.1f MiB (ratio after/idle %.2f); "
           "job memory held after: %llu bytes\n",
           cold / 1048576.0, idle / 1048576.0, s.peak / 1048576.0,
           after / 1048576.0, idle ? (double)after / (double)idle : 0.0,
           (unsigned long long)held);
  }
  for (int k = 0; k < jobs; k++)
    free(xyz[k]);
  free(xyz);
  free(t);
}

static void usage(void) {
  printf("Usage: shortcrustd-bench [--daemon PATH] [--shortcrust PATH] "
         "[--points N]\n"
         "                         [--jobs N] [--job-points N] "
         "[--workers-max W]\n"
         "                         [--stream-points N] [--stream-seconds S] "
         "[--repeat R]\n"
         "                         [--only latency|throughput|round-trip|"
         "streaming]\n"
         "Defaults: shortcrustd and shortcrust next to this program, 100000 "
         "points, 16 jobs\n"
         "of 20000 points, W = number of cores, 300000 streamed points over "
         "12 s, R = 3.\n");
}

/* The path of a program in this program's directory, or NULL. */
static const char *beside_self(const char *name, char *buf, size_t len) {
  ssize_t n = readlink("/proc/self/exe", buf, len - 1);
  if (n <= 0)
    return NULL;
  buf[n] = '\0';
  char *slash = strrchr(buf, '/');
  char *at = slash ? slash + 1 : buf;
  if ((size_t)(at - buf) + strlen(name) + 1 > len)
    return NULL;
  strcpy(at, name);
  return buf;
}

int main(int argc, char **argv) {
  static char daemon_path[4096], shortcrust_path[4096];
  const char *daemon = NULL, *shortcrust = NULL, *only = NULL;
  size_t points = 100000, job_points = 20000, stream_points = 300000;
  double stream_seconds = 12;
  int jobs = 16, repeat = 3;
  unsigned wmax = (unsigned)sysconf(_SC_NPROCESSORS_ONLN);
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
    if (strcmp(a, "--help") == 0) {
      usage();
      return 0;
    }
    if (!v) {
      usage();
      return 2;
    }
    if (strcmp(a, "--daemon") == 0)
      daemon = v;
    else if (strcmp(a, "--points") == 0)
      points = (size_t)atol(v);
    else if (strcmp(a, "--jobs") == 0)
      jobs = atoi(v);
    else if (strcmp(a, "--job-points") == 0)
      job_points = (size_t)atol(v);
    else if (strcmp(a, "--workers-max") == 0)
      wmax = (unsigned)atoi(v);
    else if (strcmp(a, "--repeat") == 0)
      repeat = atoi(v);
    else if (strcmp(a, "--shortcrust") == 0)
      shortcrust = v;
    else if (strcmp(a, "--stream-points") == 0)
      stream_points = (size_t)atol(v);
    else if (strcmp(a, "--stream-seconds") == 0)
      stream_seconds = atof(v);
    else if (strcmp(a, "--only") == 0)
      only = v;
    else {
      usage();
      return 2;
    }
    i++;
  }
  if (!daemon)
    daemon = beside_self("shortcrustd", daemon_path, sizeof daemon_path);
  if (!shortcrust)
    shortcrust =
        beside_self("shortcrust", shortcrust_path, sizeof shortcrust_path);
  static const char *const sections[] = {"latency", "throughput", "round-trip",
                                         "streaming"};
  int known = !only;
  for (size_t k = 0; k < sizeof sections / sizeof *sections; k++)
    known |= only && strcmp(only, sections[k]) == 0;
  if (!daemon || !shortcrust || !known || points < 4 || job_points < 4 ||
      stream_points < 4 || !(stream_seconds >= 0) || jobs < 1 || repeat < 1 ||
      wmax < 1) {
    usage();
    return 2;
  }
  char *fake[] = {argv[0], (char *)daemon, NULL};
  scdt_setup(2, fake);
  if (!only || strcmp(only, "latency") == 0)
    latency(points, repeat);
  if (!only || strcmp(only, "throughput") == 0)
    throughput(job_points, jobs, wmax, repeat);
  int bad = 0;
  if (!only || strcmp(only, "round-trip") == 0)
    bad |= bench_round_trip(shortcrust, points, repeat);
  if (!only || strcmp(only, "streaming") == 0)
    bad |= bench_streaming(shortcrust, stream_points, stream_seconds, repeat);
  scdt_cleanup(0);
  /* A wrong or missing mesh fails the run (and the smoke test). */
  return bad;
}
