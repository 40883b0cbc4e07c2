/*
 * Each way a stream or a frame can be wrong gives its own error: truncation,
 * an oversize length, bad magic or version, an unknown type, a length that
 * lies about its payload, reserved bits, and every field out of range. The
 * decoder's errors are sticky and distinct from "need more bytes", and the
 * encoders refuse what the parsers refuse.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <math.h>

#include "frames.h"

static scp_decoder_t *decoder(int role, uint32_t max_frame) {
  scp_limits_t lim;
  scp_limits_init(&lim);
  lim.role = role;
  lim.max_frame = max_frame;
  scp_decoder_t *d = scp_decoder_new(&lim);
  ASSERT_NOT_NULL(d);
  return d;
}

/* Checks that the error stuck: every entry point now returns it. */
static void check_sticky(scp_decoder_t *d, int code) {
  scp_frame_t f;
  uint8_t ping[16];
  pt_header(ping, SCP_PING, 0, 8);
  memset(ping + 8, 0, 8);
  ASSERT_CODE_EQ(scp_decoder_error(d), code, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_next(d, &f), code, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_feed(d, ping, sizeof ping), code, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_next(d, &f), code, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_eof(d), code, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_error(d), code, scp_err_name);
}

static void test_truncation(void) {
  scp_buf_t b;
  scp_buf_init(&b, 0);
  ASSERT_CODE_EQ(scp_enc_ping(&b, 1), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_enc_ping(&b, 2), 0, scp_err_name);
  /* The stream may end after any whole frame, and at no other point. */
  for (size_t cut = 0; cut <= b.len; cut++) {
    scp_decoder_t *d = decoder(SCP_ROLE_ANY, SCP_FRAME_MIN);
    scp_frame_t f;
    ASSERT_CODE_EQ(scp_decoder_feed(d, b.data, cut), 0, scp_err_name);
    int frames = 0, rc;
    while ((rc = scp_decoder_next(d, &f)) == 1)
      frames++;
    /* Missing bytes are not an error until the stream ends. */
    ASSERT_CODE_EQ(rc, 0, scp_err_name);
    ASSERT_EQ(frames, (int)(cut / 16));
    int want = cut % 16 == 0 ? 0 : SCP_ETRUNCATED;
    ASSERT_CODE_EQ(scp_decoder_eof(d), want, scp_err_name);
    if (want)
      check_sticky(d, want);
    scp_decoder_free(d);
  }

  /* Ending inside an ignorable frame that is being skipped. */
  uint8_t ign[8 + 10];
  pt_header(ign, 0x8fff, 0, 10);
  memset(ign + 8, 0, 10);
  scp_decoder_t *d = decoder(SCP_ROLE_ANY, SCP_FRAME_MIN);
  scp_frame_t f;
  ASSERT_CODE_EQ(scp_decoder_feed(d, ign, 12), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_next(d, &f), 0, scp_err_name);
  ASSERT_EQ(scp_decoder_pending(d), 0); /* dropped, not buffered */
  ASSERT_CODE_EQ(scp_decoder_eof(d), SCP_ETRUNCATED, scp_err_name);
  scp_decoder_free(d);
  d = decoder(SCP_ROLE_ANY, SCP_FRAME_MIN);
  ASSERT_CODE_EQ(scp_decoder_feed(d, ign, sizeof ign), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_next(d, &f), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_eof(d), 0, scp_err_name);
  scp_decoder_free(d);
  scp_buf_free(&b);
}

static void test_oversize(void) {
  uint8_t h[SCP_HEADER_SIZE];
  scp_frame_t f;
  /* The largest frame allowed and the smallest refused, at two limits. The
   * refusal comes from the header alone, before any payload arrives. */
  uint32_t limits[2] = {SCP_FRAME_MIN, 1u << 20};
  for (int i = 0; i < 2; i++) {
    scp_decoder_t *d = decoder(SCP_ROLE_ANY, limits[i]);
    pt_header(h, SCP_POINTS, 0, limits[i] - SCP_HEADER_SIZE);
    ASSERT_CODE_EQ(scp_decoder_feed(d, h, sizeof h), 0, scp_err_name);
    ASSERT_CODE_EQ(scp_decoder_next(d, &f), 0, scp_err_name);
    scp_decoder_free(d);

    d = decoder(SCP_ROLE_ANY, limits[i]);
    pt_header(h, SCP_POINTS, 0, limits[i] - SCP_HEADER_SIZE + 1);
    ASSERT_CODE_EQ(scp_decoder_feed(d, h, sizeof h), 0, scp_err_name);
    ASSERT_CODE_EQ(scp_decoder_next(d, &f), SCP_ETOOBIG, scp_err_name);
    check_sticky(d, SCP_ETOOBIG);
    scp_decoder_free(d);
  }

  /* Lengths that would wrap a 32-bit sum with the header. */
  uint32_t huge[3] = {0xFFFFFFFFu, 0xFFFFFFF8u, 0x80000000u};
  for (int i = 0; i < 3; i++) {
    scp_decoder_t *d = decoder(SCP_ROLE_ANY, SCP_FRAME_CEILING);
    pt_header(h, SCP_TRIANGLES, 0, huge[i]);
    ASSERT_CODE_EQ(scp_decoder_feed(d, h, sizeof h), 0, scp_err_name);
    ASSERT_CODE_EQ(scp_decoder_next(d, &f), SCP_ETOOBIG, scp_err_name);
    scp_decoder_free(d);
  }

  /* Ignorable frames obey the limit too. */
  scp_decoder_t *d = decoder(SCP_ROLE_ANY, SCP_FRAME_MIN);
  pt_header(h, 0x8001, 0, SCP_FRAME_MIN);
  ASSERT_CODE_EQ(scp_decoder_feed(d, h, sizeof h), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_next(d, &f), SCP_ETOOBIG, scp_err_name);
  scp_decoder_free(d);

  /* A limit lowered before the header is judged applies to it. */
  d = decoder(SCP_ROLE_ANY, 1u << 20);
  pt_header(h, SCP_POINTS, 0, 5000);
  ASSERT_CODE_EQ(scp_decoder_feed(d, h, sizeof h), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_set_max_frame(d, SCP_FRAME_MIN), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_next(d, &f), SCP_ETOOBIG, scp_err_name);
  scp_decoder_free(d);

  /* Limits outside the protocol's range are refused. */
  d = decoder(SCP_ROLE_ANY, SCP_FRAME_MIN);
  ASSERT_CODE_EQ(scp_decoder_set_max_frame(d, SCP_FRAME_MIN - 1), SCP_EINVAL,
                 scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_set_max_frame(d, SCP_FRAME_CEILING + 1),
                 SCP_EINVAL, scp_err_name);
  ASSERT_EQ(scp_decoder_max_frame(d), SCP_FRAME_MIN);
  scp_decoder_free(d);
  scp_limits_t lim;
  scp_limits_init(&lim);
  lim.max_frame = SCP_FRAME_MIN - 1;
  ASSERT_NULL(scp_decoder_new(&lim));
  lim.max_frame = SCP_FRAME_CEILING + 1;
  ASSERT_NULL(scp_decoder_new(&lim));
  scp_limits_init(&lim);
  lim.role = 3;
  ASSERT_NULL(scp_decoder_new(&lim));

  /* The encoder will not write a frame over its limit either. */
  scp_buf_t b;
  scp_buf_init(&b, SCP_FRAME_MIN);
  scp_value_t v[400];
  for (int i = 0; i < 400; i++)
    v[i] = (scp_value_t){.name = "abc", .kind = SCP_KIND_U64, .v.u = 1};
  ASSERT_CODE_EQ(scp_enc_stats(&b, 1, v, 400), SCP_ETOOBIG, scp_err_name);
  ASSERT_EQ(b.len, 0);
  ASSERT_CODE_EQ(scp_enc_stats(&b, 1, v, 300), 0, scp_err_name);
  scp_buf_free(&b);
}

