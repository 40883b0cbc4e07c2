/*
 * Writes the fuzz target's seed corpus: whole sessions in each direction,
 * every message alone, and the ways a stream goes wrong. Each file is the
 * fuzz input format: a byte for the role and frame limit, a byte seeding
 * the cuts, then the stream.
 *
 * Usage: proto_make_corpus DIR          write the files into DIR
 *        proto_make_corpus --check DIR  fail unless each file in DIR matches
 *
 * The corpus in tests/proto/corpus is this program's output; the check runs
 * as a test, so the committed files follow every change to the encoder.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scproto.h"

#define ROLE_ANY 0
#define ROLE_SERVER 1
#define ROLE_CLIENT 2
#define BIG_LIMIT 0x80 /* start with a 64 KiB frame limit */

static int check_mode;
static const char *dir;
static const char *prog = "proto_make_corpus";
static int failures;

static void die(const char *what, int rc) {
  fprintf(stderr, "%s: %s: %s\n", prog, what, scp_strerror(rc));
  exit(1);
}

#define E(call)                                                                \
  do {                                                                         \
    int rc_ = (call);                                                          \
    if (rc_ != 0)                                                              \
      die(#call, rc_);                                                         \
  } while (0)

static void put(const char *name, uint8_t role, uint8_t seed,
                const uint8_t *bytes, size_t len) {
  char path[4096];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  size_t total = len + 2;
  uint8_t *want = malloc(total);
  if (!want)
    die("malloc", SCP_ENOMEM);
  want[0] = role;
  want[1] = seed;
  if (len)
    memcpy(want + 2, bytes, len);
  if (check_mode) {
    FILE *fp = fopen(path, "rb");
    uint8_t *have = malloc(total + 1);
    size_t got = fp && have ? fread(have, 1, total + 1, fp) : 0;
    if (!fp || got != total || memcmp(have, want, total) != 0) {
      fprintf(stderr, "%s: %s is missing or stale; regenerate it with %s %s\n",
              prog, path, prog, dir);
      failures++;
    }
    if (fp)
      fclose(fp);
    free(have);
  } else {
    FILE *fp = fopen(path, "wb");
    if (!fp || fwrite(want, 1, total, fp) != total || fclose(fp) != 0) {
      fprintf(stderr, "%s: cannot write %s\n", prog, path);
      exit(1);
    }
  }
  free(want);
}

static void put_buf(const char *name, uint8_t role, uint8_t seed,
                    scp_buf_t *b) {
  put(name, role, seed, b->data, b->len);
  scp_buf_consume(b, b->len);
}

static void hello(scp_buf_t *b) {
  scp_hello_t h = {.version_min = 1, .version_max = 1, .features = 0,
                   .max_frame = 1u << 16};
  E(scp_enc_hello(b, &h));
}

static void welcome(scp_buf_t *b) {
  scp_welcome_t w = {.version = 1, .features = 0, .max_frame = 1u << 16,
                     .max_jobs = 8, .max_points = 10000000};
  E(scp_enc_welcome(b, &w));
}

static void job_begin(scp_buf_t *b) {
  scp_job_begin_t jb = {.job_id = 7, .mode = SCP_MODE_COCONE, .r = 0.25,
                        .theta = 0.3927, .point_count = 6,
                        .flags = SCP_JOB_NORMALS};
  E(scp_enc_job_begin(b, &jb));
}

/* A JOB_BEGIN with job options, as a client with the feature sends it. */
static void job_begin_options(scp_buf_t *b) {
  scp_job_begin_t jb = {.job_id = 9, .mode = SCP_MODE_BOUNDARY, .r = 0.18};
  const scp_value_t o[] = {
      {.name = "max_hole_edges", .kind = SCP_KIND_U64, .v.u = 0},
      {.name = "boundary_alpha", .kind = SCP_KIND_F64, .v.f = 0.4}};
  E(scp_enc_job_begin_options(b, &jb, o, 2));
}

static const double octahedron[18] = {1, 0, 0, -1, 0, 0, 0, 1, 0,
                                      0, -1, 0, 0, 0, 1, 0, 0, -1};
static const uint32_t faces[24] = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4,
                                   2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};

static void points(scp_buf_t *b) {
  E(scp_enc_points(b, 7, 0, SCP_F64_XYZ, octahedron, 3));
  float f[9];
  for (int i = 0; i < 9; i++)
    f[i] = (float)octahedron[9 + i];
  E(scp_enc_points_f32(b, 7, 3, f, 3));
}

