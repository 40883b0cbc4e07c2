/*
 * The subcommands of the `shortcrust` command. Each gets its own argv, with
 * argv[0] the subcommand's name, and returns an SC_EXIT_* code.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SC_CLI_COMMANDS_H
#define SC_CLI_COMMANDS_H

typedef struct sc_cli_command {
  const char *name;
  int (*run)(int argc, char **argv);
  const char *summary;
} sc_cli_command_t;

int sc_cmd_reconstruct(int argc, char **argv);
#ifdef SC_HAVE_CLIENT
int sc_cmd_submit(int argc, char **argv);
int sc_cmd_stats(int argc, char **argv);
int sc_cmd_ping(int argc, char **argv);
#endif

#endif /* SC_CLI_COMMANDS_H */
