/*
 * The token in HELLO (PROTOCOL.md 5, feature TOKEN), its comparison, and
 * the addresses of daemons: what is written is read back, what the spec
 * calls malformed is refused with the code it gives, the comparison looks
 * at every byte, and only well-formed addresses parse.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "frames.h"

static const uint8_t secret[] = "0123456789abcdef0123456789abcdef";
#define SECRET_LEN 32

/* HELLO with the token, decoded back through a fresh decoder. */
static void test_hello_token(void) {
  scp_hello_t h = {.version_min = 1,
                   .version_max = 1,
                   .features = SCP_FEATURE_TOKEN | SCP_FEATURE_JOB_OPTIONS,
                   .max_frame = 4096,
                   .token = secret,
                   .token_len = SECRET_LEN};
  scp_buf_t b;
  scp_buf_init(&b, 0);
  ASSERT_CODE_EQ(scp_enc_hello(&b, &h), SCP_OK, scp_err_name);
  /* The layout of section 5: the fixed part, u32 token_len, the bytes. */
  ASSERT_EQ(b.len, (size_t)(8 + 24 + 4 + SECRET_LEN));
  ASSERT_EQ(b.data[8 + 24], SECRET_LEN);
  ASSERT_EQ(memcmp(b.data + 8 + 28, secret, SECRET_LEN), 0);
  scp_frame_t f;
  scp_decoder_t *d = pt_decode_one(b.data, b.len, &f);
  scp_hello_t got;
  ASSERT_CODE_EQ(scp_parse_hello(&f, &got), SCP_OK, scp_err_name);
  ASSERT_EQ(got.token_len, (uint32_t)SECRET_LEN);
  EXPECT_MEM_EQ(got.token, got.token_len, secret, SECRET_LEN);
  EXPECT_EQ(scp_token_equal(&got, secret, SECRET_LEN), 1);
  scp_decoder_free(d);

  /* Section 3.3: bytes after the token are a later version's tail. */
  uint8_t raw[256];
  memcpy(raw, b.data, b.len);
  memset(raw + b.len, 0xAB, 8);
  pt_header(raw, SCP_HELLO, 0, (uint32_t)(b.len - 8 + 8));
  d = pt_decode_one(raw, b.len + 8, &f);
  ASSERT_CODE_EQ(scp_parse_hello(&f, &got), SCP_OK, scp_err_name);
  EXPECT_EQ(got.token_len, (uint32_t)SECRET_LEN);
  scp_decoder_free(d);

  /* A token_len past the payload, or above the limit, and a payload that
   * stops inside the token_len field. */
  memcpy(raw, b.data, b.len);
  pt_put32(raw + 8 + 24, SECRET_LEN + 1);
  d = pt_decode_one(raw, b.len, &f);
  EXPECT_CODE_EQ(scp_parse_hello(&f, &got), SCP_ELENGTH, scp_err_name);
  scp_decoder_free(d);
  pt_put32(raw + 8 + 24, SCP_TOKEN_MAX + 1);
  d = pt_decode_one(raw, b.len, &f);
  EXPECT_CODE_EQ(scp_parse_hello(&f, &got), SCP_ERANGE, scp_err_name);
  scp_decoder_free(d);
  pt_header(raw, SCP_HELLO, 0, 26);
  d = pt_decode_one(raw, 8 + 26, &f);
  EXPECT_CODE_EQ(scp_parse_hello(&f, &got), SCP_ESHORT, scp_err_name);
  scp_decoder_free(d);

  /* Without the bit, the same bytes are a tail and carry no token. */
  memcpy(raw, b.data, b.len);
  pt_put64(raw + 8 + 8, 0);
  d = pt_decode_one(raw, b.len, &f);
  ASSERT_CODE_EQ(scp_parse_hello(&f, &got), SCP_OK, scp_err_name);
  EXPECT_EQ(got.token_len, 0u);
  EXPECT_EQ(scp_token_equal(&got, secret, SECRET_LEN), 0);
  scp_decoder_free(d);

  /* The encoder refuses what the parser would. */
  h.token_len = SCP_TOKEN_MAX + 1;
  EXPECT_CODE_EQ(scp_enc_hello(&b, &h), SCP_ERANGE, scp_err_name);
  scp_buf_free(&b);
}