static void test_header_flags(void) {
  uint8_t h[16];
  scp_frame_t f;
  for (int bit = 0; bit < 16; bit++) {
    scp_decoder_t *d = decoder(SCP_ROLE_ANY, SCP_FRAME_MIN);
    pt_header(h, SCP_PING, (uint16_t)(1u << bit), 8);
    memset(h + 8, 0, 8);
    ASSERT_CODE_EQ(scp_decoder_feed(d, h, sizeof h), 0, scp_err_name);
    ASSERT_CODE_EQ(scp_decoder_next(d, &f), SCP_ERESERVED, scp_err_name);
    check_sticky(d, SCP_ERESERVED);
    scp_decoder_free(d);
  }
}

static void test_magic_and_version(void) {
  scp_buf_t b;
  scp_buf_init(&b, 0);
  scp_hello_t h = {.version_min = 1, .version_max = 1, .max_frame = 4096};
  ASSERT_CODE_EQ(scp_enc_hello(&b, &h), 0, scp_err_name);
  /* Any change to the magic is caught as soon as the magic is in, before
   * the rest of the frame arrives. */
  for (int i = 0; i < SCP_MAGIC_LEN; i++) {
    uint8_t bad[32];
    memcpy(bad, b.data, 32);
    bad[8 + i] ^= 0x20;
    scp_decoder_t *d = decoder(SCP_ROLE_SERVER, SCP_FRAME_MIN);
    scp_frame_t f;
    ASSERT_CODE_EQ(scp_decoder_feed(d, bad, 8 + SCP_MAGIC_LEN - 1), 0,
                   scp_err_name);
    ASSERT_CODE_EQ(scp_decoder_next(d, &f), 0, scp_err_name);
    ASSERT_CODE_EQ(scp_decoder_feed(d, bad + 11, 1), 0, scp_err_name);
    ASSERT_CODE_EQ(scp_decoder_next(d, &f), SCP_EBADMAGIC, scp_err_name);
    check_sticky(d, SCP_EBADMAGIC);
    scp_decoder_free(d);

    /* The parser says the same of a frame it is handed directly. */
    f = (scp_frame_t){.type = SCP_HELLO, .length = 24, .payload = bad + 8};
    scp_hello_t out;
    ASSERT_CODE_EQ(scp_parse_hello(&f, &out), SCP_EBADMAGIC, scp_err_name);
  }
  scp_buf_consume(&b, b.len);

  /* WELCOME's magic is checked in the client role too. */
  scp_welcome_t w = {.version = 1, .max_frame = 4096, .max_jobs = 1,
                     .max_points = 1};
  ASSERT_CODE_EQ(scp_enc_welcome(&b, &w), 0, scp_err_name);
  b.data[8] = 'X';
  scp_decoder_t *d = decoder(SCP_ROLE_CLIENT, SCP_FRAME_MIN);
  scp_frame_t f;
  ASSERT_CODE_EQ(scp_decoder_feed(d, b.data, b.len), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_next(d, &f), SCP_EBADMAGIC, scp_err_name);
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);

  /* A peer speaking HTTP: "GET / HTTP/1.1" is no handshake at all. */
  d = decoder(SCP_ROLE_SERVER, SCP_FRAME_MIN);
  ASSERT_CODE_EQ(scp_decoder_feed(d, "GET / HTTP/1.1\r\n", 16), 0,
                 scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_next(d, &f), SCP_EHANDSHAKE, scp_err_name);
  scp_decoder_free(d);

  /* Version fields: an empty or zero range in HELLO, and a WELCOME naming
   * a version this library does not speak. */
  scp_hello_t bad_h[3] = {
      {.version_min = 0, .version_max = 1, .max_frame = 4096},
      {.version_min = 2, .version_max = 1, .max_frame = 4096},
      {.version_min = 0, .version_max = 0, .max_frame = 4096}};
  for (int i = 0; i < 3; i++) {
    ASSERT_CODE_EQ(scp_enc_hello(&b, &bad_h[i]), SCP_EVERSION, scp_err_name);
    ASSERT_EQ(b.len, 0);
    uint8_t raw[32];
    pt_header(raw, SCP_HELLO, 0, 24);
    memset(raw + 8, 0, 24);
    memcpy(raw + 8, SCP_MAGIC, 4);
    raw[12] = (uint8_t)bad_h[i].version_min;
    raw[14] = (uint8_t)bad_h[i].version_max;
    pt_put32(raw + 24, 4096);
    f = (scp_frame_t){.type = SCP_HELLO, .length = 24, .payload = raw + 8};
    scp_hello_t out;
    ASSERT_CODE_EQ(scp_parse_hello(&f, &out), SCP_EVERSION, scp_err_name);
  }
  uint8_t raw[40];
  pt_header(raw, SCP_WELCOME, 0, 32);
  memset(raw + 8, 0, 32);
  memcpy(raw + 8, SCP_MAGIC, 4);
  raw[12] = 2;
  pt_put32(raw + 24, 4096);
  pt_put32(raw + 28, 1);
  pt_put64(raw + 32, 1);
  f = (scp_frame_t){.type = SCP_WELCOME, .length = 32, .payload = raw + 8};
  scp_welcome_t wout;
  ASSERT_CODE_EQ(scp_parse_welcome(&f, &wout), SCP_EVERSION, scp_err_name);
  raw[12] = 1;
  ASSERT_CODE_EQ(scp_parse_welcome(&f, &wout), 0, scp_err_name);

  /* Negotiation: a client offering only versions 2 to 5 gets VERSION. */
  scp_hello_t later = {.version_min = 2, .version_max = 5, .max_frame = 4096};
  scp_welcome_t server = {.max_frame = 1u << 20, .max_jobs = 1,
                          .max_points = 1};
  scp_welcome_t ans;
  ASSERT_CODE_EQ(scp_handshake_answer(&later, &server, &ans), SCP_EVERSION,
                 scp_err_name);
  ASSERT_EQ(scp_err_to_wire(SCP_EVERSION), SCP_WIRE_VERSION);
  scp_hello_t tiny = {.version_min = 1, .version_max = 1, .max_frame = 4095};
  ASSERT_CODE_EQ(scp_handshake_answer(&tiny, &server, &ans), SCP_ERANGE,
                 scp_err_name);
  server.max_frame = SCP_FRAME_CEILING + 1;
  ASSERT_CODE_EQ(scp_handshake_answer(&h, &server, &ans), SCP_EINVAL,
                 scp_err_name);

  /* The client's checks of WELCOME against its HELLO. */
  scp_hello_t sent = {.version_min = 1, .version_max = 1, .features = 0x2,
                      .max_frame = 1u << 16};
  scp_welcome_t got = {.version = 1, .features = 0x2, .max_frame = 1u << 16,
                       .max_jobs = 1, .max_points = 1};
  ASSERT_CODE_EQ(scp_handshake_check(&sent, &got), 0, scp_err_name);
  got.max_frame = (1u << 16) + 1;
  ASSERT_CODE_EQ(scp_handshake_check(&sent, &got), SCP_ERANGE, scp_err_name);
  got.max_frame = 1u << 16;
  got.features = 0x3;
  ASSERT_CODE_EQ(scp_handshake_check(&sent, &got), SCP_EFLAGS, scp_err_name);
  got.features = 0;
  got.max_jobs = 0;
  ASSERT_CODE_EQ(scp_handshake_check(&sent, &got), SCP_ERANGE, scp_err_name);
  scp_buf_free(&b);
}

