/*
 * Every way a job or a connection can fail, against the real daemon, each
 * with its code and a message that says why: no daemon, jobs refused
 * (too many points, no memory budget, too many jobs in use), jobs that
 * fail (degenerate or non-finite input), parameters out of range, and the
 * daemon dying in the middle of a job.
 *
 *   test_clients_errors DAEMON
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include "common.h"

static int try_connect(const char *sock, char *msg, size_t len,
                       sc_client_t **out) {
  sc_client_options_t o;
  sc_client_options_init(&o);
  o.socket_path = sock;
  o.io_timeout_ms = 5000;
  return sc_client_connect(&o, out, msg, len);
}

static void no_daemon(void) {
  scdt_daemon_t d;
  ASSERT_MSG(scdt_daemon_prepare(&d) == 0, "temporary directory");
  char msg[512];
  static char junk;
  sc_client_t *c = (sc_client_t *)(void *)&junk;
  /* No socket file at all. */
  int rc = try_connect(d.sock, msg, sizeof msg, &c);
  EXPECT_EQ(rc, SC_CLIENT_ENODAEMON);
  EXPECT_MSG(c == NULL, "a handle came back");
  EXPECT_STR_CONTAINS(msg, "not running");
  EXPECT_STR_CONTAINS(msg, d.sock);
  /* A socket file left behind by a daemon that is gone. */
  int fd = socket(AF_UNIX, SOCK_STREAM, 0);
  struct sockaddr_un sa;
  memset(&sa, 0, sizeof sa);
  sa.sun_family = AF_UNIX;
  ASSERT_MSG(strlen(d.sock) < sizeof sa.sun_path, "path too long: %s", d.sock);
  memcpy(sa.sun_path, d.sock, strlen(d.sock) + 1);
  ASSERT_MSG(fd >= 0 && bind(fd, (struct sockaddr *)&sa, sizeof sa) == 0,
             "bind %s", d.sock);
  close(fd);
  rc = try_connect(d.sock, msg, sizeof msg, &c);
  EXPECT_EQ(rc, SC_CLIENT_ENODAEMON);
  EXPECT_STR_CONTAINS(msg, "not running");
  unlink(d.sock);
  /* A path no socket can have. */
  char longpath[300];
  memset(longpath, 'x', sizeof longpath - 1);
  longpath[0] = '/';
  longpath[sizeof longpath - 1] = '\0';
  rc = try_connect(longpath, msg, sizeof msg, &c);
  EXPECT_EQ(rc, SC_CLIENT_ECONNECT);
  EXPECT_STR_CONTAINS(msg, "too long");
  /* Names and messages for every code. */
  EXPECT_MSG(strcmp(sc_client_err_name(SC_CLIENT_ENODAEMON), "NODAEMON") == 0,
             "%s", sc_client_err_name(SC_CLIENT_ENODAEMON));
  EXPECT_MSG(strcmp(sc_client_strerror(SC_CLIENT_ENODAEMON),
                    "the daemon is not running") == 0,
             "%s", sc_client_strerror(SC_CLIENT_ENODAEMON));
  EXPECT_MSG(strcmp(sc_client_err_name(-1), "UNKNOWN") == 0, "unknown code");
  EXPECT_MSG(strcmp(sc_client_server_code_name(15), "DEGENERATE_INPUT") == 0,
             "%s", sc_client_server_code_name(15));
}

typedef struct busy {
  sc_client_t *c;
  const double *xyz;
  int calls, rc;
  uint32_t server_code;
  char msg[1200];
} busy_t;

/* Submits a job on another connection while the first one's upload is
 * still open. */
static int submit_second(void *user, sc_client_job_t *job, uint32_t stage,
                         double fraction) {
  busy_t *b = user;
  if (stage != SC_CLIENT_STAGE_UPLOAD || b->calls++)
    return 0;
  sc_client_job_t *j;
  b->rc = sc_client_submit(b->c, NULL, b->xyz, 900, &j);
  if (b->rc == 0) {
    b->rc = sc_client_wait(b->c, j, SCCT_WAIT_MS);
    b->server_code = sc_client_job_server_code(j);
    snprintf(b->msg, sizeof b->msg, "%s", sc_client_job_message(j));
    sc_client_job_free(j);
  }
  return 0;
}

