/*
 * A client that never reads. The daemon must throttle it with its bounded
 * output queue (stop reading that socket, stop emitting its mesh chunks)
 * instead of growing, keep serving everybody else meanwhile, and free
 * everything once the client goes away.
 *
 *   test_slow_reader DAEMON [big]
 *
 * The small variant floods STATS_REQUESTs, whose replies are far larger
 * than the requests, with a job whose mesh is then held back; "big" sends
 * jobs whose meshes alone are larger than every buffer on the way.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <errno.h>
#include <poll.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>

#include "daemontest.h"
#include "synth.h"

#define T_MS 120000
/* The daemon's caps (daemon/server.c). */
#define OUT_SOFT (4u << 20)
#define OUT_HARD (16u << 20)

static scdt_daemon_t d;

/* Writes STATS_REQUESTs without ever reading, until the socket has stayed
 * full for a while: the daemon has stopped reading us. Returns how many
 * went out. */
static uint64_t flood(scdt_conn_t *c) {
  uint8_t frame[16];
  scp_buf_t b;
  scp_buf_init(&b, SCP_FRAME_MIN);
  scp_enc_stats_request(&b, 1);
  memcpy(frame, b.data, sizeof frame);
  scp_buf_free(&b);
  uint8_t burst[16 * 256];
  for (size_t i = 0; i < sizeof burst; i += 16)
    memcpy(burst + i, frame, 16);
  uint64_t sent = 0;
  size_t partial = 0; /* bytes of a burst already out */
  uint64_t idle_since = scdt_now_ms();
  while (scdt_now_ms() - idle_since < 1500) {
    ssize_t n = send(c->fd, burst + partial, sizeof burst - partial,
                     MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n > 0) {
      partial += (size_t)n;
      sent += (uint64_t)n;
      if (partial == sizeof burst)
        partial = 0;
      idle_since = scdt_now_ms();
    } else if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      struct pollfd p = {.fd = c->fd, .events = POLLOUT};
      poll(&p, 1, 100);
    } else {
      break;
    }
  }
  return sent / 16;
}

static void check_serving(const char *when) {
  double *xyz = scdt_sample(SCS_SURF_TORUS, 3000, 42);
  ASSERT_MSG(xyz != NULL, "%s: sample", when);
  scdt_check_serving(d.sock, SCS_SURF_TORUS, xyz, 3000, T_MS, when);
  free(xyz);
}

static void check_bounded(const char *when) {
  uint64_t q = scdt_stat_fresh(d.sock, "output_queued_bytes");
  printf("%s: %llu bytes of output queued\n", when, (unsigned long long)q);
  EXPECT_MSG(q != UINT64_MAX && q <= OUT_HARD, "%s: %llu bytes queued", when,
             (unsigned long long)q);
}

static void small(void) {
  scdt_conn_t *c;
  ASSERT_MSG(scdt_open(d.sock, SCP_FRAME_MIN, &c) == 0, "connect");
  double *xyz = scdt_sample(SCS_SURF_SPHERE, 4000, 1);
  scdt_job_t j;
  scdt_job_init(&j, 3, xyz, 4000);
  j.flags = SCP_JOB_NORMALS | SCP_JOB_NORMALS_F64;
  EXPECT_MSG(scdt_job_send(c, &j) == 0, "send");
  uint64_t n = flood(c);
  printf("sent %llu STATS_REQUESTs before the daemon stopped reading\n",
         (unsigned long long)n);
  /* The replies are about 40 times the requests: with the queue bounded,
   * the daemon must have stopped reading long before all of them. */
  EXPECT_MSG(n > 0, "nothing sent");
  EXPECT_MSG(scdt_log_wait(&d, "not reading until the client catches up", T_MS),
             "no log line for the throttled connection");
  /* The job finishes computing, but its mesh waits for room. */
  EXPECT_EQ(scdt_stat_wait(d.sock, "workers_busy", 0, T_MS), 0);
  EXPECT_EQ(scdt_stat_wait(d.sock, "queue_depth", 0, T_MS), 0);
  check_bounded("flooded");
  check_serving("while a client does not read");
  check_bounded("flooded, after another client's job");
  scdt_close(c);
  free(xyz);
  EXPECT_EQ(scdt_stat_wait(d.sock, "jobs_active", 0, T_MS), 0);
  EXPECT_EQ(scdt_stat_wait(d.sock, "memory_jobs_bytes", 0, T_MS), 0);
  EXPECT_EQ(scdt_stat_wait(d.sock, "output_queued_bytes", 0, T_MS), 0);
  EXPECT_EQ(scdt_stat_wait(d.sock, "connections", 1, T_MS), 1);
}

