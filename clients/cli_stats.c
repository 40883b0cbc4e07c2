/*
 * `shortcrust stats` and `shortcrust ping`: the daemon's counters, and
 * whether it answers.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "cli_commands.h"
#include "shortcrust_client.h"

/* The options that say where the daemon is, in both commands' help. */
#define CONNECT_HELP                                                           \
  "      --connect ADDR    the daemon: tcp://HOST:PORT, unix://PATH or a\n"    \
  "                        socket path (default %s)\n"                         \
  "      --socket PATH     the same as --connect unix://PATH\n"                \
  "      --token-file FILE the token of a daemon on TCP (default: the\n"       \
  "                        variable SHORTCRUST_TOKEN)\n"

/* How long the daemon has to answer. */
#define SC_CLI_ANSWER_MS 10000

enum { OPT_SOCKET = 256, OPT_CONNECT, OPT_TOKEN_FILE, OPT_JSON };

static const struct option long_options[] = {
    {"socket", required_argument, NULL, OPT_SOCKET},
    {"connect", required_argument, NULL, OPT_CONNECT},
    {"token-file", required_argument, NULL, OPT_TOKEN_FILE},
    {"json", no_argument, NULL, OPT_JSON},
    {"help", no_argument, NULL, 'h'},
    {NULL, 0, NULL, 0},
};

/* Options shared by both commands: 0 to go on, otherwise the exit code + 1
 * (help printed, or a bad command line). */
static int parse(const char *cmd, int argc, char **argv, int allow_json,
                 const char **socket_path, const char **token_file, int *json,
                 void (*usage)(FILE *f)) {
  opterr = 0;
  int c;
  while ((c = getopt_long(argc, argv, ":h", long_options, NULL)) != -1) {
    switch (c) {
    case OPT_SOCKET:
    case OPT_CONNECT:
      *socket_path = optarg;
      break;
    case OPT_TOKEN_FILE:
      *token_file = optarg;
      break;
    case OPT_JSON:
      if (!allow_json) {
        sc_cli_error("%s: unknown option '--json' (see shortcrust %s --help)",
                     cmd, cmd);
        return SC_EXIT_USAGE + 1;
      }
      *json = 1;
      break;
    case 'h':
      usage(stdout);
      return SC_EXIT_OK + 1;
    case ':':
      sc_cli_error("%s: %s needs a value", cmd, argv[optind - 1]);
      return SC_EXIT_USAGE + 1;
    default:
      sc_cli_error("%s: unknown option '%s' (see shortcrust %s --help)", cmd,
                   argv[optind - 1], cmd);
      return SC_EXIT_USAGE + 1;
    }
  }
  if (optind < argc) {
    sc_cli_error("%s: unexpected argument '%s'", cmd, argv[optind]);
    return SC_EXIT_USAGE + 1;
  }
  return 0;
}

static sc_client_t *connect_or_say(const char *socket_path,
                                   const char *token_file) {
  sc_client_options_t opts;
  sc_client_options_init(&opts);
  opts.socket_path = socket_path;
  opts.token_file = token_file;
  opts.io_timeout_ms = SC_CLI_ANSWER_MS;
  sc_client_t *c = NULL;
  char msg[1024];
  if (sc_client_connect(&opts, &c, msg, sizeof msg) < 0) {
    sc_cli_error("%s", msg);
    return NULL;
  }
  return c;
}

static void stats_usage(FILE *f) {
  char sock[256];
  fprintf(f,
          "usage: shortcrust stats [--connect ADDR | --socket PATH]\n"
          "                        [--token-file FILE] [--json]\n\n"
          "Prints the daemon's counters: connections, jobs, points, bytes,\n"
          "workers, memory. Names ending in _total only grow.\n\n"
          "options:\n" CONNECT_HELP
          "      --json            one JSON object instead of a table\n"
          "  -h, --help            this text\n\n"
          "Exit status: 0 done, 1 no answer from the daemon, 2 bad command "
          "line.\n",
          sc_client_default_socket(sock, sizeof sock));
}

