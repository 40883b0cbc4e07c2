/*
 * Every message survives encode -> decode -> parse with every field intact,
 * and scp_enc_msg() writes a parsed message back byte for byte. Also the
 * chunk helpers that split arrays to the frame limit, and the typed views.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <math.h>

#include "frames.h"

/* Decodes the single frame in b, parses it, checks that re-encoding the
 * parsed message gives the same bytes, and hands back the message. The
 * decoder is returned because views in *msg point into it. */
static scp_decoder_t *reparse(const scp_buf_t *b, uint16_t type,
                              scp_msg_t *msg) {
  scp_frame_t f;
  scp_decoder_t *d = pt_decode_one(b->data, b->len, &f);
  ASSERT_EQ(f.type, type);
  ASSERT_EQ(f.length + SCP_HEADER_SIZE, b->len);
  ASSERT_CODE_EQ(scp_parse(&f, msg), 0, scp_err_name);
  ASSERT_EQ(msg->type, type);

  scp_buf_t again;
  scp_buf_init(&again, SCP_FRAME_CEILING);
  ASSERT_CODE_EQ(scp_enc_msg(&again, msg), 0, scp_err_name);
  ASSERT_MEM_EQ(again.data, again.len, b->data, b->len);
  scp_buf_free(&again);
  return d;
}

static void test_handshake(void) {
  scp_buf_t b;
  scp_msg_t m;
  scp_buf_init(&b, 0);

  scp_hello_t h = {.version_min = 1,
                   .version_max = 7,
                   .features = 0x8000000000000001u,
                   .max_frame = 0xFFFFFFFFu};
  ASSERT_CODE_EQ(scp_enc_hello(&b, &h), 0, scp_err_name);
  ASSERT_EQ(b.len, 8 + 24);
  scp_decoder_t *d = reparse(&b, SCP_HELLO, &m);
  ASSERT_EQ(m.u.hello.version_min, 1);
  ASSERT_EQ(m.u.hello.version_max, 7);
  ASSERT_EQ(m.u.hello.features, 0x8000000000000001u);
  ASSERT_EQ(m.u.hello.max_frame, 0xFFFFFFFFu);
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);

  scp_welcome_t w = {.version = 1,
                     .features = 0,
                     .max_frame = SCP_FRAME_CEILING,
                     .max_jobs = 0xFFFFFFFFu,
                     .max_points = UINT64_MAX};
  ASSERT_CODE_EQ(scp_enc_welcome(&b, &w), 0, scp_err_name);
  ASSERT_EQ(b.len, 8 + 32);
  d = reparse(&b, SCP_WELCOME, &m);
  ASSERT_EQ(m.u.welcome.version, 1);
  ASSERT_EQ(m.u.welcome.features, 0);
  ASSERT_EQ(m.u.welcome.max_frame, SCP_FRAME_CEILING);
  ASSERT_EQ(m.u.welcome.max_jobs, 0xFFFFFFFFu);
  ASSERT_EQ(m.u.welcome.max_points, UINT64_MAX);
  scp_decoder_free(d);
  scp_buf_free(&b);

  /* The handshake decisions: newest common version, the smaller frame
   * limit, the common features; and the client's check of the answer. */
  scp_welcome_t server = {.features = 0x5,
                          .max_frame = 1u << 20,
                          .max_jobs = 8,
                          .max_points = 10000000};
  scp_welcome_t ans;
  ASSERT_CODE_EQ(scp_handshake_answer(&h, &server, &ans), 0, scp_err_name);
  ASSERT_EQ(ans.version, SCP_VERSION);
  ASSERT_EQ(ans.features, 0x1);
  ASSERT_EQ(ans.max_frame, 1u << 20);
  ASSERT_EQ(ans.max_jobs, 8);
  ASSERT_EQ(ans.max_points, 10000000);
  ASSERT_CODE_EQ(scp_handshake_check(&h, &ans), 0, scp_err_name);
  scp_hello_t small = {.version_min = 1, .version_max = 1,
                       .max_frame = SCP_FRAME_MIN};
  ASSERT_CODE_EQ(scp_handshake_answer(&small, &server, &ans), 0, scp_err_name);
  ASSERT_EQ(ans.max_frame, SCP_FRAME_MIN);
  ASSERT_EQ(ans.features, 0);
  ASSERT_CODE_EQ(scp_handshake_check(&small, &ans), 0, scp_err_name);
}