static void test_handshake_position(void) {
  scp_buf_t b;
  scp_buf_init(&b, 0);
  scp_frame_t f;
  scp_hello_t h = {.version_min = 1, .version_max = 1, .max_frame = 4096};
  scp_welcome_t w = {.version = 1, .max_frame = 4096, .max_jobs = 1,
                     .max_points = 1};

  /* Server role: the first frame must be HELLO... */
  ASSERT_CODE_EQ(scp_enc_ping(&b, 1), 0, scp_err_name);
  scp_decoder_t *d = decoder(SCP_ROLE_SERVER, SCP_FRAME_MIN);
  ASSERT_CODE_EQ(scp_decoder_feed(d, b.data, b.len), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_next(d, &f), SCP_EHANDSHAKE, scp_err_name);
  check_sticky(d, SCP_EHANDSHAKE);
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);

  /* ...even an ignorable one may not come first... */
  uint8_t ign[8];
  pt_header(ign, 0x8001, 0, 0);
  d = decoder(SCP_ROLE_SERVER, SCP_FRAME_MIN);
  ASSERT_CODE_EQ(scp_decoder_feed(d, ign, sizeof ign), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_next(d, &f), SCP_EHANDSHAKE, scp_err_name);
  scp_decoder_free(d);

  /* ...and HELLO or WELCOME may not come again. */
  uint16_t again[2] = {SCP_HELLO, SCP_WELCOME};
  for (int i = 0; i < 2; i++) {
    ASSERT_CODE_EQ(scp_enc_hello(&b, &h), 0, scp_err_name);
    ASSERT_CODE_EQ(scp_enc_ping(&b, 1), 0, scp_err_name);
    if (again[i] == SCP_HELLO)
      ASSERT_CODE_EQ(scp_enc_hello(&b, &h), 0, scp_err_name);
    else
      ASSERT_CODE_EQ(scp_enc_welcome(&b, &w), 0, scp_err_name);
    d = decoder(SCP_ROLE_SERVER, SCP_FRAME_MIN);
    ASSERT_CODE_EQ(scp_decoder_feed(d, b.data, b.len), 0, scp_err_name);
    ASSERT_CODE_EQ(scp_decoder_next(d, &f), 1, scp_err_name);
    ASSERT_EQ(f.type, SCP_HELLO);
    ASSERT_CODE_EQ(scp_decoder_next(d, &f), 1, scp_err_name);
    ASSERT_EQ(f.type, SCP_PING);
    ASSERT_CODE_EQ(scp_decoder_next(d, &f), SCP_EHANDSHAKE, scp_err_name);
    scp_decoder_free(d);
    scp_buf_consume(&b, b.len);
  }

  /* Client role: WELCOME, or a fatal ERROR instead of it. */
  scp_error_t e = {.code = SCP_WIRE_VERSION, .flags = SCP_ERROR_FATAL};
  strcpy(e.message, "server speaks versions 1 to 1");
  ASSERT_CODE_EQ(scp_enc_error(&b, &e), 0, scp_err_name);
  d = decoder(SCP_ROLE_CLIENT, SCP_FRAME_MIN);
  ASSERT_CODE_EQ(scp_decoder_feed(d, b.data, b.len), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_next(d, &f), 1, scp_err_name);
  ASSERT_EQ(f.type, SCP_ERROR);
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);

  ASSERT_CODE_EQ(scp_enc_hello(&b, &h), 0, scp_err_name);
  d = decoder(SCP_ROLE_CLIENT, SCP_FRAME_MIN);
  ASSERT_CODE_EQ(scp_decoder_feed(d, b.data, b.len), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_next(d, &f), SCP_EHANDSHAKE, scp_err_name);
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);

  ASSERT_CODE_EQ(scp_enc_accepted(&b, &(scp_accepted_t){.job_id = 1}), 0,
                 scp_err_name);
  d = decoder(SCP_ROLE_CLIENT, SCP_FRAME_MIN);
  ASSERT_CODE_EQ(scp_decoder_feed(d, b.data, b.len), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_next(d, &f), SCP_EHANDSHAKE, scp_err_name);
  scp_decoder_free(d);
  scp_buf_consume(&b, b.len);

  ASSERT_CODE_EQ(scp_enc_welcome(&b, &w), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_enc_welcome(&b, &w), 0, scp_err_name);
  d = decoder(SCP_ROLE_CLIENT, SCP_FRAME_MIN);
  ASSERT_CODE_EQ(scp_decoder_feed(d, b.data, b.len), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_next(d, &f), 1, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_next(d, &f), SCP_EHANDSHAKE, scp_err_name);
  scp_decoder_free(d);
  scp_buf_free(&b);
}

static void test_unknown_type(void) {
  /* A type version 1 lacks is returned by the decoder, and the parser
   * reports it as unknown; the stream goes on. */
  uint8_t s[8 + 3 + 8 + 8];
  pt_header(s, 0x0099, 0, 3);
  memset(s + 8, 0xee, 3);
  pt_header(s + 11, SCP_PING, 0, 8);
  memset(s + 19, 0, 8);
  scp_decoder_t *d = decoder(SCP_ROLE_ANY, SCP_FRAME_MIN);
  scp_frame_t f;
  scp_msg_t m;
  ASSERT_CODE_EQ(scp_decoder_feed(d, s, sizeof s), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_next(d, &f), 1, scp_err_name);
  ASSERT_EQ(f.type, 0x0099);
  ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_EUNKNOWN_TYPE, scp_err_name);
  ASSERT_EQ(m.type, 0x0099);
  ASSERT_EQ(scp_err_to_wire(SCP_EUNKNOWN_TYPE), SCP_WIRE_UNKNOWN_TYPE);
  ASSERT_EQ(scp_err_is_fatal(SCP_EUNKNOWN_TYPE), 0);
  ASSERT_CODE_EQ(scp_decoder_next(d, &f), 1, scp_err_name);
  ASSERT_EQ(f.type, SCP_PING);
  ASSERT_CODE_EQ(scp_decoder_next(d, &f), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_error(d), 0, scp_err_name);
  scp_decoder_free(d);

  /* Type 0 is never used. */
  f = (scp_frame_t){.type = 0, .length = 0, .payload = s};
  ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_EUNKNOWN_TYPE, scp_err_name);

  /* A frame travelling the wrong way is an unknown type for its receiver,
   * whatever its payload (here even a malformed one). */
  uint8_t tri[24];
  memset(tri, 0xff, sizeof tri);
  f = (scp_frame_t){.type = SCP_TRIANGLES, .length = 24, .payload = tri};
  ASSERT_CODE_EQ(scp_parse_as(&f, SCP_ROLE_SERVER, &m), SCP_EUNKNOWN_TYPE,
                 scp_err_name);
  ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ERESERVED, scp_err_name);
  f.type = SCP_POINTS;
  ASSERT_CODE_EQ(scp_parse_as(&f, SCP_ROLE_CLIENT, &m), SCP_EUNKNOWN_TYPE,
                 scp_err_name);
  uint8_t ping[8] = {0};
  f = (scp_frame_t){.type = SCP_PING, .length = 8, .payload = ping};
  ASSERT_CODE_EQ(scp_parse_as(&f, SCP_ROLE_CLIENT, &m), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_parse_as(&f, SCP_ROLE_SERVER, &m), 0, scp_err_name);

  /* Ignorable types are dropped and counted, never returned. */
  uint8_t ign[8 + 5 + 16];
  pt_header(ign, 0xABCD, 0, 5);
  memset(ign + 8, 1, 5);
  pt_header(ign + 13, SCP_PONG, 0, 8);
  memset(ign + 21, 2, 8);
  d = decoder(SCP_ROLE_ANY, SCP_FRAME_MIN);
  ASSERT_CODE_EQ(scp_decoder_feed(d, ign, sizeof ign), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_next(d, &f), 1, scp_err_name);
  ASSERT_EQ(f.type, SCP_PONG);
  scp_decoder_counters_t c;
  scp_decoder_get_counters(d, &c);
  ASSERT_EQ(c.skipped, 1);
  ASSERT_EQ(c.frames, 1);
  scp_decoder_free(d);

  /* VERTICES is ignorable but known: a server drops it like an unknown
   * type (it travels the wrong way, PROTOCOL.md 3.2), a client gets it. */
  scp_buf_t vb;
  scp_buf_init(&vb, SCP_FRAME_MIN);
  scp_hello_t hello = {
      .version_min = 1, .version_max = 1, .max_frame = SCP_FRAME_MIN};
  double xyz[3] = {1, 2, 3};
  ASSERT_CODE_EQ(scp_enc_hello(&vb, &hello), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_enc_vertices(&vb, 4, 0, xyz, 1), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_enc_ping(&vb, 9), 0, scp_err_name);
  d = decoder(SCP_ROLE_SERVER, SCP_FRAME_MIN);
  ASSERT_CODE_EQ(scp_decoder_feed(d, vb.data, vb.len), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_next(d, &f), 1, scp_err_name);
  ASSERT_EQ(f.type, SCP_HELLO);
  ASSERT_CODE_EQ(scp_decoder_next(d, &f), 1, scp_err_name);
  ASSERT_EQ(f.type, SCP_PING);
  scp_decoder_get_counters(d, &c);
  ASSERT_EQ(c.skipped, 1);
  scp_decoder_free(d);
  scp_buf_consume(&vb, vb.len);

  scp_welcome_t welcome = {.version = 1,
                           .max_frame = SCP_FRAME_MIN,
                           .max_jobs = 1,
                           .max_points = 10};
  ASSERT_CODE_EQ(scp_enc_welcome(&vb, &welcome), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_enc_vertices(&vb, 4, 0, xyz, 1), 0, scp_err_name);
  d = decoder(SCP_ROLE_CLIENT, SCP_FRAME_MIN);
  ASSERT_CODE_EQ(scp_decoder_feed(d, vb.data, vb.len), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_next(d, &f), 1, scp_err_name);
  ASSERT_EQ(f.type, SCP_WELCOME);
  ASSERT_CODE_EQ(scp_decoder_next(d, &f), 1, scp_err_name);
  ASSERT_EQ(f.type, SCP_VERTICES);
  ASSERT_CODE_EQ(scp_parse_as(&f, SCP_ROLE_CLIENT, &m), 0, scp_err_name);
  ASSERT_EQ(m.u.chunk.job_id, 4);
  ASSERT_CODE_EQ(scp_parse_as(&f, SCP_ROLE_SERVER, &m), SCP_EUNKNOWN_TYPE,
                 scp_err_name);
  scp_decoder_get_counters(d, &c);
  ASSERT_EQ(c.skipped, 0);
  scp_decoder_free(d);
  scp_buf_free(&vb);
}

