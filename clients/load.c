/*
 * shortcrust-load: a load generator for shortcrustd. C client threads, each
 * with its own connection, submit their share of J jobs with K of them in
 * flight at a time, and the tool reports throughput, latency percentiles,
 * errors by code, the daemon's counters before and after, and (--verify)
 * whether every mesh that came back is right.
 *
 * DESIGN. The main thread prepares the inputs (samples of closed test
 * surfaces, or the points of the given files), reads the daemon's counters,
 * starts the client threads and joins them. Inputs are read-only once the
 * threads start. Each thread owns its client handle and its tally (jobs,
 * points, latencies, errors by code, verification failures); the main
 * thread reads a tally only after joining its thread. The one thing the
 * threads share is the stop time, written before they start. No locks.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "shortcrust_files.h"
#include "shortcrust_client.h"
#include "synth.h"

#ifndef SC_VERSION
#define SC_VERSION "unknown"
#endif

/* Distinct samples made for --points: jobs take them in turn. */
#define LOAD_SAMPLES 6
/* Verification failures described on stderr; the rest are only counted. */
#define LOAD_SHOW_FAILURES 5
#define LOAD_MAX_CODES 32
/* A job is a pure function of its points and options: by default a job
 * whose connection is lost runs again, and counts as lost only when it
 * never completes. */
#define LOAD_RETRIES 3
#define LOAD_RETRY_BACKOFF_MS 200

static const scs_surface_t surfaces[] = {SCS_SURF_SPHERE, SCS_SURF_TORUS,
                                         SCS_SURF_GENUS2};

typedef struct input {
  const char *name; /* surface name or file path */
  int surface;      /* scs_surface_t, or -1 for a file */
  double *xyz;
  uint64_t n;
} input_t;

typedef struct config {
  const char *socket_path; /* the address */
  const char *token_file;
  unsigned clients;
  uint64_t jobs; /* UINT64_MAX: bounded by the duration only */
  unsigned in_flight;
  double duration; /* 0: none */
  double timeout;  /* seconds a job may take */
  int verify;
  int json;
  sc_client_params_t params;
  input_t *inputs;
  size_t ninputs;
  double stop_at; /* monotonic time after which no job starts */
} config_t;

typedef struct code_count {
  char name[48];
  uint64_t count;
} code_count_t;

/* One thread's results. */
typedef struct tally {
  uint64_t done, failed, points;
  uint64_t retries;      /* resubmissions, in all */
  uint64_t jobs_retried; /* jobs that needed at least one */
  uint64_t lost;         /* jobs that never completed: their connection
                            went, and their retries with it */
  double *latency_ms;
  size_t nlat, latcap;
  code_count_t codes[LOAD_MAX_CODES];
  size_t ncodes;
  uint64_t verified, verify_failures;
  char first_failure[LOAD_SHOW_FAILURES][512];
  unsigned nshown;
  char first_error[512];
} tally_t;

typedef struct worker {
  const config_t *cfg;
  unsigned index;
  uint64_t share;
  pthread_t thread;
  tally_t t;
} worker_t;

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void say(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
static void say(const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  fputs("shortcrust-load: ", stderr);
  vfprintf(stderr, fmt, ap);
  fputc('\n', stderr);
  va_end(ap);
}

static void count_error(tally_t *t, int rc, uint32_t server_code, uint64_t jobs,
                        const char *msg) {
  char name[48];
  if (server_code)
    snprintf(name, sizeof name, "%s:%s", sc_client_err_name(rc),
             sc_client_server_code_name(server_code));
  else
    snprintf(name, sizeof name, "%s", sc_client_err_name(rc));
  t->failed += jobs;
  if (!t->first_error[0] && msg)
    snprintf(t->first_error, sizeof t->first_error, "%s", msg);
  for (size_t i = 0; i < t->ncodes; i++) {
    if (strcmp(t->codes[i].name, name) == 0) {
      t->codes[i].count += jobs;
      return;
    }
  }
  size_t i = t->ncodes < LOAD_MAX_CODES ? t->ncodes++ : LOAD_MAX_CODES - 1;
  snprintf(t->codes[i].name, sizeof t->codes[i].name, "%s", name);
  t->codes[i].count += jobs;
}

static void add_latency(tally_t *t, double ms) {
  if (t->nlat == t->latcap) {
    size_t cap = t->latcap ? 2 * t->latcap : 256;
    double *p = realloc(t->latency_ms, cap * sizeof *p);
    if (!p)
      return;
    t->latency_ms = p;
    t->latcap = cap;
  }
  t->latency_ms[t->nlat++] = ms;
}

static void verify_failed(tally_t *t, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));
static void verify_failed(tally_t *t, const char *fmt, ...) {
  t->verify_failures++;
  if (t->nshown >= LOAD_SHOW_FAILURES)
    return;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(t->first_failure[t->nshown++], sizeof t->first_failure[0], fmt, ap);
  va_end(ap);
}

