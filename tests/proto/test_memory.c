/*
 * The decoder's memory follows the bytes it is fed, never a length field:
 * a header claiming a huge frame costs nothing until the bytes arrive, an
 * ignorable frame is dropped without being buffered, a drained decoder
 * holds one partial frame plus one feed, and an idle decoder gives a large
 * buffer back.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "frames.h"

static uint64_t buffer_of(const scp_decoder_t *d) {
  scp_decoder_counters_t c;
  scp_decoder_get_counters(d, &c);
  return c.buffer;
}

static scp_decoder_t *decoder(uint32_t max_frame) {
  scp_limits_t lim;
  scp_limits_init(&lim);
  lim.max_frame = max_frame;
  scp_decoder_t *d = scp_decoder_new(&lim);
  ASSERT_NOT_NULL(d);
  return d;
}

static void test_claimed_length(void) {
  /* The largest frame the protocol allows, announced and never sent. */
  scp_decoder_t *d = decoder(SCP_FRAME_CEILING);
  uint8_t h[SCP_HEADER_SIZE + 24];
  pt_header(h, SCP_POINTS, 0, SCP_FRAME_CEILING - SCP_HEADER_SIZE);
  memset(h + SCP_HEADER_SIZE, 0, 24);
  scp_frame_t f;
  ASSERT_CODE_EQ(scp_decoder_feed(d, h, sizeof h), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_next(d, &f), 0, scp_err_name);
  ASSERT_LE(buffer_of(d), SCP_FRAME_MIN);
  ASSERT_EQ(scp_decoder_pending(d), sizeof h);
  scp_decoder_free(d);
}

static void test_ignorable_not_buffered(void) {
  scp_decoder_t *d = decoder(1u << 16);
  uint8_t piece[1000];
  memset(piece, 0x11, sizeof piece);
  pt_header(piece, 0x8765, 0, 60000);
  size_t total = SCP_HEADER_SIZE + 60000, sent = 0;
  scp_frame_t f;
  while (sent < total) {
    size_t n = total - sent < sizeof piece ? total - sent : sizeof piece;
    ASSERT_CODE_EQ(scp_decoder_feed(d, piece, n), 0, scp_err_name);
    ASSERT_CODE_EQ(scp_decoder_next(d, &f), 0, scp_err_name);
    ASSERT_EQ(scp_decoder_pending(d), 0);
    ASSERT_LE(buffer_of(d), SCP_FRAME_MIN);
    sent += n;
    memset(piece, 0x22, SCP_HEADER_SIZE); /* later pieces are payload */
  }
  /* The next frame is read normally. */
  uint8_t ping[16];
  pt_header(ping, SCP_PING, 0, 8);
  memset(ping + 8, 0, 8);
  ASSERT_CODE_EQ(scp_decoder_feed(d, ping, sizeof ping), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_next(d, &f), 1, scp_err_name);
  ASSERT_EQ(f.type, SCP_PING);
  ASSERT_CODE_EQ(scp_decoder_eof(d), 0, scp_err_name);
  scp_decoder_free(d);
}

static void test_large_frame_then_idle(void) {
  const uint32_t limit = 2u << 20;
  const uint32_t npoints = 43689; /* about 1 MiB as F64_XYZ */
  double *xyz = calloc(3 * (size_t)npoints, sizeof *xyz);
  ASSERT_NOT_NULL(xyz);
  scp_buf_t b;
  scp_buf_init(&b, limit);
  ASSERT_CODE_EQ(scp_enc_points(&b, 1, 0, SCP_F64_XYZ, xyz, npoints), 0,
                 scp_err_name);
  ASSERT_CODE_EQ(scp_enc_ping(&b, 5), 0, scp_err_name);
  free(xyz);

  scp_decoder_t *d = decoder(limit);
  const size_t piece = 64 * 1024;
  size_t frame = SCP_HEADER_SIZE + SCP_CHUNK_HEADER + 24 * (size_t)npoints;
  uint64_t peak = 0;
  int frames = 0;
  scp_frame_t f;
  for (size_t at = 0; at < b.len; at += piece) {
    size_t n = b.len - at < piece ? b.len - at : piece;
    ASSERT_CODE_EQ(scp_decoder_feed(d, b.data + at, n), 0, scp_err_name);
    /* One partial frame plus one feed, with room to double. */
    ASSERT_LE(scp_decoder_pending(d), frame + piece);
    uint64_t now = buffer_of(d);
    if (now > peak)
      peak = now;
    int rc;
    while ((rc = scp_decoder_next(d, &f)) == 1)
      frames++;
    ASSERT_CODE_EQ(rc, 0, scp_err_name);
  }
  ASSERT_EQ(frames, 2);
  ASSERT_GE(peak, frame);
  ASSERT_LE(peak, 2 * (frame + piece));
  ASSERT_CODE_EQ(scp_decoder_eof(d), 0, scp_err_name);

  /* Idle now: the next small feed finds the big buffer given back. */
  ASSERT_CODE_EQ(scp_decoder_feed(d, b.data + b.len - 16, 16), 0, scp_err_name);
  ASSERT_LE(buffer_of(d), 64 * 1024);
  ASSERT_CODE_EQ(scp_decoder_next(d, &f), 1, scp_err_name);
  ASSERT_EQ(f.type, SCP_PING);
  scp_decoder_free(d);
  scp_buf_free(&b);
}

int main(void) {
  test_claimed_length();
  test_ignorable_not_buffered();
  test_large_frame_then_idle();
  return sct_finish("proto_memory");
}
