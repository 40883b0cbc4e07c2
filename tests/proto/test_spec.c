/*
 * The byte examples of PROTOCOL.md section 11, read from the document
 * itself, are exactly what the encoder writes for the messages they
 * describe, and decode back to them. A change to either side that breaks
 * the other fails here.
 *
 * Usage: test_proto_spec path/to/PROTOCOL.md
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <ctype.h>

#include "frames.h"

typedef struct example {
  char dir;       /* 'C' or 'S' */
  char name[32];
  uint8_t bytes[256];
  size_t len;
} example_t;

static int hexval(int c) {
  if (c >= '0' && c <= '9')
    return c - '0';
  if (c >= 'a' && c <= 'f')
    return c - 'a' + 10;
  if (c >= 'A' && c <= 'F')
    return c - 'A' + 10;
  return -1;
}

/* Appends the hex byte pairs of a line; returns 0 if the line holds
 * anything else, so that prose after a frame ends it. */
static int hex_line(const char *s, example_t *e) {
  size_t start = e->len;
  while (*s) {
    if (isspace((unsigned char)*s)) {
      s++;
      continue;
    }
    int hi = hexval(s[0]), lo = s[0] ? hexval(s[1]) : -1;
    if (hi < 0 || lo < 0 || (s[2] && !isspace((unsigned char)s[2]))) {
      e->len = start;
      return 0;
    }
    ASSERT_LT(e->len, sizeof e->bytes);
    e->bytes[e->len++] = (uint8_t)(hi << 4 | lo);
    s += 2;
  }
  return e->len > start;
}

/* Reads every "C: NAME hex..." / "S: NAME hex..." frame of section 11. */
static size_t read_examples(const char *path, example_t *out, size_t max) {
  FILE *fp = fopen(path, "r");
  if (!fp)
    ASSERT_FAIL("cannot open %s", path);
  char line[512];
  int in_section = 0;
  size_t n = 0;
  example_t *cur = NULL;
  while (fgets(line, sizeof line, fp)) {
    if (strncmp(line, "## ", 3) == 0) {
      in_section = strncmp(line, "## 11.", 6) == 0;
      cur = NULL;
      continue;
    }
    if (!in_section)
      continue;
    if ((line[0] == 'C' || line[0] == 'S') && line[1] == ':') {
      ASSERT_LT(n, max);
      cur = &out[n];
      memset(cur, 0, sizeof *cur);
      cur->dir = line[0];
      const char *p = line + 2;
      while (*p == ' ')
        p++;
      size_t k = 0;
      while ((isupper((unsigned char)*p) || *p == '_') &&
             k < sizeof cur->name - 1)
        cur->name[k++] = *p++;
      ASSERT_GT(k, 0);
      if (!hex_line(p, cur))
        ASSERT_FAIL("example %s: no bytes on its first line", cur->name);
      n++;
      continue;
    }
    if (cur && !hex_line(line, cur))
      cur = NULL;
  }
  fclose(fp);
  return n;
}

