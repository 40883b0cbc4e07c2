/*
 * The client library over TCP: addresses (tcp://, unix://, a plain path,
 * and text that is none), the token from the options, a file or
 * SHORTCRUST_TOKEN, refusals with AUTH, and retries: a job whose daemon is
 * killed under it runs again on the daemon restarted at the same address
 * and comes back right, counting its retries, and so does one whose
 * daemon shuts down under it; with retries run out, it ends with the
 * loss.
 *
 *   test_clients_tcp DAEMON
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "common.h"

#define TOKEN "0123456789abcdef-a-token-for-tests"

static scdt_daemon_t d;
static char addr[64], token_file[200], port_arg[64];

/* The port the daemon chose, from its log. */
static void read_address(void) {
  ASSERT_MSG(scdt_log_tcp_address(&d, 30000, addr, sizeof addr),
             "no TCP listener in the log");
  ASSERT_MSG(strncmp(addr, "tcp://127.0.0.1:", 16) == 0, "address '%s'", addr);
}

static void start(void) {
  /* First on a port of the system's choosing; restarts take the same. */
  const char *args[] = {"--listen",
                        port_arg[0] ? port_arg : "tcp://127.0.0.1:0",
                        "--token-file", token_file, NULL};
  ASSERT_MSG(scdt_daemon_spawn(&d, args, 1) == 0, "daemon did not start");
  if (!port_arg[0]) {
    read_address();
    snprintf(port_arg, sizeof port_arg, "%s", addr);
  }
}

static int try_connect(const char *address, const char *token, const char *file,
                       char *msg, size_t len, sc_client_t **out) {
  sc_client_options_t o;
  sc_client_options_init(&o);
  o.socket_path = address;
  o.token = token;
  o.token_file = file;
  o.io_timeout_ms = 10000;
  return sc_client_connect(&o, out, msg, len);
}

static void run_sphere(sc_client_t *c, const char *what) {
  double *xyz = scdt_sample(SCS_SURF_SPHERE, 2000, 3);
  sc_client_job_t *j = NULL;
  EXPECT_EQ(sc_client_submit(c, NULL, xyz, 2000, &j), 0);
  if (j) {
    EXPECT_EQ(sc_client_wait(c, j, SCCT_WAIT_MS), 0);
    scct_check_mesh(what, SCS_SURF_SPHERE, xyz, 2000, j);
    EXPECT_EQ(sc_client_job_retries(j), 0u);
  }
  sc_client_job_free(j);
  free(xyz);
}

static void addresses_and_tokens(void) {
  char msg[512];
  sc_client_t *c = NULL;
  /* The token from the options, from a file, from the environment. */
  EXPECT_EQ(try_connect(addr, TOKEN, NULL, msg, sizeof msg, &c), 0);
  if (c) {
    sc_client_info_t info;
    sc_client_get_info(c, &info);
    EXPECT_STR_EQ(info.socket_path, addr);
    run_sphere(c, "TCP, token in the options");
  }
  sc_client_free(c);
  EXPECT_EQ(try_connect(addr, NULL, token_file, msg, sizeof msg, &c), 0);
  if (c)
    run_sphere(c, "TCP, token file");
  sc_client_free(c);
  setenv("SHORTCRUST_TOKEN", TOKEN, 1);
  EXPECT_EQ(try_connect(addr, NULL, NULL, msg, sizeof msg, &c), 0);
  sc_client_free(c);
  /* The options come before the environment. */
  EXPECT_EQ(try_connect(addr, "a-wrong-token-of-some-length", NULL, msg,
                        sizeof msg, &c),
            SC_CLIENT_EAUTH);
  EXPECT_STR_CONTAINS(msg, "AUTH");
  unsetenv("SHORTCRUST_TOKEN");

  /* None at all: the daemon says AUTH, and the message says what to do. */
  EXPECT_EQ(try_connect(addr, NULL, NULL, msg, sizeof msg, &c),
            SC_CLIENT_EAUTH);
  EXPECT_MSG(c == NULL, "a handle came back");
  EXPECT_STR_CONTAINS(msg, "SHORTCRUST_TOKEN");

  /* A token file others may read is refused here too, before any byte
   * goes out. */
  char loose[220];
  snprintf(loose, sizeof loose, "%s/loose-token", d.dir);
  ASSERT_EQ(scdt_write_file(loose, TOKEN "\n", 0644), 0);
  EXPECT_EQ(try_connect(addr, NULL, loose, msg, sizeof msg, &c),
            SC_CLIENT_EAUTH);
  EXPECT_STR_CONTAINS(msg, "chmod 600");

  /* The Unix socket, by path and by unix://, needs no token; the library
   * does not send one there even when it has one. */
  char unix_addr[200];
  snprintf(unix_addr, sizeof unix_addr, "unix://%s", d.sock);
  EXPECT_EQ(try_connect(unix_addr, NULL, NULL, msg, sizeof msg, &c), 0);
  if (c)
    run_sphere(c, "unix:// address");
  sc_client_free(c);
  EXPECT_EQ(try_connect(d.sock, "a-wrong-token-of-some-length", NULL, msg,
                        sizeof msg, &c),
            0);
  sc_client_free(c);

  /* Text that is no address, and a port nothing listens on. */
  static const char *const bad[] = {"http://127.0.0.1:80", "tcp://127.0.0.1",
                                    "tcp://127.0.0.1:99999", "tcp://:1"};
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    int rc = try_connect(bad[i], TOKEN, NULL, msg, sizeof msg, &c);
    EXPECT_MSG(rc == SC_CLIENT_EINVAL, "%s: %s", bad[i],
               sc_client_err_name(rc));
    EXPECT_STR_CONTAINS(msg, "not an address");
  }
  EXPECT_EQ(try_connect("tcp://127.0.0.1:1", TOKEN, NULL, msg, sizeof msg, &c),
            SC_CLIENT_ENODAEMON);

  /* The daemon counted the refusals: the wrong token and the missing one
   * (the loose file never reached it). */
  uint64_t v = scdt_stat_fresh(d.sock, "auth_refused_total");
  EXPECT_MSG(v == 2, "auth_refused_total %llu, want 2", (unsigned long long)v);
}

