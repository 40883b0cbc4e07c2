/*
 * shortcrustd-bench's shared pieces: medians, clocks, a process's memory
 * and CPU, and the measurements of whole commands (bench_cmd.c).
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SCDT_BENCH_H
#define SCDT_BENCH_H

#include <stddef.h>
#include <stdint.h>
#include <sys/types.h>

#include "harness.h"

#define BENCH_T_MS 600000

/* Sorts v. */
double bench_median(double *v, int n);
/* Seconds from a monotonic clock. */
double bench_seconds(void);
/* CPU seconds a process has used (user and system); 0 when unknown. */
double bench_cpu_of(pid_t pid);
/* CPU seconds this process has used. */
double bench_cpu_self(void);
/* Starts a daemon with that many workers, logging warnings only. */
int bench_start(scdt_daemon_t *d, unsigned workers);

/* `shortcrust submit` to a one-worker daemon against `shortcrust
 * reconstruct` of the same file, alternated, as whole processes. These two
 * return 1 when a run failed or the meshes differ, else 0. */
int bench_round_trip(const char *shortcrust, size_t n, int repeat);
/* An upload paced over upload_s seconds, then JOB_END: the time to
 * JOB_DONE against `shortcrust reconstruct` of the same points, in random
 * and in scan order. */
int bench_streaming(const char *shortcrust, size_t n, double upload_s,
                    int repeat);

#endif