static void test_error_ping(void) {
  scp_buf_t b;
  scp_msg_t m;
  scp_buf_init(&b, 0);

  scp_error_t e = {.code = SCP_WIRE_UNKNOWN_TYPE,
                   .flags = 0,
                   .job_id = 0,
                   .ref_type = 0x0099};
  strcpy(e.message, "frame type 0x0099 is not known");
  ASSERT_CODE_EQ(scp_enc_error(&b, &e), 0, scp_err_name);
  scp_decoder_t *d = reparse(&b, SCP_ERROR, &m);
  ASSERT_EQ(m.u.error.code, SCP_WIRE_UNKNOWN_TYPE);
  ASSERT_EQ(m.u.error.flags, 0);
  ASSERT_EQ(m.u.error.job_id, 0);
  ASSERT_EQ(m.u.error.ref_type, 0x0099);
  ASSERT_STR_EQ(m.u.error.message, "frame type 0x0099 is not known");
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);

  /* The longest message, fatal, a code this version does not know. */
  e.code = 1000;
  e.flags = SCP_ERROR_FATAL;
  e.job_id = 42;
  e.ref_type = SCP_POINTS;
  memset(e.message, 'x', SCP_MESSAGE_MAX);
  e.message[SCP_MESSAGE_MAX] = '\0';
  ASSERT_CODE_EQ(scp_enc_error(&b, &e), 0, scp_err_name);
  ASSERT_EQ(b.len, 8 + 20 + SCP_MESSAGE_MAX);
  d = reparse(&b, SCP_ERROR, &m);
  ASSERT_EQ(m.u.error.code, 1000);
  ASSERT_EQ(m.u.error.flags, SCP_ERROR_FATAL);
  ASSERT_EQ(m.u.error.job_id, 42);
  ASSERT_EQ(strlen(m.u.error.message), SCP_MESSAGE_MAX);
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);

  /* An empty message. */
  e.message[0] = '\0';
  ASSERT_CODE_EQ(scp_enc_error(&b, &e), 0, scp_err_name);
  d = reparse(&b, SCP_ERROR, &m);
  ASSERT_STR_EQ(m.u.error.message, "");
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);

  ASSERT_CODE_EQ(scp_enc_ping(&b, 0x0123456789abcdefu), 0, scp_err_name);
  d = reparse(&b, SCP_PING, &m);
  ASSERT_EQ(m.u.token, 0x0123456789abcdefu);
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);

  ASSERT_CODE_EQ(scp_enc_pong(&b, UINT64_MAX), 0, scp_err_name);
  d = reparse(&b, SCP_PONG, &m);
  ASSERT_EQ(m.u.token, UINT64_MAX);
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);

  ASSERT_CODE_EQ(scp_enc_stats_request(&b, 77), 0, scp_err_name);
  d = reparse(&b, SCP_STATS_REQUEST, &m);
  ASSERT_EQ(m.u.tag, 77);
  scp_decoder_free(d);
  scp_buf_free(&b);
}

