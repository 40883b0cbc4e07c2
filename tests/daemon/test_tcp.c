/*
 * TCP listeners and their token (PROTOCOL.md 5.1): a client with the token
 * gets its mesh; no token, an empty one, a wrong one or a prefix of the
 * right one get a fatal ERROR AUTH and nothing else, not even a PONG for a
 * PING sent behind the HELLO; each refusal is counted in STATS and logged
 * without the token; on the Unix socket a token is ignored, wrong or not.
 * TCP peers that say nothing hold at most a quarter of the connections.
 * The daemon refuses to start with a TCP listener and no token file, and
 * with a token file that group or others may read or that holds too short
 * a token.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "daemontest.h"
#include "synth.h"

#define T_MS 120000
#define TOKEN "f3a9c1d2e4b5a6978877665544332211"

static double *sphere; /* 2000 points */

/* The address the daemon logged for its TCP listener (port 0 given). */
static void tcp_address(const scdt_daemon_t *dm, char *out, size_t len) {
  ASSERT_MSG(scdt_log_tcp_address(dm, T_MS, out, len),
             "no TCP listener in the log");
  ASSERT_MSG(strncmp(out, "tcp://127.0.0.1:", 16) == 0, "address '%s'", out);
}

/* A handshake with the given token (NULL: the TOKEN bit not offered):
 * 0, the wire code of the ERROR, or -1. */
static int hello_with(const char *addr, const char *token, size_t len,
                      scdt_conn_t **out) {
  scdt_conn_t *c;
  int rc = scdt_connect(addr, &c);
  EXPECT_MSG(rc == 0, "cannot connect to %s: %d", addr, rc);
  if (rc != 0)
    return -1;
  c->features = SCP_FEATURE_JOB_OPTIONS;
  if (token) {
    c->features |= SCP_FEATURE_TOKEN;
    c->token = (const uint8_t *)token;
    c->token_len = (uint32_t)len;
  }
  rc = scdt_handshake(c, 1u << 20);
  *out = c;
  return rc;
}

/* A refused handshake: ERROR AUTH, fatal, naming HELLO, then the close. */
static void expect_refused(const char *addr, const char *token, size_t len,
                           const char *what) {
  scdt_conn_t *c;
  int rc = hello_with(addr, token, len, &c);
  EXPECT_MSG(rc == SCP_WIRE_AUTH, "%s: handshake gave %d, want AUTH", what, rc);
  if (rc == SCP_WIRE_AUTH) {
    EXPECT_EQ(c->last_error.flags, SCP_ERROR_FATAL);
    EXPECT_EQ(c->last_error.ref_type, SCP_HELLO);
    EXPECT_MSG(strstr(c->last_error.message, TOKEN) == NULL,
               "%s: the message holds the token", what);
  }
  EXPECT_MSG(scdt_wait_closed(c, T_MS), "%s: not closed", what);
  scdt_close(c);
}

/* A daemon listening on a free loopback port with TOKEN in its token file,
 * and --max-connections max_conns unless NULL; its address in addr. */
static void spawn_tcp(scdt_daemon_t *d, const char *max_conns, char *addr,
                      size_t len) {
  ASSERT_MSG(scdt_daemon_prepare(d) == 0, "prepare");
  char token_file[200];
  snprintf(token_file, sizeof token_file, "%s/token", d->dir);
  ASSERT_EQ(scdt_write_file(token_file, TOKEN "\n", 0600), 0);
  const char *args[] = {"--listen",          "tcp://127.0.0.1:0",
                        "--token-file",      token_file,
                        "--max-connections", max_conns,
                        NULL};
  if (!max_conns)
    args[4] = NULL;
  ASSERT_MSG(scdt_daemon_spawn(d, args, 1) == 0, "daemon did not start");
  tcp_address(d, addr, len);
}

