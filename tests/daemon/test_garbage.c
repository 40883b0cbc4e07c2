/*
 * Bad input on the wire: garbage bytes, a wrong magic, a wrong version,
 * truncated frames, non-zero header flags, unknown and misdirected frame
 * types, invalid requests of every kind, and bad points. Malformed streams
 * cost the connection (a fatal ERROR); well-framed invalid requests cost
 * an error reply only; and the daemon serves on regardless.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "daemontest.h"
#include "synth.h"

#define T_MS 120000

static scdt_daemon_t d;
static double *sphere; /* 3000 points */

static void check_serving(const char *when) {
  scdt_check_serving(d.sock, SCS_SURF_SPHERE, sphere, 3000, T_MS, when);
}

/* Sends raw bytes on a fresh connection (before any handshake unless
 * handshake is set) and expects a fatal ERROR with the code, then close. */
static void expect_fatal(const char *what, int handshake, const void *bytes,
                         size_t len, uint32_t code) {
  scdt_conn_t *c;
  ASSERT_MSG(scdt_connect(d.sock, &c) == 0, "%s: connect", what);
  if (handshake)
    EXPECT_MSG(scdt_handshake(c, SCP_FRAME_MIN) == 0, "%s: handshake", what);
  scdt_send_raw(c, bytes, len, T_MS);
  EXPECT_MSG(scdt_wait_closed(c, T_MS), "%s: not closed", what);
  EXPECT_MSG(c->got_error && c->last_error.code == code &&
                 (c->last_error.flags & SCP_ERROR_FATAL),
             "%s: want a fatal %s, got %s%s", what, scp_wire_name(code),
             c->got_error ? "" : "nothing ",
             c->got_error ? scp_wire_name(c->last_error.code) : "");
  printf("%s: fatal %s: %s\n", what, scp_wire_name(c->last_error.code),
         c->last_error.message);
  scdt_close(c);
  check_serving(what);
}

/* Sends raw bytes and closes without waiting for anything. */
static void hang_up_after(const char *what, int handshake, const void *bytes,
                          size_t len) {
  scdt_conn_t *c;
  ASSERT_MSG(scdt_connect(d.sock, &c) == 0, "%s: connect", what);
  if (handshake)
    EXPECT_MSG(scdt_handshake(c, SCP_FRAME_MIN) == 0, "%s: handshake", what);
  scdt_send_raw(c, bytes, len, T_MS);
  scdt_close(c);
  check_serving(what);
}

static void malformed(void) {
  uint8_t junk[64];
  for (size_t i = 0; i < sizeof junk; i++)
    junk[i] = (uint8_t)(i * 37 + 11);
  expect_fatal("garbage bytes", 0, junk, sizeof junk, SCP_WIRE_PROTOCOL);
  expect_fatal("HTTP request", 0, "GET / HTTP/1.1\r\nHost: x\r\n\r\n", 27,
               SCP_WIRE_PROTOCOL);

  scp_buf_t b;
  scp_buf_init(&b, SCP_FRAME_MIN);
  scp_hello_t h = {.version_min = 1, .version_max = 1,
                   .max_frame = SCP_FRAME_MIN};
  scp_enc_hello(&b, &h);
  b.data[8] = 'X'; /* the magic */
  expect_fatal("wrong magic", 0, b.data, b.len, SCP_WIRE_PROTOCOL);
  b.len = 0;

  /* Versions the server does not speak: the handshake itself fails. */
  scdt_conn_t *c;
  ASSERT_MSG(scdt_connect(d.sock, &c) == 0, "connect");
  int rc = scdt_handshake_v(c, 2, 3, SCP_FRAME_MIN, T_MS);
  EXPECT_EQ(rc, SCP_WIRE_VERSION);
  EXPECT_MSG(strstr(c->last_error.message, "versions 1 to 1") != NULL,
             "message: %s", c->last_error.message);
  printf("wrong version: %s\n", c->last_error.message);
  EXPECT_MSG(scdt_wait_closed(c, T_MS), "not closed");
  scdt_close(c);

  /* A frame before the handshake. */
  scp_enc_ping(&b, 1);
  expect_fatal("PING before HELLO", 0, b.data, b.len, SCP_WIRE_PROTOCOL);
  b.len = 0;

  /* Header flags must be zero. */
  scp_enc_ping(&b, 1);
  b.data[2] = 1;
  expect_fatal("header flags", 1, b.data, b.len, SCP_WIRE_PROTOCOL);
  b.len = 0;

  /* A second HELLO. */
  scp_enc_hello(&b, &h);
  expect_fatal("second HELLO", 1, b.data, b.len, SCP_WIRE_PROTOCOL);
  b.len = 0;

  /* A length near 2^32. */
  uint8_t huge[8] = {0x11, 0, 0, 0, 0xf8, 0xff, 0xff, 0xff};
  expect_fatal("huge length", 1, huge, sizeof huge, SCP_WIRE_LIMIT);

  /* Payload shorter than the message's fixed part. */
  uint8_t shorty[8 + 4] = {0x13, 0, 0, 0, 4, 0, 0, 0, 1, 0, 0, 0};
  expect_fatal("short CANCEL", 1, shorty, sizeof shorty, SCP_WIRE_PROTOCOL);

  /* Truncated: the stream ends inside a frame, during and after the
   * handshake. */
  scp_enc_hello(&b, &h);
  hang_up_after("truncated HELLO", 0, b.data, 13);
  b.len = 0;
  scp_enc_points(&b, 1, 0, SCP_F64_XYZ, sphere, 100);
  hang_up_after("truncated POINTS", 1, b.data, b.len - 7);
  b.len = 0;
  hang_up_after("nothing at all", 0, "", 0);
  scp_buf_free(&b);
}