/* Checks a returned mesh against its own input: indices in range and a
 * manifold always; for a surface sample, closed, outward and the surface's
 * components and genus too. */
static void verify(tally_t *t, const input_t *in, const sc_client_job_t *job) {
  sc_client_mesh_t m;
  sc_client_job_mesh(job, &m);
  t->verified++;
  scs_meshcheck_t mc;
  if (scs_meshcheck((size_t)in->n, in->xyz, m.triangles,
                    (size_t)m.triangle_count, NULL, &mc) != SCS_OK) {
    verify_failed(t, "%s: the mesh checker could not run", in->name);
    return;
  }
  char why[256] = "", sum[256];
  int ok;
  if (in->surface >= 0) {
    ok = scs_meshcheck_expect(&mc, (scs_surface_t)in->surface,
                              SCS_EXPECT_OUTWARD, why, sizeof why);
  } else {
    ok = mc.out_of_range == 0 && mc.manifold;
    if (!ok)
      snprintf(why, sizeof why,
               "%llu triangles with an index out of range, or not a manifold",
               (unsigned long long)mc.out_of_range);
  }
  double diag_tri =
      sc_client_value_get(m.values, m.value_count, "triangles", -1);
  if (ok && diag_tri >= 0 && diag_tri != (double)m.triangle_count) {
    ok = 0;
    snprintf(why, sizeof why, "diagnostics say %.0f triangles, %llu came",
             diag_tri, (unsigned long long)m.triangle_count);
  }
  if (!ok)
    verify_failed(t, "%s (%llu points): %s; %s", in->name,
                  (unsigned long long)in->n, why,
                  scs_meshcheck_summary(&mc, sum, sizeof sum));
  scs_meshcheck_free(&mc);
}

/* A job in flight on a connection. */
typedef struct slot {
  sc_client_job_t *job;
  const input_t *in;
  double t0;
} slot_t;

/* Whether a job that ended with rc lost its connection (and its retries)
 * rather than failed on the daemon. */
static int is_lost(int rc) {
  return rc == SC_CLIENT_ELOST || rc == SC_CLIENT_ESHUTDOWN ||
         rc == SC_CLIENT_ENODAEMON || rc == SC_CLIENT_ETIMEOUT;
}

static void sleep_ms(long ms) {
  struct timespec ts = {.tv_sec = ms / 1000, .tv_nsec = (ms % 1000) * 1000000};
  while (nanosleep(&ts, &ts) != 0 && errno == EINTR)
    ;
}

/* Connects, trying again as the retry policy says when the daemon is gone
 * or going (through a balancer, the next try may reach another). */
static sc_client_t *connect_client(const config_t *cfg, tally_t *t,
                                   int *rc_out) {
  sc_client_options_t o;
  sc_client_options_init(&o);
  o.socket_path = cfg->socket_path;
  o.token_file = cfg->token_file;
  sc_client_t *c = NULL;
  char msg[512];
  long wait = cfg->params.retry_backoff_ms;
  for (int attempt = 0;; attempt++) {
    *rc_out = sc_client_connect(&o, &c, msg, sizeof msg);
    if (*rc_out == 0 || attempt >= cfg->params.retries || !is_lost(*rc_out))
      break;
    t->retries++;
    sleep_ms(wait);
    wait = wait * 2 > 10000 ? 10000 : wait * 2;
  }
  if (*rc_out < 0 && !t->first_error[0])
    snprintf(t->first_error, sizeof t->first_error, "%s", msg);
  return c;
}