static void refused(void) {
  /* At most 1000 points per job, 2 jobs per connection. */
  scdt_daemon_t d;
  const char *args[] = {"--max-points", "1000", "--max-jobs", "2", NULL};
  ASSERT_MSG(scdt_daemon_start(&d, args) == 0, "daemon did not start");
  sc_client_t *c = scct_open(d.sock, 0);
  sc_client_info_t info;
  sc_client_get_info(c, &info);
  EXPECT_EQ(info.max_points, 1000);
  EXPECT_EQ(info.max_jobs, 2);
  const uint64_t n = 3000;
  double *xyz = scdt_sample(SCS_SURF_SPHERE, n, 1);
  sc_client_job_t *j;
  /* Too many points: refused, and why. */
  EXPECT_EQ(sc_client_submit(c, NULL, xyz, n, &j), 0);
  EXPECT_STATUS(j, SC_CLIENT_EREFUSED);
  EXPECT_EQ(sc_client_job_server_code(j), 8 /* LIMIT */);
  EXPECT_STR_CONTAINS(sc_client_job_message(j), "LIMIT");
  EXPECT_STR_CONTAINS(sc_client_job_message(j), "at most 1000");
  EXPECT_EQ(sc_client_wait(c, j, 0), SC_CLIENT_EREFUSED);
  sc_client_job_free(j);
  /* The connection is fine, and a job of the right size goes through. */
  EXPECT_EQ(sc_client_submit(c, NULL, xyz, 1000, &j), 0);
  EXPECT_EQ(sc_client_wait(c, j, SCCT_WAIT_MS), 0);
  sc_client_job_free(j);

  /* Two jobs in use at once at most: the third is refused here. */
  sc_client_job_t *a, *b;
  EXPECT_EQ(sc_client_submit(c, NULL, xyz, 1000, &a), 0);
  EXPECT_EQ(sc_client_submit(c, NULL, xyz + 3000, 1000, &b), 0);
  int rc = sc_client_submit(c, NULL, xyz, 1000, &j);
  EXPECT_EQ(rc, SC_CLIENT_ELIMIT);
  EXPECT_MSG(j == NULL, "a job came back");
  EXPECT_STR_CONTAINS(sc_client_last_error(c), "wait for one");
  EXPECT_EQ(sc_client_wait(c, a, SCCT_WAIT_MS), 0);
  EXPECT_EQ(sc_client_submit(c, NULL, xyz, 1000, &j), 0);
  EXPECT_EQ(sc_client_wait(c, b, SCCT_WAIT_MS), 0);
  EXPECT_EQ(sc_client_wait(c, j, SCCT_WAIT_MS), 0);
  sc_client_job_free(a);
  sc_client_job_free(b);
  sc_client_job_free(j);
  sc_client_free(c);
  EXPECT_EQ(scdt_daemon_stop(&d), 0);

  /* A memory budget for one job of about 950 points at a time: while one
   * job holds it, the daemon refuses another, BUSY. The second job goes
   * out on a second connection from the first one's upload callback, when
   * the first has sent its points but not its JOB_END. */
  const char *args2[] = {"--memory-budget", "2M", NULL};
  ASSERT_MSG(scdt_daemon_start(&d, args2) == 0, "daemon did not start");
  busy_t b2;
  memset(&b2, 0, sizeof b2);
  b2.c = scct_open(d.sock, 0);
  b2.xyz = xyz;
  c = scct_open(d.sock, 0);
  sc_client_params_t p;
  sc_client_params_init(&p);
  p.progress = submit_second;
  p.progress_user = &b2;
  EXPECT_EQ(sc_client_submit(c, &p, xyz, 900, &j), 0);
  EXPECT_EQ(sc_client_wait(c, j, SCCT_WAIT_MS), 0);
  sc_client_job_free(j);
  EXPECT_EQ(b2.rc, SC_CLIENT_EREFUSED);
  EXPECT_EQ(b2.server_code, 10 /* BUSY */);
  EXPECT_STR_CONTAINS(b2.msg, "BUSY");
  EXPECT_STR_CONTAINS(b2.msg, "memory budget");
  /* Once the first job is over, there is room again. */
  EXPECT_EQ(sc_client_submit(b2.c, NULL, xyz, 900, &j), 0);
  EXPECT_EQ(sc_client_wait(b2.c, j, SCCT_WAIT_MS), 0);
  sc_client_job_free(j);
  sc_client_free(b2.c);
  sc_client_free(c);
  EXPECT_EQ(scdt_daemon_stop(&d), 0);
  free(xyz);
}