/* Appends raw bytes to an encoder buffer. */
static void put(scp_buf_t *b, const void *bytes, size_t len) {
  if (b->cap - b->len < len) {
    size_t cap = b->len + len + 256;
    b->data = realloc(b->data, cap);
    ASSERT_MSG(b->data != NULL, "out of memory");
    b->cap = cap;
  }
  memcpy(b->data + b->len, bytes, len);
  b->len += len;
}

/* Sends the frames in b on c and expects a non-fatal ERROR with the code,
 * then a PONG to show the connection still works. */
static void expect_error(scdt_conn_t *c, scp_buf_t *b, uint32_t code,
                         const char *what) {
  scp_enc_ping(b, 99);
  EXPECT_MSG(scdt_send_raw(c, b->data, b->len, T_MS) == 0, "%s: send", what);
  b->len = 0;
  scdt_frame_t *f = scdt_recv(c, T_MS);
  scp_frame_t v;
  scp_error_t e;
  memset(&e, 0, sizeof e);
  EXPECT_MSG(f && f->type == SCP_ERROR, "%s: want ERROR, got %s", what,
             f ? scp_type_name(f->type) : "nothing");
  if (f && f->type == SCP_ERROR) {
    scdt_frame_view(f, &v);
    EXPECT_MSG(scp_parse_error(&v, &e) == 0, "%s: bad ERROR", what);
    EXPECT_MSG(e.code == code && !(e.flags & SCP_ERROR_FATAL),
               "%s: want %s, got %s%s (%s)", what, scp_wire_name(code),
               (e.flags & SCP_ERROR_FATAL) ? "fatal " : "",
               scp_wire_name(e.code), e.message);
  }
  free(f);
  f = scdt_recv(c, T_MS);
  EXPECT_MSG(f && f->type == SCP_PONG, "%s: want PONG, got %s", what,
             f ? scp_type_name(f->type) : "nothing");
  free(f);
}

/* Expects exactly one JOB_ERROR for the job with the code. */
static void expect_job_error(scdt_conn_t *c, scdt_job_t *j, uint32_t code) {
  char why[512] = "";
  EXPECT_MSG(scdt_collect(c, &j, 1, T_MS, why, sizeof why) == 0, "%s", why);
  EXPECT_MSG(j->error_code == code, "job %u: got %s (%s), want %s", j->id,
             scp_wire_name(j->error_code), j->error_msg, scp_wire_name(code));
  printf("job %u: %s: %s\n", j->id, scp_wire_name(j->error_code),
         j->error_msg);
}