static void *run_worker(void *arg) {
  worker_t *w = arg;
  const config_t *cfg = w->cfg;
  tally_t *t = &w->t;
  slot_t *slots = calloc(cfg->in_flight, sizeof *slots);
  if (!slots) {
    count_error(t, SC_CLIENT_ENOMEM, 0, 1, "out of memory");
    return NULL;
  }
  uint64_t submitted = 0;
  unsigned inflight = 0;
  sc_client_t *c = NULL;
  int rc;
  for (;;) {
    int more = submitted < w->share && now_s() < cfg->stop_at;
    if (!c && more) {
      c = connect_client(cfg, t, &rc);
      if (!c) {
        /* Nothing more can run on this thread: its jobs are errors. */
        uint64_t left = w->share == UINT64_MAX ? 1 : w->share - submitted;
        count_error(t, rc, 0, left, NULL);
        break;
      }
    }
    while (more && inflight < cfg->in_flight) {
      /* Threads start at different inputs, so that they do not all send
       * the same sample at the same moment. */
      const input_t *in =
          &cfg->inputs[(w->index + submitted * cfg->clients) % cfg->ninputs];
      double t0 = now_s();
      sc_client_job_t *job = NULL;
      rc = sc_client_submit(c, &cfg->params, in->xyz, in->n, &job);
      submitted++;
      if (rc < 0) {
        count_error(t, rc, 0, 1, sc_client_last_error(c));
        break;
      }
      unsigned k = 0;
      while (slots[k].job)
        k++;
      slots[k] = (slot_t){.job = job, .in = in, .t0 = t0};
      inflight++;
      more = submitted < w->share && now_s() < cfg->stop_at;
    }
    if (inflight == 0) {
      if (c && sc_client_status(c) < 0) {
        /* The connection died between jobs; start a new one. */
        sc_client_free(c);
        c = NULL;
        continue;
      }
      if (!more)
        break;
      continue;
    }
    sc_client_job_t *job = NULL;
    rc = sc_client_wait_any(c, (int)(cfg->timeout * 1000), &job);
    if (!job) {
      /* Nothing ended in time: every job in flight counts as timed out,
       * and the connection goes (closing it cancels them). */
      count_error(t, SC_CLIENT_ETIMEOUT, 0, inflight, sc_client_last_error(c));
      sc_client_free(c);
      c = NULL;
      memset(slots, 0, cfg->in_flight * sizeof *slots);
      inflight = 0;
      continue;
    }
    unsigned k = 0;
    while (k < cfg->in_flight && slots[k].job != job)
      k++;
    if (k == cfg->in_flight) {
      /* Not ours: cannot happen, but must not crash the run. */
      sc_client_job_free(job);
      continue;
    }
    double ms = (now_s() - slots[k].t0) * 1e3;
    unsigned retried = sc_client_job_retries(job);
    t->retries += retried;
    t->jobs_retried += retried > 0;
    if (rc < 0 && is_lost(rc))
      t->lost++;
    if (rc == 0) {
      t->done++;
      t->points += slots[k].in->n;
      add_latency(t, ms);
      if (cfg->verify)
        verify(t, slots[k].in, job);
    } else {
      count_error(t, rc, sc_client_job_server_code(job), 1,
                  sc_client_job_message(job));
    }
    sc_client_job_free(job);
    slots[k].job = NULL;
    inflight--;
  }
  sc_client_free(c);
  free(slots);
  return NULL;
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return x < y ? -1 : x > y;
}

/* The q-quantile of sorted values, by the nearest-rank method. */
static double quantile(const double *v, size_t n, double q) {
  if (n == 0)
    return 0;
  size_t rank = (size_t)ceil(q * (double)n);
  if (rank < 1)
    rank = 1;
  if (rank > n)
    rank = n;
  return v[rank - 1];
}

/* The daemon's counters on a connection of their own; NULL when it does
 * not answer. */
static sc_client_value_t *daemon_stats(const config_t *cfg, size_t *n) {
  sc_client_options_t o;
  sc_client_options_init(&o);
  o.socket_path = cfg->socket_path;
  o.token_file = cfg->token_file;
  o.io_timeout_ms = 10000;
  sc_client_t *c = NULL;
  char msg[512];
  sc_client_value_t *v = NULL;
  *n = 0;
  if (sc_client_connect(&o, &c, msg, sizeof msg) == 0 &&
      sc_client_stats(c, 10000, &v, n) < 0)
    v = NULL;
  sc_client_free(c);
  return v;
}

static void json_values(FILE *f, const sc_client_value_t *v, size_t n) {
  if (!v) {
    fputs("null", f);
    return;
  }
  fputc('{', f);
  for (size_t i = 0; i < n; i++) {
    fprintf(f, "%s\"%s\": ", i ? ", " : "", v[i].name);
    if (v[i].kind == SC_CLIENT_U64)
      fprintf(f, "%llu", (unsigned long long)v[i].v.u);
    else if (v[i].kind == SC_CLIENT_I64)
      fprintf(f, "%lld", (long long)v[i].v.i);
    else if (v[i].kind == SC_CLIENT_F64 && isfinite(v[i].v.f))
      fprintf(f, "%.17g", v[i].v.f);
    else
      fputs("null", f);
  }
  fputc('}', f);
}