static void tcp_and_unix(void) {
  scdt_daemon_t d;
  char addr[64];
  spawn_tcp(&d, NULL, addr, sizeof addr);

  /* The right token: WELCOME says the field was read, and a job runs. */
  scdt_conn_t *c;
  ASSERT_EQ(hello_with(addr, TOKEN, strlen(TOKEN), &c), 0);
  EXPECT_EQ(c->welcome.features & SCP_FEATURE_TOKEN, SCP_FEATURE_TOKEN);
  scdt_run_ok(c, 1, SCS_SURF_SPHERE, sphere, 2000, T_MS, "TCP with token");
  scdt_close(c);

  /* Refused, one way after another. */
  char wrong[] = TOKEN;
  wrong[7] ^= 1;
  expect_refused(addr, NULL, 0, "no TOKEN bit");
  expect_refused(addr, "", 0, "an empty token");
  expect_refused(addr, wrong, strlen(wrong), "a wrong token");
  expect_refused(addr, TOKEN, strlen(TOKEN) - 1, "a prefix of the token");
  expect_refused(addr, TOKEN "x", strlen(TOKEN) + 1, "a longer token");

  /* Nothing behind a refused HELLO is carried out: a PING and a
   * STATS_REQUEST in the same write get no answer. */
  ASSERT_EQ(scdt_connect(addr, &c), 0);
  scp_hello_t h = {.version_min = 1, .version_max = 1, .max_frame = 4096};
  ASSERT_EQ(scp_enc_hello(&c->out, &h), 0);
  ASSERT_EQ(scp_enc_ping(&c->out, 42), 0);
  ASSERT_EQ(scp_enc_stats_request(&c->out, 7), 0);
  scdt_flush(c, T_MS);
  int errors = 0, others = 0;
  scdt_frame_t *f;
  while ((f = scdt_recv(c, T_MS)) != NULL) {
    if (f->type == SCP_ERROR)
      errors++;
    else
      others++;
    free(f);
  }
  EXPECT_EQ(errors, 1);
  EXPECT_MSG(others == 0, "%d frames answered a refused connection", others);
  EXPECT(c->eof);
  scdt_close(c);

  /* The Unix socket needs no token, and ignores a wrong one. */
  ASSERT_EQ(hello_with(d.sock, NULL, 0, &c), 0);
  scdt_run_ok(c, 1, SCS_SURF_SPHERE, sphere, 2000, T_MS, "Unix, no token");
  scdt_close(c);
  ASSERT_EQ(hello_with(d.sock, wrong, strlen(wrong), &c), 0);
  scdt_run_ok(c, 1, SCS_SURF_SPHERE, sphere, 2000, T_MS, "Unix, a wrong token");
  scdt_close(c);

  /* Six refusals counted apart from protocol errors; logged, and never
   * with the token. */
  uint64_t v = scdt_stat_fresh(d.sock, "auth_refused_total");
  EXPECT_MSG(v == 6, "auth_refused_total %llu, want 6", (unsigned long long)v);
  v = scdt_stat_fresh(d.sock, "protocol_errors_total");
  EXPECT_MSG(v == 0, "protocol_errors_total %llu", (unsigned long long)v);
  EXPECT_EQ(scdt_log_count(&d, "refused 127.0.0.1:"), 6);
  EXPECT_MSG(!scdt_log_contains(&d, TOKEN) && !scdt_log_contains(&d, wrong),
             "the log holds a token");
  EXPECT_EQ(scdt_daemon_stop(&d), 0);
}

/* Peers that connect over TCP and say nothing hold at most a quarter of
 * --max-connections: the next TCP connection gets BUSY, while the Unix
 * socket, and TCP again once they leave, still serve. */