static void failed_and_invalid(void) {
  scdt_daemon_t d;
  ASSERT_MSG(scdt_daemon_start(&d, NULL) == 0, "daemon did not start");
  sc_client_t *c = scct_open(d.sock, 0);
  sc_client_job_t *j;

  /* Points all in one plane: the daemon accepts the job and fails it. */
  double flat[3 * 100];
  for (int i = 0; i < 100; i++) {
    flat[3 * i] = i % 10;
    flat[3 * i + 1] = i / 10;
    flat[3 * i + 2] = 0;
  }
  EXPECT_EQ(sc_client_submit(c, NULL, flat, 100, &j), 0);
  EXPECT_EQ(sc_client_wait(c, j, SCCT_WAIT_MS), SC_CLIENT_EFAILED);
  EXPECT_EQ(sc_client_job_server_code(j), 15 /* DEGENERATE_INPUT */);
  EXPECT_STR_CONTAINS(sc_client_job_message(j), "DEGENERATE_INPUT");
  EXPECT_STR_CONTAINS(sc_client_job_message(j), "coplanar");
  sc_client_job_free(j);

  /* A NaN. */
  double *xyz = scdt_sample(SCS_SURF_SPHERE, 500, 2);
  xyz[3 * 17 + 1] = NAN;
  EXPECT_EQ(sc_client_submit(c, NULL, xyz, 500, &j), 0);
  EXPECT_EQ(sc_client_wait(c, j, SCCT_WAIT_MS), SC_CLIENT_EFAILED);
  EXPECT_EQ(sc_client_job_server_code(j), 16 /* NONFINITE */);
  EXPECT_STR_CONTAINS(sc_client_job_message(j), "NONFINITE");
  sc_client_job_free(j);
  free(xyz);

  /* Parameters out of range never leave the client. */
  sc_client_params_t p;
  sc_client_params_init(&p);
  p.r = 0.7;
  EXPECT_EQ(sc_client_submit(c, &p, flat, 100, &j), SC_CLIENT_EINVAL);
  EXPECT_STR_CONTAINS(sc_client_last_error(c), "r must be in (0, 0.5)");
  sc_client_params_init(&p);
  p.theta = 2;
  EXPECT_EQ(sc_client_submit(c, &p, flat, 100, &j), SC_CLIENT_EINVAL);
  EXPECT_STR_CONTAINS(sc_client_last_error(c), "theta");
  sc_client_params_init(&p);
  p.mode = 9;
  EXPECT_EQ(sc_client_submit(c, &p, flat, 100, &j), SC_CLIENT_EINVAL);
  EXPECT_EQ(sc_client_submit(c, NULL, NULL, 100, &j), SC_CLIENT_EINVAL);
  EXPECT_EQ(sc_client_jobs_in_use(c), 0);
  EXPECT_EQ(sc_client_ping(c, SCCT_WAIT_MS, NULL), 0);
  sc_client_free(c);
  EXPECT_EQ(scdt_daemon_stop(&d), 0);
}

/* Kills the daemon as soon as it reports progress on the job once armed.
 * The daemon reports progress while points are still arriving, and the
 * client may read that report within the submit call: killing the daemon
 * there would fail the submit itself, which is not what is tested. */
struct killer {
  scdt_daemon_t *d;
  int armed;
};

static int kill_daemon(void *user, sc_client_job_t *job, uint32_t stage,
                       double fraction) {
  struct killer *k = user;
  if (k->armed && stage < 6 && k->d->pid > 0)
    kill(k->d->pid, SIGKILL);
  return 0;
}