static void invalid_requests(void) {
  scdt_conn_t *c;
  ASSERT_MSG(scdt_open(d.sock, SCP_FRAME_MIN, &c) == 0, "connect");
  scp_buf_t b;
  scp_buf_init(&b, SCP_FRAME_MIN);

  /* An unknown type, and a type only servers send. */
  uint8_t unknown[8] = {0x00, 0x01, 0, 0, 0, 0, 0, 0};
  put(&b, unknown, sizeof unknown);
  expect_error(c, &b, SCP_WIRE_UNKNOWN_TYPE, "unknown type");
  uint32_t tri[3] = {0, 1, 2};
  scp_enc_triangles(&b, 1, 0, tri, 1);
  expect_error(c, &b, SCP_WIRE_UNKNOWN_TYPE, "TRIANGLES from a client");
  /* An unknown ignorable type is skipped silently: the PONG comes next. */
  uint8_t ignorable[12] = {0x00, 0x90, 0, 0, 4, 0, 0, 0, 1, 2, 3, 4};
  scp_enc_ping(&b, 5);
  EXPECT_MSG(scdt_send_raw(c, ignorable, sizeof ignorable, T_MS) == 0, "send");
  EXPECT_MSG(scdt_send_raw(c, b.data, b.len, T_MS) == 0, "send");
  b.len = 0;
  scdt_frame_t *f = scdt_recv(c, T_MS);
  EXPECT_MSG(f && f->type == SCP_PONG, "ignorable type: want PONG, got %s",
             f ? scp_type_name(f->type) : "nothing");
  free(f);
  /* So is an ignorable type only servers send (PROTOCOL.md 3.2). */
  double xyz[3] = {1, 2, 3};
  scp_enc_vertices(&b, 1, 0, xyz, 1);
  scp_enc_ping(&b, 6);
  EXPECT_MSG(scdt_send_raw(c, b.data, b.len, T_MS) == 0, "send");
  b.len = 0;
  f = scdt_recv(c, T_MS);
  EXPECT_MSG(f && f->type == SCP_PONG, "client's VERTICES: want PONG, got %s",
             f ? scp_type_name(f->type) : "nothing");
  free(f);

  /* Frames for jobs not in use. */
  scp_enc_points(&b, 42, 0, SCP_F64_XYZ, sphere, 10);
  expect_error(c, &b, SCP_WIRE_UNKNOWN_JOB, "POINTS for no job");
  scp_job_end_t end = {.job_id = 42, .point_count = 10};
  scp_enc_job_end(&b, &end);
  expect_error(c, &b, SCP_WIRE_UNKNOWN_JOB, "JOB_END for no job");

  /* Job id 0. */
  uint8_t zero_cancel[16] = {0x13, 0, 0, 0, 8, 0, 0, 0};
  put(&b, zero_cancel, sizeof zero_cancel);
  expect_error(c, &b, SCP_WIRE_INVALID, "CANCEL of job 0");

  /* An invalid JOB_BEGIN claims the id and drains it. */
  scdt_job_t j;
  scdt_job_init(&j, 3, sphere, 3000);
  scp_job_begin_t jb = {.job_id = 3, .mode = 1, .r = 0.25, .point_count = 10};
  scp_enc_job_begin(&b, &jb);
  b.data[8 + 8 + 7] = 0x3f;
  b.data[8 + 8 + 6] = 0xf0; /* r = 1.0 */
  EXPECT_MSG(scdt_send_raw(c, b.data, b.len, T_MS) == 0, "send");
  b.len = 0;
  expect_job_error(c, &j, SCP_WIRE_INVALID);
  scp_enc_points(&b, 3, 0, SCP_F64_XYZ, sphere, 10); /* discarded */
  scp_enc_job_end(&b, &(scp_job_end_t){.job_id = 3, .point_count = 10});
  EXPECT_MSG(scdt_send_raw(c, b.data, b.len, T_MS) == 0, "send");
  b.len = 0;

  /* A mode version 1 does not have. */
  scp_enc_job_begin(&b, &jb);
  b.data[8 + 4] = 5;
  EXPECT_MSG(scdt_send_raw(c, b.data, b.len, T_MS) == 0, "send");
  b.len = 0;
  scdt_job_reset(&j);
  expect_job_error(c, &j, SCP_WIRE_INVALID);
  EXPECT_MSG(scdt_job_cancel(c, &j) == 0, "cancel");

  /* Duplicate id. */
  scdt_job_reset(&j);
  j.mode = SCP_MODE_COCONE;
  EXPECT_MSG(scdt_job_begin(c, &j) == 0, "send");
  scp_job_begin_t dup = {.job_id = 3, .mode = 1, .r = 0.25};
  scp_enc_job_begin(&b, &dup);
  scdt_frame_t *acc = scdt_recv(c, T_MS);
  EXPECT_MSG(acc && acc->type == SCP_ACCEPTED, "want ACCEPTED");
  free(acc);
  expect_error(c, &b, SCP_WIRE_DUPLICATE_JOB, "duplicate job");
  /* An invalid JOB_BEGIN is judged by its id first: one in use is a
   * duplicate, and 0 claims nothing. */
  scp_enc_job_begin(&b, &dup);
  b.data[8 + 8 + 6] = 0xf0; /* r = 1.0 */
  expect_error(c, &b, SCP_WIRE_DUPLICATE_JOB, "invalid duplicate job");
  scp_enc_job_begin(&b, &dup);
  b.data[8] = 0; /* job id 0 */
  expect_error(c, &b, SCP_WIRE_INVALID, "JOB_BEGIN of job 0");

  /* Points out of order. */
  scp_enc_points(&b, 3, 5, SCP_F64_XYZ, sphere, 10);
  EXPECT_MSG(scdt_send_raw(c, b.data, b.len, T_MS) == 0, "send");
  b.len = 0;
  j.accepted = 0;
  expect_job_error(c, &j, SCP_WIRE_INVALID);
  EXPECT_MSG(scdt_job_end(c, &j) == 0, "end");

  /* JOB_END with the wrong count. */
  scdt_job_reset(&j);
  EXPECT_MSG(scdt_job_begin(c, &j) == 0 && scdt_job_points(c, &j, 3000) == 0,
             "send");
  j.sent = 2999;
  EXPECT_MSG(scdt_job_end(c, &j) == 0, "end");
  expect_job_error(c, &j, SCP_WIRE_INVALID);

  /* POINTS after JOB_END: the job is working, not uploading. */
  scdt_job_reset(&j);
  EXPECT_MSG(scdt_job_send(c, &j) == 0, "send");
  scp_enc_points(&b, 3, 3000, SCP_F64_XYZ, sphere, 10);
  EXPECT_MSG(scdt_send_raw(c, b.data, b.len, T_MS) == 0, "send");
  b.len = 0;
  char why[512] = "";
  scdt_job_t *pj = &j;
  EXPECT_MSG(scdt_collect(c, &pj, 1, T_MS, why, sizeof why) == 0, "%s", why);
  EXPECT_MSG(c->got_error && c->last_error.code == SCP_WIRE_STATE,
             "want ERROR STATE, got %s", scp_wire_name(c->last_error.code));
  EXPECT_MSG(scdt_mesh_ok(SCS_SURF_SPHERE, &j, why, sizeof why), "%s", why);
  scdt_job_reset(&j);

  /* Bad points: a NaN, and points all in one plane. */
  double *bad = malloc(3000 * 3 * sizeof(double));
  memcpy(bad, sphere, 3000 * 3 * sizeof(double));
  bad[3 * 1234 + 1] = NAN;
  scdt_job_init(&j, 4, bad, 3000);
  EXPECT_MSG(scdt_job_send(c, &j) == 0, "send");
  expect_job_error(c, &j, SCP_WIRE_NONFINITE);
  double flat[3 * 50];
  for (int i = 0; i < 50; i++) {
    flat[3 * i] = i % 7;
    flat[3 * i + 1] = i / 7;
    flat[3 * i + 2] = 0;
  }
  scdt_job_init(&j, 5, flat, 50);
  EXPECT_MSG(scdt_job_send(c, &j) == 0, "send");
  expect_job_error(c, &j, SCP_WIRE_DEGENERATE_INPUT);
  scdt_job_init(&j, 6, flat, 0);
  EXPECT_MSG(scdt_job_send(c, &j) == 0, "send");
  expect_job_error(c, &j, SCP_WIRE_DEGENERATE_INPUT);
  free(bad);

  /* A client that keeps sending invalid requests is cut off. */
  for (int i = 0; i < 150; i++)
    put(&b, zero_cancel, sizeof zero_cancel);
  scdt_send_raw(c, b.data, b.len, T_MS);
  b.len = 0;
  EXPECT_MSG(scdt_wait_closed(c, T_MS),
             "not closed after 150 invalid requests");
  EXPECT_MSG(c->got_error && c->last_error.code == SCP_WIRE_PROTOCOL &&
                 (c->last_error.flags & SCP_ERROR_FATAL),
             "want a fatal PROTOCOL, got %s",
             scp_wire_name(c->last_error.code));
  scp_buf_free(&b);
  scdt_close(c);
  check_serving("after invalid requests");
}

int main(int argc, char **argv) {
  scdt_init(argc, argv);
  const char *args[] = {"--workers", "2", NULL};
  ASSERT_MSG(scdt_daemon_start(&d, args) == 0, "daemon did not start");
  sphere = scdt_sample(SCS_SURF_SPHERE, 3000, 11);
  malformed();
  invalid_requests();
  EXPECT_EQ(scdt_stat_wait(d.sock, "jobs_active", 0, T_MS), 0);
  EXPECT_EQ(scdt_stat_wait(d.sock, "memory_jobs_bytes", 0, T_MS), 0);
  EXPECT_EQ(scdt_daemon_stop(&d), 0);
  free(sphere);
  return scdt_finish();
}
