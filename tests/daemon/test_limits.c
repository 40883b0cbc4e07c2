/*
 * Every limit gives its error, and the daemon keeps serving the others:
 * connections, jobs per connection, points per job, the memory budget, and
 * the frame size agreed in the handshake.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <stdlib.h>
#include <string.h>

#include "daemontest.h"
#include "synth.h"

#define T_MS 120000

/* 8 MiB: one job of 4000 points (about 5.4 MB estimated) fits, two do
 * not. */
#define BUDGET "8M"

static scdt_daemon_t d;
static double *sphere;   /* 4000 points */

static void run_ok(scdt_conn_t *c, uint32_t id, const char *when) {
  scdt_run_ok(c, id, SCS_SURF_SPHERE, sphere, 4000, T_MS, when);
}

static void check_serving(const char *when) {
  scdt_check_serving(d.sock, SCS_SURF_SPHERE, sphere, 4000, T_MS, when);
}

/* Collects one job that must fail with the code; `other`, when not NULL,
 * is another job in use on the connection. */
static void expect_job_error2(scdt_conn_t *c, scdt_job_t *j,
                              scdt_job_t *other, uint32_t code,
                              const char *text) {
  char why[512] = "";
  scdt_job_t *js[2] = {j, other};
  EXPECT_MSG(
      scdt_collect_some(c, js, other ? 2 : 1, 1, T_MS, why, sizeof why) == 0,
      "%s", why);
  EXPECT_MSG(j->error_code == code, "job %u: got %s (%s), want %s", j->id,
             scp_wire_name(j->error_code), j->error_msg, scp_wire_name(code));
  EXPECT_MSG(strstr(j->error_msg, text) != NULL,
             "job %u: message '%s' lacks '%s'", j->id, j->error_msg, text);
  printf("job %u: %s: %s\n", j->id, scp_wire_name(j->error_code),
         j->error_msg);
}

static void expect_job_error(scdt_conn_t *c, scdt_job_t *j, uint32_t code,
                             const char *text) {
  expect_job_error2(c, j, NULL, code, text);
}

static void connections(void) {
  scdt_conn_t *a, *b, *c;
  /* Only the connection asking. */
  EXPECT_EQ(scdt_stat_wait(d.sock, "connections", 1, T_MS), 1);
  ASSERT_MSG(scdt_open(d.sock, SCP_FRAME_MIN, &a) == 0, "a");
  ASSERT_MSG(scdt_open(d.sock, SCP_FRAME_MIN, &b) == 0, "b");
  ASSERT_MSG(scdt_connect(d.sock, &c) == 0, "c");
  int rc = scdt_handshake(c, SCP_FRAME_MIN);
  EXPECT_EQ(rc, SCP_WIRE_BUSY);
  EXPECT_MSG(c->got_error && (c->last_error.flags & SCP_ERROR_FATAL),
             "not a fatal ERROR");
  printf("third connection: %s\n", c->last_error.message);
  EXPECT_MSG(scdt_wait_closed(c, T_MS), "not closed");
  scdt_close(c);
  /* The two still work. */
  run_ok(a, 1, "first connection at the limit");
  uint64_t v = 0;
  EXPECT_MSG(scdt_stat(b, "connections_refused_total", &v) == 0 && v == 1,
             "connections_refused_total %llu", (unsigned long long)v);
  scdt_close(b);
  /* A freed slot is usable again. */
  EXPECT_EQ(scdt_stat_wait(d.sock, "connections", 2, T_MS), 2);
  scdt_close(a);
}