static void connection_lost(void) {
  scdt_daemon_t d;
  /* One worker: the second job waits behind the first, so it cannot finish
   * before the first one's progress kills the daemon. */
  const char *args[] = {"--workers", "1", NULL};
  ASSERT_MSG(scdt_daemon_start(&d, args) == 0, "daemon did not start");
  sc_client_t *c = scct_open(d.sock, 0);
  const uint64_t n = 50000;
  double *xyz = scdt_sample(SCS_SURF_TORUS, n, 4);
  sc_client_params_t p;
  sc_client_params_init(&p);
  struct killer killer = {&d, 0};
  p.progress = kill_daemon;
  p.progress_user = &killer;
  sc_client_job_t *j, *k;
  EXPECT_EQ(sc_client_submit(c, &p, xyz, n, &j), 0);
  /* A second job, whose end is the same. */
  EXPECT_EQ(sc_client_submit(c, NULL, xyz, 1000, &k), 0);
  killer.armed = 1;
  EXPECT_EQ(sc_client_wait(c, j, SCCT_WAIT_MS), SC_CLIENT_ELOST);
  /* A killed daemon shows as end of file or, when the kernel still held
   * unread upload bytes for it, as a reset: either message names the
   * connection. */
  EXPECT_STR_CONTAINS(sc_client_job_message(j), "connection");
  EXPECT_EQ(sc_client_wait(c, k, SCCT_WAIT_MS), SC_CLIENT_ELOST);
  EXPECT_EQ(sc_client_status(c), SC_CLIENT_ELOST);
  EXPECT_EQ(sc_client_jobs_in_use(c), 0);
  /* Every later call says so. */
  sc_client_job_t *l = NULL;
  EXPECT_EQ(sc_client_submit(c, NULL, xyz, 1000, &l), SC_CLIENT_ELOST);
  EXPECT_MSG(l == NULL, "a job on a dead connection");
  EXPECT_EQ(sc_client_ping(c, 1000, NULL), SC_CLIENT_ELOST);
  EXPECT_STR_CONTAINS(sc_client_last_error(c), "connection");
  sc_client_job_free(j);
  sc_client_job_free(k);
  sc_client_free(c);
  scdt_daemon_wait(&d, 60000);
  EXPECT_MSG(d.status == 128 + SIGKILL, "daemon status %d", d.status);
  free(xyz);
}

/* A daemon that stops gracefully with a job in flight: the job either
 * finishes in the grace period or ends with SHUTDOWN, and then the daemon
 * closes the connection, saying why. */
static void shutdown_(void) {
  scdt_daemon_t d;
  const char *args[] = {"--grace", "0", NULL};
  ASSERT_MSG(scdt_daemon_start(&d, args) == 0, "daemon did not start");
  sc_client_t *c = scct_open(d.sock, 0);
  const uint64_t n = 200000;
  double *xyz = malloc(n * 3 * sizeof(double));
  ASSERT_MSG(xyz &&
                 scs_sample_surface(SCS_SURF_SPHERE, SCS_DENSITY_UNIFORM_RANDOM,
                                    n, 9, xyz) == SCS_OK,
             "sample");
  sc_client_job_t *j;
  EXPECT_EQ(sc_client_submit(c, NULL, xyz, n, &j), 0);
  kill(d.pid, SIGTERM);
  int rc = sc_client_wait(c, j, SCCT_WAIT_MS);
  EXPECT_MSG(rc == 0 || rc == SC_CLIENT_ESHUTDOWN, "job ended with %s: %s",
             sc_client_err_name(rc), sc_client_job_message(j));
  sc_client_job_free(j);
  /* Once its jobs are over the daemon closes the connection with a fatal
   * ERROR SHUTDOWN. */
  rc = sc_client_ping(c, SCCT_WAIT_MS, NULL);
  EXPECT_MSG(rc == SC_CLIENT_ESHUTDOWN || rc == SC_CLIENT_ELOST,
             "ping after shutdown: %s: %s", sc_client_err_name(rc),
             sc_client_last_error(c));
  sc_client_free(c);
  EXPECT_EQ(scdt_daemon_wait(&d, 60000), 0);
  free(xyz);
}

int main(int argc, char **argv) {
  scdt_init(argc, argv);
  no_daemon();
  refused();
  failed_and_invalid();
  connection_lost();
  shutdown_();
  return scdt_finish();
}
