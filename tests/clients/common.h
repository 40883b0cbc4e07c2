/*
 * What the client library's tests share: a handle on the test daemon, and
 * checks of a returned mesh against the points it was made from.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SCCT_COMMON_H
#define SCCT_COMMON_H

#include <stdint.h>

#include "daemontest.h"
#include "shortcrust_client.h"
#include "synth.h"

/* Generous: sanitizer builds run the core many times slower. */
#define SCCT_WAIT_MS 300000

/* Connects to the socket with the given frame limit (0: the default);
 * stops the test when that fails. */
sc_client_t *scct_open(const char *sock, uint32_t max_frame);

/* Checks that the job is done and that its mesh is a correct
 * reconstruction of `surface` over xyz (n points): closed, manifold,
 * outward, the right components and genus, and the diagnostics agree. */
void scct_check_mesh(const char *what, int surface, const double *xyz,
                     uint64_t n, const sc_client_job_t *job);

/* The status, with the job's message when it is not the expected one. */
#define EXPECT_STATUS(job, want)                                               \
  do {                                                                         \
    int got_ = sc_client_job_status(job);                                      \
    EXPECT_MSG(got_ == (want), "status %s, expected %s: %s",                   \
               sc_client_err_name(got_), sc_client_err_name(want),             \
               sc_client_job_message(job));                                    \
  } while (0)

#endif /* SCCT_COMMON_H */
