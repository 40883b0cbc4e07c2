/*
 * The decoder gives the same frames however the stream is cut: at every
 * single split point, one byte at a time, in random pieces, with and
 * without draining between feeds, and for many frames back to back.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "frames.h"

typedef struct expect {
  uint16_t type;
  uint32_t length;
  size_t offset; /* of the frame's header in the stream */
} expect_t;

typedef struct stream {
  uint8_t *bytes;
  size_t len;
  size_t cap;
  expect_t *frames;
  size_t n;
  size_t skipped; /* ignorable frames the decoder must drop */
  int role;
} stream_t;

static void append(stream_t *s, const uint8_t *p, size_t n) {
  if (s->len + n > s->cap) {
    size_t cap = s->cap ? s->cap : 1024;
    while (cap < s->len + n)
      cap *= 2;
    s->bytes = realloc(s->bytes, cap);
    ASSERT_NOT_NULL(s->bytes);
    s->cap = cap;
  }
  memcpy(s->bytes + s->len, p, n);
  s->len += n;
}

/* Appends the frames an encoder left in b, each one expected back. */
static void take(stream_t *s, scp_buf_t *b) {
  size_t at = 0;
  while (at < b->len) {
    ASSERT_GE(b->len - at, SCP_HEADER_SIZE);
    uint16_t type = (uint16_t)(b->data[at] | b->data[at + 1] << 8);
    uint32_t length = (uint32_t)b->data[at + 4] |
                      (uint32_t)b->data[at + 5] << 8 |
                      (uint32_t)b->data[at + 6] << 16 |
                      (uint32_t)b->data[at + 7] << 24;
    s->frames = realloc(s->frames, (s->n + 1) * sizeof *s->frames);
    ASSERT_NOT_NULL(s->frames);
    s->frames[s->n++] = (expect_t){type, length, s->len + at};
    at += SCP_HEADER_SIZE + length;
  }
  ASSERT_EQ(at, b->len);
  append(s, b->data, b->len);
  scp_buf_consume(b, b->len);
}

/* A hand-made frame of an ignorable type, which the decoder must drop. */
static void ignorable(stream_t *s, uint16_t type, uint32_t length) {
  uint8_t h[SCP_HEADER_SIZE];
  pt_header(h, type, 0, length);
  append(s, h, sizeof h);
  for (uint32_t i = 0; i < length; i++) {
    uint8_t x = (uint8_t)(i * 31 + 7);
    append(s, &x, 1);
  }
  s->skipped++;
}

/* A hand-made frame of a type version 1 lacks, without the ignorable bit:
 * the decoder must return it for the caller to answer UNKNOWN_TYPE. */
static void unknown(stream_t *s, uint16_t type, uint32_t length) {
  uint8_t h[SCP_HEADER_SIZE];
  pt_header(h, type, 0, length);
  s->frames = realloc(s->frames, (s->n + 1) * sizeof *s->frames);
  ASSERT_NOT_NULL(s->frames);
  s->frames[s->n++] = (expect_t){type, length, s->len};
  append(s, h, sizeof h);
  for (uint32_t i = 0; i < length; i++) {
    uint8_t x = (uint8_t)(i ^ 0x5a);
    append(s, &x, 1);
  }
}

static void stream_free(stream_t *s) {
  free(s->bytes);
  free(s->frames);
}

/* What a client sends: HELLO, then two jobs, pings and the odd unknown or
 * ignorable frame. Small enough to try every pair of cut points. */
static void build_client_stream(stream_t *s, int pieces) {
  scp_buf_t b;
  scp_buf_init(&b, SCP_FRAME_MIN);
  memset(s, 0, sizeof *s);
  s->role = SCP_ROLE_SERVER;
  scp_hello_t h = {.version_min = 1, .version_max = 1, .max_frame = 4096};
  ASSERT_CODE_EQ(scp_enc_hello(&b, &h), 0, scp_err_name);
  take(s, &b);
  ignorable(s, 0x8001, 0);
  scp_job_begin_t jb = {.job_id = 7, .mode = 1, .r = 0.25, .point_count = 40,
                        .flags = SCP_JOB_NORMALS};
  ASSERT_CODE_EQ(scp_enc_job_begin(&b, &jb), 0, scp_err_name);
  take(s, &b);
  double xyz[3 * 40];
  for (int i = 0; i < 120; i++)
    xyz[i] = i * 0.25;
  for (int k = 0; k < pieces; k++) {
    uint32_t count = 40 / (uint32_t)pieces;
    ASSERT_CODE_EQ(scp_enc_points(&b, 7, (uint64_t)k * count,
                                  k % 2 ? SCP_F32_XYZ : SCP_F64_XYZ,
                                  xyz + 3 * k * count, count),
                   0, scp_err_name);
    take(s, &b);
    if (k == 0)
      ignorable(s, 0xFFFF, 13);
  }
  ASSERT_CODE_EQ(scp_enc_ping(&b, 99), 0, scp_err_name);
  unknown(s, 0x0099, 3);
  unknown(s, 0x0000, 0);
  ASSERT_CODE_EQ(scp_enc_stats_request(&b, 5), 0, scp_err_name);
  scp_job_end_t je = {.job_id = 7, .point_count = 40};
  ASSERT_CODE_EQ(scp_enc_job_end(&b, &je), 0, scp_err_name);
  jb.job_id = 8;
  ASSERT_CODE_EQ(scp_enc_job_begin(&b, &jb), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_enc_cancel(&b, 8), 0, scp_err_name);
  scp_error_t e = {.code = SCP_WIRE_UNKNOWN_TYPE, .ref_type = 0x8123};
  strcpy(e.message, "?");
  ASSERT_CODE_EQ(scp_enc_error(&b, &e), 0, scp_err_name);
  take(s, &b);
  ignorable(s, 0x8fff, 1);
  scp_buf_free(&b);
}