/* Builds a frame from a hex-free description: type plus payload bytes. */
typedef struct raw {
  uint8_t p[256];
  uint32_t len;
} raw_t;

static scp_frame_t frame_of(uint16_t type, const raw_t *r) {
  return (scp_frame_t){.type = type, .length = r->len, .payload = r->p};
}

/* Encodes a message into raw payload bytes, to be broken afterwards. */
static raw_t encoded(int (*enc)(scp_buf_t *, const void *), const void *m) {
  scp_buf_t b;
  scp_buf_init(&b, 0);
  raw_t r;
  ASSERT_CODE_EQ(enc(&b, m), 0, scp_err_name);
  ASSERT_LE(b.len - SCP_HEADER_SIZE, sizeof r.p);
  r.len = (uint32_t)(b.len - SCP_HEADER_SIZE);
  memcpy(r.p, b.data + SCP_HEADER_SIZE, r.len);
  scp_buf_free(&b);
  return r;
}

static int enc_job_begin_(scp_buf_t *b, const void *m) {
  return scp_enc_job_begin(b, m);
}
static int enc_job_end_(scp_buf_t *b, const void *m) {
  return scp_enc_job_end(b, m);
}
static int enc_cancel_(scp_buf_t *b, const void *m) {
  return scp_enc_cancel(b, *(const uint32_t *)m);
}
static int enc_stats_request_(scp_buf_t *b, const void *m) {
  return scp_enc_stats_request(b, *(const uint32_t *)m);
}
static int enc_error_(scp_buf_t *b, const void *m) {
  return scp_enc_error(b, m);
}
static int enc_job_error_(scp_buf_t *b, const void *m) {
  return scp_enc_job_error(b, m);
}
static int enc_hello_(scp_buf_t *b, const void *m) {
  return scp_enc_hello(b, m);
}
static int enc_welcome_(scp_buf_t *b, const void *m) {
  return scp_enc_welcome(b, m);
}