static void test_job_frames(void) {
  scp_buf_t b;
  scp_msg_t m;
  scp_buf_init(&b, 0);

  scp_job_begin_t jb = {.job_id = 0xFFFFFFFFu,
                        .mode = SCP_MODE_AUTO,
                        .r = 0.4999999999999999,
                        .theta = 1.5707963267948963,
                        .point_count = 123456789012345u,
                        .flags = SCP_JOB_NORMALS | SCP_JOB_NORMALS_F64};
  ASSERT_CODE_EQ(scp_enc_job_begin(&b, &jb), 0, scp_err_name);
  scp_decoder_t *d = reparse(&b, SCP_JOB_BEGIN, &m);
  ASSERT_EQ(m.u.job_begin.job_id, 0xFFFFFFFFu);
  ASSERT_EQ(m.u.job_begin.mode, SCP_MODE_AUTO);
  ASSERT_DBL_SAME(m.u.job_begin.r, 0.4999999999999999);
  ASSERT_DBL_SAME(m.u.job_begin.theta, 1.5707963267948963);
  ASSERT_EQ(m.u.job_begin.point_count, 123456789012345u);
  ASSERT_EQ(m.u.job_begin.flags, SCP_JOB_NORMALS | SCP_JOB_NORMALS_F64);
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);

  /* The smallest r, the default theta, no normals, unknown count. */
  jb = (scp_job_begin_t){.job_id = 1, .mode = 0, .r = 4.9e-324};
  ASSERT_CODE_EQ(scp_enc_job_begin(&b, &jb), 0, scp_err_name);
  d = reparse(&b, SCP_JOB_BEGIN, &m);
  ASSERT_DBL_SAME(m.u.job_begin.r, 4.9e-324);
  ASSERT_DBL_SAME(m.u.job_begin.theta, 0.0);
  ASSERT_EQ(m.u.job_begin.point_count, 0);
  ASSERT_EQ(m.u.job_begin.flags, 0);
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);

  /* With job options: written back byte for byte from the view, and read
   * back entry by entry. */
  const scp_value_t opts[] = {
      {.name = "max_hole_edges", .kind = SCP_KIND_U64, .v.u = 0},
      {.name = "boundary_rho", .kind = SCP_KIND_F64, .v.f = 1.25},
      {.name = "later.option", .kind = 200, .v.u = 0x0102030405060708u}};
  jb = (scp_job_begin_t){.job_id = 3, .mode = SCP_MODE_BOUNDARY, .r = 0.18};
  ASSERT_CODE_EQ(scp_enc_job_begin_options(&b, &jb, opts, 3), 0, scp_err_name);
  ASSERT_EQ(b.len, SCP_HEADER_SIZE + 48 + (10 + 14) + (10 + 12) + (10 + 12));
  d = reparse(&b, SCP_JOB_BEGIN, &m);
  ASSERT_EQ(m.u.job_begin.job_id, 3);
  ASSERT_EQ(m.u.job_begin.options.count, 3);
  {
    scp_value_iter_t it;
    scp_value_t v;
    scp_values_begin(&m.u.job_begin.options, &it);
    for (int i = 0; i < 3; i++) {
      ASSERT_EQ(scp_values_next(&it, &v), 1);
      ASSERT_EQ(strcmp(v.name, opts[i].name), 0);
      ASSERT_EQ(v.kind, opts[i].kind);
      ASSERT_EQ(v.v.u, opts[i].v.u);
    }
    ASSERT_EQ(scp_values_next(&it, &v), 0);
  }
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);
  /* No options: the 40-byte form, whatever the array pointer. */
  ASSERT_CODE_EQ(scp_enc_job_begin_options(&b, &jb, opts, 0), 0, scp_err_name);
  ASSERT_EQ(b.len, SCP_HEADER_SIZE + 40);
  d = reparse(&b, SCP_JOB_BEGIN, &m);
  ASSERT_EQ(m.u.job_begin.options.count, 0);
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);

  scp_job_end_t je = {.job_id = 9, .point_count = UINT64_MAX};
  ASSERT_CODE_EQ(scp_enc_job_end(&b, &je), 0, scp_err_name);
  d = reparse(&b, SCP_JOB_END, &m);
  ASSERT_EQ(m.u.job_end.job_id, 9);
  ASSERT_EQ(m.u.job_end.point_count, UINT64_MAX);
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);

  ASSERT_CODE_EQ(scp_enc_cancel(&b, 12), 0, scp_err_name);
  d = reparse(&b, SCP_CANCEL, &m);
  ASSERT_EQ(m.u.job_id, 12);
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);

  scp_accepted_t acc = {.job_id = 3, .queue_position = 0xFFFFFFFFu};
  ASSERT_CODE_EQ(scp_enc_accepted(&b, &acc), 0, scp_err_name);
  d = reparse(&b, SCP_ACCEPTED, &m);
  ASSERT_EQ(m.u.accepted.job_id, 3);
  ASSERT_EQ(m.u.accepted.queue_position, 0xFFFFFFFFu);
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);

  for (uint32_t stage = 0; stage < SCP_STAGE_COUNT; stage++) {
    scp_progress_t pr = {.job_id = 3, .stage = stage, .fraction = stage / 5.0};
    ASSERT_CODE_EQ(scp_enc_progress(&b, &pr), 0, scp_err_name);
    d = reparse(&b, SCP_PROGRESS, &m);
    ASSERT_EQ(m.u.progress.stage, stage);
    ASSERT_DBL_SAME(m.u.progress.fraction, stage / 5.0);
    scp_decoder_free(d);
    scp_buf_consume(&b, b.len);
  }

  scp_job_error_t jerr = {.job_id = 3, .code = SCP_WIRE_DEGENERATE_INPUT};
  strcpy(jerr.message, "all 12 points lie in one plane \xc3\xa9");
  ASSERT_CODE_EQ(scp_enc_job_error(&b, &jerr), 0, scp_err_name);
  d = reparse(&b, SCP_JOB_ERROR, &m);
  ASSERT_EQ(m.u.job_error.job_id, 3);
  ASSERT_EQ(m.u.job_error.code, SCP_WIRE_DEGENERATE_INPUT);
  ASSERT_STR_EQ(m.u.job_error.message,
                "all 12 points lie in one plane \xc3\xa9");
  scp_decoder_free(d);
  scp_buf_free(&b);
}