/* What a server sends: WELCOME raising the limit to 64 KiB, then frames
 * above the 4 KiB handshake limit, which the decoder accepts only because
 * the caller raises its limit after WELCOME. */
static void build_server_stream(stream_t *s) {
  scp_buf_t b;
  scp_buf_init(&b, 1u << 16);
  memset(s, 0, sizeof *s);
  s->role = SCP_ROLE_CLIENT;
  scp_welcome_t w = {.version = 1, .max_frame = 1u << 16, .max_jobs = 4,
                     .max_points = 1000000};
  ASSERT_CODE_EQ(scp_enc_welcome(&b, &w), 0, scp_err_name);
  scp_accepted_t a = {.job_id = 1, .queue_position = 2};
  ASSERT_CODE_EQ(scp_enc_accepted(&b, &a), 0, scp_err_name);
  scp_progress_t pr = {.job_id = 1, .stage = 1, .fraction = 0.5};
  ASSERT_CODE_EQ(scp_enc_progress(&b, &pr), 0, scp_err_name);
  take(s, &b);
  ignorable(s, 0x9000, 5000); /* larger than 4 KiB: skipped, not buffered */
  uint32_t tris[3 * 1000];
  for (uint32_t i = 0; i < 3 * 1000; i++)
    tris[i] = i;
  ASSERT_CODE_EQ(scp_enc_triangles(&b, 1, 0, tris, 1000), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_enc_triangles(&b, 1, 1000, tris, 1), 0, scp_err_name);
  int32_t g[2] = {0, -1};
  ASSERT_CODE_EQ(scp_enc_components(&b, 1, 0, g, 2), 0, scp_err_name);
  scp_value_t v[2] = {{.name = "triangles", .kind = SCP_KIND_U64, .v.u = 1001},
                      {.name = "genus", .kind = SCP_KIND_I64, .v.i = 0}};
  scp_job_done_t jd = {.job_id = 1, .triangles = 1001, .components = 2};
  ASSERT_CODE_EQ(scp_enc_job_done(&b, &jd, v, 2), 0, scp_err_name);
  scp_job_error_t je = {.job_id = 2, .code = SCP_WIRE_BUSY};
  strcpy(je.message, "queue full");
  ASSERT_CODE_EQ(scp_enc_job_error(&b, &je), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_enc_pong(&b, 99), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_enc_stats(&b, 5, v, 2), 0, scp_err_name);
  take(s, &b);
  scp_buf_free(&b);
}

/* Many small frames back to back. */
static void build_many(stream_t *s, int count) {
  scp_buf_t b;
  scp_buf_init(&b, SCP_FRAME_MIN);
  memset(s, 0, sizeof *s);
  s->role = SCP_ROLE_ANY;
  for (int i = 0; i < count; i++) {
    switch (i % 4) {
    case 0:
      ASSERT_CODE_EQ(scp_enc_ping(&b, (uint64_t)i), 0, scp_err_name);
      break;
    case 1:
      ASSERT_CODE_EQ(scp_enc_cancel(&b, (uint32_t)i), 0, scp_err_name);
      break;
    case 2: {
      double p[3] = {i, -i, 0.5};
      ASSERT_CODE_EQ(scp_enc_points(&b, 1, (uint64_t)i, SCP_F64_XYZ, p, 1), 0,
                     scp_err_name);
      break;
    }
    default: {
      scp_accepted_t a = {.job_id = (uint32_t)i, .queue_position = 0};
      ASSERT_CODE_EQ(scp_enc_accepted(&b, &a), 0, scp_err_name);
      break;
    }
    }
  }
  take(s, &b);
  scp_buf_free(&b);
}

/* Decoders run, streams tried, for the summary line. */
static unsigned long runs_, streams_;

/* Takes every frame the decoder has ready, checking each against the next
 * expected one; follows WELCOME with the limit it names. */