/* Fixed-size messages one byte short and one byte long: SHORT, LENGTH. */
static void test_wrong_lengths(void) {
  static const struct {
    uint16_t type;
    uint32_t size;
  } fixed[] = {{SCP_PING, 8},      {SCP_PONG, 8},     {SCP_JOB_BEGIN, 40},
               {SCP_JOB_END, 16},  {SCP_CANCEL, 8},   {SCP_STATS_REQUEST, 8},
               {SCP_ACCEPTED, 8},  {SCP_PROGRESS, 16}};
  uint8_t zero[64] = {0};
  scp_msg_t m;
  for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; i++) {
    scp_frame_t f = {.type = fixed[i].type, .payload = zero};
    f.length = fixed[i].size - 1;
    ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ESHORT, scp_err_name);
    f.length = 0;
    ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ESHORT, scp_err_name);
    f.length = fixed[i].size + 1;
    ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ELENGTH, scp_err_name);
    ASSERT_EQ(scp_err_is_fatal(SCP_ESHORT), 1);
    ASSERT_EQ(scp_err_is_fatal(SCP_ELENGTH), 1);
  }
  /* Fixed parts of the variable messages. */
  static const struct {
    uint16_t type;
    uint32_t size;
  } var[] = {{SCP_HELLO, 24},    {SCP_WELCOME, 32},   {SCP_ERROR, 20},
             {SCP_JOB_DONE, 32}, {SCP_JOB_ERROR, 16}, {SCP_STATS, 8},
             {SCP_POINTS, 24},   {SCP_TRIANGLES, 24}, {SCP_NORMALS, 24},
             {SCP_VERTICES, 24}, {SCP_COMPONENTS, 24}};
  uint8_t hs[64] = {0};
  memcpy(hs, SCP_MAGIC, 4);
  for (size_t i = 0; i < sizeof var / sizeof var[0]; i++) {
    scp_frame_t f = {.type = var[i].type, .payload = hs};
    f.length = var[i].size - 1;
    ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ESHORT, scp_err_name);
  }

  /* JOB_BEGIN with job options: 41 to 47 bytes malformed; a list that
   * does not fill the payload malformed; no entries invalid. */
  {
    scp_value_t o = {.name = "max_hole_edges", .kind = SCP_KIND_U64, .v.u = 3};
    scp_job_begin_t jb = {.job_id = 2, .r = 0.2};
    scp_buf_t ob;
    scp_buf_init(&ob, 0);
    ASSERT_CODE_EQ(scp_enc_job_begin_options(&ob, &jb, &o, 1), 0, scp_err_name);
    scp_frame_t g = {.type = SCP_JOB_BEGIN,
                     .payload = ob.data + SCP_HEADER_SIZE,
                     .length = (uint32_t)(ob.len - SCP_HEADER_SIZE)};
    ASSERT_CODE_EQ(scp_parse(&g, &m), 0, scp_err_name);
    /* Without the JOB_OPTIONS feature, anything past the fixed part is
     * malformed however it reads; with it, the same as scp_parse(). */
    scp_job_begin_t jm;
    ASSERT_CODE_EQ(scp_parse_job_begin_features(&g, SCP_FEATURE_JOB_OPTIONS, &jm),
             0, scp_err_name);
    ASSERT_EQ(jm.options.count, 1);
    ASSERT_CODE_EQ(scp_parse_job_begin_features(&g, 0, &jm), SCP_ELENGTH, scp_err_name);
    g.length = SCP_JOB_BEGIN_FIXED;
    ASSERT_CODE_EQ(scp_parse_job_begin_features(&g, 0, &jm), 0, scp_err_name);
    ASSERT_EQ(jm.options.count, 0);
    g.length = (uint32_t)(ob.len - SCP_HEADER_SIZE);
    for (uint32_t n = 41; n < 48; n++) {
      g.length = n;
      ASSERT_CODE_EQ(scp_parse(&g, &m), SCP_ELENGTH, scp_err_name);
    }
    g.length = (uint32_t)(ob.len - SCP_HEADER_SIZE) - 1;
    ASSERT_CODE_EQ(scp_parse(&g, &m), SCP_ELENGTH, scp_err_name);
    g.length = (uint32_t)(ob.len - SCP_HEADER_SIZE);
    pt_put32(ob.data + SCP_HEADER_SIZE + 40, 2);
    ASSERT_CODE_EQ(scp_parse(&g, &m), SCP_ELENGTH, scp_err_name);
    pt_put32(ob.data + SCP_HEADER_SIZE + 44, 1);
    pt_put32(ob.data + SCP_HEADER_SIZE + 40, 1);
    ASSERT_CODE_EQ(scp_parse(&g, &m), SCP_ERESERVED, scp_err_name);
    pt_put32(ob.data + SCP_HEADER_SIZE + 44, 0);
    g.length = 48;
    pt_put32(ob.data + SCP_HEADER_SIZE + 40, 0);
    ASSERT_CODE_EQ(scp_parse(&g, &m), SCP_ERANGE, scp_err_name);
    ASSERT_CODE_EQ(scp_parse_job_begin_features(&g, 0, &jm), SCP_ELENGTH, scp_err_name);
    ASSERT_EQ(scp_err_is_fatal(SCP_ERANGE), 0);
    /* The encoder refuses an empty view of options that claims entries. */
    jb.options = (scp_values_t){.count = 1, .data = NULL, .len = 0};
    ASSERT_CODE_EQ(scp_enc_job_begin(&ob, &jb), SCP_EINVAL, scp_err_name);
    scp_buf_free(&ob);
  }

  /* ERROR and JOB_ERROR whose text length lies about the payload. */
  scp_error_t e = {.code = SCP_WIRE_BUSY};
  strcpy(e.message, "abc");
  raw_t r = encoded(enc_error_, &e);
  scp_frame_t f = frame_of(SCP_ERROR, &r);
  ASSERT_CODE_EQ(scp_parse(&f, &m), 0, scp_err_name);
  pt_put32(r.p + 16, 4);
  ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ELENGTH, scp_err_name);
  pt_put32(r.p + 16, 2);
  ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ELENGTH, scp_err_name);
  pt_put32(r.p + 16, 0xFFFFFFFFu);
  ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ELENGTH, scp_err_name);

  scp_job_error_t je = {.job_id = 1, .code = SCP_WIRE_BUSY};
  strcpy(je.message, "abc");
  r = encoded(enc_job_error_, &je);
  f = frame_of(SCP_JOB_ERROR, &r);
  ASSERT_CODE_EQ(scp_parse(&f, &m), 0, scp_err_name);
  pt_put32(r.p + 8, 0xFFFFFFF0u);
  ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ELENGTH, scp_err_name);
  /* And one that tells the truth about a payload longer than allowed. */
  uint8_t big[16 + SCP_MESSAGE_MAX + 1];
  memset(big, 'm', sizeof big);
  pt_put32(big, 1);
  pt_put32(big + 4, SCP_WIRE_BUSY);
  pt_put32(big + 8, SCP_MESSAGE_MAX + 1);
  pt_put32(big + 12, 0);
  f = (scp_frame_t){.type = SCP_JOB_ERROR, .length = sizeof big,
                    .payload = big};
  ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ERANGE, scp_err_name);
  pt_put32(big + 8, SCP_MESSAGE_MAX);
  f.length--;
  ASSERT_CODE_EQ(scp_parse(&f, &m), 0, scp_err_name);

  /* Chunks whose count does not match the data. */
  double xyz[6] = {0};
  scp_buf_t b;
  scp_buf_init(&b, 0);
  ASSERT_CODE_EQ(scp_enc_points(&b, 1, 0, SCP_F64_XYZ, xyz, 2), 0,
                 scp_err_name);
  memcpy(r.p, b.data + 8, b.len - 8);
  r.len = (uint32_t)(b.len - 8);
  f = frame_of(SCP_POINTS, &r);
  ASSERT_CODE_EQ(scp_parse(&f, &m), 0, scp_err_name);
  pt_put32(r.p + 4, 3);
  ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ELENGTH, scp_err_name);
  pt_put32(r.p + 4, 1);
  ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ELENGTH, scp_err_name);
  pt_put32(r.p + 4, 0xFFFFFFFFu);
  ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ELENGTH, scp_err_name);
  pt_put32(r.p + 4, 2);
  /* Same count, but the element size of the other format. */
  pt_put32(r.p + 16, SCP_F32_XYZ);
  ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ELENGTH, scp_err_name);
  pt_put32(r.p + 16, SCP_F64_XYZ);
  f.length--;
  ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ELENGTH, scp_err_name);
  scp_buf_free(&b);

  /* Value lists whose count lies, or whose names run past the end. */
  scp_value_t v[2] = {{.name = "ab", .kind = SCP_KIND_U64, .v.u = 1},
                      {.name = "cd", .kind = SCP_KIND_U64, .v.u = 2}};
  scp_buf_init(&b, 0);
  ASSERT_CODE_EQ(scp_enc_stats(&b, 1, v, 2), 0, scp_err_name);
  memcpy(r.p, b.data + 8, b.len - 8);
  r.len = (uint32_t)(b.len - 8);
  f = frame_of(SCP_STATS, &r);
  ASSERT_CODE_EQ(scp_parse(&f, &m), 0, scp_err_name);
  pt_put32(r.p + 4, 3);
  ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ELENGTH, scp_err_name);
  pt_put32(r.p + 4, 1);
  ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ELENGTH, scp_err_name);
  pt_put32(r.p + 4, 0xFFFFFFFFu);
  ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ELENGTH, scp_err_name);
  pt_put32(r.p + 4, 2);
  r.p[8 + 12 + 1] = 200; /* second name_len */
  ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ELENGTH, scp_err_name);
  r.p[8 + 12 + 1] = 2;
  f.length++;
  ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ELENGTH, scp_err_name);
  f.length--;
  /* A bad name in a list that is also misframed is reported as misframed:
   * the stream cannot be trusted, which matters more. */
  r.p[8 + 2] = 'A';
  ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ERANGE, scp_err_name);
  pt_put32(r.p + 4, 3);
  ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ELENGTH, scp_err_name);
  scp_buf_free(&b);

  /* HELLO and WELCOME may be longer: the tail is for later versions. */
  scp_hello_t h = {.version_min = 1, .version_max = 1, .max_frame = 4096};
  r = encoded(enc_hello_, &h);
  memset(r.p + r.len, 0xAB, 16);
  r.len += 16;
  f = frame_of(SCP_HELLO, &r);
  ASSERT_CODE_EQ(scp_parse(&f, &m), 0, scp_err_name);
  scp_welcome_t w = {.version = 1, .max_frame = 4096, .max_jobs = 1,
                     .max_points = 1};
  r = encoded(enc_welcome_, &w);
  r.len += 100;
  f = frame_of(SCP_WELCOME, &r);
  ASSERT_CODE_EQ(scp_parse(&f, &m), 0, scp_err_name);
}