static void test_values(void) {
  scp_buf_t b;
  scp_msg_t m;
  scp_buf_init(&b, 0);
  char longname[SCP_NAME_MAX + 1];
  memset(longname, 'z', SCP_NAME_MAX);
  longname[0] = 'a';
  longname[SCP_NAME_MAX] = '\0';
  scp_value_t vals[] = {
      {.name = "triangles", .kind = SCP_KIND_U64, .v.u = UINT64_MAX},
      {.name = "euler", .kind = SCP_KIND_I64, .v.i = INT64_MIN},
      {.name = "seconds.total", .kind = SCP_KIND_F64, .v.f = -0.0},
      {.name = "a", .kind = 200, .v.u = 0x1122334455667788u},
      {.name = longname, .kind = SCP_KIND_F64, .v.f = NAN},
      {.name = "x9_.y", .kind = SCP_KIND_I64, .v.i = -1},
  };
  uint32_t n = sizeof vals / sizeof vals[0];

  scp_job_done_t jd = {.job_id = 5,
                       .triangles = 199996,
                       .normals = 100000,
                       .components = UINT64_MAX};
  ASSERT_CODE_EQ(scp_enc_job_done(&b, &jd, vals, n), 0, scp_err_name);
  scp_decoder_t *d = reparse(&b, SCP_JOB_DONE, &m);
  ASSERT_EQ(m.u.job_done.job_id, 5);
  ASSERT_EQ(m.u.job_done.triangles, 199996);
  ASSERT_EQ(m.u.job_done.normals, 100000);
  ASSERT_EQ(m.u.job_done.components, UINT64_MAX);
  ASSERT_EQ(m.u.job_done.values.count, n);

  scp_value_iter_t it;
  scp_value_t v;
  uint32_t i = 0;
  scp_values_begin(&m.u.job_done.values, &it);
  while (scp_values_next(&it, &v)) {
    ASSERT_LT(i, n);
    ASSERT_STR_EQ(v.name, vals[i].name);
    ASSERT_EQ(v.kind, vals[i].kind);
    /* Every kind, known or not, keeps its eight bytes. */
    ASSERT_EQ(v.v.u, vals[i].v.u);
    i++;
  }
  ASSERT_EQ(i, n);
  ASSERT(scp_values_find(&m.u.job_done.values, "euler", &it, &v));
  ASSERT_EQ(v.v.i, INT64_MIN);
  ASSERT(scp_values_find(&m.u.job_done.values, longname, &it, &v));
  ASSERT(isnan(v.v.f));
  ASSERT(!scp_values_find(&m.u.job_done.values, "genus", &it, &v));
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);

  /* A repeated name is the sender's fault, and the receiver takes the first
   * one (PROTOCOL.md 6.11). */
  scp_value_t twice[] = {{.name = "jobs_total", .kind = SCP_KIND_U64, .v.u = 1},
                         {.name = "jobs_total", .kind = SCP_KIND_U64, .v.u = 2}};
  ASSERT_CODE_EQ(scp_enc_stats(&b, 0xabcdef, twice, 2), 0, scp_err_name);
  d = reparse(&b, SCP_STATS, &m);
  ASSERT_EQ(m.u.stats.tag, 0xabcdef);
  ASSERT(scp_values_find(&m.u.stats.values, "jobs_total", &it, &v));
  ASSERT_EQ(v.v.u, 1);
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);

  /* Empty lists. */
  ASSERT_CODE_EQ(scp_enc_stats(&b, 0, NULL, 0), 0, scp_err_name);
  ASSERT_EQ(b.len, 8 + 8);
  d = reparse(&b, SCP_STATS, &m);
  ASSERT_EQ(m.u.stats.values.count, 0);
  scp_values_begin(&m.u.stats.values, &it);
  ASSERT(!scp_values_next(&it, &v));
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);
  ASSERT_CODE_EQ(scp_enc_job_done(&b, &jd, NULL, 0), 0, scp_err_name);
  ASSERT_EQ(b.len, 8 + 32);
  d = reparse(&b, SCP_JOB_DONE, &m);
  scp_decoder_free(d);
  scp_buf_free(&b);
}

