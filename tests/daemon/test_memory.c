/*
 * The daemon's size after a burst of jobs: once idle, it must give back
 * what the jobs took (their heap, and the pools of TBB's allocator, where
 * CGAL's k-d trees keep their nodes), within a tenth of its idle size.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <stdlib.h>

#include "daemontest.h"
#include "synth.h"

#define T_MS 300000

enum { CONNS = 4, PER_CONN = 2, JOB_POINTS = 20000 };

/* jobs[k] of n points each on as many connections, all sent before any is
 * collected, so that every worker runs one at a time; each mesh checked. */
static void burst(const char *sock, int nconn, int per_conn, double **xyz,
                  size_t n) {
  scdt_conn_t *c[CONNS];
  scdt_job_t j[CONNS][PER_CONN];
  for (int i = 0; i < nconn; i++) {
    ASSERT_MSG(scdt_open(sock, 1u << 20, &c[i]) == 0, "connect %d", i);
    for (int k = 0; k < per_conn; k++) {
      scdt_job_init(&j[i][k], (uint32_t)k + 1, xyz[i * per_conn + k], n);
      EXPECT_MSG(scdt_job_send(c[i], &j[i][k]) == 0, "send %d/%d", i, k);
    }
  }
  for (int i = 0; i < nconn; i++) {
    scdt_job_t *pj[PER_CONN];
    for (int k = 0; k < per_conn; k++)
      pj[k] = &j[i][k];
    char why[512] = "";
    EXPECT_MSG(
        scdt_collect(c[i], pj, (size_t)per_conn, T_MS, why, sizeof why) == 0,
        "collect %d: %s", i, why);
    for (int k = 0; k < per_conn; k++) {
      EXPECT_MSG(scdt_mesh_ok(SCS_SURF_TORUS, &j[i][k], why, sizeof why), "%s",
                 why);
      scdt_job_reset(&j[i][k]);
    }
    scdt_close(c[i]);
  }
}

/* The resident size once the daemon has been idle for a second. */
static uint64_t idle_rss(const scdt_daemon_t *d) {
  EXPECT_EQ(scdt_stat_wait(d->sock, "jobs_active", 0, T_MS), 0);
  scdt_sleep_ms(1000);
  return scdt_rss(d->pid);
}

int main(int argc, char **argv) {
  scdt_init(argc, argv);
  scdt_daemon_t d;
  const char *args[] = {"--workers", "2", NULL};
  ASSERT_MSG(scdt_daemon_start(&d, args) == 0, "daemon did not start");

  /* A small job on each worker first: what a daemon keeps after its first
   * jobs (thread stacks, libraries' one-time state) is not the burst's. */
  double *xyz[CONNS * PER_CONN];
  for (int k = 0; k < CONNS * PER_CONN; k++) {
    xyz[k] = scdt_sample(SCS_SURF_TORUS, JOB_POINTS, (uint64_t)k + 1);
    ASSERT_MSG(xyz[k] != NULL, "sample");
  }
  burst(d.sock, 2, 1, xyz, 2000);
  uint64_t idle = idle_rss(&d);
  ASSERT_MSG(idle > 0, "no resident size for pid %d", (int)d.pid);

  burst(d.sock, CONNS, PER_CONN, xyz, JOB_POINTS);
  uint64_t after = idle_rss(&d);
  EXPECT_MSG((double)after <= 1.1 * (double)idle,
             "resident size %.2f MiB after the burst, %.2f MiB idle before "
             "(%.3fx)",
             after / 1048576.0, idle / 1048576.0, (double)after / (double)idle);
  for (int k = 0; k < CONNS * PER_CONN; k++)
    free(xyz[k]);
  return scdt_finish();
}