static void usage(FILE *f) {
  char sock[256];
  sc_client_params_t def;
  sc_client_params_init(&def);
  fprintf(
      f,
      "usage: shortcrust-load [--connect ADDR | --socket PATH] [--token-file "
      "FILE]\n"
      "                       [--retries N] [--retry-backoff MS] --clients C "
      "--jobs J\n"
      "                       (--points N | --files F...) [--jobs-in-flight "
      "K]\n"
      "                       [--duration S] [--verify] [--json]\n\n"
      "Puts load on a running shortcrustd: C client threads, each with its\n"
      "own connection, submit their share of J jobs, K in flight at a time\n"
      "on each connection. The points are samples of N points of closed test\n"
      "surfaces (sphere, torus, genus 2; %d distinct samples, used in turn)\n"
      "or the points of the given files, used in turn. Prints throughput,\n"
      "latency (from submit to the end of the job), errors by code and the\n"
      "daemon's counters before and after.\n\n"
      "options:\n"
      "      --connect ADDR      the daemon: tcp://HOST:PORT, unix://PATH or a "
      "socket\n"
      "                          path (default %s)\n"
      "      --socket PATH       the same as --connect unix://PATH\n"
      "      --token-file FILE   the token of a daemon on TCP (default: the "
      "variable\n"
      "                          SHORTCRUST_TOKEN)\n"
      "      --retries N         submit a job again up to N times when its "
      "connection\n"
      "                          is lost or the daemon shuts down; connect "
      "again as\n"
      "                          often (default %d)\n"
      "      --retry-backoff MS  wait MS ms before the first retry, twice as "
      "long\n"
      "                          before each next one (default %d)\n"
      "  -c, --clients C         connections, one thread each (default 1)\n"
      "  -n, --jobs J            jobs in all; optional with --duration\n"
      "  -p, --points N          points per generated sample, at least 100\n"
      "  -f, --files F...        point files (every input format of "
      "`shortcrust\n"
      "                          reconstruct`); the arguments after the "
      "options are\n"
      "                          files too\n"
      "  -k, --jobs-in-flight K  jobs in flight per connection (default 1)\n"
      "  -d, --duration S        start no job after S seconds\n"
      "      --timeout S         a job taking longer fails (default 300)\n"
      "      --mode MODE         cocone, shortcrust, boundary, watertight or "
      "auto\n"
      "                          (default cocone)\n"
      "      --r R               shortcrust parameter (default %g)\n"
      "      --verify            check every mesh: indices in range and a\n"
      "                          manifold; closed, outward and of the right\n"
      "                          genus for the generated samples\n"
      "      --json              also print one JSON object, on the last "
      "line\n"
      "  -h, --help              this text\n"
      "  -V, --version           the version\n\n"
      "Exit status: 0 every job done (and verified), 1 errors or "
      "verification\nfailures, 2 bad command line.\n",
      LOAD_SAMPLES, sc_client_default_socket(sock, sizeof sock), LOAD_RETRIES,
      LOAD_RETRY_BACKOFF_MS, def.r);
}

static int parse_u64(const char *opt, const char *arg, uint64_t min,
                     uint64_t max, uint64_t *out) {
  char *end;
  errno = 0;
  unsigned long long v = strtoull(arg, &end, 10);
  if (!*arg || *arg == '-' || *end || errno || v < min || v > max) {
    say("%s: '%s' is not an integer in [%llu, %llu]", opt, arg,
        (unsigned long long)min, (unsigned long long)max);
    return -1;
  }
  *out = v;
  return 0;
}

static int parse_seconds(const char *opt, const char *arg, double *out) {
  char *end;
  errno = 0;
  double v = strtod(arg, &end);
  if (end == arg || *end || errno || !isfinite(v) || v <= 0) {
    say("%s: '%s' is not a positive number of seconds", opt, arg);
    return -1;
  }
  *out = v;
  return 0;
}

enum {
  OPT_SOCKET = 256,
  OPT_TOKEN_FILE,
  OPT_RETRIES,
  OPT_RETRY_BACKOFF,
  OPT_TIMEOUT,
  OPT_MODE,
  OPT_R,
  OPT_VERIFY,
  OPT_JSON
};

