/*
 * CANCEL, and clients that go away: during the upload, while the job
 * runs, and in the middle of the download. Each time the daemon must stop
 * the job, free everything it held, and go on serving.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <stdlib.h>
#include <string.h>

#include "daemontest.h"
#include "synth.h"

#define T_MS 120000

static scdt_daemon_t d;

/* Waits until the daemon holds no job and no memory for one. */
static void check_idle(const char *when) {
  uint64_t jobs = scdt_stat_wait(d.sock, "jobs_active", 0, T_MS);
  uint64_t mem = scdt_stat_wait(d.sock, "memory_jobs_bytes", 0, T_MS);
  uint64_t busy = scdt_stat_wait(d.sock, "workers_busy", 0, T_MS);
  EXPECT_MSG(jobs == 0 && mem == 0 && busy == 0,
             "%s: jobs_active %llu, memory_jobs_bytes %llu, workers_busy %llu",
             when, (unsigned long long)jobs, (unsigned long long)mem,
             (unsigned long long)busy);
}

/* A job must still come out right on a fresh connection. */
static void check_serving(const char *when) {
  double *xyz = scdt_sample(SCS_SURF_SPHERE, 2000, 99);
  ASSERT_MSG(xyz != NULL, "%s: sample", when);
  scdt_check_serving(d.sock, SCS_SURF_SPHERE, xyz, 2000, T_MS, when);
  free(xyz);
}

static void cancel_during_upload(void) {
  scdt_conn_t *c;
  ASSERT_MSG(scdt_open(d.sock, 1u << 20, &c) == 0, "connect");
  double *xyz = scdt_sample(SCS_SURF_TORUS, 3000, 3);
  scdt_job_t j;
  scdt_job_init(&j, 7, xyz, 3000);
  scdt_job_t *pj = &j;
  char why[512] = "";
  EXPECT_MSG(scdt_job_begin(c, &j) == 0 && scdt_job_points(c, &j, 1000) == 0,
             "send");
  EXPECT_MSG(scdt_job_cancel(c, &j) == 0, "cancel");
  EXPECT_MSG(scdt_collect(c, &pj, 1, T_MS, why, sizeof why) == 0, "%s", why);
  EXPECT_MSG(j.accepted, "not accepted");
  EXPECT_EQ(j.error_code, SCP_WIRE_CANCELLED);
  /* The id is free again at once: the same id runs a whole job. */
  scdt_job_reset(&j);
  EXPECT_MSG(scdt_job_send(c, &j) == 0, "resend");
  EXPECT_MSG(scdt_collect(c, &pj, 1, T_MS, why, sizeof why) == 0, "%s", why);
  EXPECT_MSG(scdt_mesh_ok(SCS_SURF_TORUS, &j, why, sizeof why), "%s", why);
  scdt_job_reset(&j);
  /* CANCEL for an id not in use is not an error: the PING's PONG is the
   * next frame. */
  scp_enc_cancel(&c->out, 12345);
  scp_enc_ping(&c->out, 77);
  EXPECT_MSG(scdt_flush(c, T_MS) == 0, "flush");
  scdt_frame_t *f = scdt_recv(c, T_MS);
  EXPECT_MSG(f && f->type == SCP_PONG, "expected PONG, got %s",
             f ? scp_type_name(f->type) : "nothing");
  free(f);
  scdt_close(c);
  free(xyz);
  check_idle("cancel during upload");
}

static void cancel_while_running(void) {
  scdt_conn_t *c;
  ASSERT_MSG(scdt_open(d.sock, 1u << 20, &c) == 0, "connect");
  size_t n = 40000;
  double *xyz = scdt_sample_random(SCS_SURF_SPHERE, n, 4);
  scdt_job_t j;
  scdt_job_init(&j, 8, xyz, n);
  scdt_job_t *pj = &j;
  char why[512] = "";
  EXPECT_MSG(scdt_job_send(c, &j) == 0, "send");
  /* Wait until a worker has the job, then cancel it. */
  uint64_t busy = scdt_stat_wait(d.sock, "workers_busy", 1, T_MS);
  EXPECT_EQ(busy, 1);
  uint64_t t0 = scdt_now_ms();
  EXPECT_MSG(scdt_job_cancel(c, &j) == 0, "cancel");
  EXPECT_MSG(scdt_collect(c, &pj, 1, T_MS, why, sizeof why) == 0, "%s", why);
  EXPECT_EQ(j.error_code, SCP_WIRE_CANCELLED);
  /* The worker lets go within a stage boundary or chunk, not after the
   * whole reconstruction. */
  EXPECT_EQ(scdt_stat_wait(d.sock, "workers_busy", 0, T_MS), 0);
  printf("cancel of a running %zu-point job: worker free after %llu ms\n", n,
         (unsigned long long)(scdt_now_ms() - t0));
  scdt_job_reset(&j);
  scdt_close(c);
  free(xyz);
  check_idle("cancel while running");
}

