/*
 * A client that connects and never says HELLO is closed with a fatal
 * TIMEOUT after the handshake time (10 s), and nothing else is held up
 * meanwhile.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <stdlib.h>

#include "daemontest.h"
#include "synth.h"

#define T_MS 120000

int main(int argc, char **argv) {
  scdt_init(argc, argv);
  scdt_daemon_t d;
  ASSERT_MSG(scdt_daemon_start(&d, NULL) == 0, "daemon did not start");
  scdt_conn_t *mute;
  ASSERT_MSG(scdt_connect(d.sock, &mute) == 0, "connect");
  uint64_t t0 = scdt_now_ms();

  /* Others are served while the silent one waits. */
  scdt_conn_t *c;
  ASSERT_MSG(scdt_open(d.sock, 1u << 20, &c) == 0, "connect");
  double *xyz = scdt_sample(SCS_SURF_SPHERE, 2000, 1);
  scdt_job_t j;
  scdt_job_init(&j, 1, xyz, 2000);
  scdt_job_t *pj = &j;
  char why[512] = "";
  EXPECT_MSG(scdt_job_send(c, &j) == 0, "send");
  EXPECT_MSG(scdt_collect(c, &pj, 1, T_MS, why, sizeof why) == 0, "%s", why);
  EXPECT_MSG(scdt_mesh_ok(SCS_SURF_SPHERE, &j, why, sizeof why), "%s", why);
  scdt_job_reset(&j);
  scdt_close(c);

  EXPECT_MSG(scdt_wait_closed(mute, T_MS), "silent client not closed");
  uint64_t waited = scdt_now_ms() - t0;
  EXPECT_MSG(mute->got_error && mute->last_error.code == SCP_WIRE_TIMEOUT &&
                 (mute->last_error.flags & SCP_ERROR_FATAL),
             "want a fatal TIMEOUT");
  EXPECT_MSG(waited >= 9000 && waited <= 20000, "closed after %llu ms",
             (unsigned long long)waited);
  printf("silent client closed after %llu ms: %s\n",
         (unsigned long long)waited, mute->last_error.message);
  scdt_close(mute);
  free(xyz);
  EXPECT_EQ(scdt_daemon_stop(&d), 0);
  return scdt_finish();
}