static void mesh(scp_buf_t *b) {
  int32_t genus[1] = {0};
  scp_mesh_view_t mv = {.job_id = 7,
                        .triangles = faces,
                        .triangle_count = 8,
                        .normals = octahedron,
                        .normal_count = 6,
                        .normal_format = SCP_F32_XYZ,
                        .genus = genus,
                        .component_count = 1};
  scp_mesh_cursor_t c = {0};
  int rc;
  while ((rc = scp_enc_mesh_next(b, &mv, &c)) == 1)
    ;
  if (rc)
    die("scp_enc_mesh_next", rc);
}

static void job_done(scp_buf_t *b) {
  scp_value_t v[] = {
      {.name = "points_in", .kind = SCP_KIND_U64, .v.u = 6},
      {.name = "triangles", .kind = SCP_KIND_U64, .v.u = 8},
      {.name = "euler", .kind = SCP_KIND_I64, .v.i = 2},
      {.name = "seconds.total", .kind = SCP_KIND_F64, .v.f = 0.00125},
      {.name = "future", .kind = 9, .v.u = 1},
  };
  scp_job_done_t jd = {.job_id = 7, .triangles = 8, .normals = 6,
                       .components = 1};
  E(scp_enc_job_done(b, &jd, v, 5));
}

static void job_error(scp_buf_t *b) {
  scp_job_error_t je = {.job_id = 8, .code = SCP_WIRE_DEGENERATE_INPUT};
  strcpy(je.message, "all points lie in one plane");
  E(scp_enc_job_error(b, &je));
}

static void stats(scp_buf_t *b) {
  scp_value_t v[] = {{.name = "connections", .kind = SCP_KIND_U64, .v.u = 3},
                     {.name = "jobs_total", .kind = SCP_KIND_U64, .v.u = 40}};
  E(scp_enc_stats(b, 5, v, 2));
}

static void error(scp_buf_t *b, uint32_t flags) {
  scp_error_t e = {.code = SCP_WIRE_UNKNOWN_TYPE, .flags = flags,
                   .job_id = 0, .ref_type = 0x0099};
  strcpy(e.message, "unknown frame type 0x0099");
  E(scp_enc_error(b, &e));
}

static void raw_frame(scp_buf_t *out, uint16_t type, uint16_t flags,
                      uint32_t length, const uint8_t *payload,
                      size_t payload_len) {
  /* Appended through an encoder's buffer so one scp_buf_t holds the whole
   * stream; the header is written by hand because these frames are ones
   * the encoder refuses to make. */
  uint8_t h[8] = {(uint8_t)type,         (uint8_t)(type >> 8),
                  (uint8_t)flags,        (uint8_t)(flags >> 8),
                  (uint8_t)length,       (uint8_t)(length >> 8),
                  (uint8_t)(length >> 16), (uint8_t)(length >> 24)};
  size_t need = out->len + 8 + payload_len;
  if (need > out->cap) {
    uint8_t *p = realloc(out->data, need);
    if (!p)
      die("realloc", SCP_ENOMEM);
    out->data = p;
    out->cap = need;
  }
  memcpy(out->data + out->len, h, 8);
  if (payload_len)
    memcpy(out->data + out->len + 8, payload, payload_len);
  out->len = need;
}

