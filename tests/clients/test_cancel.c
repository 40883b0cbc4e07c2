/*
 * Cancelling jobs through the client library: while the daemon works, from
 * the progress callback during the upload, from the chunk callback during
 * the download, and by freeing a job still under way. Each time the job
 * ends as cancelled, the connection goes on serving, and the daemon lets
 * go of everything the job held.
 *
 *   test_clients_cancel DAEMON
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <stdlib.h>
#include <string.h>

#include "common.h"

static scdt_daemon_t d;

/* A sample that takes the daemon a while: random points are quick to make
 * and slow to reconstruct. */
static double *big_sample(uint64_t n) {
  double *xyz = malloc((size_t)n * 3 * sizeof(double));
  ASSERT_MSG(xyz &&
                 scs_sample_surface(SCS_SURF_SPHERE, SCS_DENSITY_UNIFORM_RANDOM,
                                    (size_t)n, 77, xyz) == SCS_OK,
             "sample");
  return xyz;
}

/* A small job must still come out right on the same connection. */
static void check_serving(sc_client_t *c, const char *when) {
  const uint64_t n = 2000;
  double *xyz = scdt_sample(SCS_SURF_SPHERE, n, 3);
  sc_client_job_t *j;
  int rc = sc_client_submit(c, NULL, xyz, n, &j);
  EXPECT_MSG(rc == 0, "%s: submit: %s", when, sc_client_last_error(c));
  if (rc == 0) {
    EXPECT_EQ(sc_client_wait(c, j, SCCT_WAIT_MS), 0);
    scct_check_mesh(when, SCS_SURF_SPHERE, xyz, n, j);
    sc_client_job_free(j);
  }
  free(xyz);
}

static void check_idle(const char *when) {
  uint64_t jobs = scdt_stat_wait(d.sock, "jobs_active", 0, SCCT_WAIT_MS);
  uint64_t mem = scdt_stat_wait(d.sock, "memory_jobs_bytes", 0, SCCT_WAIT_MS);
  EXPECT_MSG(jobs == 0 && mem == 0,
             "%s: jobs_active %llu, memory_jobs_bytes %llu", when,
             (unsigned long long)jobs, (unsigned long long)mem);
}

static void while_working(void) {
  const uint64_t n = 60000;
  double *xyz = big_sample(n);
  sc_client_t *c = scct_open(d.sock, 0);
  sc_client_job_t *j;
  ASSERT_MSG(sc_client_submit(c, NULL, xyz, n, &j) == 0, "submit: %s",
             sc_client_last_error(c));
  EXPECT_EQ(sc_client_cancel(c, j), 0);
  /* Whether the CANCEL met the job running or crossed its end, the job
   * ends as cancelled and its mesh is not kept. Here it met it: the job
   * takes seconds, and the daemon says it stopped it. */
  EXPECT_EQ(sc_client_wait(c, j, SCCT_WAIT_MS), SC_CLIENT_ECANCELLED);
  EXPECT_STATUS(j, SC_CLIENT_ECANCELLED);
  EXPECT_EQ(sc_client_job_server_code(j), 12 /* CANCELLED */);
  sc_client_mesh_t m;
  EXPECT_EQ(sc_client_job_mesh(j, &m), SC_CLIENT_ECANCELLED);
  EXPECT_MSG(m.triangles == NULL, "a cancelled job has a mesh");
  /* Cancelling an ended job changes nothing. */
  EXPECT_EQ(sc_client_cancel(c, j), 0);
  EXPECT_STATUS(j, SC_CLIENT_ECANCELLED);
  EXPECT_EQ(sc_client_jobs_in_use(c), 0);
  sc_client_job_free(j);
  check_serving(c, "after a cancel while working");
  sc_client_free(c);
  free(xyz);
  check_idle("cancel while working");
}

static int stop_upload(void *user, sc_client_job_t *job, uint32_t stage,
                       double fraction) {
  unsigned *calls = user;
  ++*calls;
  return stage == SC_CLIENT_STAGE_UPLOAD;
}