static const struct option long_options[] = {
    {"socket", required_argument, NULL, OPT_SOCKET},
    {"connect", required_argument, NULL, OPT_SOCKET},
    {"token-file", required_argument, NULL, OPT_TOKEN_FILE},
    {"retries", required_argument, NULL, OPT_RETRIES},
    {"retry-backoff", required_argument, NULL, OPT_RETRY_BACKOFF},
    {"clients", required_argument, NULL, 'c'},
    {"jobs", required_argument, NULL, 'n'},
    {"points", required_argument, NULL, 'p'},
    {"files", required_argument, NULL, 'f'},
    {"jobs-in-flight", required_argument, NULL, 'k'},
    {"duration", required_argument, NULL, 'd'},
    {"timeout", required_argument, NULL, OPT_TIMEOUT},
    {"mode", required_argument, NULL, OPT_MODE},
    {"r", required_argument, NULL, OPT_R},
    {"verify", no_argument, NULL, OPT_VERIFY},
    {"json", no_argument, NULL, OPT_JSON},
    {"help", no_argument, NULL, 'h'},
    {"version", no_argument, NULL, 'V'},
    {NULL, 0, NULL, 0},
};

/* The command line into *cfg, the files and the point count: -1 to go on,
 * or the status to exit with (after --help, or a message). */
static int parse_args(int argc, char **argv, config_t *cfg,
                      const char **files, size_t *nfiles, uint64_t *points) {
  uint64_t v;
  opterr = 0;
  int c;
  while ((c = getopt_long(argc, argv, ":c:n:p:f:k:d:hV", long_options, NULL)) !=
         -1) {
    switch (c) {
    case OPT_SOCKET:
      cfg->socket_path = optarg;
      break;
    case OPT_TOKEN_FILE:
      cfg->token_file = optarg;
      break;
    case OPT_RETRIES:
      if (parse_u64("--retries", optarg, 0, 1000, &v) < 0)
        return 2;
      cfg->params.retries = (int)v;
      break;
    case OPT_RETRY_BACKOFF:
      if (parse_u64("--retry-backoff", optarg, 0, 60000, &v) < 0)
        return 2;
      cfg->params.retry_backoff_ms = (int)v;
      break;
    case 'c':
      if (parse_u64("--clients", optarg, 1, 1000, &v) < 0)
        return 2;
      cfg->clients = (unsigned)v;
      break;
    case 'n':
      if (parse_u64("--jobs", optarg, 1, UINT64_MAX - 1, &v) < 0)
        return 2;
      cfg->jobs = v;
      break;
    case 'p':
      if (parse_u64("--points", optarg, 100, 100000000, points) < 0)
        return 2;
      break;
    case 'f':
      files[(*nfiles)++] = optarg;
      break;
    case 'k':
      if (parse_u64("--jobs-in-flight", optarg, 1, 100000, &v) < 0)
        return 2;
      cfg->in_flight = (unsigned)v;
      break;
    case 'd':
      if (parse_seconds("--duration", optarg, &cfg->duration) < 0)
        return 2;
      break;
    case OPT_TIMEOUT:
      if (parse_seconds("--timeout", optarg, &cfg->timeout) < 0)
        return 2;
      if (cfg->timeout > 2e6)
        cfg->timeout = 2e6;
      break;
    case OPT_MODE: {
      static const struct {
        const char *name;
        int mode;
      } modes[] = {{"cocone", SC_CLIENT_MODE_COCONE},
                   {"shortcrust", SC_CLIENT_MODE_SHORTCRUST},
                   {"boundary", SC_CLIENT_MODE_BOUNDARY},
                   {"watertight", SC_CLIENT_MODE_WATERTIGHT},
                   {"auto", SC_CLIENT_MODE_AUTO}};
      size_t m = 0;
      while (m < sizeof modes / sizeof modes[0] &&
             strcmp(optarg, modes[m].name) != 0)
        m++;
      if (m == sizeof modes / sizeof modes[0]) {
        say("--mode: unknown mode '%s' (expected cocone, shortcrust, "
            "boundary, watertight or auto)",
            optarg);
        return 2;
      }
      cfg->params.mode = modes[m].mode;
      break;
    }
    case OPT_R: {
      char *end;
      cfg->params.r = strtod(optarg, &end);
      if (end == optarg || *end || !(cfg->params.r > 0 && cfg->params.r < 0.5)) {
        say("--r: '%s' is not a number in (0, 0.5)", optarg);
        return 2;
      }
      break;
    }
    case OPT_VERIFY:
      cfg->verify = 1;
      break;
    case OPT_JSON:
      cfg->json = 1;
      break;
    case 'h':
      usage(stdout);
      return 0;
    case 'V':
      printf("shortcrust-load %s\n", SC_VERSION);
      return 0;
    case ':':
      say("%s needs a value", argv[optind - 1]);
      return 2;
    default:
      say("unknown option '%s' (see shortcrust-load --help)", argv[optind - 1]);
      return 2;
    }
  }
  if (optind < argc && *nfiles == 0) {
    say("unexpected argument '%s'; files go after --files", argv[optind]);
    return 2;
  }
  while (optind < argc)
    files[(*nfiles)++] = argv[optind++];
  if ((*points == 0) == (*nfiles == 0)) {
    say("give either --points N or --files F... (see shortcrust-load --help)");
    return 2;
  }
  if (cfg->jobs == 0 && cfg->duration == 0) {
    say("give --jobs J, --duration S or both");
    return 2;
  }
  if (cfg->jobs == 0)
    cfg->jobs = UINT64_MAX;
  return -1;
}

