/*
 * libFuzzer target for the decoder and the parsers.
 *
 * Input: one byte choosing the role and the first frame limit, one byte
 * seeding how the stream is cut, then the stream. The stream is decoded
 * twice, once in a single feed and once in pieces; both runs must see the
 * same frames, parse results and final error. Every frame that parses must
 * be written back byte for byte by scp_enc_msg(), and every view is read
 * through its accessors, so that a parser accepting more than it checked
 * shows up as a mismatch or a sanitizer report.
 *
 * Built with -fsanitize=fuzzer as fuzz_proto_decoder, and without it as a
 * replay program that runs the seed corpus in every test build.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scproto.h"

#define FZ_ASSERT(cond)                                                        \
  do {                                                                         \
    if (!(cond)) {                                                             \
      fprintf(stderr, "%s:%d: %s\n", __FILE__, __LINE__, #cond);               \
      abort();                                                                 \
    }                                                                          \
  } while (0)

typedef struct trace {
  uint64_t hash;
  uint64_t frames;
} trace_t;

static void mix(trace_t *t, uint64_t v) {
  for (int i = 0; i < 8; i++) {
    t->hash ^= (uint8_t)(v >> (8 * i));
    t->hash *= 1099511628211u;
  }
}

/* Reads every element of a view, so the sanitizers see any read past the
 * frame. The sum goes into the trace to keep the reads alive. */
static uint64_t touch(const scp_msg_t *m) {
  uint64_t sum = 0;
  if (m->type == SCP_POINTS || m->type == SCP_NORMALS ||
      m->type == SCP_VERTICES || m->type == SCP_TRIANGLES ||
      m->type == SCP_COMPONENTS) {
    const scp_chunk_t *c = &m->u.chunk;
    for (uint32_t i = 0; i < c->count; i++) {
      double xyz[3];
      float f[3];
      uint32_t t[3];
      scp_chunk_xyz(c, i, xyz);
      scp_chunk_xyz_f32(c, i, f);
      scp_chunk_triangle(c, i, t);
      sum += (uint64_t)scp_chunk_i32(c, i) + t[0] + t[1] + t[2];
      sum += (xyz[0] == xyz[0]) + (f[2] == f[2]);
    }
  }
  const scp_values_t *v = NULL;
  if (m->type == SCP_JOB_DONE)
    v = &m->u.job_done.values;
  if (m->type == SCP_STATS)
    v = &m->u.stats.values;
  if (v) {
    scp_value_iter_t it;
    scp_value_t val;
    uint32_t n = 0;
    scp_values_begin(v, &it);
    while (scp_values_next(&it, &val)) {
      FZ_ASSERT(strlen(val.name) >= 1 && strlen(val.name) <= SCP_NAME_MAX);
      sum += val.v.u + val.kind;
      n++;
    }
    FZ_ASSERT(n == v->count);
    if (n > 0) {
      scp_values_begin(v, &it);
      FZ_ASSERT(scp_values_next(&it, &val));
      char first[SCP_NAME_MAX + 1];
      memcpy(first, val.name, strlen(val.name) + 1);
      FZ_ASSERT(scp_values_find(v, first, &it, &val));
    }
  }
  return sum;
}

/* The frame as it was on the wire, header included. */
static size_t frame_bytes(const scp_frame_t *f, uint8_t *out, size_t max) {
  size_t n = SCP_HEADER_SIZE + (size_t)f->length;
  FZ_ASSERT(n <= max);
  out[0] = (uint8_t)f->type;
  out[1] = (uint8_t)(f->type >> 8);
  out[2] = out[3] = 0;
  for (int i = 0; i < 4; i++)
    out[4 + i] = (uint8_t)(f->length >> (8 * i));
  memcpy(out + SCP_HEADER_SIZE, f->payload, f->length);
  return n;
}

