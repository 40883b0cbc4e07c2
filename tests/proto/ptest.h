/*
 * Assertions for the protocol tests. Each prints both sides and the place,
 * then exits, so a failing ctest run says what differed without a debugger.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SC_TESTS_PTEST_H
#define SC_TESTS_PTEST_H

#include <inttypes.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scproto.h"

/* Counts the assertions that passed, so each program can say how much it
 * checked. */
static unsigned long pt_checks_;

#define PT_FAIL_(...)                                                          \
  do {                                                                         \
    fprintf(stderr, "%s:%d: ", __FILE__, __LINE__);                            \
    fprintf(stderr, __VA_ARGS__);                                              \
    fputc('\n', stderr);                                                       \
    exit(1);                                                                   \
  } while (0)

#define CHECK(cond)                                                            \
  do {                                                                         \
    if (!(cond))                                                               \
      PT_FAIL_("check failed: %s", #cond);                                     \
    pt_checks_++;                                                              \
  } while (0)

#define CHECK_INT_EQ(a, b)                                                     \
  do {                                                                         \
    long long a_ = (long long)(a), b_ = (long long)(b);                        \
    if (a_ != b_)                                                              \
      PT_FAIL_("%s == %s failed: %lld != %lld", #a, #b, a_, b_);               \
    pt_checks_++;                                                              \
  } while (0)

#define CHECK_U64_EQ(a, b)                                                     \
  do {                                                                         \
    uint64_t a_ = (uint64_t)(a), b_ = (uint64_t)(b);                           \
    if (a_ != b_)                                                              \
      PT_FAIL_("%s == %s failed: %" PRIu64 " != %" PRIu64, #a, #b, a_, b_);    \
    pt_checks_++;                                                              \
  } while (0)

/* Library return codes, shown by name. */
#define CHECK_RC(a, b)                                                         \
  do {                                                                         \
    int a_ = (a), b_ = (b);                                                    \
    if (a_ != b_)                                                              \
      PT_FAIL_("%s == %s failed: %d (%s) != %d (%s)", #a, #b, a_,              \
               scp_err_name(a_), b_, scp_err_name(b_));                        \
    pt_checks_++;                                                              \
  } while (0)

/* Equal as bit patterns, so that it also holds for NaN and tells -0 from 0. */
#define CHECK_DBL_SAME(a, b)                                                   \
  do {                                                                         \
    double a_ = (a), b_ = (b);                                                 \
    if (memcmp(&a_, &b_, sizeof a_) != 0)                                      \
      PT_FAIL_("%s == %s failed: %.17g != %.17g", #a, #b, a_, b_);             \
    pt_checks_++;                                                              \
  } while (0)

#define CHECK_STR_EQ(a, b)                                                     \
  do {                                                                         \
    const char *a_ = (a), *b_ = (b);                                           \
    if (strcmp(a_, b_) != 0)                                                   \
      PT_FAIL_("%s == %s failed: \"%s\" != \"%s\"", #a, #b, a_, b_);           \
    pt_checks_++;                                                              \
  } while (0)

/* Byte arrays: reports the lengths, then the first differing offset with
 * both bytes. */
#define CHECK_MEM_EQ(a, alen, b, blen)                                         \
  do {                                                                         \
    const uint8_t *a_ = (const uint8_t *)(a), *b_ = (const uint8_t *)(b);      \
    size_t al_ = (alen), bl_ = (blen);                                         \
    if (al_ != bl_)                                                            \
      PT_FAIL_("%s and %s differ in length: %zu != %zu", #a, #b, al_, bl_);    \
    for (size_t i_ = 0; i_ < al_; i_++)                                        \
      if (a_[i_] != b_[i_])                                                    \
        PT_FAIL_("%s and %s differ at byte %zu: %02x != %02x", #a, #b, i_,     \
                 a_[i_], b_[i_]);                                              \
    pt_checks_++;                                                              \
  } while (0)

static inline void pt_done(const char *name) {
  printf("%s: %lu checks passed\n", name, pt_checks_);
}

/* A small deterministic generator, so every run splits streams the same
 * way and a failure can be replayed. */
static inline uint32_t pt_rand(uint64_t *state) {
  *state = *state * 6364136223846793005u + 1442695040888963407u;
  return (uint32_t)(*state >> 33);
}

/* Writes a frame header by hand, for frames the encoder refuses to make. */
static inline void pt_header(uint8_t *p, uint16_t type, uint16_t flags,
                             uint32_t length) {
  p[0] = (uint8_t)type;
  p[1] = (uint8_t)(type >> 8);
  p[2] = (uint8_t)flags;
  p[3] = (uint8_t)(flags >> 8);
  for (int i = 0; i < 4; i++)
    p[4 + i] = (uint8_t)(length >> (8 * i));
}

static inline void pt_put32(uint8_t *p, uint32_t v) {
  for (int i = 0; i < 4; i++)
    p[i] = (uint8_t)(v >> (8 * i));
}

static inline void pt_put64(uint8_t *p, uint64_t v) {
  for (int i = 0; i < 8; i++)
    p[i] = (uint8_t)(v >> (8 * i));
}

/* Decodes one whole buffer holding exactly one frame with a fresh decoder
 * (any role, the largest limit) and returns it; the decoder is returned
 * too, since the frame points into it. */
static inline scp_decoder_t *pt_decode_one(const uint8_t *bytes, size_t len,
                                           scp_frame_t *frame) {
  scp_limits_t lim;
  scp_limits_init(&lim);
  lim.max_frame = SCP_FRAME_CEILING;
  scp_decoder_t *d = scp_decoder_new(&lim);
  if (!d)
    PT_FAIL_("scp_decoder_new failed");
  int rc = scp_decoder_feed(d, bytes, len);
  if (rc)
    PT_FAIL_("feed: %s", scp_err_name(rc));
  rc = scp_decoder_next(d, frame);
  if (rc != 1)
    PT_FAIL_("next: %d (%s), expected one frame", rc, scp_err_name(rc));
  if (scp_decoder_pending(d) != 0)
    PT_FAIL_("%zu bytes left after the frame", scp_decoder_pending(d));
  pt_checks_ += 3;
  return d;
}

#endif /* SC_TESTS_PTEST_H */
