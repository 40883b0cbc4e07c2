/*
 * The daemon tests' side of the harness: harness.h (starting daemons,
 * samples, mesh checks) plus the assertions of sct_assert.h, wired so that
 * a failed ASSERT_ stops every daemon and prints their logs before the
 * test exits, and the checks every test repeats.
 *
 *   int main(int argc, char **argv) {
 *     scdt_init(argc, argv);
 *     ...EXPECT_*, ASSERT_*...
 *     return scdt_finish();
 *   }
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SCDT_DAEMONTEST_H
#define SCDT_DAEMONTEST_H

#include "harness.h"
#include "sct_assert.h"

/* scdt_setup(), and a failed ASSERT_ now cleans up as scdt_finish() does
 * before the exit. */
void scdt_init(int argc, char **argv);
/* Stops the daemons and removes their directories, printing their logs
 * when a check failed; returns the exit status (sct_finish()). */
int scdt_finish(void);

/* Runs the n points as job `id` on c and checks, recording any failure,
 * that a correct mesh of `surface` comes back; `when` heads the messages. */
void scdt_run_ok(scdt_conn_t *c, uint32_t id, int surface, const double *xyz,
                 size_t n, int timeout_ms, const char *when);
/* The same on a fresh connection to sock: the daemon still serves. */
void scdt_check_serving(const char *sock, int surface, const double *xyz,
                        size_t n, int timeout_ms, const char *when);

#endif /* SCDT_DAEMONTEST_H */
