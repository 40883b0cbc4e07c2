/*
 * What the protocol tests share besides the assertions (sct_assert.h): a
 * replayable random generator, frames written by hand, and decoding one
 * frame from a buffer.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SC_TESTS_FRAMES_H
#define SC_TESTS_FRAMES_H

#include <inttypes.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scproto.h"
#include "sct_assert.h"

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
  ASSERT_NOT_NULL(d);
  ASSERT_CODE_EQ(scp_decoder_feed(d, bytes, len), SCP_OK, scp_err_name);
  /* 1: one frame; anything else is an error code. */
  ASSERT_CODE_EQ(scp_decoder_next(d, frame), 1, scp_err_name);
  ASSERT_EQ(scp_decoder_pending(d), 0);
  return d;
}

#endif /* SC_TESTS_FRAMES_H */