/* The points of the jobs: samples of the test surfaces, or the files'.
 * 0, or 1 after a message. */
static int load_inputs(config_t *cfg, uint64_t points, const char **files,
                       size_t nfiles) {
  if (points) {
    cfg->ninputs = LOAD_SAMPLES;
    cfg->inputs = calloc(cfg->ninputs, sizeof *cfg->inputs);
    for (size_t i = 0; cfg->inputs && i < cfg->ninputs; i++) {
      input_t *in = &cfg->inputs[i];
      in->surface = surfaces[i % (sizeof surfaces / sizeof surfaces[0])];
      in->name = scs_surface_name((scs_surface_t)in->surface);
      in->n = points;
      in->xyz = malloc((size_t)points * 3 * sizeof(double));
      if (!in->xyz ||
          scs_sample_surface((scs_surface_t)in->surface, SCS_DENSITY_UNIFORM,
                             (size_t)points, 1000 + i, in->xyz) != SCS_OK) {
        say("cannot make a sample of %llu points", (unsigned long long)points);
        return 1;
      }
    }
  } else {
    cfg->ninputs = nfiles;
    cfg->inputs = calloc(cfg->ninputs, sizeof *cfg->inputs);
    for (size_t i = 0; cfg->inputs && i < nfiles; i++) {
      input_t *in = &cfg->inputs[i];
      scf_points_t pts;
      char msg[1024];
      if (scf_points_read(files[i], &pts, msg, sizeof msg) < 0) {
        say("%s", msg);
        return 1;
      }
      in->name = files[i];
      in->surface = -1;
      in->xyz = pts.xyz;
      in->n = pts.count;
    }
  }
  if (!cfg->inputs) {
    say("out of memory");
    return 1;
  }
  return 0;
}

/* Runs the clients, one thread each, until they are done; returns how
 * many started. */
static unsigned run_workers(config_t *cfg, worker_t *w) {
  unsigned started = 0;
  for (unsigned i = 0; i < cfg->clients; i++) {
    w[i].cfg = cfg;
    w[i].index = i;
    if (cfg->jobs == UINT64_MAX)
      w[i].share = UINT64_MAX;
    else
      w[i].share = cfg->jobs / cfg->clients + (i < cfg->jobs % cfg->clients);
    if (pthread_create(&w[i].thread, NULL, run_worker, &w[i]) != 0) {
      say("cannot start thread %u: %s", i, strerror(errno));
      break;
    }
    started++;
  }
  for (unsigned i = 0; i < started; i++)
    pthread_join(w[i].thread, NULL);
  return started;
}

/* The threads' tallies, together, latencies sorted. */
static void merge_tallies(const worker_t *w, unsigned started, tally_t *all) {
  memset(all, 0, sizeof *all);
  for (unsigned i = 0; i < started; i++) {
    const tally_t *t = &w[i].t;
    all->done += t->done;
    all->points += t->points;
    all->verified += t->verified;
    all->verify_failures += t->verify_failures;
    for (size_t k = 0; k < t->nlat; k++)
      add_latency(all, t->latency_ms[k]);
    for (size_t k = 0; k < t->ncodes; k++) {
      size_t j = 0;
      while (j < all->ncodes && strcmp(all->codes[j].name, t->codes[k].name))
        j++;
      if (j == all->ncodes && all->ncodes < LOAD_MAX_CODES)
        snprintf(all->codes[all->ncodes++].name, sizeof all->codes[0].name,
                 "%s", t->codes[k].name);
      if (j < LOAD_MAX_CODES)
        all->codes[j].count += t->codes[k].count;
    }
    all->failed += t->failed;
    all->retries += t->retries;
    all->jobs_retried += t->jobs_retried;
    all->lost += t->lost;
    if (!all->first_error[0] && t->first_error[0])
      snprintf(all->first_error, sizeof all->first_error, "%s",
               t->first_error);
    for (unsigned k = 0; k < t->nshown && all->nshown < LOAD_SHOW_FAILURES;
         k++)
      snprintf(all->first_failure[all->nshown++], sizeof all->first_failure[0],
               "%s", t->first_failure[k]);
  }
  if (all->nlat)
    qsort(all->latency_ms, all->nlat, sizeof(double), cmp_double);
}

