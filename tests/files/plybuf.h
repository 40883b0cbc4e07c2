/*
 * Building PLY files byte by byte for the reader tests: a growing buffer,
 * and values of every PLY scalar type in either byte order or as text.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SC_TESTS_PLYBUF_H
#define SC_TESTS_PLYBUF_H

#include "tmpdir.h"

#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct buf {
  unsigned char *p;
  size_t n, cap;
} buf_t;

static inline void buf_put(buf_t *b, const void *data, size_t len) {
  if (b->n + len + 1 > b->cap) {
    size_t cap = b->cap ? b->cap : 256;
    while (cap < b->n + len + 1)
      cap *= 2;
    unsigned char *p = realloc(b->p, cap);
    if (p == NULL)
      ASSERT_FAIL("out of memory building a test file");
    b->p = p;
    b->cap = cap;
  }
  memcpy(b->p + b->n, data, len);
  b->n += len;
  b->p[b->n] = 0;
}

__attribute__((format(printf, 2, 3))) static inline void
buf_printf(buf_t *b, const char *fmt, ...) {
  char tmp[512];
  va_list ap;
  va_start(ap, fmt);
  int n = vsnprintf(tmp, sizeof tmp, fmt, ap);
  va_end(ap);
  if (n < 0 || (size_t)n >= sizeof tmp)
    ASSERT_FAIL("buf_printf: line too long");
  buf_put(b, tmp, (size_t)n);
}

static inline void buf_free(buf_t *b) {
  free(b->p);
  b->p = NULL;
  b->n = b->cap = 0;
}

/* The PLY scalar types, with their two names each. */
typedef enum ty { I8, U8, I16, U16, I32, U32, F32, F64, TY_COUNT } ty_t;

static const char *const ty_name[TY_COUNT] = {
    "char", "uchar", "short", "ushort", "int", "uint", "float", "double"};
static const char *const ty_alias[TY_COUNT] = {"int8",    "uint8",  "int16",
                                               "uint16",  "int32",  "uint32",
                                               "float32", "float64"};
static const size_t ty_size[TY_COUNT] = {1, 1, 2, 2, 4, 4, 4, 8};

/* v converted to the type, as the reader must return it. */
static inline double ty_round(ty_t t, double v) {
  switch (t) {
  case I8:
    return (double)(int8_t)v;
  case U8:
    return (double)(uint8_t)v;
  case I16:
    return (double)(int16_t)v;
  case U16:
    return (double)(uint16_t)v;
  case I32:
    return (double)(int32_t)v;
  case U32:
    return (double)(uint32_t)v;
  case F32:
    return (double)(float)v;
  default:
    return v;
  }
}

enum { FMT_ASCII, FMT_LE, FMT_BE, FMT_COUNT };
static const char *const fmt_name[FMT_COUNT] = {"ascii", "binary_little_endian",
                                                "binary_big_endian"};

/* Appends v as type t: a token and a space in ascii, else its bytes. */
static inline void buf_val(buf_t *b, int fmt, ty_t t, double v) {
  if (fmt == FMT_ASCII) {
    if (t == F32 || t == F64)
      buf_printf(b, "%.17g ", ty_round(t, v));
    else
      buf_printf(b, "%lld ", (long long)ty_round(t, v));
    return;
  }
  uint64_t bits;
  if (t == F32) {
    float f = (float)v;
    uint32_t w;
    memcpy(&w, &f, sizeof w);
    bits = w;
  } else if (t == F64) {
    memcpy(&bits, &v, sizeof bits);
  } else {
    bits = (uint64_t)(int64_t)ty_round(t, v);
  }
  unsigned char bytes[8];
  size_t n = ty_size[t];
  for (size_t i = 0; i < n; i++)
    bytes[fmt == FMT_BE ? n - 1 - i : i] = (unsigned char)(bits >> (8 * i));
  buf_put(b, bytes, n);
}

/* Ends an ascii record; binary records have no separator. */
static inline void buf_eol(buf_t *b, int fmt) {
  if (fmt == FMT_ASCII)
    buf_put(b, "\n", 1);
}

static inline void buf_write(const buf_t *b, const char *path) {
  write_bytes(path, b->p, b->n);
}

#endif /* SC_TESTS_PLYBUF_H */