static void test_chunks(void) {
  scp_buf_t b;
  scp_msg_t m;
  scp_decoder_t *d;
  scp_buf_init(&b, 0);
  double xyz[3 * 5];
  for (int i = 0; i < 15; i++)
    xyz[i] = (i - 7) * 0.1;
  xyz[4] = INFINITY; /* points may carry anything; the server judges them */
  xyz[5] = -0.0;

  /* POINTS as f64 keep every bit. */
  ASSERT_CODE_EQ(scp_enc_points(&b, 7, 100, SCP_F64_XYZ, xyz, 5), 0,
                 scp_err_name);
  ASSERT_EQ(b.len, 8 + 24 + 5 * 24);
  d = reparse(&b, SCP_POINTS, &m);
  ASSERT_EQ(m.u.chunk.type, SCP_POINTS);
  ASSERT_EQ(m.u.chunk.job_id, 7);
  ASSERT_EQ(m.u.chunk.count, 5);
  ASSERT_EQ(m.u.chunk.first, 100);
  ASSERT_EQ(m.u.chunk.format, SCP_F64_XYZ);
  double back[15];
  ASSERT_CODE_EQ(scp_chunk_copy_xyz(&m.u.chunk, back), 0, scp_err_name);
  for (int i = 0; i < 15; i++)
    ASSERT_DBL_SAME(back[i], xyz[i]);
  double one[3];
  scp_chunk_xyz(&m.u.chunk, 4, one);
  ASSERT_DBL_SAME(one[2], xyz[14]);
  uint32_t tri[3];
  ASSERT_CODE_EQ(scp_chunk_copy_triangles(&m.u.chunk, tri), SCP_EINVAL,
                 scp_err_name);
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);

  /* POINTS as f32 round to float, beyond-range values to infinity. */
  double big[3] = {1e300, -1e300, 0.1};
  ASSERT_CODE_EQ(scp_enc_points(&b, 7, 0, SCP_F32_XYZ, big, 1), 0,
                 scp_err_name);
  d = reparse(&b, SCP_POINTS, &m);
  float f[3];
  scp_chunk_xyz_f32(&m.u.chunk, 0, f);
  ASSERT(isinf(f[0]) && f[0] > 0);
  ASSERT(isinf(f[1]) && f[1] < 0);
  ASSERT_DBL_SAME(f[2], (double)0.1f);
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);

  /* f32 input is sent bit for bit, NaN payload included. */
  float fin[6] = {1.5f, -2.25f, 3.0f, 0.0f, 0.0f, 0.0f};
  uint32_t nan_bits = 0x7fc01234u;
  memcpy(&fin[3], &nan_bits, sizeof nan_bits);
  ASSERT_CODE_EQ(scp_enc_points_f32(&b, 2, 5, fin, 2), 0, scp_err_name);
  d = reparse(&b, SCP_POINTS, &m);
  ASSERT_EQ(m.u.chunk.format, SCP_F32_XYZ);
  scp_chunk_xyz_f32(&m.u.chunk, 1, f);
  uint32_t got_bits;
  memcpy(&got_bits, &f[0], sizeof got_bits);
  ASSERT_EQ(got_bits, nan_bits);
  scp_chunk_xyz(&m.u.chunk, 0, one);
  ASSERT_DBL_SAME(one[0], 1.5);
  ASSERT_DBL_SAME(one[1], -2.25);
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);

  uint32_t tris[6] = {0, 2, 1, 0xFFFFFFFFu, 1, 3};
  ASSERT_CODE_EQ(scp_enc_triangles(&b, 7, UINT64_MAX - 2, tris, 2), 0,
                 scp_err_name);
  d = reparse(&b, SCP_TRIANGLES, &m);
  ASSERT_EQ(m.u.chunk.first, UINT64_MAX - 2);
  uint32_t tback[6];
  ASSERT_CODE_EQ(scp_chunk_copy_triangles(&m.u.chunk, tback), 0, scp_err_name);
  for (int i = 0; i < 6; i++)
    ASSERT_EQ(tback[i], tris[i]);
  scp_chunk_triangle(&m.u.chunk, 1, tri);
  ASSERT_EQ(tri[0], 0xFFFFFFFFu);
  ASSERT_EQ(tri[2], 3);
  ASSERT_CODE_EQ(scp_chunk_copy_xyz(&m.u.chunk, back), SCP_EINVAL,
                 scp_err_name);
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);

  double normals[6] = {0, 0, 1, 0.6, 0.8, 0};
  ASSERT_CODE_EQ(scp_enc_normals(&b, 7, 0, SCP_F32_XYZ, normals, 2), 0,
                 scp_err_name);
  d = reparse(&b, SCP_NORMALS, &m);
  ASSERT_EQ(m.u.chunk.format, SCP_F32_XYZ);
  scp_chunk_xyz(&m.u.chunk, 1, one);
  ASSERT_DBL_SAME(one[0], (double)0.6f);
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);
  ASSERT_CODE_EQ(scp_enc_normals(&b, 7, 2, SCP_F64_XYZ, normals, 2), 0,
                 scp_err_name);
  d = reparse(&b, SCP_NORMALS, &m);
  scp_chunk_xyz(&m.u.chunk, 1, one);
  ASSERT_DBL_SAME(one[0], 0.6);
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);

  /* Smoothed positions travel as exact doubles, whatever their size. */
  double vertices[6] = {0.1, -2.5e300, 1.0 / 3, 4e-310, 5, -0.0};
  ASSERT_CODE_EQ(scp_enc_vertices(&b, 7, 3, vertices, 2), 0, scp_err_name);
  d = reparse(&b, SCP_VERTICES, &m);
  ASSERT_EQ(m.u.chunk.format, SCP_F64_XYZ);
  ASSERT_EQ(m.u.chunk.first, 3);
  ASSERT_EQ(m.u.chunk.count, 2);
  double vback[6];
  ASSERT_CODE_EQ(scp_chunk_copy_xyz(&m.u.chunk, vback), 0, scp_err_name);
  for (int i = 0; i < 6; i++)
    ASSERT_DBL_SAME(vback[i], vertices[i]);
  scp_frame_t vf = {.type = SCP_VERTICES,
                    .length = (uint32_t)b.len - SCP_HEADER_SIZE,
                    .payload = b.data + SCP_HEADER_SIZE};
  uint32_t vid = 0;
  ASSERT(scp_frame_job_id(&vf, &vid));
  ASSERT_EQ(vid, 7);
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);

  int32_t genus[4] = {-1, 0, 7, INT32_MAX};
  ASSERT_CODE_EQ(scp_enc_components(&b, 7, 0, genus, 4), 0, scp_err_name);
  d = reparse(&b, SCP_COMPONENTS, &m);
  int32_t gback[4];
  ASSERT_CODE_EQ(scp_chunk_copy_i32(&m.u.chunk, gback), 0, scp_err_name);
  for (int i = 0; i < 4; i++) {
    ASSERT_EQ(gback[i], genus[i]);
    ASSERT_EQ(scp_chunk_i32(&m.u.chunk, (uint32_t)i), genus[i]);
  }
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);

  /* scp_enc_chunk() from a view in wire form: little-endian u32 triples. */
  uint8_t raw[24];
  for (int i = 0; i < 6; i++)
    pt_put32(raw + 4 * i, (uint32_t)(10 * i));
  scp_chunk_t c = {.type = SCP_TRIANGLES, .job_id = 4, .count = 2,
                   .first = 0, .format = SCP_U32_TRIANGLE, .data = raw};
  ASSERT_CODE_EQ(scp_enc_chunk(&b, &c), 0, scp_err_name);
  d = reparse(&b, SCP_TRIANGLES, &m);
  scp_chunk_triangle(&m.u.chunk, 1, tri);
  ASSERT_EQ(tri[0], 30);
  ASSERT_EQ(tri[2], 50);
  scp_decoder_free(d);
  scp_buf_free(&b);
}