static void drain(scp_decoder_t *d, const stream_t *s, size_t *seen) {
  scp_frame_t f;
  int rc;
  while ((rc = scp_decoder_next(d, &f)) == 1) {
    if (*seen >= s->n)
      ASSERT_FAIL("frame %zu (type 0x%04x) beyond the %zu expected", *seen,
                  f.type, s->n);
    const expect_t *e = &s->frames[*seen];
    if (f.type != e->type || f.length != e->length ||
        memcmp(f.payload, s->bytes + e->offset + SCP_HEADER_SIZE,
               f.length) != 0)
      ASSERT_FAIL("frame %zu: got type 0x%04x length %u, expected type 0x%04x "
                  "length %u at offset %zu",
                  *seen, f.type, f.length, e->type, e->length, e->offset);
    if (f.type == SCP_WELCOME) {
      scp_welcome_t w;
      ASSERT_CODE_EQ(scp_parse_welcome(&f, &w), 0, scp_err_name);
      ASSERT_CODE_EQ(scp_decoder_set_max_frame(d, w.max_frame), 0,
                     scp_err_name);
    }
    (*seen)++;
  }
  if (rc != 0)
    ASSERT_FAIL("decoder error %s after %zu frames", scp_err_name(rc), *seen);
}

/* Feeds the stream cut at cuts[0] < cuts[1] < ... (each inside the
 * stream), draining after every feed or only at the end. */
static void run(const stream_t *s, const size_t *cuts, size_t ncuts,
                int drain_each) {
  scp_limits_t lim;
  scp_limits_init(&lim);
  lim.role = s->role;
  scp_decoder_t *d = scp_decoder_new(&lim);
  ASSERT_NOT_NULL(d);
  runs_++;
  size_t seen = 0, at = 0;
  for (size_t i = 0; i <= ncuts; i++) {
    size_t to = i < ncuts ? cuts[i] : s->len;
    int rc = scp_decoder_feed(d, s->bytes + at, to - at);
    if (rc != 0)
      ASSERT_FAIL("feed [%zu, %zu): %s", at, to, scp_err_name(rc));
    at = to;
    if (drain_each)
      drain(d, s, &seen);
  }
  drain(d, s, &seen);
  if (seen != s->n)
    ASSERT_FAIL("%zu frames decoded, %zu expected", seen, s->n);
  ASSERT_CODE_EQ(scp_decoder_eof(d), 0, scp_err_name);
  ASSERT_EQ(scp_decoder_pending(d), 0);
  scp_decoder_counters_t c;
  scp_decoder_get_counters(d, &c);
  ASSERT_EQ(c.frames, s->n);
  ASSERT_EQ(c.bytes, s->len);
  ASSERT_EQ(c.skipped, s->skipped);
  scp_decoder_free(d);
}

static void every_split(const stream_t *s) {
  printf("stream of %zu frames, %zu bytes (%zu skipped frames)\n", s->n,
         s->len, s->skipped);
  streams_++;
  run(s, NULL, 0, 1);
  for (size_t k = 1; k < s->len; k++) {
    run(s, &k, 1, 1);
    run(s, &k, 1, 0);
  }
}

static void every_pair(const stream_t *s) {
  printf("stream of %zu frames, %zu bytes: every pair of cuts\n", s->n,
         s->len);
  streams_++;
  for (size_t i = 1; i < s->len; i++)
    for (size_t j = i + 1; j < s->len; j++) {
      size_t cuts[2] = {i, j};
      run(s, cuts, 2, 1);
    }
}

static void byte_at_a_time(const stream_t *s) {
  size_t *cuts = malloc(s->len * sizeof *cuts);
  ASSERT_NOT_NULL(cuts);
  for (size_t i = 1; i < s->len; i++)
    cuts[i - 1] = i;
  run(s, cuts, s->len - 1, 1);
  run(s, cuts, s->len - 1, 0);
  free(cuts);
}

static void random_pieces(const stream_t *s, int rounds, uint64_t seed) {
  size_t *cuts = malloc(s->len * sizeof *cuts);
  ASSERT_NOT_NULL(cuts);
  for (int r = 0; r < rounds; r++) {
    size_t n = 0, at = 0;
    /* Pieces from 1 byte to a few frames, so that cuts fall inside
     * headers, inside payloads and between frames alike. */
    uint32_t scale = 1u << (pt_rand(&seed) % 14);
    for (;;) {
      at += 1 + pt_rand(&seed) % scale;
      if (at >= s->len)
        break;
      cuts[n++] = at;
    }
    run(s, cuts, n, r % 2 == 0);
  }
  free(cuts);
}

int main(void) {
  stream_t s;

  build_client_stream(&s, 2);
  every_split(&s);
  byte_at_a_time(&s);
  random_pieces(&s, 500, 1);
  stream_free(&s);

  /* A shorter stream: every pair of cut points as well. */
  build_client_stream(&s, 40);
  every_split(&s);
  stream_free(&s);
  build_many(&s, 6);
  every_pair(&s);
  stream_free(&s);

  build_server_stream(&s);
  every_split(&s);
  byte_at_a_time(&s);
  random_pieces(&s, 500, 2);
  stream_free(&s);

  build_many(&s, 5000);
  printf("stream of %zu frames, %zu bytes: byte at a time, random pieces\n",
         s.n, s.len);
  streams_++;
  byte_at_a_time(&s);
  random_pieces(&s, 50, 3);
  stream_free(&s);

  printf("%lu decoder runs over %lu streams\n", runs_, streams_);
  return sct_finish("proto_split");
}