int main(int argc, char **argv) {
  if (argc > 0 && argv[0][0])
    prog = argv[0];
  if (argc == 3 && strcmp(argv[1], "--check") == 0) {
    check_mode = 1;
    dir = argv[2];
  } else if (argc == 2) {
    dir = argv[1];
  } else {
    fprintf(stderr, "usage: %s [--check] DIR\n", prog);
    return 2;
  }
  scp_buf_t b;
  scp_buf_init(&b, 1u << 16);

  /* Whole sessions, as each side receives them. */
  hello(&b);
  job_begin(&b);
  job_begin_options(&b);
  points(&b);
  scp_job_end_t je = {.job_id = 7, .point_count = 6};
  E(scp_enc_job_end(&b, &je));
  E(scp_enc_ping(&b, 1));
  E(scp_enc_stats_request(&b, 5));
  E(scp_enc_cancel(&b, 8));
  error(&b, 0);
  put_buf("session-client.bin", ROLE_SERVER, 0, &b);

  welcome(&b);
  scp_accepted_t a = {.job_id = 7, .queue_position = 1};
  E(scp_enc_accepted(&b, &a));
  scp_progress_t pr = {.job_id = 7, .stage = SCP_STAGE_DELAUNAY,
                       .fraction = 0.5};
  E(scp_enc_progress(&b, &pr));
  mesh(&b);
  job_done(&b);
  job_error(&b);
  E(scp_enc_pong(&b, 1));
  stats(&b);
  error(&b, SCP_ERROR_FATAL);
  put_buf("session-server.bin", ROLE_CLIENT, 3, &b);

  /* Every message alone. */
  hello(&b);
  put_buf("msg-hello.bin", ROLE_ANY, 1, &b);
  welcome(&b);
  put_buf("msg-welcome.bin", ROLE_ANY, 1, &b);
  error(&b, SCP_ERROR_FATAL);
  put_buf("msg-error.bin", ROLE_ANY, 1, &b);
  E(scp_enc_ping(&b, 0x0102030405060708u));
  put_buf("msg-ping.bin", ROLE_ANY, 1, &b);
  E(scp_enc_pong(&b, 0x0102030405060708u));
  put_buf("msg-pong.bin", ROLE_ANY, 1, &b);
  job_begin(&b);
  put_buf("msg-job-begin.bin", ROLE_ANY, 1, &b);
  job_begin_options(&b);
  put_buf("msg-job-begin-options.bin", ROLE_ANY, 1, &b);
  points(&b);
  put_buf("msg-points.bin", ROLE_ANY, 1, &b);
  E(scp_enc_job_end(&b, &je));
  put_buf("msg-job-end.bin", ROLE_ANY, 1, &b);
  E(scp_enc_cancel(&b, 7));
  put_buf("msg-cancel.bin", ROLE_ANY, 1, &b);
  E(scp_enc_stats_request(&b, 5));
  put_buf("msg-stats-request.bin", ROLE_ANY, 1, &b);
  E(scp_enc_accepted(&b, &a));
  put_buf("msg-accepted.bin", ROLE_ANY, 1, &b);
  E(scp_enc_progress(&b, &pr));
  put_buf("msg-progress.bin", ROLE_ANY, 1, &b);
  mesh(&b);
  put_buf("msg-mesh.bin", ROLE_ANY, 1, &b);
  job_done(&b);
  put_buf("msg-job-done.bin", ROLE_ANY, 1, &b);
  job_error(&b);
  put_buf("msg-job-error.bin", ROLE_ANY, 1, &b);
  stats(&b);
  put_buf("msg-stats.bin", ROLE_ANY, 1, &b);

  /* Frames to skip or to answer with UNKNOWN_TYPE. */
  uint8_t junk[16] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16};
  raw_frame(&b, 0x8fff, 0, 16, junk, 16);
  raw_frame(&b, 0x0099, 0, 3, junk, 3);
  raw_frame(&b, 0x0000, 0, 0, NULL, 0);
  E(scp_enc_ping(&b, 2));
  put_buf("unknown-types.bin", ROLE_ANY, 2, &b);

  /* Broken streams, one fault each. */
  hello(&b);
  b.data[8] = 'X';
  put_buf("bad-magic.bin", ROLE_SERVER, 1, &b);
  hello(&b);
  hello(&b);
  put_buf("hello-twice.bin", ROLE_SERVER, 1, &b);
  E(scp_enc_ping(&b, 3));
  put_buf("no-hello.bin", ROLE_SERVER, 1, &b);
  raw_frame(&b, SCP_POINTS, 0, 0xFFFFFFF0u, NULL, 0);
  put_buf("oversize.bin", ROLE_ANY, 1, &b);
  raw_frame(&b, SCP_PING, 1, 8, junk, 8);
  put_buf("header-flags.bin", ROLE_ANY, 1, &b);
  job_begin(&b);
  b.len -= 5;
  put_buf("truncated.bin", ROLE_ANY, 1, &b);
  /* An ERROR whose message_len says 200 in a 30-byte payload. */
  error(&b, 0);
  b.data[8 + 16] = 200;
  put_buf("lying-length.bin", ROLE_ANY, 1, &b);
  /* JOB_BEGIN with mode 9: well framed, invalid. */
  job_begin(&b);
  b.data[8 + 4] = 9;
  E(scp_enc_cancel(&b, 7));
  put_buf("bad-mode.bin", ROLE_ANY, 1, &b);
  put("http.bin", ROLE_SERVER, 1, (const uint8_t *)"GET / HTTP/1.1\r\n\r\n",
      18);

  scp_buf_free(&b);
  if (failures) {
    fprintf(stderr, "%s: %d files differ from the encoder's output\n", prog,
            failures);
    return 1;
  }
  return 0;
}
