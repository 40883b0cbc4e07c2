/*
 * The daemon tests' side of the harness; see daemontest.h.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "daemontest.h"

#include <string.h>

static const char *test_name;

static void on_fatal(void) { scdt_cleanup(1); }

void scdt_init(int argc, char **argv) {
  scdt_setup(argc, argv);
  const char *slash = argc > 0 ? strrchr(argv[0], '/') : NULL;
  test_name = slash ? slash + 1 : argc > 0 ? argv[0] : NULL;
  sct_on_fatal(on_fatal);
}

int scdt_finish(void) {
  scdt_cleanup(sct_failures() > 0);
  return sct_finish(test_name);
}

void scdt_run_ok(scdt_conn_t *c, uint32_t id, int surface, const double *xyz,
                 size_t n, int timeout_ms, const char *when) {
  scdt_job_t j;
  scdt_job_init(&j, id, xyz, n);
  scdt_job_t *pj = &j;
  char why[512] = "";
  EXPECT_MSG(scdt_job_send(c, &j) == 0, "%s: send", when);
  EXPECT_MSG(scdt_collect(c, &pj, 1, timeout_ms, why, sizeof why) == 0,
             "%s: %s", when, why);
  EXPECT_MSG(scdt_mesh_ok(surface, &j, why, sizeof why), "%s: %s", when, why);
  scdt_job_reset(&j);
}

void scdt_check_serving(const char *sock, int surface, const double *xyz,
                        size_t n, int timeout_ms, const char *when) {
  scdt_conn_t *c;
  int rc = scdt_open(sock, 1u << 20, &c);
  EXPECT_MSG(rc == 0, "%s: cannot connect: %d", when, rc);
  if (rc != 0)
    return;
  scdt_run_ok(c, 1, surface, xyz, n, timeout_ms, when);
  scdt_close(c);
}
