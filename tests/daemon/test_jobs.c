/*
 * Jobs end to end: many connections at once, each with several jobs in
 * flight whose frames interleave, and every mesh checked against its own
 * points (closed manifold, outward, right genus), so that a mesh delivered
 * to the wrong job cannot pass. Half the connections use the smallest
 * frame limit, so points and meshes travel in many small chunks; jobs use
 * every mode, f32 and f64 points, with and without normals.
 *
 *   test_daemon_jobs DAEMON CONNECTIONS JOBS_PER_CONNECTION
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "daemontest.h"
#include "synth.h"

static const int surfaces[] = {SCS_SURF_SPHERE, SCS_SURF_TORUS,
                               SCS_SURF_GENUS2};
static const size_t sizes[] = {2000, 3000, 4000};

typedef struct client_arg {
  const char *sock;
  int index;
  int njobs;
} client_arg_t;

static void check_normals(const scdt_job_t *j) {
  if (!(j->flags & SCP_JOB_NORMALS))
    return;
  EXPECT_EQ(j->nnormals, j->n);
  unsigned char *used = calloc(j->n, 1);
  for (uint64_t i = 0; i < 3 * j->ntri; i++)
    used[j->tri[i]] = 1;
  uint64_t bad = 0;
  for (uint64_t i = 0; i < j->nnormals; i++) {
    const double *v = j->normals + 3 * i;
    double len = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (used[i] && fabs(len - 1) > 1e-5)
      bad++;
  }
  EXPECT_MSG(bad == 0, "job %u: %llu normals of used points are not unit",
             j->id, (unsigned long long)bad);
  free(used);
}

static void *run_client(void *p) {
  const client_arg_t *a = p;
  int nj = a->njobs;
  uint32_t max_frame = (a->index % 2) ? SCP_FRAME_MIN : (1u << 20);
  scdt_conn_t *c;
  int rc = scdt_open(a->sock, max_frame, &c);
  EXPECT_MSG(rc == 0, "client %d: open: %d", a->index, rc);
  if (rc != 0)
    return NULL;
  EXPECT_EQ(c->welcome.max_frame, max_frame);

  scdt_job_t *jobs = calloc((size_t)nj, sizeof *jobs);
  scdt_job_t **ptrs = calloc((size_t)nj, sizeof *ptrs);
  int *surf = calloc((size_t)nj, sizeof *surf);
  for (int k = 0; k < nj; k++) {
    int s = (a->index + k) % 3;
    surf[k] = surfaces[s];
    /* Distinct sizes, so a mixed-up mesh fails the index checks too. */
    size_t n = sizes[s] + (size_t)(a->index * 13 + k);
    double *xyz = scdt_sample(surf[k], n, (uint64_t)(a->index * 100 + k + 1));
    scdt_job_init(&jobs[k], (uint32_t)(1000 * k + a->index + 1), xyz, n);
    if (k % 2)
      jobs[k].flags = SCP_JOB_NORMALS | (k % 4 == 3 ? SCP_JOB_NORMALS_F64 : 0);
    if (a->index % 3 == 2)
      jobs[k].format = SCP_F32_XYZ;
    /* f32 points are what the server reconstructs; check against them. */
    if (jobs[k].format == SCP_F32_XYZ)
      for (size_t i = 0; i < 3 * n; i++)
        xyz[i] = (double)(float)xyz[i];
    jobs[k].declare = (k != 1);
    /* Every mode goes through. How well each mode does on these sample
     * sizes is the core's business (its own tests measure it): cocone
     * meshes must have the surface's topology, watertight ones must be
     * closed, and shortcrust and auto ones must be valid meshes of their
     * job's points. */
    static const uint32_t modes[] = {SCP_MODE_COCONE, SCP_MODE_COCONE,
                                     SCP_MODE_WATERTIGHT, SCP_MODE_SHORTCRUST,
                                     SCP_MODE_AUTO};
    jobs[k].mode = modes[k % 5];
    ptrs[k] = &jobs[k];
  }
  /* Every job in flight at once, their POINTS frames interleaved. */
  int ok = 1;
  for (int k = 0; k < nj && ok; k++)
    ok = scdt_job_begin(c, &jobs[k]) == 0;
  for (int more = 1; more && ok;) {
    more = 0;
    for (int k = 0; k < nj && ok; k++) {
      if (jobs[k].sent < jobs[k].n) {
        ok = scdt_job_points(c, &jobs[k], 700) == 0;
        more = 1;
      }
    }
  }
  for (int k = 0; k < nj && ok; k++)
    ok = scdt_job_end(c, &jobs[k]) == 0;
  EXPECT_MSG(ok, "client %d: sending failed", a->index);
  char why[512] = "";
  rc = scdt_collect(c, ptrs, (size_t)nj, 300000, why, sizeof why);
  EXPECT_MSG(rc == 0, "client %d: %s", a->index, why);
  for (int k = 0; k < nj; k++) {
    EXPECT_MSG(jobs[k].accepted, "job %u not accepted", jobs[k].id);
    if (jobs[k].mode == SCP_MODE_SHORTCRUST || jobs[k].mode == SCP_MODE_AUTO) {
      EXPECT_MSG(jobs[k].done && jobs[k].ntri > 0, "job %u (mode %s): %s",
                 jobs[k].id, scp_mode_name(jobs[k].mode), jobs[k].error_msg);
    } else if (jobs[k].mode == SCP_MODE_WATERTIGHT) {
      ok = scdt_mesh_closed(&jobs[k], why, sizeof why);
      EXPECT_MSG(ok, "mode watertight: %s", why);
    } else {
      ok = scdt_mesh_ok(surf[k], &jobs[k], why, sizeof why);
      EXPECT_MSG(ok, "mode %s: %s", scp_mode_name(jobs[k].mode), why);
    }
    check_normals(&jobs[k]);
    free((void *)jobs[k].xyz);
    scdt_job_reset(&jobs[k]);
  }
  scdt_close(c);
  free(jobs);
  free(ptrs);
  free(surf);
  return NULL;
}

