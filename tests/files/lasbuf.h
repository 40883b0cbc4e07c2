/*
 * Building LAS files byte by byte for the tests and benchmarks: the public
 * header of each version, optional variable-length records, and point
 * records of any format whose bytes after X, Y, Z are a pattern that must
 * not matter.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SC_TESTS_LASBUF_H
#define SC_TESTS_LASBUF_H

#include "plybuf.h"

/* The smallest record of each point data format, from the specification. */
static const unsigned min_len[11]
    __attribute__((unused)) = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};

/* The public header size of LAS 1.minor. */
static inline unsigned header_len(unsigned minor) {
  return minor >= 4 ? 375 : minor == 3 ? 235 : 227;
}

/* What a test file looks like; zeroed fields take the defaults. */
typedef struct las_spec {
  unsigned minor, format;
  unsigned record_len;   /* 0: the format's minimum */
  unsigned extra_header; /* bytes after the version's header */
  unsigned vlr_payload;  /* > 0: one variable-length record of this size */
  double scale[3], offset[3];
  size_t n;
  const int32_t *xyz; /* 3 * n values */
} las_spec_t;

static inline void poke(buf_t *b, size_t at, uint64_t v, size_t n) {
  ASSERT(at + n <= b->n);
  for (size_t i = 0; i < n; i++)
    b->p[at + i] = (unsigned char)(v >> (8 * i));
}

static inline void poke_f64(buf_t *b, size_t at, double d) {
  uint64_t w;
  memcpy(&w, &d, sizeof w);
  poke(b, at, w, 8);
}

static inline void put_zeros(buf_t *b, size_t n) {
  static const unsigned char zeros[64];
  for (; n > sizeof zeros; n -= sizeof zeros)
    buf_put(b, zeros, sizeof zeros);
  buf_put(b, zeros, n);
}

/* The fields the reader uses, at their offsets in the public header. */
enum {
  AT_VERSION = 24,
  AT_HEADER_SIZE = 94,
  AT_DATA_OFFSET = 96,
  AT_NUM_VLRS = 100,
  AT_FORMAT = 104,
  AT_RECORD_LEN = 105,
  AT_COUNT = 107,
  AT_SCALE = 131,
  AT_OFFSET = 155,
  AT_COUNT_64 = 247
};

/* A LAS file as a writer following the specification makes it. Bytes
 * after X, Y, Z are a pattern, never zero, that must not matter. */
static inline void las_build(buf_t *b, const las_spec_t *s) {
  unsigned hsize = header_len(s->minor) + s->extra_header;
  unsigned vlr = s->vlr_payload ? 54 + s->vlr_payload : 0;
  unsigned rlen = s->record_len ? s->record_len : min_len[s->format];
  *b = (buf_t){0};
  put_zeros(b, hsize);
  memcpy(b->p, "LASF", 4);
  memcpy(b->p + 26, "shortcrust test", 15);
  b->p[AT_VERSION] = 1;
  b->p[AT_VERSION + 1] = (unsigned char)s->minor;
  poke(b, AT_HEADER_SIZE, hsize, 2);
  poke(b, AT_DATA_OFFSET, hsize + vlr, 4);
  poke(b, AT_NUM_VLRS, s->vlr_payload ? 1 : 0, 4);
  b->p[AT_FORMAT] = (unsigned char)s->format;
  poke(b, AT_RECORD_LEN, rlen, 2);
  /* 1.4 keeps the legacy count 0 for formats 6 to 10. */
  if (s->minor < 4 || s->format < 6)
    poke(b, AT_COUNT, s->n, 4);
  if (s->minor >= 4)
    poke(b, AT_COUNT_64, s->n, 8);
  for (int a = 0; a < 3; a++) {
    poke_f64(b, AT_SCALE + 8 * a, s->scale[a]);
    poke_f64(b, AT_OFFSET + 8 * a, s->offset[a]);
  }
  if (vlr > 0) {
    unsigned char head[54];
    memset(head, 0, sizeof head);
    memcpy(head + 2, "shortcrust", 10);
    head[18] = 7; /* record id */
    head[20] = (unsigned char)s->vlr_payload;
    head[21] = (unsigned char)(s->vlr_payload >> 8);
    buf_put(b, head, sizeof head);
    for (unsigned i = 0; i < s->vlr_payload; i++)
      buf_put(b, "V", 1);
  }
  unsigned char rec[256];
  ASSERT(rlen <= sizeof rec);
  for (size_t k = 0; k < s->n; k++) {
    for (unsigned j = 0; j < rlen; j++)
      rec[j] = (unsigned char)(1 + (k * 7 + j * 13) % 255);
    for (int a = 0; a < 3; a++)
      for (int i = 0; i < 4; i++)
        rec[4 * a + i] =
            (unsigned char)((uint32_t)s->xyz[3 * k + a] >> (8 * i));
    buf_put(b, rec, rlen);
  }
}

/* The coordinate LAS defines, in two statements so that no compiler fuses
 * them into one fma. */
static inline double las_value(int32_t v, double scale, double offset) {
  double scaled = (double)v * scale;
  return scaled + offset;
}

#endif /* SC_TESTS_LASBUF_H */