static void test_token_equal(void) {
  uint8_t other[SECRET_LEN];
  scp_hello_t h = {.version_min = 1,
                   .version_max = 1,
                   .features = SCP_FEATURE_TOKEN,
                   .max_frame = 4096,
                   .token = other,
                   .token_len = SECRET_LEN};
  memcpy(other, secret, SECRET_LEN);
  EXPECT_EQ(scp_token_equal(&h, secret, SECRET_LEN), 1);
  /* A difference at any place, in any bit. */
  for (int i = 0; i < SECRET_LEN; i++)
    for (int bit = 0; bit < 8; bit++) {
      other[i] ^= (uint8_t)(1u << bit);
      EXPECT_MSG(scp_token_equal(&h, secret, SECRET_LEN) == 0, "byte %d bit %d",
                 i, bit);
      other[i] ^= (uint8_t)(1u << bit);
    }
  /* A prefix, a longer token, none. */
  h.token_len = SECRET_LEN - 1;
  EXPECT_EQ(scp_token_equal(&h, secret, SECRET_LEN), 0);
  EXPECT_EQ(scp_token_equal(&h, secret, SECRET_LEN - 2), 0);
  h.token_len = SECRET_LEN;
  EXPECT_EQ(scp_token_equal(&h, secret, SECRET_LEN - 1), 0);
  h.token_len = 0;
  h.token = NULL;
  EXPECT_EQ(scp_token_equal(&h, secret, SECRET_LEN), 0);
  EXPECT_EQ(scp_token_equal(&h, NULL, 0), 0);
}

static void test_addresses(void) {
  scp_address_t a;
  char buf[512];
  ASSERT_CODE_EQ(scp_address_parse("tcp://127.0.0.1:7341", &a), SCP_OK,
                 scp_err_name);
  EXPECT_EQ(a.kind, SCP_ADDR_TCP);
  EXPECT_STR_EQ(a.host, "127.0.0.1");
  EXPECT_EQ(a.port, 7341);
  EXPECT_STR_EQ(scp_address_format(&a, buf, sizeof buf),
                "tcp://127.0.0.1:7341");
  ASSERT_CODE_EQ(scp_address_parse("tcp://[::1]:0", &a), SCP_OK, scp_err_name);
  EXPECT_STR_EQ(a.host, "::1");
  EXPECT_EQ(a.port, 0);
  EXPECT_STR_EQ(scp_address_format(&a, buf, sizeof buf), "tcp://[::1]:0");
  ASSERT_CODE_EQ(scp_address_parse("tcp://recon.example:65535", &a), SCP_OK,
                 scp_err_name);
  EXPECT_STR_EQ(a.host, "recon.example");
  EXPECT_EQ(a.port, 65535);
  ASSERT_CODE_EQ(scp_address_parse("unix:///run/sc.sock", &a), SCP_OK,
                 scp_err_name);
  EXPECT_EQ(a.kind, SCP_ADDR_UNIX);
  EXPECT_STR_EQ(a.path, "/run/sc.sock");
  EXPECT_STR_EQ(scp_address_format(&a, buf, sizeof buf), "unix:///run/sc.sock");
  ASSERT_CODE_EQ(scp_address_parse("relative/sc.sock", &a), SCP_OK,
                 scp_err_name);
  EXPECT_EQ(a.kind, SCP_ADDR_UNIX);
  EXPECT_STR_EQ(a.path, "relative/sc.sock");

  static const char *const bad[] = {"",
                                    "unix://",
                                    "tcp://",
                                    "tcp://host",
                                    "tcp://host:",
                                    "tcp://:80",
                                    "tcp://host:65536",
                                    "tcp://host:-1",
                                    "tcp://host:+80",
                                    "tcp://host:8x",
                                    "tcp://host:123456",
                                    "tcp://::1:80",
                                    "tcp://[::1]80",
                                    "tcp://[host]:80",
                                    "tcp://[::1:80",
                                    "tcp://a b:80",
                                    "tcp://a/b:80",
                                    "tcp://u@h:80",
                                    "http://host:80",
                                    "udp://host:80"};
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
    EXPECT_MSG(scp_address_parse(bad[i], &a) == SCP_ERANGE, "'%s' parsed",
               bad[i]);
  char longpath[SCP_ADDR_PATH_MAX + 8];
  memset(longpath, 'p', sizeof longpath);
  longpath[SCP_ADDR_PATH_MAX] = '\0';
  EXPECT_CODE_EQ(scp_address_parse(longpath, &a), SCP_ERANGE, scp_err_name);
  longpath[SCP_ADDR_PATH_MAX - 1] = '\0';
  EXPECT_CODE_EQ(scp_address_parse(longpath, &a), SCP_OK, scp_err_name);
  EXPECT_CODE_EQ(scp_address_parse(NULL, &a), SCP_EINVAL, scp_err_name);
}

int main(void) {
  test_hello_token();
  test_token_equal();
  test_addresses();
  return sct_finish("proto_auth");
}
