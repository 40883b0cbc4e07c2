/*
 * The token of TCP clients (PROTOCOL.md 5.1): read once at start-up from
 * --token-file (by scp_token_read()'s rules: the daemon's alone, one line),
 * checked in every HELLO that comes over TCP.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "conn.h"
#include "daemon.h"
#include "log.h"

#include <string.h>

/* The shortest token taken: 16 bytes leave no room for guessing over a
 * network, and any generator of secrets makes more. */
#define SCD_TOKEN_MIN 16

int scd_token_load(scd_server_t *srv, const char *path) {
  char msg[512];
  if (scp_token_read(path, SCD_TOKEN_MIN, srv->token, &srv->token_len, msg,
                     sizeof msg) != 0) {
    scd_error("%s", msg);
    return -1;
  }
  return 0;
}

void scd_token_forget(scd_server_t *srv) {
  scp_wipe(srv->token, sizeof srv->token);
  srv->token_len = 0;
}

int scd_auth_hello(scd_conn_t *c, const scp_hello_t *h) {
  /* On a Unix socket the file's mode is the access control, and a token
   * sent anyway is ignored (PROTOCOL.md 5.1). */
  if (!c->tcp)
    return 1;
  scd_server_t *srv = c->srv;
  if (srv->token_len && scp_token_equal(h, srv->token, srv->token_len))
    return 1;
  /* Which of the two it was helps whoever configures a client, and says
   * nothing of the token itself. */
  const char *what = (h->features & SCP_FEATURE_TOKEN) && h->token_len
                         ? "wrong token"
                         : "no token";
  scd_warn("conn %llu: refused %s: %s", (ull)c->id, c->peer, what);
  scd_conn_fatal(c, SCP_WIRE_AUTH, 0, SCP_HELLO,
                 "authentication failed: %s (give the daemon's token)", what);
  return 0;
}
