/*
 * Little-endian loads and stores, private to proto/.
 *
 * Integers are assembled from single bytes and floats are moved to and from
 * their integer bit patterns with memcpy, so nothing here depends on the
 * host's byte order or on the alignment of the buffer, and nothing breaks
 * strict aliasing. Compilers turn each helper into a single move on
 * little-endian machines.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SCP_WIRE_H
#define SCP_WIRE_H

#include <stdint.h>
#include <string.h>

#include "scproto.h"

static inline uint16_t scp__ld16(const uint8_t *p) {
  return (uint16_t)(p[0] | (p[1] << 8));
}

static inline uint32_t scp__ld32(const uint8_t *p) {
  return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) |
         ((uint32_t)p[3] << 24);
}

static inline uint64_t scp__ld64(const uint8_t *p) {
  return (uint64_t)scp__ld32(p) | ((uint64_t)scp__ld32(p + 4) << 32);
}

static inline void scp__st16(uint8_t *p, uint16_t v) {
  p[0] = (uint8_t)v;
  p[1] = (uint8_t)(v >> 8);
}

static inline void scp__st32(uint8_t *p, uint32_t v) {
  p[0] = (uint8_t)v;
  p[1] = (uint8_t)(v >> 8);
  p[2] = (uint8_t)(v >> 16);
  p[3] = (uint8_t)(v >> 24);
}

static inline void scp__st64(uint8_t *p, uint64_t v) {
  scp__st32(p, (uint32_t)v);
  scp__st32(p + 4, (uint32_t)(v >> 32));
}

/* Floats go through their bit patterns, which keeps NaN payloads intact. */
static inline float scp__ldf32(const uint8_t *p) {
  uint32_t u = scp__ld32(p);
  float f;
  memcpy(&f, &u, sizeof f);
  return f;
}

static inline double scp__ldf64(const uint8_t *p) {
  uint64_t u = scp__ld64(p);
  double d;
  memcpy(&d, &u, sizeof d);
  return d;
}

static inline void scp__stf32(uint8_t *p, float f) {
  uint32_t u;
  memcpy(&u, &f, sizeof u);
  scp__st32(p, u);
}

static inline void scp__stf64(uint8_t *p, double d) {
  uint64_t u;
  memcpy(&u, &d, sizeof u);
  scp__st64(p, u);
}

/*
 * Field checks shared by the encoder and the parsers, so that what one
 * writes the other accepts and neither can drift from PROTOCOL.md. Each
 * returns 0 or the SCP_E* code of the first field that is wrong.
 */
int scp__name_ok(const char *name, size_t len);
int scp__text_ok(const char *text, size_t len);
int scp__chunk_format_ok(uint16_t type, uint32_t format);
int scp__check_hello(const scp_hello_t *m);
int scp__check_welcome(const scp_welcome_t *m);
int scp__check_error_fields(const scp_error_t *m);
int scp__check_job_begin(const scp_job_begin_t *m);
int scp__check_job_id(uint32_t job_id);
int scp__check_progress(const scp_progress_t *m);
int scp__check_job_error_fields(const scp_job_error_t *m);
/* A value list in wire form: SCP_ELENGTH when its entries do not exactly
 * fill len bytes, SCP_ERANGE for a bad kind or name. */
int scp__values_check(const uint8_t *p, size_t len, uint32_t count);
int scp__check_chunk_fields(uint16_t type, uint32_t job_id, uint32_t count,
                            uint64_t first, uint32_t format);

#endif /* SCP_WIRE_H */