static void silent_peers(void) {
  scdt_daemon_t d;
  char addr[64];
  spawn_tcp(&d, "8", addr, sizeof addr);

  /* One client in, then two silent peers: the quarter of 8. */
  scdt_conn_t *in, *quiet[2], *c;
  ASSERT_EQ(hello_with(addr, TOKEN, strlen(TOKEN), &in), 0);
  for (int i = 0; i < 2; ++i)
    ASSERT_EQ(scdt_connect(addr, &quiet[i]), 0);
  /* The listener accepts in order: both are in before the next. */
  EXPECT_EQ(hello_with(addr, TOKEN, strlen(TOKEN), &c), SCP_WIRE_BUSY);
  EXPECT_MSG(strstr(c->last_error.message, "before their handshake") != NULL,
             "BUSY says '%s'", c->last_error.message);
  scdt_close(c);
  ASSERT_EQ(hello_with(d.sock, NULL, 0, &c), 0);
  scdt_run_ok(c, 1, SCS_SURF_SPHERE, sphere, 2000, T_MS, "Unix, peers silent");
  scdt_close(c);
  scdt_run_ok(in, 1, SCS_SURF_SPHERE, sphere, 2000, T_MS,
              "TCP client in before the silent peers");
  EXPECT_EQ(scdt_stat_fresh(d.sock, "connections_refused_total"), 1);

  /* Once they leave, TCP serves again. */
  for (int i = 0; i < 2; ++i)
    scdt_close(quiet[i]);
  int rc = -1;
  for (int tries = 0; tries < 100 && rc != 0; ++tries) {
    rc = hello_with(addr, TOKEN, strlen(TOKEN), &c);
    if (rc != 0) {
      scdt_close(c);
      scdt_sleep_ms(20);
    }
  }
  ASSERT_EQ(rc, 0);
  scdt_run_ok(c, 1, SCS_SURF_SPHERE, sphere, 2000, T_MS, "TCP, peers gone");
  scdt_close(c);
  scdt_close(in);
  EXPECT_EQ(scdt_daemon_stop(&d), 0);
}

/* Start-up: a TCP listener needs a token file, and the file must be the
 * daemon's alone and hold a token long enough. */
static void refuses_to_start(void) {
  scdt_daemon_t d;
  ASSERT_MSG(scdt_daemon_prepare(&d) == 0, "prepare");
  char token_file[200];
  snprintf(token_file, sizeof token_file, "%s/token", d.dir);

  const char *no_token[] = {"--listen", "tcp://127.0.0.1:0", NULL};
  ASSERT_EQ(scdt_daemon_spawn(&d, no_token, 0), 0);
  EXPECT_EQ(scdt_daemon_wait(&d, T_MS), 2);

  const char *args[] = {"--listen", "tcp://127.0.0.1:0", "--token-file",
                        token_file, NULL};
  ASSERT_EQ(scdt_write_file(token_file, TOKEN "\n", 0640), 0);
  ASSERT_EQ(scdt_daemon_spawn(&d, args, 0), 0);
  EXPECT_EQ(scdt_daemon_wait(&d, T_MS), 1);
  EXPECT_MSG(scdt_log_contains(&d, "open to group or others (mode 0640)"),
             "no clear message for a readable token file");
  EXPECT_MSG(!scdt_log_contains(&d, TOKEN), "the log holds the token");

  ASSERT_EQ(scdt_write_file(token_file, "short\n", 0600), 0);
  ASSERT_EQ(scdt_daemon_spawn(&d, args, 0), 0);
  EXPECT_EQ(scdt_daemon_wait(&d, T_MS), 1);
  EXPECT_MSG(scdt_log_contains(&d, "must have 16 to 1024 bytes"),
             "no clear message for a short token");

  unlink(token_file);
  ASSERT_EQ(scdt_daemon_spawn(&d, args, 0), 0);
  EXPECT_EQ(scdt_daemon_wait(&d, T_MS), 1);
  EXPECT_MSG(scdt_log_contains(&d, "cannot open the token file"),
             "no clear message for a missing token file");

  const char *bad_listen[] = {"--listen", "udp://127.0.0.1:1", NULL};
  ASSERT_EQ(scdt_daemon_spawn(&d, bad_listen, 0), 0);
  EXPECT_EQ(scdt_daemon_wait(&d, T_MS), 2);
}

int main(int argc, char **argv) {
  scdt_init(argc, argv);
  sphere = scdt_sample(SCS_SURF_SPHERE, 2000, 1);
  tcp_and_unix();
  silent_peers();
  refuses_to_start();
  free(sphere);
  return scdt_finish();
}