/* Once armed, the first progress report of the big job kills the daemon
 * and starts it again at the same address; the job then has to be run
 * again there. */
struct restarter {
  int armed, done;
  int sig; /* SIGKILL, or SIGTERM for a daemon that shuts down */
};

static int kill_and_restart(void *user, sc_client_job_t *job, uint32_t stage,
                            double fraction) {
  struct restarter *r = user;
  if (!r->armed || r->done || stage >= 6)
    return 0;
  r->done = 1;
  kill(d.pid, r->sig);
  scdt_daemon_wait(&d, 60000);
  const char *args[] = {
      "--listen", port_arg, "--token-file", token_file, "--grace", "0", NULL};
  scdt_daemon_spawn(&d, args, 0);
  return 0;
}

static void retries(void) {
  char msg[512];
  sc_client_t *c = NULL;
  ASSERT_EQ(try_connect(addr, TOKEN, NULL, msg, sizeof msg, &c), 0);
  const uint64_t n = 50000, m = 2000;
  double *big = scdt_sample(SCS_SURF_TORUS, n, 4);
  double *small = scdt_sample(SCS_SURF_SPHERE, m, 5);
  sc_client_params_t p;
  sc_client_params_init(&p);
  EXPECT_EQ(p.retries, 0);
  p.retries = 6;
  p.retry_backoff_ms = 50;
  struct restarter r = {0, 0, SIGKILL};
  p.progress = kill_and_restart;
  p.progress_user = &r;
  sc_client_params_t q = p;
  q.progress = NULL;
  sc_client_job_t *j = NULL, *k = NULL;
  EXPECT_EQ(sc_client_submit(c, &p, big, n, &j), 0);
  EXPECT_EQ(sc_client_submit(c, &q, small, m, &k), 0);
  r.armed = 1;
  ASSERT_NOT_NULL(j);
  ASSERT_NOT_NULL(k);
  EXPECT_EQ(sc_client_wait(c, j, SCCT_WAIT_MS), 0);
  EXPECT_EQ(sc_client_wait(c, k, SCCT_WAIT_MS), 0);
  EXPECT(r.done);
  scct_check_mesh("the big job, retried", SCS_SURF_TORUS, big, n, j);
  EXPECT_MSG(sc_client_job_retries(j) >= 1, "retries %u",
             sc_client_job_retries(j));
  /* The small one may have ended before the kill. */
  if (sc_client_job_status(k) == 0)
    scct_check_mesh("the small job", SCS_SURF_SPHERE, small, m, k);
  EXPECT_EQ(sc_client_status(c), 0);
  sc_client_job_free(j);
  sc_client_job_free(k);
  /* The handle goes on, on the new daemon. */
  run_sphere(c, "after the retry");
  EXPECT_EQ(sc_client_ping(c, 10000, NULL), 0);

  /* A daemon that shuts down (no grace: the job ends with SHUTDOWN, then
   * the connection) is left the same way. */
  r = (struct restarter){0, 0, SIGTERM};
  EXPECT_EQ(sc_client_submit(c, &p, big, n, &j), 0);
  r.armed = 1;
  ASSERT_NOT_NULL(j);
  EXPECT_EQ(sc_client_wait(c, j, SCCT_WAIT_MS), 0);
  EXPECT(r.done);
  scct_check_mesh("the big job, after a shutdown", SCS_SURF_TORUS, big, n, j);
  EXPECT_MSG(sc_client_job_retries(j) >= 1, "retries %u",
             sc_client_job_retries(j));
  sc_client_job_free(j);

  /* Retries run out: the daemon is killed and not started again. */
  p.retries = 2;
  p.retry_backoff_ms = 10;
  p.progress = NULL;
  EXPECT_EQ(sc_client_submit(c, &p, big, n, &j), 0);
  kill(d.pid, SIGKILL);
  scdt_daemon_wait(&d, 60000);
  int rc = sc_client_wait(c, j, SCCT_WAIT_MS);
  EXPECT_MSG(rc == SC_CLIENT_ENODAEMON || rc == SC_CLIENT_ELOST, "%s: %s",
             sc_client_err_name(rc), sc_client_job_message(j));
  EXPECT_EQ(sc_client_job_retries(j), 2u);
  sc_client_job_free(j);
  sc_client_free(c);
  free(big);
  free(small);
}

int main(int argc, char **argv) {
  scdt_init(argc, argv);
  unsetenv("SHORTCRUST_TOKEN");
  ASSERT_MSG(scdt_daemon_prepare(&d) == 0, "prepare");
  snprintf(token_file, sizeof token_file, "%s/token", d.dir);
  ASSERT_EQ(scdt_write_file(token_file, TOKEN "\n", 0600), 0);
  start();
  addresses_and_tokens();
  retries();
  return scdt_finish();
}