/* Every reserved field, one bit at a time. */
static void test_reserved(void) {
  scp_msg_t m;
  typedef struct {
    uint16_t type;
    raw_t r;
    uint32_t off, width;
  } reserved_case_t;
  reserved_case_t cases[16];
  int n = 0;

  scp_hello_t h = {.version_min = 1, .version_max = 1, .max_frame = 4096};
  cases[n++] = (reserved_case_t){SCP_HELLO, encoded(enc_hello_, &h), 20, 4};
  scp_welcome_t w = {.version = 1, .max_frame = 4096, .max_jobs = 1,
                     .max_points = 1};
  cases[n++] =
      (reserved_case_t){SCP_WELCOME, encoded(enc_welcome_, &w), 6, 2};
  scp_error_t e = {.code = 1};
  cases[n++] = (reserved_case_t){SCP_ERROR, encoded(enc_error_, &e), 14, 2};
  scp_job_begin_t jb = {.job_id = 1, .r = 0.1};
  cases[n++] =
      (reserved_case_t){SCP_JOB_BEGIN, encoded(enc_job_begin_, &jb), 36, 4};
  scp_job_end_t jend = {.job_id = 1};
  cases[n++] =
      (reserved_case_t){SCP_JOB_END, encoded(enc_job_end_, &jend), 4, 4};
  uint32_t one = 1;
  cases[n++] = (reserved_case_t){SCP_CANCEL, encoded(enc_cancel_, &one), 4, 4};
  cases[n++] = (reserved_case_t){SCP_STATS_REQUEST,
                                  encoded(enc_stats_request_, &one), 4, 4};
  scp_job_error_t je = {.job_id = 1, .code = 1};
  cases[n++] =
      (reserved_case_t){SCP_JOB_ERROR, encoded(enc_job_error_, &je), 12, 4};

  for (int i = 0; i < n; i++) {
    scp_frame_t f = frame_of(cases[i].type, &cases[i].r);
    ASSERT_CODE_EQ(scp_parse(&f, &m), 0, scp_err_name);
    for (uint32_t bit = 0; bit < 8 * cases[i].width; bit++) {
      uint8_t *p = cases[i].r.p + cases[i].off + bit / 8;
      *p ^= (uint8_t)(1u << (bit % 8));
      int rc = scp_parse(&f, &m);
      if (rc != SCP_ERESERVED)
        ASSERT_FAIL("%s: reserved bit %u gives %s",
                    scp_type_name(cases[i].type), bit, scp_err_name(rc));
      *p ^= (uint8_t)(1u << (bit % 8));
    }
    ASSERT_CODE_EQ(scp_parse(&f, &m), 0, scp_err_name);
  }

  /* The chunk frames' reserved word. */
  uint16_t chunk_types[5] = {SCP_POINTS, SCP_TRIANGLES, SCP_NORMALS,
                             SCP_VERTICES, SCP_COMPONENTS};
  uint32_t formats[5] = {SCP_F32_XYZ, SCP_U32_TRIANGLE, SCP_F64_XYZ,
                         SCP_F64_XYZ, SCP_I32};
  for (int i = 0; i < 5; i++) {
    uint8_t p[24 + 24] = {0};
    pt_put32(p, 1);
    pt_put32(p + 4, 1);
    pt_put32(p + 16, formats[i]);
    scp_frame_t f = {.type = chunk_types[i],
                     .length = (uint32_t)(24 + scp_format_size(formats[i])),
                     .payload = p};
    ASSERT_CODE_EQ(scp_parse(&f, &m), 0, scp_err_name);
    p[23] = 0x80;
    ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ERESERVED, scp_err_name);
  }
  ASSERT_EQ(scp_err_is_fatal(SCP_ERESERVED), 1);
  ASSERT_EQ(scp_err_to_wire(SCP_ERESERVED), SCP_WIRE_PROTOCOL);
}

/* A job frame that fails on a field still names its job (PROTOCOL.md 8.3),
 * and the parser's error is the non-fatal kind. */
static void expect_invalid(uint16_t type, const raw_t *r, int code,
                           uint32_t job) {
  scp_frame_t f = frame_of(type, r);
  scp_msg_t m;
  int rc = scp_parse(&f, &m);
  if (rc != code)
    ASSERT_FAIL("%s: got %s, expected %s", scp_type_name(type),
                scp_err_name(rc), scp_err_name(code));
  ASSERT_EQ(scp_err_is_fatal(rc), 0);
  uint32_t id = 0;
  if (job) {
    ASSERT(scp_frame_job_id(&f, &id));
    ASSERT_EQ(id, job);
  }
}