static void disconnect_during_upload(void) {
  scdt_conn_t *c;
  ASSERT_MSG(scdt_open(d.sock, SCP_FRAME_MIN, &c) == 0, "connect");
  double *xyz = scdt_sample(SCS_SURF_SPHERE, 3000, 5);
  scdt_job_t a, b;
  scdt_job_init(&a, 1, xyz, 3000);
  scdt_job_init(&b, 2, xyz, 3000);
  b.declare = 0;
  EXPECT_MSG(scdt_job_begin(c, &a) == 0 && scdt_job_points(c, &a, 1500) == 0,
             "send a");
  EXPECT_MSG(scdt_job_begin(c, &b) == 0 && scdt_job_points(c, &b, 100) == 0,
             "send b");
  /* Both ACCEPTED frames in hand first: with nothing left for the daemon
   * to write, the close it sees is the read side's, inside a frame, and not
   * a write to a socket already gone. */
  for (int k = 0; k < 2; k++) {
    scdt_frame_t *f = scdt_recv(c, T_MS);
    EXPECT_MSG(f && f->type == SCP_ACCEPTED, "expected ACCEPTED, got %s",
               f ? scp_type_name(f->type) : "nothing");
    free(f);
  }
  /* Half a frame, then gone. */
  scp_buf_t raw;
  scp_buf_init(&raw, SCP_FRAME_MIN);
  scp_enc_points(&raw, 1, 1500, SCP_F64_XYZ, xyz + 4500, 100);
  scdt_send_raw(c, raw.data, raw.len / 2, T_MS);
  scp_buf_free(&raw);
  scdt_close(c);
  free(xyz);
  check_idle("disconnect during upload");
}

static void disconnect_while_running(void) {
  scdt_conn_t *c;
  ASSERT_MSG(scdt_open(d.sock, 1u << 20, &c) == 0, "connect");
  size_t n = 40000;
  double *xyz = scdt_sample_random(SCS_SURF_SPHERE, n, 6);
  scdt_job_t j;
  scdt_job_init(&j, 9, xyz, n);
  EXPECT_MSG(scdt_job_send(c, &j) == 0, "send");
  EXPECT_EQ(scdt_stat_wait(d.sock, "workers_busy", 1, T_MS), 1);
  scdt_close(c);
  free(xyz);
  check_idle("disconnect while running");
}

static void disconnect_during_download(void) {
  scdt_conn_t *c;
  ASSERT_MSG(scdt_open(d.sock, SCP_FRAME_MIN, &c) == 0, "connect");
  double *xyz = scdt_sample(SCS_SURF_GENUS2, 4000, 7);
  scdt_job_t j;
  scdt_job_init(&j, 10, xyz, 4000);
  j.flags = SCP_JOB_NORMALS | SCP_JOB_NORMALS_F64;
  EXPECT_MSG(scdt_job_send(c, &j) == 0, "send");
  /* Take a few chunks of the mesh, then leave. */
  int chunks = 0;
  while (chunks < 5) {
    scdt_frame_t *f = scdt_recv(c, T_MS);
    if (!f)
      break;
    chunks += f->type == SCP_TRIANGLES;
    free(f);
  }
  EXPECT_EQ(chunks, 5);
  scdt_close(c);
  free(xyz);
  check_idle("disconnect during download");
}

int main(int argc, char **argv) {
  scdt_init(argc, argv);
  const char *args[] = {"--workers", "2", NULL};
  ASSERT_MSG(scdt_daemon_start(&d, args) == 0, "daemon did not start");

  cancel_during_upload();
  check_serving("after cancel during upload");
  cancel_while_running();
  check_serving("after cancel while running");
  disconnect_during_upload();
  check_serving("after disconnect during upload");
  disconnect_while_running();
  check_serving("after disconnect while running");
  disconnect_during_download();
  check_serving("after disconnect during download");

  EXPECT_EQ(scdt_stat_fresh(d.sock, "jobs_cancelled_total"), 5);
  EXPECT_EQ(scdt_stat_wait(d.sock, "connections", 1, T_MS), 1);
  EXPECT_EQ(scdt_daemon_stop(&d), 0);
  EXPECT_MSG(
      scdt_log_contains(&d, "closed (closed by the client inside a frame)"),
      "no log line for the truncated frame");
  return scdt_finish();
}
