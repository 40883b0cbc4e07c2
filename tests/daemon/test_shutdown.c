/*
 * SIGTERM and SIGINT: the daemon stops accepting, lets running jobs finish
 * within --grace, ends queued jobs with SHUTDOWN, closes every connection
 * with a fatal SHUTDOWN, removes its socket file and exits 0. A job still
 * running when the grace period ends gets SHUTDOWN too.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "daemontest.h"
#include "synth.h"

#define T_MS 120000

static int exists(const char *path) {
  struct stat st;
  return lstat(path, &st) == 0;
}

/* One worker: a job runs, another waits behind it, and a third is still
 * uploading on another connection when SIGTERM comes. */
static void running_and_queued(void) {
  scdt_daemon_t d;
  const char *args[] = {"--workers", "1", "--grace", "60", NULL};
  ASSERT_MSG(scdt_daemon_start(&d, args) == 0, "daemon did not start");
  size_t big = 15000;
  double *xyz = scdt_sample(SCS_SURF_SPHERE, big, 1);
  double *small = scdt_sample(SCS_SURF_TORUS, 3000, 2);
  scdt_conn_t *a, *b;
  ASSERT_MSG(scdt_open(d.sock, 1u << 20, &a) == 0, "a");
  ASSERT_MSG(scdt_open(d.sock, 1u << 20, &b) == 0, "b");
  scdt_job_t run, queued, uploading;
  scdt_job_init(&run, 1, xyz, big);
  scdt_job_init(&queued, 2, small, 3000);
  scdt_job_init(&uploading, 3, small, 3000);
  EXPECT_MSG(scdt_job_send(a, &run) == 0, "send");
  EXPECT_EQ(scdt_stat_wait(d.sock, "workers_busy", 1, T_MS), 1);
  /* From here on, no waiting: the signal must come while the first job
   * still runs (it takes far longer than sending the others). */
  EXPECT_MSG(scdt_job_send(a, &queued) == 0, "send");
  EXPECT_MSG(scdt_job_begin(b, &uploading) == 0 &&
                 scdt_job_points(b, &uploading, 1000) == 0,
             "send");
  scdt_frame_t *acc = scdt_recv(b, T_MS);
  EXPECT_MSG(acc && acc->type == SCP_ACCEPTED, "want ACCEPTED");
  free(acc);
  uploading.accepted = 1;

  kill(d.pid, SIGTERM);
  scdt_job_t *pa[2] = {&run, &queued}, *pb = &uploading;
  char why[512] = "";
  EXPECT_MSG(scdt_collect(a, pa, 2, T_MS, why, sizeof why) == 0, "%s", why);
  EXPECT_MSG(scdt_collect(b, &pb, 1, T_MS, why, sizeof why) == 0, "%s", why);
  EXPECT_MSG(scdt_mesh_ok(SCS_SURF_SPHERE, &run, why, sizeof why),
             "the running job must finish: %s", why);
  EXPECT_MSG(queued.error_code == SCP_WIRE_SHUTDOWN,
             "queued job: want SHUTDOWN, got %s",
             scp_wire_name(queued.error_code));
  EXPECT_MSG(uploading.error_code == SCP_WIRE_SHUTDOWN,
             "uploading job: want SHUTDOWN, got %s",
             scp_wire_name(uploading.error_code));
  printf("queued job: %s\n", queued.error_msg);
  /* Then each connection gets a fatal SHUTDOWN and is closed. */
  EXPECT_MSG(scdt_wait_closed(a, T_MS), "a not closed");
  EXPECT_MSG(a->got_error && a->last_error.code == SCP_WIRE_SHUTDOWN &&
                 (a->last_error.flags & SCP_ERROR_FATAL),
             "a: want a fatal SHUTDOWN");
  EXPECT_MSG(scdt_wait_closed(b, T_MS), "b not closed");
  EXPECT_MSG(b->got_error && b->last_error.code == SCP_WIRE_SHUTDOWN,
             "b: want SHUTDOWN");
  EXPECT_EQ(scdt_daemon_wait(&d, T_MS), 0);
  EXPECT_MSG(!exists(d.sock), "socket file %s left behind", d.sock);
  char lock[200];
  snprintf(lock, sizeof lock, "%s.lock", d.sock);
  EXPECT_MSG(!exists(lock), "lock file %s left behind", lock);
  scdt_conn_t *late;
  EXPECT_MSG(scdt_connect(d.sock, &late) != 0, "connected after shutdown");
  scdt_job_reset(&run);
  scdt_job_reset(&queued);
  scdt_job_reset(&uploading);
  scdt_close(a);
  scdt_close(b);
  free(xyz);
  free(small);
}

/* A job that cannot finish within the grace period. */
static void grace_over(void) {
  scdt_daemon_t d;
  const char *args[] = {"--workers", "1", "--grace", "0.2", NULL};
  ASSERT_MSG(scdt_daemon_start(&d, args) == 0, "daemon did not start");
  size_t big = 60000;
  double *xyz = scdt_sample_random(SCS_SURF_SPHERE, big, 3);
  scdt_conn_t *a;
  ASSERT_MSG(scdt_open(d.sock, 1u << 20, &a) == 0, "a");
  scdt_job_t run;
  scdt_job_init(&run, 1, xyz, big);
  EXPECT_MSG(scdt_job_send(a, &run) == 0, "send");
  EXPECT_EQ(scdt_stat_wait(d.sock, "workers_busy", 1, T_MS), 1);
  uint64_t t0 = scdt_now_ms();
  kill(d.pid, SIGINT);
  scdt_job_t *pa = &run;
  char why[512] = "";
  EXPECT_MSG(scdt_collect(a, &pa, 1, T_MS, why, sizeof why) == 0, "%s", why);
  EXPECT_MSG(run.error_code == SCP_WIRE_SHUTDOWN, "want SHUTDOWN, got %s",
             run.done ? "JOB_DONE" : scp_wire_name(run.error_code));
  printf("job ended %llu ms after SIGINT: %s\n",
         (unsigned long long)(scdt_now_ms() - t0), run.error_msg);
  EXPECT_MSG(scdt_wait_closed(a, T_MS), "not closed");
  EXPECT_EQ(scdt_daemon_wait(&d, T_MS), 0);
  EXPECT_MSG(!exists(d.sock), "socket file left behind");
  scdt_job_reset(&run);
  scdt_close(a);
  free(xyz);
}

/* Idle, and a connection that never said HELLO. */
static void idle(void) {
  scdt_daemon_t d;
  ASSERT_MSG(scdt_daemon_start(&d, NULL) == 0, "daemon did not start");
  scdt_conn_t *c;
  ASSERT_MSG(scdt_connect(d.sock, &c) == 0, "connect");
  EXPECT_EQ(scdt_stat_wait(d.sock, "connections", 2, T_MS), 2);
  kill(d.pid, SIGTERM);
  EXPECT_MSG(scdt_wait_closed(c, T_MS), "not closed");
  EXPECT_MSG(c->got_error && c->last_error.code == SCP_WIRE_SHUTDOWN,
             "want SHUTDOWN before the handshake");
  EXPECT_EQ(scdt_daemon_wait(&d, T_MS), 0);
  EXPECT_MSG(!exists(d.sock), "socket file left behind");
  EXPECT_MSG(scdt_log_contains(&d, "SIGTERM: shutting down"), "no log line");
  scdt_close(c);
}

int main(int argc, char **argv) {
  scdt_init(argc, argv);
  idle();
  running_and_queued();
  grace_over();
  return scdt_finish();
}