/* The capacity figures that PROTOCOL.md 6.4 and 7.2 quote. */
static void test_capacity(void) {
  ASSERT_EQ(scp_chunk_capacity(SCP_U32_TRIANGLE, 4096), 338);
  ASSERT_EQ(scp_chunk_capacity(SCP_F32_XYZ, 4096), 338);
  ASSERT_EQ(scp_chunk_capacity(SCP_F64_XYZ, 4096), 169);
  ASSERT_EQ(scp_chunk_capacity(SCP_I32, 4096), 1016);
  ASSERT_EQ(scp_chunk_capacity(SCP_F64_XYZ, 1u << 20), 43689);
  ASSERT_EQ(scp_chunk_capacity(SCP_U32_TRIANGLE, 1u << 20), 87378);
  ASSERT_EQ(scp_chunk_capacity(99, 1u << 20), 0);
  ASSERT_EQ(scp_chunk_capacity(SCP_I32, 4095), 0);

  /* A chunk of exactly the capacity fits the frame limit; one more does
   * not, and leaves the buffer as it was. */
  scp_buf_t b;
  scp_buf_init(&b, 4096);
  double *xyz = calloc(3 * 170, sizeof *xyz);
  ASSERT_NOT_NULL(xyz);
  ASSERT_CODE_EQ(scp_enc_points(&b, 1, 0, SCP_F64_XYZ, xyz, 169), 0,
                 scp_err_name);
  ASSERT_LE(b.len, 4096);
  size_t len = b.len;
  ASSERT_CODE_EQ(scp_enc_points(&b, 1, 169, SCP_F64_XYZ, xyz, 170), SCP_ETOOBIG,
                 scp_err_name);
  ASSERT_EQ(b.len, len);
  free(xyz);
  scp_buf_free(&b);
}