static void print_value(FILE *f, const sc_client_value_t *v) {
  switch (v->kind) {
  case SC_CLIENT_U64:
    fprintf(f, "%llu", (unsigned long long)v->v.u);
    break;
  case SC_CLIENT_I64:
    fprintf(f, "%lld", (long long)v->v.i);
    break;
  case SC_CLIENT_F64:
    fprintf(f, "%.17g", v->v.f);
    break;
  default:
    fprintf(f, "null");
  }
}

int sc_cmd_stats(int argc, char **argv) {
  const char *socket_path = NULL, *token_file = NULL;
  int json = 0;
  int rc = parse("stats", argc, argv, 1, &socket_path, &token_file, &json,
                 stats_usage);
  if (rc)
    return rc - 1;
  sc_client_t *c = connect_or_say(socket_path, token_file);
  if (!c)
    return SC_EXIT_FAILURE;
  sc_client_value_t *v = NULL;
  size_t n = 0;
  rc = sc_client_stats(c, SC_CLI_ANSWER_MS, &v, &n);
  if (rc < 0) {
    sc_cli_error("stats: %s", sc_client_last_error(c));
    sc_client_free(c);
    return SC_EXIT_FAILURE;
  }
  sc_client_info_t info;
  sc_client_get_info(c, &info);
  if (json) {
    /* Names are lower-case letters, digits, '_' and '.' (PROTOCOL.md
     * 6.11), so they need no escaping. */
    printf("{\"socket\": \"");
    for (const char *p = info.socket_path; *p; ++p) {
      if (*p == '"' || *p == '\\')
        putchar('\\');
      if ((unsigned char)*p < 0x20)
        printf("\\u%04x", (unsigned char)*p);
      else
        putchar(*p);
    }
    printf("\"");
    for (size_t i = 0; i < n; i++) {
      printf(", \"%s\": ", v[i].name);
      print_value(stdout, &v[i]);
    }
    printf("}\n");
  } else {
    printf("daemon on %s: protocol %u%s, at most %u jobs per connection "
           "and %llu points per job\n",
           info.socket_path, info.version,
           info.job_options ? " with job options" : "", info.max_jobs,
           (unsigned long long)info.max_points);
    for (size_t i = 0; i < n; i++) {
      printf("  %-28s ", v[i].name);
      print_value(stdout, &v[i]);
      putchar('\n');
    }
  }
  free(v);
  sc_client_free(c);
  return SC_EXIT_OK;
}

static void ping_usage(FILE *f) {
  char sock[256];
  fprintf(f,
          "usage: shortcrust ping [--connect ADDR | --socket PATH] "
          "[--token-file FILE]\n\n"
          "Checks that the daemon answers, and prints the round trip.\n\n"
          "options:\n" CONNECT_HELP "  -h, --help            this text\n\n"
          "Exit status: 0 the daemon answered, 1 it did not (the message "
          "says why),\n2 bad command line.\n",
          sc_client_default_socket(sock, sizeof sock));
}

int sc_cmd_ping(int argc, char **argv) {
  const char *socket_path = NULL, *token_file = NULL;
  int json = 0;
  int rc = parse("ping", argc, argv, 0, &socket_path, &token_file, &json,
                 ping_usage);
  if (rc)
    return rc - 1;
  sc_client_t *c = connect_or_say(socket_path, token_file);
  if (!c)
    return SC_EXIT_FAILURE;
  double rtt = 0;
  rc = sc_client_ping(c, SC_CLI_ANSWER_MS, &rtt);
  if (rc < 0) {
    sc_cli_error("ping: %s", sc_client_last_error(c));
    sc_client_free(c);
    return SC_EXIT_FAILURE;
  }
  sc_client_info_t info;
  sc_client_get_info(c, &info);
  printf("%s: daemon alive, protocol %u%s, round trip %.3f ms\n",
         info.socket_path, info.version,
         info.job_options ? " with job options" : "", rtt * 1e3);
  sc_client_free(c);
  return SC_EXIT_OK;
}