static void big(void) {
  scdt_conn_t *c;
  ASSERT_MSG(scdt_open(d.sock, 1u << 20, &c) == 0, "connect");
  enum { NJ = 4 };
  size_t n = 40000;
  double *xyz = scdt_sample(SCS_SURF_SPHERE, n, 2);
  scdt_job_t j[NJ];
  for (int k = 0; k < NJ; k++) {
    scdt_job_init(&j[k], (uint32_t)k + 1, xyz, n);
    j[k].flags = SCP_JOB_NORMALS | SCP_JOB_NORMALS_F64;
    EXPECT_MSG(scdt_job_send(c, &j[k]) == 0, "send %d", k);
  }
  /* Each mesh is about 1.9 MB: together more than the socket buffers and
   * the soft cap. */
  EXPECT_EQ(scdt_stat_wait(d.sock, "queue_depth", 0, T_MS), 0);
  EXPECT_EQ(scdt_stat_wait(d.sock, "workers_busy", 0, T_MS), 0);
  scdt_sleep_ms(500);
  check_bounded("meshes waiting");
  uint64_t q = scdt_stat_fresh(d.sock, "output_queued_bytes");
  EXPECT_MSG(q >= OUT_SOFT / 2, "only %llu bytes queued: not throttled?",
             (unsigned long long)q);
  check_serving("while a client does not read its meshes");
  /* Now read everything: the throttled meshes must all arrive intact. */
  scdt_job_t *pj[NJ];
  for (int k = 0; k < NJ; k++)
    pj[k] = &j[k];
  char why[512] = "";
  EXPECT_MSG(scdt_collect(c, pj, NJ, T_MS, why, sizeof why) == 0, "%s", why);
  for (int k = 0; k < NJ; k++) {
    EXPECT_MSG(scdt_mesh_ok(SCS_SURF_SPHERE, &j[k], why, sizeof why), "%s",
               why);
    scdt_job_reset(&j[k]);
  }
  /* And once more, leaving in the middle. */
  for (int k = 0; k < NJ; k++)
    EXPECT_MSG(scdt_job_send(c, &j[k]) == 0, "send %d", k);
  EXPECT_EQ(scdt_stat_wait(d.sock, "workers_busy", 0, T_MS), 0);
  EXPECT_EQ(scdt_stat_wait(d.sock, "queue_depth", 0, T_MS), 0);
  scdt_close(c);
  EXPECT_EQ(scdt_stat_wait(d.sock, "jobs_active", 0, T_MS), 0);
  EXPECT_EQ(scdt_stat_wait(d.sock, "memory_jobs_bytes", 0, T_MS), 0);
  EXPECT_EQ(scdt_stat_wait(d.sock, "output_queued_bytes", 0, T_MS), 0);
  free(xyz);
}

int main(int argc, char **argv) {
  scdt_init(argc, argv);
  int is_big = argc > 2 && strcmp(argv[2], "big") == 0;
  const char *args[] = {"--workers", "2", NULL};
  ASSERT_MSG(scdt_daemon_start(&d, args) == 0, "daemon did not start");
  if (is_big)
    big();
  else
    small();
  EXPECT_EQ(scdt_daemon_stop(&d), 0);
  return scdt_finish();
}