int main(int argc, char **argv) {
  scdt_init(argc, argv);
  int nconn = argc > 2 ? atoi(argv[2]) : 4;
  int njobs = argc > 3 ? atoi(argv[3]) : 3;
  scdt_daemon_t d;
  const char *args[] = {"--workers", "2", NULL};
  ASSERT_MSG(scdt_daemon_start(&d, args) == 0, "daemon did not start");

  uint64_t t0 = scdt_now_ms();
  pthread_t *th = calloc((size_t)nconn, sizeof *th);
  client_arg_t *ca = calloc((size_t)nconn, sizeof *ca);
  for (int i = 0; i < nconn; i++) {
    ca[i] = (client_arg_t){.sock = d.sock, .index = i, .njobs = njobs};
    pthread_create(&th[i], NULL, run_client, &ca[i]);
  }
  for (int i = 0; i < nconn; i++)
    pthread_join(th[i], NULL);
  printf("%d connections x %d jobs in %.2f s\n", nconn, njobs,
         (double)(scdt_now_ms() - t0) / 1e3);

  uint64_t total = (uint64_t)nconn * (uint64_t)njobs;
  EXPECT_EQ(scdt_stat_fresh(d.sock, "jobs_done_total"), total);
  EXPECT_EQ(scdt_stat_fresh(d.sock, "jobs_failed_total"), 0);
  EXPECT_EQ(scdt_stat_wait(d.sock, "jobs_active", 0, 10000), 0);
  EXPECT_EQ(scdt_stat_wait(d.sock, "memory_jobs_bytes", 0, 10000), 0);
  EXPECT_EQ(scdt_stat_wait(d.sock, "connections", 1, 10000), 1);
  EXPECT_EQ(scdt_daemon_stop(&d), 0);
  EXPECT_EQ(scdt_log_count(&d, " done: points="), total);
  free(th);
  free(ca);
  return scdt_finish();
}