/* Splits n points with scp_enc_points_next() and reads them back through a
 * decoder, checking each chunk's first and the limit. */
static void test_points_next(uint32_t max_frame, uint32_t format,
                             uint64_t n) {
  double *xyz = malloc(3 * n * sizeof *xyz);
  double *back = malloc(3 * n * sizeof *back);
  ASSERT(xyz != NULL && back != NULL);
  for (uint64_t i = 0; i < 3 * n; i++)
    xyz[i] = (double)i * 0.5; /* exact in float too */

  scp_buf_t b;
  scp_buf_init(&b, max_frame);
  scp_limits_t lim;
  scp_limits_init(&lim);
  lim.max_frame = max_frame;
  scp_decoder_t *d = scp_decoder_new(&lim);
  ASSERT_NOT_NULL(d);
  uint64_t next = 0, got = 0, frames = 0;
  int rc;
  while ((rc = scp_enc_points_next(&b, 3, format, xyz, n, &next)) == 1) {
    /* Flush the buffer into the decoder after every frame, as a caller
     * writing to a socket would. */
    ASSERT_CODE_EQ(scp_decoder_feed(d, b.data, b.len), 0, scp_err_name);
    scp_buf_consume(&b, b.len);
    scp_frame_t f;
    ASSERT_CODE_EQ(scp_decoder_next(d, &f), 1, scp_err_name);
    ASSERT_LE(f.length + SCP_HEADER_SIZE, max_frame);
    scp_chunk_t c;
    ASSERT_CODE_EQ(scp_parse_chunk(&f, &c), 0, scp_err_name);
    ASSERT_EQ(c.first, got);
    ASSERT_CODE_EQ(scp_chunk_copy_xyz(&c, back + 3 * got), 0, scp_err_name);
    got += c.count;
    frames++;
    ASSERT_CODE_EQ(scp_decoder_next(d, &f), 0, scp_err_name);
  }
  ASSERT_CODE_EQ(rc, 0, scp_err_name);
  ASSERT_EQ(next, n);
  ASSERT_EQ(got, n);
  uint32_t cap = scp_chunk_capacity(format, max_frame);
  ASSERT_EQ(frames, (n + cap - 1) / cap);
  for (uint64_t i = 0; i < 3 * n; i++)
    ASSERT_DBL_SAME(back[i], xyz[i]);
  scp_decoder_free(d);
  scp_buf_free(&b);
  free(xyz);
  free(back);
}

/* A mesh sent with scp_enc_mesh_next() at the smallest limit, reassembled
 * by the rules a client follows: chunks in order, totals as JOB_DONE says. */
