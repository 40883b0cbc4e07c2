/*
 * Running the real daemon for a test: each test starts shortcrustd on a
 * private socket in a fresh temporary directory, with its stderr in a log
 * file there, and stops it with SIGTERM (checking the exit status) at the
 * end. Plus point samples and the mesh check every result goes through.
 *
 * Nothing here checks or counts: the benchmark uses it too. The tests'
 * side (recording failures, stopping on a fatal one) is daemontest.h.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SCDT_HARNESS_H
#define SCDT_HARNESS_H

#include <stdint.h>
#include <stdio.h>
#include <sys/types.h>

#include "client.h"

typedef struct scdt_daemon {
  pid_t pid;
  char dir[128];
  char sock[160];
  char log[160];
  int status; /* exit code once it has exited, or 128 + signal */
  int slot;   /* the harness's own record of it, for scdt_finish() */
} scdt_daemon_t;

/* argv[1] is the daemon binary. Also ignores SIGPIPE. */
void scdt_setup(int argc, char **argv);
const char *scdt_daemon_binary(void);
/* Kills the daemons still running and removes every daemon's directory,
 * printing their logs first when show_logs is set (or SCDT_SHOW_LOGS is
 * in the environment). */
void scdt_cleanup(int show_logs);

/* A new private directory; fills d->dir, d->sock ("DIR/d.sock") and d->log
 * without starting anything. */
int scdt_daemon_prepare(scdt_daemon_t *d);
/* Starts the daemon with --socket d->sock --log-level debug and the extra
 * arguments (NULL-terminated, may be NULL); stderr goes to d->log. With
 * wait_ready, returns once the socket accepts connections (-1 if the
 * daemon exited first or took too long). */
int scdt_daemon_spawn(scdt_daemon_t *d, const char *const *args,
                      int wait_ready);
/* prepare + spawn(wait_ready). */
int scdt_daemon_start(scdt_daemon_t *d, const char *const *args);
/* Waits for the process: its exit status as in d->status, or -1 after
 * timeout_ms (the process then still runs). */
int scdt_daemon_wait(scdt_daemon_t *d, int timeout_ms);
/* SIGTERM and wait up to a minute; the exit status, or -1. */
int scdt_daemon_stop(scdt_daemon_t *d);
/* 1 when the log contains the text. */
int scdt_log_contains(const scdt_daemon_t *d, const char *text);
/* Waits up to timeout_ms for the text to appear in the log: 1 when it
 * did. */
int scdt_log_wait(const scdt_daemon_t *d, const char *text, int timeout_ms);
/* Counts lines of the log containing the text. */
int scdt_log_count(const scdt_daemon_t *d, const char *text);
/* Waits up to timeout_ms for the log to name the daemon's TCP listener
 * ("listening on tcp://...", where port 0 was given) and copies that
 * address into out: 1 when it did, else 0 (out then empty). */
int scdt_log_tcp_address(const scdt_daemon_t *d, int timeout_ms, char *out,
                         size_t len);
/* Writes text to path, then gives it the mode: 0, or -1. */
int scdt_write_file(const char *path, const char *text, mode_t mode);

/* Well-spaced samples of a test surface (scs_surface_t), malloc'd. */
double *scdt_sample(int surface, size_t n, uint64_t seed);
/* Independent uniform samples: much quicker to make, for jobs that are
 * meant to be stopped rather than checked. */
double *scdt_sample_random(int surface, size_t n, uint64_t seed);
/* 1 when job j came back as a correct mesh of `surface` over its own points
 * (closed manifold, oriented, right components and genus); otherwise 0
 * with the reason in why. */
int scdt_mesh_ok(int surface, const scdt_job_t *j, char *why, size_t len);

/* 1 when job j came back as a closed, oriented 2-manifold over its own
 * points, whatever its genus; otherwise 0 with the reason in why. */
int scdt_mesh_closed(const scdt_job_t *j, char *why, size_t len);

/* A STATS value read on a fresh connection; UINT64_MAX when that fails. */
uint64_t scdt_stat_fresh(const char *sock, const char *name);
/* Polls scdt_stat_fresh() until the value equals want or timeout_ms pass;
 * returns the last value read. */
uint64_t scdt_stat_wait(const char *sock, const char *name, uint64_t want,
                        int timeout_ms);

/* Resident size of a process, bytes (VmRSS); 0 when unknown. */
uint64_t scdt_rss(pid_t pid);

/* A one-shot sleep. */
void scdt_sleep_ms(unsigned ms);

#endif /* SCDT_HARNESS_H */
