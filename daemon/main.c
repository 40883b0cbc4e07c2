/*
 * shortcrustd: command line and start-up.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "daemon.h"
#include "log.h"

#include <errno.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif
#include <getopt.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef SC_VERSION
#define SC_VERSION "unknown"
#endif

/* The protocol numbers modes and stages like the core, which the daemon
 * hands them to unchanged; the two modules know nothing of each other, so
 * the daemon, which sees both, holds them to it. */
#define SCD_SAME_MODE_(name, value, str)                                       \
  _Static_assert((int)SCP_MODE_##name == (int)SC_MODE_##name, "mode " str);
SC_MODE_MAP(SCD_SAME_MODE_)
#undef SCD_SAME_MODE_
_Static_assert((int)SCP_MODE_COUNT == (int)SC_MODE_COUNT_, "the number of modes");
#define SCD_SAME_STAGE_(name, value, str, what)                                \
  _Static_assert((int)SCP_STAGE_##name == (int)SC_STAGE_##name, "stage " str);
SC_STAGE_MAP(SCD_SAME_STAGE_)
#undef SCD_SAME_STAGE_
_Static_assert((int)SCP_STAGE_COUNT == (int)SC_STAGE_COUNT, "the number of stages");

static char default_socket[4096];

static const char *socket_default(void) {
  return scp_default_socket(default_socket, sizeof default_socket);
}

static void usage(FILE *f, const scd_config_t *d) {
  fprintf(f,
          "Usage: shortcrustd [OPTION]...\n"
          "Reconstruct triangle meshes from point clouds for clients on a "
          "Unix socket,\n"
          "and on TCP with a shared token.\n"
          "\n"
          "  --socket PATH          listen on PATH (default:\n"
          "                         $XDG_RUNTIME_DIR/shortcrust.sock, else\n"
          "                         /run/shortcrust/shortcrust.sock; here\n"
          "                         %s);\n"
          "                         ignored under systemd socket "
          "activation\n"
          "  --socket-mode MODE     permissions of the socket file, in octal "
          "(default 0660)\n"
          "  --listen tcp://HOST:PORT\n"
          "                         also accept clients over TCP there "
          "(repeatable, up to\n"
          "                         %d; port 0 picks a free one, logged); "
          "needs --token-file\n"
          "  --token-file FILE      the token TCP clients must send: one "
          "line of 16 to 1024\n"
          "                         bytes in a file only its owner may "
          "read (mode 0600 or\n"
          "                         0400); Unix socket clients need none\n"
          "  --workers N            reconstruction threads (default: the "
          "number of cores,\n"
          "                         here %u)\n"
          "  --max-connections N    clients connected at once (default %u), "
          "of which at\n"
          "                         most a quarter TCP ones before their "
          "handshake\n"
          "  --max-jobs N           jobs in use at once on one connection "
          "(default %u)\n"
          "  --max-points N         points in one job (default %llu)\n"
          "  --memory-budget BYTES  memory for the points and meshes of all "
          "jobs, as\n"
          "                         estimated per point; suffixes K, M, G, T "
          "are powers of\n"
          "                         1024 (default: half of the memory or of "
          "the cgroup\n"
          "                         limit, here %llu)\n"
          "  --tile-points N        a job that announces at least N points "
          "(not watertight\n"
          "                         mode's labelling alone) gathers them all, "
          "then runs in\n"
          "                         tiles, when no other job waits, on its "
          "worker and on\n"
          "                         every worker idle then: the same mesh, "
          "sooner on scans,\n"
          "                         later on exact samples of closed surfaces "
          "(default 0:\n"
          "                         never)\n"
          "  --grace SECONDS        on SIGTERM or SIGINT, how long running "
          "jobs may take to\n"
          "                         finish (default %g)\n"
          "  --log-level LEVEL      error, warn, info or debug (default "
          "info)\n"
          "  --help                 show this help and exit\n"
          "  --version              show the version and exit\n"
          "\n"
          "Logs go to stderr. SIGTERM and SIGINT stop accepting clients, let "
          "running jobs\n"
          "finish within the grace period, end queued jobs with SHUTDOWN, "
          "remove the\n"
          "socket file and exit 0; a second signal ends the grace period at "
          "once.\n",
          socket_default(), SCD_MAX_LISTEN, d->workers, d->max_connections,
          d->max_jobs, (unsigned long long)d->max_points,
          (unsigned long long)d->memory_budget, d->grace);
}

static int bad_value(const char *opt, const char *value, const char *want) {
  fprintf(stderr, "shortcrustd: invalid %s '%s': %s\n", opt, value, want);
  return -1;
}

static int parse_u64(const char *s, uint64_t min, uint64_t max,
                     uint64_t *out) {
  if (!*s || *s == '-' || *s == '+')
    return -1;
  char *end;
  errno = 0;
  unsigned long long v = strtoull(s, &end, 10);
  if (errno || *end || v < min || v > max)
    return -1;
  *out = v;
  return 0;
}

enum {
  OPT_SOCKET = 256,
  OPT_SOCKET_MODE,
  OPT_LISTEN,
  OPT_TOKEN_FILE,
  OPT_WORKERS,
  OPT_MAX_CONNECTIONS,
  OPT_MAX_JOBS,
  OPT_MAX_POINTS,
  OPT_MEMORY_BUDGET,
  OPT_TILE_POINTS,
  OPT_GRACE,
  OPT_LOG_LEVEL,
  OPT_HELP,
  OPT_VERSION
};

/* 0: run; 1: exit 0 (help, version); -1: exit 2. */
static int parse_args(int argc, char **argv, scd_config_t *cfg) {
  static const struct option opts[] = {
      {"socket", required_argument, NULL, OPT_SOCKET},
      {"socket-mode", required_argument, NULL, OPT_SOCKET_MODE},
      {"listen", required_argument, NULL, OPT_LISTEN},
      {"token-file", required_argument, NULL, OPT_TOKEN_FILE},
      {"workers", required_argument, NULL, OPT_WORKERS},
      {"max-connections", required_argument, NULL, OPT_MAX_CONNECTIONS},
      {"max-jobs", required_argument, NULL, OPT_MAX_JOBS},
      {"max-points", required_argument, NULL, OPT_MAX_POINTS},
      {"memory-budget", required_argument, NULL, OPT_MEMORY_BUDGET},
      {"tile-points", required_argument, NULL, OPT_TILE_POINTS},
      {"grace", required_argument, NULL, OPT_GRACE},
      {"log-level", required_argument, NULL, OPT_LOG_LEVEL},
      {"help", no_argument, NULL, OPT_HELP},
      {"version", no_argument, NULL, OPT_VERSION},
      {NULL, 0, NULL, 0}};
  scd_config_t defaults = *cfg;
  int opt;
  uint64_t v;
  opterr = 0;
  while ((opt = getopt_long(argc, argv, "", opts, NULL)) != -1) {
    const char *name = optind > 0 && optind <= argc ? argv[optind - 1] : "?";
    switch (opt) {
    case OPT_SOCKET:
      if (!*optarg)
        return bad_value("--socket", optarg, "an empty path");
      cfg->socket_path = optarg;
      break;
    case OPT_SOCKET_MODE: {
      char *end;
      errno = 0;
      unsigned long m = strtoul(optarg, &end, 8);
      if (errno || *end || !*optarg || m > 0777)
        return bad_value("--socket-mode", optarg,
                         "want an octal mode such as 0660");
      cfg->socket_mode = (unsigned)m;
      break;
    }
    case OPT_LISTEN: {
      scp_address_t a;
      if (scp_address_parse(optarg, &a) != 0 || a.kind != SCP_ADDR_TCP)
        return bad_value("--listen", optarg,
                         "want tcp://HOST:PORT (the Unix socket is --socket)");
      if (cfg->nlisten == SCD_MAX_LISTEN)
        return bad_value("--listen", optarg, "too many TCP listeners");
      cfg->listen[cfg->nlisten++] = optarg;
      break;
    }
    case OPT_TOKEN_FILE:
      if (!*optarg)
        return bad_value("--token-file", optarg, "an empty path");
      cfg->token_file = optarg;
      break;
    case OPT_WORKERS:
      if (parse_u64(optarg, 1, 1024, &v))
        return bad_value("--workers", optarg, "want 1 to 1024");
      cfg->workers = (unsigned)v;
      break;
    case OPT_MAX_CONNECTIONS:
      if (parse_u64(optarg, 1, 100000, &v))
        return bad_value("--max-connections", optarg, "want 1 to 100000");
      cfg->max_connections = (unsigned)v;
      break;
    case OPT_MAX_JOBS:
      if (parse_u64(optarg, 1, 100000, &v))
        return bad_value("--max-jobs", optarg, "want 1 to 100000");
      cfg->max_jobs = (unsigned)v;
      break;
    case OPT_MAX_POINTS:
      if (parse_u64(optarg, 4, 0xFFFFFFFEu, &v))
        return bad_value("--max-points", optarg, "want 4 to 4294967294");
      cfg->max_points = v;
      break;
    case OPT_MEMORY_BUDGET:
      if (scp_bytes_parse(optarg, &cfg->memory_budget))
        return bad_value("--memory-budget", optarg,
                         "want bytes, optionally with K, M, G or T");
      break;
    case OPT_TILE_POINTS:
      if (parse_u64(optarg, 0, 0xFFFFFFFEu, &v))
        return bad_value("--tile-points", optarg, "want 0 to 4294967294");
      cfg->tile_points = v;
      break;
    case OPT_GRACE: {
      char *end;
      errno = 0;
      double g = strtod(optarg, &end);
      if (errno || *end || !*optarg || !isfinite(g) || g < 0 || g > 86400)
        return bad_value("--grace", optarg, "want 0 to 86400 seconds");
      cfg->grace = g;
      break;
    }
    case OPT_LOG_LEVEL: {
      int l = scd_log_level_from_name(optarg);
      if (l < 0)
        return bad_value("--log-level", optarg,
                         "want error, warn, info or debug");
      cfg->log_level = l;
      break;
    }
    case OPT_HELP:
      usage(stdout, &defaults);
      return 1;
    case OPT_VERSION:
      printf("shortcrustd %s (protocol version %d)\n", SC_VERSION,
             SCP_VERSION);
      return 1;
    default:
      if (optopt)
        fprintf(stderr, "shortcrustd: option %s needs a value\n", name);
      else
        fprintf(stderr, "shortcrustd: unknown option %s\n", name);
      fprintf(stderr, "Try 'shortcrustd --help'.\n");
      return -1;
    }
  }
  if (optind < argc) {
    fprintf(stderr, "shortcrustd: unexpected argument '%s'\n", argv[optind]);
    fprintf(stderr, "Try 'shortcrustd --help'.\n");
    return -1;
  }
  if (cfg->nlisten && !cfg->token_file) {
    /* Anyone who can reach the port could use the daemon otherwise. */
    fprintf(stderr,
            "shortcrustd: --listen %s needs --token-file: TCP "
            "clients must send a shared token\n",
            cfg->listen[0]);
    return -1;
  }
  if (!cfg->socket_path)
    cfg->socket_path = socket_default();
  return 0;
}

/*
 * The jobs' memory, reused from job to job and handed back when idle.
 * With glibc's defaults every large block of a job was a fresh mapping,
 * faulted in page by page, and each worker had an arena of its own whose
 * top malloc_trim() cannot shrink. Here all threads share the main heap
 * (one arena: the reconstruction allocates in large blocks, so the lock is
 * taken rarely), blocks below 32 MiB come from it and stay in it while
 * jobs run, and the idle trim (server.c) gives the whole top back. Measured
 * with shortcrustd-bench: the daemon's size after a burst 1.01-1.02x its
 * idle size (1.06-1.12x before), jobs through the daemon no slower.
 */
static void tune_allocator(void) {
#ifdef __GLIBC__
  if (mallopt(M_ARENA_MAX, 1) != 1 ||
      mallopt(M_MMAP_THRESHOLD, 32 << 20) != 1 ||
      mallopt(M_TRIM_THRESHOLD, INT_MAX) != 1)
    scd_log(SCD_LOG_WARN, "the allocator did not take the settings (a "
                          "sanitizer's does not); "
                          "jobs run with its defaults");
#endif
}

int main(int argc, char **argv) {
  scd_config_t cfg;
  scd_config_init(&cfg);
  int rc = parse_args(argc, argv, &cfg);
  if (rc != 0)
    return rc > 0 ? 0 : 2;
  scd_log_init(cfg.log_level);
  tune_allocator();
  return scd_server_run(&cfg);
}