static void test_mesh_next(void) {
  enum { NT = 1000, NP = 502, NC = 1500 };
  uint32_t *tris = malloc(3 * NT * sizeof *tris);
  double *normals = malloc(3 * NP * sizeof *normals);
  double *vertices = malloc(3 * NP * sizeof *vertices);
  int32_t *genus = malloc(NC * sizeof *genus);
  ASSERT(tris && normals && vertices && genus);
  for (uint32_t i = 0; i < 3 * NT; i++)
    tris[i] = (i * 7919u) % NP;
  for (uint32_t i = 0; i < 3 * NP; i++) {
    normals[i] = (i % 3 == 2) ? 1.0 : 0.0;
    vertices[i] = i / 7.0;
  }
  for (int32_t i = 0; i < NC; i++)
    genus[i] = i % 5 - 1;
  scp_mesh_view_t mv = {.job_id = 11,
                        .triangles = tris,
                        .triangle_count = NT,
                        .normals = normals,
                        .normal_count = NP,
                        .normal_format = SCP_F64_XYZ,
                        .vertices = vertices,
                        .vertex_count = NP,
                        .genus = genus,
                        .component_count = NC};
  scp_mesh_cursor_t cur = {0};
  scp_buf_t b;
  scp_buf_init(&b, SCP_FRAME_MIN);
  int rc;
  while ((rc = scp_enc_mesh_next(&b, &mv, &cur)) == 1)
    ;
  ASSERT_CODE_EQ(rc, 0, scp_err_name);

  scp_decoder_t *d = scp_decoder_new(NULL);
  ASSERT_NOT_NULL(d);
  ASSERT_CODE_EQ(scp_decoder_feed(d, b.data, b.len), 0, scp_err_name);
  /* Triangles, normals, vertices, components: in this order. */
  uint64_t seen[4] = {0, 0, 0, 0};
  uint64_t frames = 0;
  scp_frame_t f;
  while ((rc = scp_decoder_next(d, &f)) == 1) {
    scp_chunk_t c;
    ASSERT_CODE_EQ(scp_parse_chunk(&f, &c), 0, scp_err_name);
    ASSERT_EQ(c.job_id, 11);
    frames++;
    if (c.type == SCP_TRIANGLES) {
      ASSERT_EQ(seen[1] + seen[2] + seen[3], 0); /* triangles come first */
      ASSERT_EQ(c.first, seen[0]);
      for (uint32_t i = 0; i < c.count; i++) {
        uint32_t t[3];
        scp_chunk_triangle(&c, i, t);
        for (int k = 0; k < 3; k++)
          ASSERT_EQ(t[k], tris[3 * (c.first + i) + (uint64_t)k]);
      }
      seen[0] += c.count;
    } else if (c.type == SCP_NORMALS) {
      ASSERT_EQ(seen[2] + seen[3], 0);
      ASSERT_EQ(c.first, seen[1]);
      ASSERT_EQ(c.format, SCP_F64_XYZ);
      seen[1] += c.count;
    } else if (c.type == SCP_VERTICES) {
      ASSERT_EQ(seen[1], NP); /* after every normal */
      ASSERT_EQ(seen[3], 0);
      ASSERT_EQ(c.first, seen[2]);
      ASSERT_EQ(c.format, SCP_F64_XYZ);
      for (uint32_t i = 0; i < c.count; i++) {
        double xyz[3];
        scp_chunk_xyz(&c, i, xyz);
        for (int k = 0; k < 3; k++)
          ASSERT_DBL_SAME(xyz[k], vertices[3 * (c.first + i) + (uint64_t)k]);
      }
      seen[2] += c.count;
    } else {
      ASSERT_EQ(c.type, SCP_COMPONENTS);
      ASSERT_EQ(c.first, seen[3]);
      for (uint32_t i = 0; i < c.count; i++)
        ASSERT_EQ(scp_chunk_i32(&c, i), genus[c.first + i]);
      seen[3] += c.count;
    }
  }
  ASSERT_CODE_EQ(rc, 0, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_eof(d), 0, scp_err_name);
  ASSERT_EQ(seen[0], NT);
  ASSERT_EQ(seen[1], NP);
  ASSERT_EQ(seen[2], NP);
  ASSERT_EQ(seen[3], NC);
  /* 338 triangles, 169 f64 normals or vertices and 1016 genera per 4 KiB
   * frame. */
  ASSERT_EQ(frames, 3 + 3 + 3 + 2);
  scp_decoder_free(d);
  scp_buf_free(&b);
  free(tris);
  free(normals);
  free(vertices);
  free(genus);
}

int main(void) {
  test_handshake();
  test_error_ping();
  test_job_frames();
  test_values();
  test_chunks();
  test_capacity();
  test_points_next(SCP_FRAME_MIN, SCP_F64_XYZ, 1000);
  test_points_next(SCP_FRAME_MIN, SCP_F32_XYZ, 338);
  test_points_next(SCP_FRAME_MIN, SCP_F32_XYZ, 339);
  test_points_next(1u << 20, SCP_F64_XYZ, 100000);
  test_points_next(1u << 20, SCP_F32_XYZ, 1);
  test_mesh_next();
  return sct_finish("proto_roundtrip");
}