/* What a run measured, for the report. */
typedef struct summary {
  const tally_t *all;
  uint64_t points; /* per job, or 0 for files */
  size_t nfiles;
  const char *where;
  double seconds, p50, p90, p99, pmax, jobs_per_s, points_per_s;
  const sc_client_value_t *before, *after;
  size_t nbefore, nafter;
} summary_t;

static void print_daemon_counters(const summary_t *s) {
  static const char *const shown[] = {
      "jobs_accepted_total",   "jobs_refused_total",       "jobs_done_total",
      "jobs_failed_total",     "jobs_cancelled_total",     "points_in_total",
      "triangles_out_total",   "bytes_in_total",           "bytes_out_total",
      "protocol_errors_total", "slow_readers_closed_total"};
  if (!s->before || !s->after) {
    printf("daemon      counters unavailable (%s)\n",
           s->before ? "after the run" : "before the run");
    return;
  }
  printf("daemon      ");
  const char *sep = "";
  for (size_t k = 0; k < sizeof shown / sizeof shown[0]; k++) {
    const sc_client_value_t *a =
        sc_client_value_find(s->before, s->nbefore, shown[k]);
    const sc_client_value_t *b =
        sc_client_value_find(s->after, s->nafter, shown[k]);
    if (!a || !b || a->kind != SC_CLIENT_U64 || b->kind != SC_CLIENT_U64)
      continue;
    printf("%s%s +%llu", sep, shown[k], (unsigned long long)(b->v.u - a->v.u));
    sep = ", ";
  }
  printf("\n");
}

static void print_text(const config_t *cfg, const summary_t *s) {
  const tally_t *all = s->all;
  uint64_t ended = all->done + all->failed;
  printf("shortcrust-load: %u client%s, %llu job%s", cfg->clients,
         cfg->clients == 1 ? "" : "s", (unsigned long long)ended,
         ended == 1 ? "" : "s");
  if (s->points)
    printf(" of %llu points", (unsigned long long)s->points);
  else
    printf(" from %zu file%s", s->nfiles, s->nfiles == 1 ? "" : "s");
  printf(", %u in flight per client, on %s\n", cfg->in_flight, s->where);
  printf("jobs        %llu done, %llu failed, in %.2f s\n",
         (unsigned long long)all->done, (unsigned long long)all->failed,
         s->seconds);
  printf("throughput  %.2f jobs/s, %.0f points/s\n", s->jobs_per_s,
         s->points_per_s);
  printf("latency     p50 %.1f ms, p90 %.1f ms, p99 %.1f ms, max %.1f ms\n",
         s->p50, s->p90, s->p99, s->pmax);
  printf("retries     %llu, %llu job%s retried, %llu lost\n",
         (unsigned long long)all->retries,
         (unsigned long long)all->jobs_retried,
         all->jobs_retried == 1 ? "" : "s", (unsigned long long)all->lost);
  printf("errors      ");
  if (all->ncodes == 0)
    printf("none\n");
  for (size_t k = 0; k < all->ncodes; k++)
    printf("%s%s %llu%s", k ? ", " : "", all->codes[k].name,
           (unsigned long long)all->codes[k].count,
           k + 1 == all->ncodes ? "\n" : "");
  if (all->first_error[0])
    printf("            first: %s\n", all->first_error);
  if (cfg->verify) {
    printf("verify      %llu mesh%s checked, %llu failure%s\n",
           (unsigned long long)all->verified, all->verified == 1 ? "" : "es",
           (unsigned long long)all->verify_failures,
           all->verify_failures == 1 ? "" : "s");
    for (unsigned k = 0; k < all->nshown; k++)
      printf("            %s\n", all->first_failure[k]);
  }
  print_daemon_counters(s);
}

