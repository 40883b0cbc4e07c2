/*
 * The two decisions of the handshake (PROTOCOL.md section 5), so that the
 * server and every client make them the same way.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "scproto.h"
#include "wire.h"

int scp_handshake_answer(const scp_hello_t *hello, const scp_welcome_t *server,
                         scp_welcome_t *out) {
  int rc = scp__check_hello(hello);
  if (rc)
    return rc;
  if (server->max_frame < SCP_FRAME_MIN ||
      server->max_frame > SCP_FRAME_CEILING || server->max_jobs < 1 ||
      server->max_points < 1)
    return SCP_EINVAL;
  /* The newest version both sides speak; this library speaks only one. */
  if (hello->version_min > SCP_VERSION || hello->version_max < SCP_VERSION)
    return SCP_EVERSION;
  out->version = SCP_VERSION;
  out->features = hello->features & server->features;
  out->max_frame = hello->max_frame < server->max_frame ? hello->max_frame
                                                        : server->max_frame;
  out->max_jobs = server->max_jobs;
  out->max_points = server->max_points;
  return 0;
}

int scp_handshake_check(const scp_hello_t *sent, const scp_welcome_t *got) {
  int rc = scp__check_welcome(got);
  if (rc)
    return rc;
  if (got->version < sent->version_min || got->version > sent->version_max)
    return SCP_EVERSION;
  if (got->max_frame > sent->max_frame)
    return SCP_ERANGE;
  if (got->features & ~sent->features)
    return SCP_EFLAGS;
  return 0;
}

int scp_token_equal(const scp_hello_t *hello, const uint8_t *expected,
                    size_t expected_len) {
  if (!(hello->features & SCP_FEATURE_TOKEN) || !expected)
    return 0;
  const uint8_t *got = hello->token;
  size_t got_len = hello->token_len;
  /* Every byte of the expected token is looked at whatever came, and the
   * differences are gathered without a branch on them; volatile keeps the
   * compiler from stopping at the first one. */
  volatile uint8_t diff = (uint8_t)(got_len != expected_len);
  for (size_t i = 0; i < expected_len; i++) {
    uint8_t g = i < got_len ? got[i] : 0;
    diff |= (uint8_t)(g ^ expected[i]);
  }
  return diff == 0;
}