static void jobs(void) {
  scdt_conn_t *c;
  ASSERT_MSG(scdt_open(d.sock, SCP_FRAME_MIN, &c) == 0, "connect");
  EXPECT_EQ(c->welcome.max_jobs, 2);
  scdt_job_t j1, j2, j3;
  scdt_job_init(&j1, 1, sphere, 100);
  scdt_job_init(&j2, 2, sphere, 100);
  scdt_job_init(&j3, 3, sphere, 100);
  EXPECT_MSG(scdt_job_begin(c, &j1) == 0 && scdt_job_begin(c, &j2) == 0 &&
                 scdt_job_begin(c, &j3) == 0,
             "send");
  EXPECT_MSG(scdt_wait_closed(c, T_MS), "not closed after too many jobs");
  EXPECT_MSG(c->got_error && c->last_error.code == SCP_WIRE_LIMIT &&
                 (c->last_error.flags & SCP_ERROR_FATAL),
             "want a fatal LIMIT, got %s", scp_wire_name(c->last_error.code));
  printf("third job: %s\n", c->last_error.message);
  scdt_close(c);

  /* An invalid JOB_BEGIN beyond the limit is judged by the limit too. */
  ASSERT_MSG(scdt_open(d.sock, SCP_FRAME_MIN, &c) == 0, "connect");
  scdt_job_reset(&j1);
  scdt_job_reset(&j2);
  EXPECT_MSG(scdt_job_begin(c, &j1) == 0 && scdt_job_begin(c, &j2) == 0, "send");
  scp_buf_t b;
  scp_buf_init(&b, SCP_FRAME_MIN);
  scp_job_begin_t bad = {.job_id = 3, .mode = 1, .r = 0.25};
  EXPECT_MSG(scp_enc_job_begin(&b, &bad) == 0, "encode");
  b.data[8 + 8 + 6] = 0xf0; /* r = 1.0 */
  EXPECT_MSG(scdt_send_raw(c, b.data, b.len, T_MS) == 0, "send");
  scp_buf_free(&b);
  EXPECT_MSG(scdt_wait_closed(c, T_MS), "not closed after too many jobs");
  EXPECT_MSG(c->got_error && c->last_error.code == SCP_WIRE_LIMIT &&
            (c->last_error.flags & SCP_ERROR_FATAL),
        "invalid third job: want a fatal LIMIT, got %s",
        scp_wire_name(c->last_error.code));
  scdt_close(c);
  EXPECT_EQ(scdt_stat_wait(d.sock, "jobs_active", 0, T_MS), 0);
}

static void points(void) {
  scdt_conn_t *c;
  ASSERT_MSG(scdt_open(d.sock, SCP_FRAME_MIN, &c) == 0, "connect");
  EXPECT_EQ(c->welcome.max_points, 5000);
  double *many = scdt_sample(SCS_SURF_SPHERE, 5001, 8);
  /* Announced too many: refused at once. */
  scdt_job_t j;
  scdt_job_init(&j, 1, many, 5001);
  EXPECT_MSG(scdt_job_begin(c, &j) == 0, "send");
  expect_job_error(c, &j, SCP_WIRE_LIMIT, "at most 5000");
  EXPECT_MSG(scdt_job_end(c, &j) == 0, "end");
  scdt_job_reset(&j);
  /* Not announced: fails at the point that goes over. */
  j.declare = 0;
  EXPECT_MSG(scdt_job_begin(c, &j) == 0 && scdt_job_points(c, &j, 5001) == 0,
             "send");
  expect_job_error(c, &j, SCP_WIRE_LIMIT, "at most 5000");
  EXPECT_MSG(scdt_job_end(c, &j) == 0, "end");
  scdt_job_reset(&j);
  /* More than announced. */
  scdt_job_init(&j, 2, many, 4000);
  EXPECT_MSG(scdt_job_begin(c, &j) == 0, "send");
  j.n = 4001;
  EXPECT_MSG(scdt_job_points(c, &j, 4001) == 0, "send");
  expect_job_error(c, &j, SCP_WIRE_INVALID, "announced");
  EXPECT_MSG(scdt_job_end(c, &j) == 0, "end");
  scdt_job_reset(&j);
  /* The ids drained and are free: a whole job on the same connection. */
  run_ok(c, 1, "after the point limits");
  scdt_close(c);
  free(many);
}