/* The messages the examples describe, in their order. */
static void expected(scp_buf_t *b, const char *name) {
  if (strcmp(name, "HELLO") == 0) {
    scp_hello_t h = {.version_min = 1, .version_max = 1, .features = 0,
                     .max_frame = 1u << 20};
    ASSERT_CODE_EQ(scp_enc_hello(b, &h), 0, scp_err_name);
  } else if (strcmp(name, "WELCOME") == 0) {
    scp_welcome_t w = {.version = 1, .features = 0, .max_frame = 1u << 20,
                       .max_jobs = 8, .max_points = 10000000};
    ASSERT_CODE_EQ(scp_enc_welcome(b, &w), 0, scp_err_name);
  } else if (strcmp(name, "JOB_BEGIN") == 0) {
    scp_job_begin_t jb = {.job_id = 7, .mode = SCP_MODE_COCONE, .r = 0.25,
                          .theta = 0, .point_count = 4,
                          .flags = SCP_JOB_NORMALS};
    ASSERT_CODE_EQ(scp_enc_job_begin(b, &jb), 0, scp_err_name);
  } else if (strcmp(name, "POINTS") == 0) {
    float p[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    ASSERT_CODE_EQ(scp_enc_points_f32(b, 7, 0, p, 4), 0, scp_err_name);
  } else if (strcmp(name, "JOB_END") == 0) {
    scp_job_end_t je = {.job_id = 7, .point_count = 4};
    ASSERT_CODE_EQ(scp_enc_job_end(b, &je), 0, scp_err_name);
  } else if (strcmp(name, "ACCEPTED") == 0) {
    scp_accepted_t a = {.job_id = 7, .queue_position = 0};
    ASSERT_CODE_EQ(scp_enc_accepted(b, &a), 0, scp_err_name);
  } else if (strcmp(name, "TRIANGLES") == 0) {
    /* In the order the daemon sends them (canonical_order() in the core:
     * each rotated to its smallest index, then sorted). */
    uint32_t t[12] = {0, 1, 3, 0, 2, 1, 0, 3, 2, 1, 2, 3};
    ASSERT_CODE_EQ(scp_enc_triangles(b, 7, 0, t, 4), 0, scp_err_name);
  } else if (strcmp(name, "COMPONENTS") == 0) {
    int32_t genus[1] = {0};
    ASSERT_CODE_EQ(scp_enc_components(b, 7, 0, genus, 1), 0, scp_err_name);
  } else if (strcmp(name, "JOB_DONE") == 0) {
    scp_value_t v = {.name = "triangles", .kind = SCP_KIND_U64, .v.u = 4};
    scp_job_done_t jd = {.job_id = 7, .triangles = 4, .normals = 4,
                         .components = 1};
    ASSERT_CODE_EQ(scp_enc_job_done(b, &jd, &v, 1), 0, scp_err_name);
  } else {
    ASSERT_FAIL("example %s is not known to this test", name);
  }
}

/* The tetrahedron of the example is closed and oriented outward: each
 * edge is used once in each direction. */
static void check_tetrahedron(const scp_chunk_t *c) {
  int used[4][4] = {{0}};
  for (uint32_t i = 0; i < c->count; i++) {
    uint32_t t[3];
    scp_chunk_triangle(c, i, t);
    for (int k = 0; k < 3; k++) {
      ASSERT_LT(t[k], 4);
      used[t[k]][t[(k + 1) % 3]]++;
    }
  }
  for (int a = 0; a < 4; a++)
    for (int b2 = 0; b2 < 4; b2++)
      if (a != b2)
        ASSERT_EQ(used[a][b2], 1);
}

/* The stream rules of sections 3.1, 3.2 and 8.2, as a server's decoder
 * applies them: frames after HELLO are judged by the limit set once
 * WELCOME is out, even when they came in the same read; a WELCOME from a
 * client is a second handshake frame (fatal), not a misdirected one; and a
 * stream that ends inside a frame is an end of stream, not a frame. */
static void stream_rules(void) {
  scp_limits_t lim;
  scp_limits_init(&lim);
  lim.role = SCP_ROLE_SERVER;
  scp_buf_t b;
  scp_buf_init(&b, 1u << 20);
  scp_hello_t h = {.version_min = 1, .version_max = 1, .max_frame = 1u << 20};
  ASSERT_CODE_EQ(scp_enc_hello(&b, &h), 0, scp_err_name);
  double xyz[3 * 400] = {0};
  ASSERT_CODE_EQ(scp_enc_points(&b, 1, 0, SCP_F64_XYZ, xyz, 400), 0,
                 scp_err_name);
  ASSERT_GT(b.len, SCP_FRAME_MIN);
  scp_welcome_t w = {
      .version = 1, .max_frame = 1u << 20, .max_jobs = 1, .max_points = 4};
  ASSERT_CODE_EQ(scp_enc_welcome(&b, &w), 0, scp_err_name);

  scp_decoder_t *d = scp_decoder_new(&lim);
  ASSERT_CODE_EQ(scp_decoder_feed(d, b.data, b.len), 0, scp_err_name);
  scp_frame_t f;
  ASSERT_EQ(scp_decoder_next(d, &f), 1);
  ASSERT_EQ(f.type, SCP_HELLO);
  ASSERT_CODE_EQ(scp_decoder_set_max_frame(d, 1u << 20), 0, scp_err_name);
  ASSERT_EQ(scp_decoder_next(d, &f), 1);
  ASSERT_EQ(f.type, SCP_POINTS);
  ASSERT_CODE_EQ(scp_decoder_next(d, &f), SCP_EHANDSHAKE, scp_err_name);
  ASSERT(scp_err_is_fatal(SCP_EHANDSHAKE));
  ASSERT_EQ(scp_err_to_wire(SCP_EHANDSHAKE), SCP_WIRE_PROTOCOL);
  scp_decoder_free(d);

  d = scp_decoder_new(&lim);
  ASSERT_CODE_EQ(scp_decoder_feed(d, b.data, 20), 0, scp_err_name);
  ASSERT_EQ(scp_decoder_next(d, &f), 0);
  ASSERT_CODE_EQ(scp_decoder_eof(d), SCP_ETRUNCATED, scp_err_name);
  scp_decoder_free(d);
  scp_buf_free(&b);
}

int main(int argc, char **argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: %s PROTOCOL.md\n", argv[0]);
    return 2;
  }
  example_t ex[16];
  size_t n = read_examples(argv[1], ex, 16);
  static const char *const order[] = {
      "HELLO",    "WELCOME",   "JOB_BEGIN",  "POINTS",  "JOB_END",
      "ACCEPTED", "TRIANGLES", "COMPONENTS", "JOB_DONE"};
  ASSERT_EQ(n, sizeof order / sizeof order[0]);
  scp_job_begin_t begin = {0};
  uint64_t triangles = 0, components = 0;

  for (size_t i = 0; i < n; i++) {
    ASSERT_STR_EQ(ex[i].name, order[i]);
    scp_buf_t b;
    scp_buf_init(&b, 1u << 20);
    expected(&b, ex[i].name);
    if (b.len != ex[i].len || memcmp(b.data, ex[i].bytes, b.len) != 0)
      fprintf(stderr, "example %s differs from the encoder\n", ex[i].name);
    ASSERT_MEM_EQ(ex[i].bytes, ex[i].len, b.data, b.len);

    /* The direction in the document matches who may send the type. */
    scp_frame_t f;
    scp_decoder_t *d = pt_decode_one(ex[i].bytes, ex[i].len, &f);
    ASSERT_STR_EQ(scp_type_name(f.type), ex[i].name);
    int from = ex[i].dir == 'C' ? SCP_FROM_CLIENT : SCP_FROM_SERVER;
    ASSERT(scp_type_senders(f.type) & from);
    scp_msg_t m;
    ASSERT_CODE_EQ(scp_parse_as(&f,
                                from == SCP_FROM_CLIENT ? SCP_ROLE_SERVER
                                                        : SCP_ROLE_CLIENT,
                                &m),
                   0, scp_err_name);
    /* The examples form one job, so they must obey the job rules too. */
    if (f.type == SCP_JOB_BEGIN)
      begin = m.u.job_begin;
    if (f.type == SCP_TRIANGLES) {
      check_tetrahedron(&m.u.chunk);
      triangles += m.u.chunk.count;
    }
    if (f.type == SCP_COMPONENTS)
      components += m.u.chunk.count;
    if (f.type == SCP_JOB_DONE) {
      ASSERT_EQ(m.u.job_done.job_id, begin.job_id);
      ASSERT_EQ(m.u.job_done.triangles, triangles);
      ASSERT_EQ(m.u.job_done.components, components);
      ASSERT_EQ(m.u.job_done.normals,
                (begin.flags & SCP_JOB_NORMALS) ? begin.point_count : 0);
      scp_value_iter_t it;
      scp_value_t v;
      ASSERT(scp_values_find(&m.u.job_done.values, "triangles", &it, &v));
      ASSERT_EQ(v.v.u, m.u.job_done.triangles);
    }
    scp_decoder_free(d);
    scp_buf_free(&b);
  }
  stream_rules();
  return sct_finish("proto_spec");
}