static void check_frame(scp_decoder_t *d, int role, const scp_frame_t *f,
                        trace_t *t, uint8_t *scratch, size_t scratch_len) {
  scp_msg_t m;
  int rc = role == SCP_ROLE_ANY ? scp_parse(f, &m) : scp_parse_as(f, role, &m);
  mix(t, f->type);
  mix(t, f->length);
  mix(t, (uint64_t)(int64_t)rc);
  FZ_ASSERT(rc <= 0);
  FZ_ASSERT(scp_err_name(rc) != NULL && scp_strerror(rc) != NULL);
  (void)scp_err_to_wire(rc);

  uint32_t job;
  if (scp_frame_job_id(f, &job))
    mix(t, job);

  /* Parsers refuse frames of other types without looking further. */
  scp_chunk_t c;
  if (f->type != SCP_POINTS && f->type != SCP_TRIANGLES &&
      f->type != SCP_NORMALS && f->type != SCP_VERTICES &&
      f->type != SCP_COMPONENTS)
    FZ_ASSERT(scp_parse_chunk(f, &c) == SCP_EINVAL);
  scp_job_end_t je;
  if (f->type != SCP_JOB_END)
    FZ_ASSERT(scp_parse_job_end(f, &je) == SCP_EINVAL);

  if (rc != 0)
    return;
  mix(t, touch(&m));

  /* What parses is written back exactly; HELLO and WELCOME drop the tail
   * a later version may add. */
  scp_buf_t b;
  scp_buf_init(&b, SCP_FRAME_CEILING);
  int erc = scp_enc_msg(&b, &m);
  if (erc != 0) {
    fprintf(stderr, "type 0x%04x parsed but does not encode: %s\n", f->type,
            scp_err_name(erc));
    abort();
  }
  size_t n = frame_bytes(f, scratch, scratch_len);
  if (f->type == SCP_HELLO || f->type == SCP_WELCOME) {
    FZ_ASSERT(b.len >= SCP_HEADER_SIZE && b.len <= n);
    FZ_ASSERT(memcmp(b.data, scratch, 4) == 0);
    FZ_ASSERT(memcmp(b.data + SCP_HEADER_SIZE, scratch + SCP_HEADER_SIZE,
                     b.len - SCP_HEADER_SIZE) == 0);
  } else {
    FZ_ASSERT(b.len == n);
    FZ_ASSERT(memcmp(b.data, scratch, n) == 0);
  }
  scp_buf_free(&b);

  /* A client follows WELCOME's limit, as a real one would. */
  if (f->type == SCP_WELCOME)
    FZ_ASSERT(scp_decoder_set_max_frame(d, m.u.welcome.max_frame) == 0);
}

static void drain(scp_decoder_t *d, int role, trace_t *t, uint8_t *scratch,
                  size_t scratch_len) {
  scp_frame_t f;
  int rc;
  while ((rc = scp_decoder_next(d, &f)) == 1) {
    t->frames++;
    check_frame(d, role, &f, t, scratch, scratch_len);
  }
  FZ_ASSERT(rc <= 0);
  if (rc < 0) {
    /* Sticky. */
    FZ_ASSERT(scp_decoder_next(d, &f) == rc);
    FZ_ASSERT(scp_decoder_error(d) == rc);
  }
}

/* Decodes the stream cut into pieces (one piece when seed is 0). */
static trace_t run(const uint8_t *s, size_t n, int role, uint32_t max_frame,
                   unsigned seed) {
  scp_limits_t lim;
  scp_limits_init(&lim);
  lim.role = role;
  lim.max_frame = max_frame;
  scp_decoder_t *d = scp_decoder_new(&lim);
  FZ_ASSERT(d != NULL);
  size_t scratch_len = SCP_HEADER_SIZE + n;
  uint8_t *scratch = malloc(scratch_len);
  FZ_ASSERT(scratch != NULL);
  trace_t t = {14695981039346656037u, 0};
  uint64_t state = seed;
  size_t at = 0;
  while (at < n) {
    size_t piece = n - at;
    if (seed) {
      state = state * 6364136223846793005u + 1442695040888963407u;
      size_t cap = (size_t)1 << (seed % 11);
      size_t k = 1 + (size_t)(state >> 33) % cap;
      if (k < piece)
        piece = k;
    }
    int rc = scp_decoder_feed(d, s + at, piece);
    FZ_ASSERT(rc <= 0);
    at += piece;
    drain(d, role, &t, scratch, scratch_len);
  }
  int erc = scp_decoder_eof(d);
  mix(&t, (uint64_t)(int64_t)erc);
  mix(&t, (uint64_t)(int64_t)scp_decoder_error(d));
  if (erc == 0)
    FZ_ASSERT(scp_decoder_pending(d) == 0);
  scp_decoder_counters_t c;
  scp_decoder_get_counters(d, &c);
  FZ_ASSERT(c.frames == t.frames);
  mix(&t, c.skipped);
  free(scratch);
  scp_decoder_free(d);
  return t;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (size < 2)
    return 0;
  int role = data[0] % 3;
  uint32_t max_frame = (data[0] & 0x80) ? (1u << 16) : SCP_FRAME_MIN;
  unsigned seed = data[1];
  const uint8_t *s = data + 2;
  size_t n = size - 2;
  trace_t whole = run(s, n, role, max_frame, 0);
  trace_t pieces = run(s, n, role, max_frame, seed ? seed : 1);
  FZ_ASSERT(whole.frames == pieces.frames);
  FZ_ASSERT(whole.hash == pieces.hash);
  return 0;
}
