/*
 * A daemon started with --tile-points runs a large job in tiles on the
 * cores of its idle workers (docs/algorithm.md section 17): the same
 * triangles as the core on one thread, in boundary mode too; jobs below
 * the size, or that did not announce their size run as before; two
 * large jobs at once both finish, and every lent core comes back
 * (workers_lent, jobs_tiled_total in STATS).
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <stdlib.h>
#include <string.h>

#include "daemontest.h"
#include "shortcrust.h"
#include "synth.h"

#define T_MS 300000
#define N 6000

static scdt_daemon_t d;
static double *torus;

/* The core's triangles on one thread, untiled. */
static sc_mesh_t *direct(sc_mode_t mode) {
  sc_params_t p;
  sc_params_init(&p);
  p.mode = mode;
  p.r = 0.25; /* the test client's */
  sc_mesh_t *m = NULL;
  char msg[256];
  ASSERT_MSG(sc_reconstruct(torus, N, &p, &m, msg, sizeof msg) == SC_OK, "%s",
             msg);
  return m;
}

static void expect_same(const scdt_job_t *j, const sc_mesh_t *m,
                        const char *what) {
  EXPECT_MSG(j->done && j->ntri == m->triangle_count &&
                 memcmp(j->tri, m->triangles,
                        3 * sizeof(uint32_t) * m->triangle_count) == 0,
             "%s: %llu triangles, the core %zu, or others", what,
             (unsigned long long)j->ntri, m->triangle_count);
}

/* Runs the jobs on c at once and collects them. */
static void run(scdt_conn_t *c, scdt_job_t **js, size_t k) {
  char why[512] = "";
  for (size_t i = 0; i < k; i++)
    ASSERT_MSG(scdt_job_send(c, js[i]) == 0, "job %u: send", js[i]->id);
  EXPECT_MSG(scdt_collect(c, js, k, T_MS, why, sizeof why) == 0, "%s", why);
}

static uint64_t tiled(void) {
  return scdt_stat_fresh(d.sock, "jobs_tiled_total");
}

int main(int argc, char **argv) {
  scdt_init(argc, argv);
  torus = scdt_sample(SCS_SURF_TORUS, N, 5);
  ASSERT_MSG(torus != NULL, "sample");
  /* With a little noise, as scanned: on an exact sample of a closed
     surface the tiles give up and the job runs on one triangulation
     (docs/algorithm.md section 17.2), and the tiles' certification would
     go unchecked here. */
  scs_add_noise(torus, N, 0.3 * scs_surface_spacing(SCS_SURF_TORUS, N), 5);
  const char *args[] = {"--workers", "2", "--tile-points", "5000", NULL};
  ASSERT_MSG(scdt_daemon_start(&d, args) == 0, "daemon");
  scdt_conn_t *c;
  ASSERT_MSG(scdt_connect(d.sock, &c) == 0, "connect");
  ASSERT_MSG(scdt_handshake(c, 1u << 20) == 0, "handshake");
  sc_mesh_t *cocone = direct(SC_MODE_COCONE);
  sc_mesh_t *crust = direct(SC_MODE_SHORTCRUST);

  /* Alone on an idle daemon: tiled, the same triangles. */
  scdt_job_t a;
  scdt_job_init(&a, 1, torus, N);
  scdt_job_t *one[1] = {&a};
  run(c, one, 1);
  expect_same(&a, cocone, "a large job on an idle daemon");
  EXPECT_EQ(tiled(), 1);
  scdt_job_reset(&a);

  /* Not announced: as before. */
  a.declare = 0;
  run(c, one, 1);
  expect_same(&a, cocone, "a job of unannounced size");
  EXPECT_EQ(tiled(), 1);
  scdt_job_reset(&a);
  /* Boundary mode: its detection runs over the tiles too. */
  a.declare = 1;
  a.mode = SCP_MODE_BOUNDARY;
  run(c, one, 1);
  sc_mesh_t *open = direct(SC_MODE_BOUNDARY);
  expect_same(&a, open, "a large boundary-mode job");
  sc_mesh_free(open);
  EXPECT_EQ(tiled(), 2);
  scdt_job_reset(&a);

  /* Two large jobs at once, one of them in the shortcrust mode: both
   * right, whether one of them found the other worker idle or not. */
  scdt_job_t b;
  scdt_job_init(&a, 2, torus, N);
  scdt_job_init(&b, 3, torus, N);
  b.mode = SCP_MODE_SHORTCRUST;
  scdt_job_t *two[2] = {&a, &b};
  run(c, two, 2);
  expect_same(&a, cocone, "two large jobs at once, the first");
  expect_same(&b, crust, "two large jobs at once, the second");
  const uint64_t after = tiled();
  EXPECT_MSG(after <= 4, "jobs_tiled_total %llu, want 2 to 4",
             (unsigned long long)after);
  EXPECT_EQ(scdt_stat_fresh(d.sock, "workers_lent"), 0);
  printf("tiles on idle workers: %llu of 5 large jobs tiled\n",
         (unsigned long long)after);
  scdt_job_reset(&a);
  scdt_job_reset(&b);

  scdt_close(c);
  sc_mesh_free(cocone);
  sc_mesh_free(crust);
  EXPECT_MSG(scdt_daemon_stop(&d) == 0, "daemon stop: status %d", d.status);
  free(torus);
  return scdt_finish();
}