static void print_json(const config_t *cfg, const summary_t *s) {
  const tally_t *all = s->all;
  printf("{\"clients\": %u, \"jobs_in_flight\": %u, ", cfg->clients,
         cfg->in_flight);
  if (s->points)
    printf("\"points\": %llu, ", (unsigned long long)s->points);
  else
    printf("\"files\": %zu, ", s->nfiles);
  printf("\"jobs\": %llu, \"jobs_done\": %llu, \"errors\": %llu, "
         "\"errors_by_code\": {",
         (unsigned long long)(all->done + all->failed),
         (unsigned long long)all->done, (unsigned long long)all->failed);
  for (size_t k = 0; k < all->ncodes; k++) {
    printf("%s", k ? ", " : "");
    scf_json_string(stdout, all->codes[k].name);
    printf(": %llu", (unsigned long long)all->codes[k].count);
  }
  printf("}, \"retries\": %llu, \"jobs_retried\": %llu, \"jobs_lost\": %llu",
         (unsigned long long)all->retries,
         (unsigned long long)all->jobs_retried, (unsigned long long)all->lost);
  printf(", \"verify\": %s, \"verified\": %llu, \"verify_failures\": %llu, "
         "\"seconds\": %.6f, \"jobs_per_s\": %.6f, \"points_per_s\": %.3f, "
         "\"latency_p50_ms\": %.3f, \"latency_p90_ms\": %.3f, "
         "\"latency_p99_ms\": %.3f, \"latency_max_ms\": %.3f, "
         "\"daemon_before\": ",
         cfg->verify ? "true" : "false", (unsigned long long)all->verified,
         (unsigned long long)all->verify_failures, s->seconds, s->jobs_per_s,
         s->points_per_s, s->p50, s->p90, s->p99, s->pmax);
  json_values(stdout, s->before, s->nbefore);
  printf(", \"daemon_after\": ");
  json_values(stdout, s->after, s->nafter);
  printf("}\n");
}

int main(int argc, char **argv) {
  config_t cfg;
  memset(&cfg, 0, sizeof cfg);
  cfg.clients = 1;
  cfg.in_flight = 1;
  cfg.jobs = 0;
  cfg.timeout = 300;
  sc_client_params_init(&cfg.params);
  cfg.params.retries = LOAD_RETRIES;
  cfg.params.retry_backoff_ms = LOAD_RETRY_BACKOFF_MS;
  uint64_t points = 0;
  const char **files = calloc((size_t)argc + 1, sizeof *files);
  size_t nfiles = 0;
  if (!files)
    return 1;

  int status = parse_args(argc, argv, &cfg, files, &nfiles, &points);
  if (status >= 0) {
    free(files);
    return status;
  }

  /* A daemon that goes away must show as an error, not kill the run. */
  signal(SIGPIPE, SIG_IGN);
  if (load_inputs(&cfg, points, files, nfiles) != 0)
    return 1;

  char sock[256];
  const char *where = cfg.socket_path
                          ? cfg.socket_path
                          : sc_client_default_socket(sock, sizeof sock);
  size_t nbefore = 0, nafter = 0;
  sc_client_value_t *before = daemon_stats(&cfg, &nbefore);

  worker_t *w = calloc(cfg.clients, sizeof *w);
  if (!w) {
    say("out of memory");
    return 1;
  }
  double t_start = now_s();
  cfg.stop_at = cfg.duration > 0 ? t_start + cfg.duration : INFINITY;
  unsigned started = run_workers(&cfg, w);
  double seconds = now_s() - t_start;
  sc_client_value_t *after = daemon_stats(&cfg, &nafter);

  tally_t all;
  merge_tallies(w, started, &all);
  summary_t sum = {
      .all = &all,
      .points = points,
      .nfiles = nfiles,
      .where = where,
      .seconds = seconds,
      .p50 = quantile(all.latency_ms, all.nlat, 0.50),
      .p90 = quantile(all.latency_ms, all.nlat, 0.90),
      .p99 = quantile(all.latency_ms, all.nlat, 0.99),
      .pmax = all.nlat ? all.latency_ms[all.nlat - 1] : 0,
      .jobs_per_s = seconds > 0 ? (double)all.done / seconds : 0,
      .points_per_s = seconds > 0 ? (double)all.points / seconds : 0,
      .before = before,
      .after = after,
      .nbefore = nbefore,
      .nafter = nafter,
  };
  print_text(&cfg, &sum);
  if (cfg.json)
    print_json(&cfg, &sum);

  for (unsigned i = 0; i < cfg.clients; i++)
    free(w[i].t.latency_ms);
  free(w);
  free(all.latency_ms);
  free(before);
  free(after);
  for (size_t i = 0; i < cfg.ninputs; i++)
    free(cfg.inputs[i].xyz);
  free(cfg.inputs);
  free(files);
  return all.failed == 0 && all.verify_failures == 0 && started == cfg.clients
             ? 0
             : 1;
}