static void test_ranges(void) {
  const double half_pi = 1.5707963267948966;
  scp_buf_t b;
  scp_buf_init(&b, 0);

  /* JOB_BEGIN: each field out of range, refused by the encoder and, when
   * written by hand, by the parser. */
  const scp_job_begin_t good = {.job_id = 5, .mode = 1, .r = 0.25,
                                .theta = 0.3, .point_count = 10,
                                .flags = SCP_JOB_NORMALS};
  raw_t base = encoded(enc_job_begin_, &good);
  struct {
    uint32_t off;
    int is_double;
    double d;
    uint64_t u;
    int code;
  } jb_cases[] = {
      {4, 0, 0, SCP_MODE_COUNT, SCP_ERANGE},
      {4, 0, 0, 0xFFFFFFFFu, SCP_ERANGE},
      {8, 1, 0.0, 0, SCP_ERANGE},
      {8, 1, -0.0, 0, SCP_ERANGE},
      {8, 1, 0.5, 0, SCP_ERANGE},
      {8, 1, -0.1, 0, SCP_ERANGE},
      {8, 1, NAN, 0, SCP_ERANGE},
      {8, 1, INFINITY, 0, SCP_ERANGE},
      {16, 1, half_pi, 0, SCP_ERANGE},
      {16, 1, -0.1, 0, SCP_ERANGE},
      {16, 1, NAN, 0, SCP_ERANGE},
      {16, 1, 4.0, 0, SCP_ERANGE},
      {32, 0, 0, 0x4, SCP_EFLAGS},
      {32, 0, 0, 0x80000000u, SCP_EFLAGS},
      {32, 0, 0, SCP_JOB_NORMALS_F64, SCP_EFLAGS},
  };
  for (size_t i = 0; i < sizeof jb_cases / sizeof jb_cases[0]; i++) {
    raw_t r = base;
    if (jb_cases[i].is_double) {
      uint64_t bits;
      memcpy(&bits, &jb_cases[i].d, sizeof bits);
      pt_put64(r.p + jb_cases[i].off, bits);
    } else {
      pt_put32(r.p + jb_cases[i].off, (uint32_t)jb_cases[i].u);
    }
    expect_invalid(SCP_JOB_BEGIN, &r, jb_cases[i].code, 5);

    /* The same value through the encoder. */
    scp_job_begin_t m = good;
    scp_frame_t f = frame_of(SCP_JOB_BEGIN, &r);
    scp_job_begin_t parsed;
    (void)scp_parse_job_begin(&f, &parsed);
    m.mode = parsed.mode;
    memcpy(&m.r, r.p + 8, 8);
    memcpy(&m.theta, r.p + 16, 8);
    m.flags = parsed.flags;
    ASSERT_CODE_EQ(scp_enc_job_begin(&b, &m), jb_cases[i].code, scp_err_name);
    ASSERT_EQ(b.len, 0);
  }
  /* Job id 0 names no job. */
  raw_t r = base;
  pt_put32(r.p, 0);
  expect_invalid(SCP_JOB_BEGIN, &r, SCP_ERANGE, 0);
  r = base;
  pt_put64(r.p + 16, 0);
  expect_invalid(SCP_JOB_BEGIN, &r, 0, 5); /* theta 0: the default */

  /* JOB_END, CANCEL and ACCEPTED with job 0. */
  scp_job_end_t jend = {.job_id = 0};
  ASSERT_CODE_EQ(scp_enc_job_end(&b, &jend), SCP_ERANGE, scp_err_name);
  ASSERT_CODE_EQ(scp_enc_cancel(&b, 0), SCP_ERANGE, scp_err_name);
  ASSERT_CODE_EQ(scp_enc_accepted(&b, &(scp_accepted_t){.job_id = 0}),
                 SCP_ERANGE, scp_err_name);
  uint8_t z[16] = {0};
  scp_frame_t f = {.type = SCP_JOB_END, .length = 16, .payload = z};
  scp_msg_t m;
  ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ERANGE, scp_err_name);
  f = (scp_frame_t){.type = SCP_CANCEL, .length = 8, .payload = z};
  ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ERANGE, scp_err_name);
  f = (scp_frame_t){.type = SCP_ACCEPTED, .length = 8, .payload = z};
  ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ERANGE, scp_err_name);

  /* PROGRESS: stage and fraction. */
  scp_progress_t pr[] = {{.job_id = 1, .stage = SCP_STAGE_COUNT},
                         {.job_id = 1, .stage = SCP_STAGE_UPLOAD},
                         {.job_id = 1, .fraction = -0.01},
                         {.job_id = 1, .fraction = 1.01},
                         {.job_id = 1, .fraction = NAN},
                         {.job_id = 0, .fraction = 0.5}};
  for (size_t i = 0; i < sizeof pr / sizeof pr[0]; i++) {
    ASSERT_CODE_EQ(scp_enc_progress(&b, &pr[i]), SCP_ERANGE, scp_err_name);
    uint8_t p[16];
    pt_put32(p, pr[i].job_id);
    pt_put32(p + 4, pr[i].stage);
    uint64_t bits;
    memcpy(&bits, &pr[i].fraction, 8);
    pt_put64(p + 8, bits);
    f = (scp_frame_t){.type = SCP_PROGRESS, .length = 16, .payload = p};
    ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ERANGE, scp_err_name);
  }
  ASSERT_EQ(b.len, 0);

  /* ERROR: code 0, unknown flags, a NUL in the text, text too long. */
  scp_error_t e = {.code = 0};
  ASSERT_CODE_EQ(scp_enc_error(&b, &e), SCP_ERANGE, scp_err_name);
  e.code = 1;
  e.flags = 2;
  ASSERT_CODE_EQ(scp_enc_error(&b, &e), SCP_EFLAGS, scp_err_name);
  e.flags = 0;
  memset(e.message, 'a', sizeof e.message); /* no terminating NUL */
  ASSERT_CODE_EQ(scp_enc_error(&b, &e), SCP_ERANGE, scp_err_name);
  ASSERT_EQ(b.len, 0);
  e.message[0] = '\0';
  r = encoded(enc_error_, &e);
  pt_put32(r.p, 0);
  expect_invalid(SCP_ERROR, &r, SCP_ERANGE, 0);
  pt_put32(r.p, 1);
  pt_put32(r.p + 4, 0x10);
  expect_invalid(SCP_ERROR, &r, SCP_EFLAGS, 0);
  pt_put32(r.p + 4, 0);
  strcpy(e.message, "a\x01z");
  r = encoded(enc_error_, &e);
  expect_invalid(SCP_ERROR, &r, 0, 0);
  r.p[21] = 0;
  expect_invalid(SCP_ERROR, &r, SCP_ERANGE, 0);

  /* JOB_ERROR: job 0, code 0. */
  scp_job_error_t je = {.job_id = 0, .code = 1};
  ASSERT_CODE_EQ(scp_enc_job_error(&b, &je), SCP_ERANGE, scp_err_name);
  je = (scp_job_error_t){.job_id = 1, .code = 0};
  ASSERT_CODE_EQ(scp_enc_job_error(&b, &je), SCP_ERANGE, scp_err_name);
  je.code = 1;
  r = encoded(enc_job_error_, &je);
  pt_put32(r.p + 4, 0);
  expect_invalid(SCP_JOB_ERROR, &r, SCP_ERANGE, 1);

  /* Chunks: job 0, count 0, unknown format, a format the type does not
   * take, first + count past 2^64 - 1, a genus below -1. */
  double xyz[3] = {1, 2, 3};
  uint32_t tri[3] = {1, 2, 3};
  int32_t g[2] = {0, -2};
  ASSERT_CODE_EQ(scp_enc_points(&b, 0, 0, SCP_F64_XYZ, xyz, 1), SCP_ERANGE,
                 scp_err_name);
  ASSERT_CODE_EQ(scp_enc_points(&b, 1, 0, SCP_F64_XYZ, xyz, 0), SCP_ERANGE,
                 scp_err_name);
  ASSERT_CODE_EQ(scp_enc_points(&b, 1, 0, SCP_U32_TRIANGLE, xyz, 1), SCP_ERANGE,
                 scp_err_name);
  ASSERT_CODE_EQ(scp_enc_points(&b, 1, 0, 77, xyz, 1), SCP_ERANGE,
                 scp_err_name);
  ASSERT_CODE_EQ(scp_enc_points(&b, 1, UINT64_MAX, SCP_F64_XYZ, xyz, 1),
                 SCP_ERANGE, scp_err_name);
  ASSERT_CODE_EQ(scp_enc_triangles(&b, 1, UINT64_MAX - 1, tri, 1), 0,
                 scp_err_name);
  scp_buf_consume(&b, b.len);
  ASSERT_CODE_EQ(scp_enc_normals(&b, 1, 0, SCP_I32, xyz, 1), SCP_ERANGE,
                 scp_err_name);
  ASSERT_CODE_EQ(scp_enc_components(&b, 1, 0, g, 2), SCP_ERANGE, scp_err_name);
  ASSERT_CODE_EQ(scp_enc_components(&b, 1, 0, g, 1), 0, scp_err_name);
  scp_buf_consume(&b, b.len);
  ASSERT_CODE_EQ(scp_enc_points(&b, 1, 0, SCP_F64_XYZ, NULL, 1), SCP_EINVAL,
                 scp_err_name);
  ASSERT_EQ(b.len, 0);

  struct {
    uint16_t type;
    uint32_t job, count, format;
    uint64_t first;
    int code;
  } ch[] = {
      {SCP_POINTS, 0, 1, SCP_F32_XYZ, 0, SCP_ERANGE},
      {SCP_POINTS, 1, 0, SCP_F32_XYZ, 0, SCP_ERANGE},
      {SCP_POINTS, 1, 1, 0, 0, SCP_ERANGE},
      {SCP_POINTS, 1, 1, 5, 0, SCP_ERANGE},
      {SCP_POINTS, 1, 1, SCP_U32_TRIANGLE, 0, SCP_ERANGE},
      {SCP_POINTS, 1, 1, SCP_I32, 0, SCP_ERANGE},
      {SCP_POINTS, 1, 1, SCP_F64_XYZ, UINT64_MAX, SCP_ERANGE},
      {SCP_POINTS, 1, 2, SCP_F32_XYZ, UINT64_MAX - 1, SCP_ERANGE},
      {SCP_POINTS, 1, 2, SCP_F32_XYZ, UINT64_MAX - 2, 0},
      {SCP_NORMALS, 1, 1, SCP_U32_TRIANGLE, 0, SCP_ERANGE},
      {SCP_NORMALS, 1, 1, SCP_F64_XYZ, 0, 0},
      {SCP_VERTICES, 1, 1, SCP_F32_XYZ, 0, SCP_ERANGE},
      {SCP_VERTICES, 1, 1, SCP_U32_TRIANGLE, 0, SCP_ERANGE},
      {SCP_VERTICES, 0, 1, SCP_F64_XYZ, 0, SCP_ERANGE},
      {SCP_VERTICES, 1, 2, SCP_F64_XYZ, 0, 0},
      {SCP_TRIANGLES, 1, 1, SCP_F32_XYZ, 0, SCP_ERANGE},
      {SCP_TRIANGLES, 1, 1, SCP_U32_TRIANGLE, 0, 0},
      {SCP_COMPONENTS, 1, 1, SCP_U32_TRIANGLE, 0, SCP_ERANGE},
      {SCP_COMPONENTS, 1, 3, SCP_I32, 0, 0},
  };
  for (size_t i = 0; i < sizeof ch / sizeof ch[0]; i++) {
    raw_t c;
    memset(&c, 0, sizeof c);
    pt_put32(c.p, ch[i].job);
    pt_put32(c.p + 4, ch[i].count);
    pt_put64(c.p + 8, ch[i].first);
    pt_put32(c.p + 16, ch[i].format);
    size_t size = scp_format_size(ch[i].format);
    c.len = (uint32_t)(24 + ch[i].count * (size ? size : 4));
    expect_invalid(ch[i].type, &c, ch[i].code, ch[i].job);
  }
  raw_t c;
  memset(&c, 0, sizeof c);
  pt_put32(c.p, 9);
  pt_put32(c.p + 4, 3);
  pt_put32(c.p + 16, SCP_I32);
  pt_put32(c.p + 24, (uint32_t)-1);
  pt_put32(c.p + 28, 5);
  pt_put32(c.p + 32, (uint32_t)-2);
  c.len = 36;
  expect_invalid(SCP_COMPONENTS, &c, SCP_ERANGE, 9);
  pt_put32(c.p + 32, (uint32_t)INT32_MIN);
  expect_invalid(SCP_COMPONENTS, &c, SCP_ERANGE, 9);
  pt_put32(c.p + 32, 0);
  expect_invalid(SCP_COMPONENTS, &c, 0, 9);

  /* Value lists: kind 0, empty, long or badly spelt names. */
  /* The last is one character longer than SCP_NAME_MAX. */
  char too_long[SCP_NAME_MAX + 2];
  memset(too_long, 'a', SCP_NAME_MAX + 1);
  too_long[SCP_NAME_MAX + 1] = '\0';
  const char *bad_names[] = {"",    "Abc", "1abc",          "_a",    ".a",
                             "a-b", "a b", "abc\xc3\xa9", too_long};
  for (size_t i = 0; i < sizeof bad_names / sizeof bad_names[0]; i++) {
    scp_value_t v = {.name = bad_names[i], .kind = SCP_KIND_U64};
    ASSERT_CODE_EQ(scp_enc_stats(&b, 1, &v, 1), SCP_ERANGE, scp_err_name);
  }
  scp_value_t v = {.name = "ok", .kind = 0};
  ASSERT_CODE_EQ(scp_enc_stats(&b, 1, &v, 1), SCP_ERANGE, scp_err_name);
  v.kind = 256;
  ASSERT_CODE_EQ(scp_enc_stats(&b, 1, &v, 1), SCP_ERANGE, scp_err_name);
  v.name = NULL;
  v.kind = 1;
  ASSERT_CODE_EQ(scp_enc_stats(&b, 1, &v, 1), SCP_EINVAL, scp_err_name);
  ASSERT_CODE_EQ(scp_enc_stats(&b, 1, NULL, 1), SCP_EINVAL, scp_err_name);
  ASSERT_EQ(b.len, 0);

  raw_t jd;
  memset(&jd, 0, sizeof jd);
  pt_put32(jd.p, 4);
  pt_put32(jd.p + 4, 1);
  jd.p[32] = SCP_KIND_U64;
  jd.p[33] = 2;
  jd.p[34] = 'o';
  jd.p[35] = 'k';
  jd.len = 32 + 12;
  expect_invalid(SCP_JOB_DONE, &jd, 0, 4);
  jd.p[32] = 0;
  expect_invalid(SCP_JOB_DONE, &jd, SCP_ERANGE, 4);
  jd.p[32] = 99; /* unknown kinds are fine */
  expect_invalid(SCP_JOB_DONE, &jd, 0, 4);
  jd.p[35] = 'K';
  expect_invalid(SCP_JOB_DONE, &jd, SCP_ERANGE, 4);
  jd.p[35] = 'k';
  pt_put32(jd.p, 0);
  expect_invalid(SCP_JOB_DONE, &jd, SCP_ERANGE, 0);

  /* HELLO and WELCOME fields. */
  scp_hello_t h = {.version_min = 1, .version_max = 1, .max_frame = 4095};
  ASSERT_CODE_EQ(scp_enc_hello(&b, &h), SCP_ERANGE, scp_err_name);
  scp_welcome_t w[] = {
      {.version = 1, .max_frame = 4095, .max_jobs = 1, .max_points = 1},
      {.version = 1, .max_frame = SCP_FRAME_CEILING + 1, .max_jobs = 1,
       .max_points = 1},
      {.version = 1, .max_frame = 4096, .max_jobs = 0, .max_points = 1},
      {.version = 1, .max_frame = 4096, .max_jobs = 1, .max_points = 0}};
  for (size_t i = 0; i < sizeof w / sizeof w[0]; i++) {
    ASSERT_CODE_EQ(scp_enc_welcome(&b, &w[i]), SCP_ERANGE, scp_err_name);
    uint8_t p[32] = {0};
    memcpy(p, SCP_MAGIC, 4);
    p[4] = 1;
    pt_put32(p + 16, w[i].max_frame);
    pt_put32(p + 20, w[i].max_jobs);
    pt_put64(p + 24, w[i].max_points);
    f = (scp_frame_t){.type = SCP_WELCOME, .length = 32, .payload = p};
    ASSERT_CODE_EQ(scp_parse(&f, &m), SCP_ERANGE, scp_err_name);
  }
  ASSERT_EQ(b.len, 0);
  scp_buf_free(&b);

  /* A parser handed the wrong type of frame. */
  f = (scp_frame_t){.type = SCP_PING, .length = 8, .payload = z};
  scp_job_end_t out;
  ASSERT_CODE_EQ(scp_parse_job_end(&f, &out), SCP_EINVAL, scp_err_name);
  scp_chunk_t chunk;
  ASSERT_CODE_EQ(scp_parse_chunk(&f, &chunk), SCP_EINVAL, scp_err_name);
}

static void test_feed_args(void) {
  scp_decoder_t *d = decoder(SCP_ROLE_ANY, SCP_FRAME_MIN);
  ASSERT_CODE_EQ(scp_decoder_feed(d, NULL, 0), 0, scp_err_name);
  ASSERT_CODE_EQ(scp_decoder_feed(d, NULL, 1), SCP_EINVAL, scp_err_name);
  /* A caller's mistake does not poison the stream. */
  ASSERT_CODE_EQ(scp_decoder_error(d), 0, scp_err_name);
  scp_decoder_free(d);
  scp_decoder_free(NULL);
  scp_buf_free(NULL);
}

int main(void) {
  test_truncation();
  test_oversize();
  test_header_flags();
  test_magic_and_version();
  test_handshake_position();
  test_unknown_type();
  test_wrong_lengths();
  test_reserved();
  test_ranges();
  test_feed_args();
  return sct_finish("proto_errors");
}