static void during_upload(void) {
  const uint64_t n = 60000;
  double *xyz = big_sample(n);
  /* Small frames: the upload takes many chunks, and stops after the
   * first. */
  sc_client_t *c = scct_open(d.sock, 4096);
  uint64_t before = scdt_stat_fresh(d.sock, "points_in_total");
  unsigned calls = 0;
  sc_client_params_t p;
  sc_client_params_init(&p);
  p.progress = stop_upload;
  p.progress_user = &calls;
  sc_client_job_t *j;
  ASSERT_MSG(sc_client_submit(c, &p, xyz, n, &j) == 0, "submit: %s",
             sc_client_last_error(c));
  EXPECT_EQ(calls, 1);
  EXPECT_EQ(sc_client_wait(c, j, SCCT_WAIT_MS), SC_CLIENT_ECANCELLED);
  EXPECT_EQ(calls, 1);
  sc_client_job_free(j);
  /* The daemon saw a fraction of the points. */
  sc_client_value_t *v;
  size_t nv;
  EXPECT_EQ(sc_client_stats(c, SCCT_WAIT_MS, &v, &nv), 0);
  double got =
      sc_client_value_get(v, nv, "points_in_total", 0) - (double)before;
  EXPECT_MSG(got < (double)n, "%g points came: the whole upload went out", got);
  free(v);
  check_serving(c, "after a cancel during the upload");
  sc_client_free(c);
  free(xyz);
  check_idle("cancel during the upload");
}

static int stop_download(void *user, sc_client_job_t *job, int array,
                         uint64_t first, uint32_t count, const void *data) {
  unsigned *calls = user;
  ++*calls;
  return 1;
}

static void during_download(void) {
  const uint64_t n = 20000;
  double *xyz = scdt_sample(SCS_SURF_TORUS, n, 8);
  sc_client_t *c = scct_open(d.sock, 4096);
  unsigned calls = 0;
  sc_client_params_t p;
  sc_client_params_init(&p);
  p.chunk = stop_download;
  p.chunk_user = &calls;
  sc_client_job_t *j;
  ASSERT_MSG(sc_client_submit(c, &p, xyz, n, &j) == 0, "submit: %s",
             sc_client_last_error(c));
  EXPECT_EQ(sc_client_wait(c, j, SCCT_WAIT_MS), SC_CLIENT_ECANCELLED);
  /* Nothing more reaches the callback once it said stop. */
  EXPECT_EQ(calls, 1);
  sc_client_job_free(j);
  check_serving(c, "after a cancel during the download");
  sc_client_free(c);
  free(xyz);
  check_idle("cancel during the download");
}

static void by_freeing(void) {
  const uint64_t n = 60000;
  double *xyz = big_sample(n);
  sc_client_t *c = scct_open(d.sock, 0);
  sc_client_job_t *j;
  ASSERT_MSG(sc_client_submit(c, NULL, xyz, n, &j) == 0, "submit: %s",
             sc_client_last_error(c));
  uint64_t cancelled = scdt_stat_fresh(d.sock, "jobs_cancelled_total");
  sc_client_job_free(j);
  /* The handle follows the freed job to its end by itself. */
  EXPECT_EQ(sc_client_jobs_in_use(c), 1);
  check_serving(c, "after freeing a running job");
  sc_client_job_t *e = NULL;
  int rc = sc_client_wait_any(c, SCCT_WAIT_MS, &e);
  EXPECT_MSG(rc == SC_CLIENT_ESTATE && e == NULL,
             "wait_any after the freed job ended: %s", sc_client_err_name(rc));
  EXPECT_EQ(sc_client_jobs_in_use(c), 0);
  /* The daemon stopped it rather than finish it. */
  EXPECT_EQ(scdt_stat_fresh(d.sock, "jobs_cancelled_total"), cancelled + 1);
  sc_client_free(c);
  free(xyz);
  check_idle("freeing a running job");

  /* Closing the handle with a job under way cancels it on the daemon. */
  c = scct_open(d.sock, 0);
  ASSERT_MSG(sc_client_submit(c, NULL, xyz = big_sample(n), n, &j) == 0,
             "submit: %s", sc_client_last_error(c));
  sc_client_free(c);
  free(xyz);
  check_idle("closing with a job under way");
}

int main(int argc, char **argv) {
  scdt_init(argc, argv);
  const char *args[] = {"--workers", "2", NULL};
  ASSERT_MSG(scdt_daemon_start(&d, args) == 0, "daemon did not start");
  while_working();
  during_upload();
  during_download();
  by_freeing();
  EXPECT_EQ(scdt_daemon_stop(&d), 0);
  return scdt_finish();
}