static void budget(void) {
  scdt_conn_t *c;
  ASSERT_MSG(scdt_open(d.sock, SCP_FRAME_MIN, &c) == 0, "connect");
  scdt_job_t a, b, u;
  scdt_job_init(&a, 1, sphere, 4000);
  scdt_job_init(&b, 2, sphere, 4000);
  scdt_job_init(&u, 3, sphere, 4000);
  u.declare = 0;
  /* a holds most of the budget while it uploads. */
  EXPECT_MSG(scdt_job_begin(c, &a) == 0 && scdt_job_points(c, &a, 100) == 0,
             "send a");
  EXPECT_MSG(scdt_job_begin(c, &b) == 0, "send b");
  expect_job_error2(c, &b, &a, SCP_WIRE_BUSY, "memory budget");
  EXPECT_MSG(scdt_job_end(c, &b) == 0, "end b");
  /* A job of unknown size is stopped where it stops fitting. */
  EXPECT_MSG(scdt_job_begin(c, &u) == 0 && scdt_job_points(c, &u, 4000) == 0,
             "send u");
  expect_job_error2(c, &u, &a, SCP_WIRE_NO_MEMORY, "memory budget");
  EXPECT_MSG(scdt_job_end(c, &u) == 0, "end u");
  /* a itself still completes, and afterwards b fits. */
  scdt_job_t *pa = &a;
  char why[512] = "";
  EXPECT_MSG(scdt_job_points(c, &a, 4000) == 0 && scdt_job_end(c, &a) == 0,
             "send a");
  EXPECT_MSG(scdt_collect(c, &pa, 1, T_MS, why, sizeof why) == 0, "%s", why);
  EXPECT_MSG(scdt_mesh_ok(SCS_SURF_SPHERE, &a, why, sizeof why), "%s", why);
  scdt_job_reset(&a);
  scdt_job_reset(&b);
  scdt_job_reset(&u);
  run_ok(c, 2, "after the budget was full");
  scdt_close(c);
}

static void frame_size(void) {
  scdt_conn_t *c;
  ASSERT_MSG(scdt_open(d.sock, SCP_FRAME_MIN, &c) == 0, "connect");
  EXPECT_EQ(c->welcome.max_frame, SCP_FRAME_MIN);
  /* A POINTS frame twice the size agreed on. */
  scp_buf_t raw;
  scp_buf_init(&raw, 1u << 20);
  scdt_job_t j;
  scdt_job_init(&j, 1, sphere, 4000);
  EXPECT_MSG(scdt_job_begin(c, &j) == 0, "send");
  EXPECT_MSG(scp_enc_points(&raw, 1, 0, SCP_F64_XYZ, sphere, 300) == 0, "enc");
  EXPECT_MSG(scdt_send_raw(c, raw.data, raw.len, T_MS) == 0, "send raw");
  scp_buf_free(&raw);
  EXPECT_MSG(scdt_wait_closed(c, T_MS), "not closed after a frame too large");
  EXPECT_MSG(c->got_error && c->last_error.code == SCP_WIRE_LIMIT &&
                 (c->last_error.flags & SCP_ERROR_FATAL),
             "want a fatal LIMIT, got %s", scp_wire_name(c->last_error.code));
  printf("frame too large: %s\n", c->last_error.message);
  scdt_close(c);
  /* The server's own limit: a client offering more gets the server's. */
  ASSERT_MSG(scdt_open(d.sock, SCP_FRAME_CEILING, &c) == 0, "connect");
  EXPECT_EQ(c->welcome.max_frame, 1u << 20);
  scdt_close(c);
}

int main(int argc, char **argv) {
  scdt_init(argc, argv);
  const char *args[] = {"--workers",    "2",      "--max-connections",
                        "2",            "--max-jobs", "2",
                        "--max-points", "5000",   "--memory-budget",
                        BUDGET,         NULL};
  ASSERT_MSG(scdt_daemon_start(&d, args) == 0, "daemon did not start");
  sphere = scdt_sample(SCS_SURF_SPHERE, 4000, 1);

  connections();
  check_serving("after the connection limit");
  jobs();
  check_serving("after the job limit");
  points();
  check_serving("after the point limit");
  budget();
  check_serving("after the memory budget");
  frame_size();
  check_serving("after the frame size limit");

  EXPECT_EQ(scdt_stat_wait(d.sock, "memory_jobs_bytes", 0, T_MS), 0);
  EXPECT_EQ(scdt_daemon_stop(&d), 0);
  EXPECT_MSG(scdt_log_contains(&d, "too many connections"), "no log line");
  EXPECT_MSG(scdt_log_contains(&d, "refused BUSY"), "no log line");
  free(sphere);
  return scdt_finish();
}
