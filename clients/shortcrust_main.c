/*
 * The `shortcrust` command: one program, one subcommand per job.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "cli_commands.h"

#ifndef SC_VERSION
#define SC_VERSION "unknown"
#endif

static const sc_cli_command_t commands[] = {
    {"reconstruct", sc_cmd_reconstruct,
     "reconstruct a mesh from a point file, here, without a daemon"},
#ifdef SC_HAVE_CLIENT
    {"submit", sc_cmd_submit,
     "the same, through the daemon (shortcrustd)"},
    {"stats", sc_cmd_stats, "the daemon's counters"},
    {"ping", sc_cmd_ping, "check that the daemon answers"},
#endif
};

static void usage(FILE *f) {
  fprintf(f, "usage: shortcrust COMMAND [OPTIONS]\n\n"
             "Surface reconstruction from unorganized 3D points by one-pass\n"
             "Delaunay filtering (the \"short crust\").\n\ncommands:\n");
  for (size_t i = 0; i < sizeof commands / sizeof commands[0]; ++i)
    fprintf(f, "  %-12s %s\n", commands[i].name, commands[i].summary);
  fprintf(f, "\n`shortcrust COMMAND --help` describes a command's options.\n"
             "  -h, --help     this text\n"
             "  -V, --version  the version\n");
}

int main(int argc, char **argv) {
  if (argc < 2) {
    usage(stderr);
    return SC_EXIT_USAGE;
  }
  const char *cmd = argv[1];
  if (strcmp(cmd, "-h") == 0 || strcmp(cmd, "--help") == 0 ||
      strcmp(cmd, "help") == 0) {
    usage(stdout);
    return SC_EXIT_OK;
  }
  if (strcmp(cmd, "-V") == 0 || strcmp(cmd, "--version") == 0) {
    printf("shortcrust %s\n", SC_VERSION);
    return SC_EXIT_OK;
  }
  for (size_t i = 0; i < sizeof commands / sizeof commands[0]; ++i)
    if (strcmp(cmd, commands[i].name) == 0)
      return commands[i].run(argc - 1, argv + 1);
  sc_cli_error("unknown command '%s' (see shortcrust --help)", cmd);
  return SC_EXIT_USAGE;
}
