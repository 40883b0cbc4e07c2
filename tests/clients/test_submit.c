/*
 * The client library against the real daemon: jobs from an array and from
 * a file, normals, several jobs in flight on one connection, ping and
 * stats. Every mesh is checked against its own points.
 *
 *   test_clients_submit DAEMON DATADIR
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "common.h"
#include "shortcrust_files.h"

static scdt_daemon_t d;
static const char *datadir;

static void from_array(void) {
  sc_client_t *c = scct_open(d.sock, 0);
  const uint64_t n = 3000;
  double *xyz = scdt_sample(SCS_SURF_TORUS, n, 1);
  sc_client_params_t p;
  sc_client_params_init(&p);
  sc_client_job_t *j = NULL;
  int rc = sc_client_submit(c, &p, xyz, n, &j);
  ASSERT_MSG(rc == 0 && j, "submit: %s: %s", sc_client_err_name(rc),
             sc_client_last_error(c));
  EXPECT_EQ(sc_client_jobs_in_use(c), 1);
  rc = sc_client_wait(c, j, SCCT_WAIT_MS);
  EXPECT_MSG(rc == 0, "wait: %s: %s", sc_client_err_name(rc),
             sc_client_job_message(j));
  EXPECT_EQ(sc_client_jobs_in_use(c), 0);
  EXPECT_MSG(strcmp(sc_client_job_message(j), "") == 0, "message '%s'",
             sc_client_job_message(j));
  EXPECT_EQ(sc_client_job_server_code(j), 0);
  scct_check_mesh("torus from an array", SCS_SURF_TORUS, xyz, n, j);
  uint64_t m;
  EXPECT_MSG(sc_client_job_points(j, &m) == NULL && m == 0,
             "an array job has no points of its own");
  /* Waiting again gives the same answer at once. */
  EXPECT_EQ(sc_client_wait(c, j, 0), 0);
  sc_client_job_free(j);

  /* The shortcrust test, and normals as doubles. */
  p.mode = SC_CLIENT_MODE_SHORTCRUST;
  p.r = 0.14;
  p.normals = 1;
  rc = sc_client_submit(c, &p, xyz, n, &j);
  ASSERT_MSG(rc == 0, "submit: %s", sc_client_last_error(c));
  EXPECT_EQ(sc_client_wait(c, j, SCCT_WAIT_MS), 0);
  scct_check_mesh("torus, shortcrust, normals", SCS_SURF_TORUS, xyz, n, j);
  sc_client_mesh_t mesh;
  sc_client_job_mesh(j, &mesh);
  EXPECT_EQ(mesh.normal_count, n);
  uint64_t bad = 0;
  for (uint64_t i = 0; mesh.normals && i < n; i++) {
    const double *v = mesh.normals + 3 * i;
    if (fabs(sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) - 1) > 1e-9)
      bad++;
  }
  EXPECT_MSG(mesh.normals && bad == 0, "%llu normals are not unit",
             (unsigned long long)bad);
  sc_client_job_free(j);
  free(xyz);
  sc_client_free(c);
}

static void from_file(void) {
  sc_client_t *c = scct_open(d.sock, 0);
  char path[512];
  snprintf(path, sizeof path, "%s/knot1_points.ply", datadir);
  scf_points_t pts;
  char msg[512];
  ASSERT_MSG(scf_points_read(path, &pts, msg, sizeof msg) == 0, "%s", msg);
  sc_client_job_t *j = NULL;
  int rc = sc_client_submit_file(c, NULL, path, &j);
  ASSERT_MSG(rc == 0, "submit_file: %s", sc_client_last_error(c));
  EXPECT_EQ(sc_client_wait(c, j, SCCT_WAIT_MS), 0);
  uint64_t n = 0;
  const double *xyz = sc_client_job_points(j, &n);
  EXPECT_EQ(n, pts.count);
  EXPECT_MSG(xyz && memcmp(xyz, pts.xyz, n * 3 * sizeof(double)) == 0,
             "the job's points are not the file's");
  sc_client_mesh_t m;
  EXPECT_EQ(sc_client_job_mesh(j, &m), 0);
  scs_meshcheck_t mc;
  ASSERT_MSG(scs_meshcheck(pts.count, pts.xyz, m.triangles,
                           (size_t)m.triangle_count, NULL, &mc) == SCS_OK,
             "mesh check");
  char sum[512];
  /* The knot is a closed surface of genus 1 (tests/cli says the same of
   * the local command). */
  EXPECT_MSG(mc.closed && mc.oriented && mc.components == 1 &&
                 mc.genus_total == 1,
             "knot: %s", scs_meshcheck_summary(&mc, sum, sizeof sum));
  scs_meshcheck_free(&mc);
  sc_client_job_free(j);

  /* A text file written here: the same points, the same triangles. */
  char txt[256];
  snprintf(txt, sizeof txt, "%s/knot.xyz", d.dir);
  FILE *f = fopen(txt, "w");
  ASSERT_MSG(f, "cannot write %s", txt);
  for (size_t i = 0; i < pts.count; i++)
    fprintf(f, "%.17g %.17g %.17g\n", pts.xyz[3 * i], pts.xyz[3 * i + 1],
            pts.xyz[3 * i + 2]);
  fclose(f);
  rc = sc_client_submit_file(c, NULL, txt, &j);
  ASSERT_MSG(rc == 0, "submit_file: %s", sc_client_last_error(c));
  EXPECT_EQ(sc_client_wait(c, j, SCCT_WAIT_MS), 0);
  sc_client_mesh_t m2;
  EXPECT_EQ(sc_client_job_mesh(j, &m2), 0);
  EXPECT_EQ(m2.triangle_count, m.triangle_count);
  sc_client_job_free(j);
  unlink(txt);

  /* A file that is not there: an error of the call, naming the file. */
  snprintf(txt, sizeof txt, "%s/missing.ply", d.dir);
  rc = sc_client_submit_file(c, NULL, txt, &j);
  EXPECT_MSG(rc == SC_CLIENT_EFILE && j == NULL, "missing file: %s",
             sc_client_err_name(rc));
  EXPECT_MSG(strstr(sc_client_last_error(c), "missing.ply") != NULL,
             "message '%s' does not name the file", sc_client_last_error(c));
  /* The connection is still fine. */
  EXPECT_EQ(sc_client_ping(c, SCCT_WAIT_MS, NULL), 0);
  scf_points_free(&pts);
  sc_client_free(c);
}

/* Several jobs in flight on one connection, of different sizes and
 * surfaces, collected in whatever order they end. */
static void many_in_flight(void) {
  /* The smallest frames: points and meshes of all jobs interleave in many
   * chunks. */
  sc_client_t *c = scct_open(d.sock, 4096);
  enum { NJ = 6 };
  static const int surf[NJ] = {SCS_SURF_SPHERE, SCS_SURF_TORUS,
                               SCS_SURF_GENUS2, SCS_SURF_SPHERE,
                               SCS_SURF_TORUS,  SCS_SURF_GENUS2};
  double *xyz[NJ];
  uint64_t n[NJ];
  sc_client_job_t *j[NJ];
  for (int k = 0; k < NJ; k++) {
    n[k] = 2000 + 337 * (uint64_t)k;
    xyz[k] = scdt_sample(surf[k], n[k], 10 + (uint64_t)k);
    sc_client_params_t p;
    sc_client_params_init(&p);
    p.normals = k % 2;
    int rc = sc_client_submit(c, &p, xyz[k], n[k], &j[k]);
    ASSERT_MSG(rc == 0, "submit %d: %s", k, sc_client_last_error(c));
  }
  int seen[NJ] = {0};
  for (int got = 0; got < NJ; got++) {
    sc_client_job_t *e = NULL;
    int rc = sc_client_wait_any(c, SCCT_WAIT_MS, &e);
    ASSERT_MSG(e != NULL, "wait_any: %s: %s", sc_client_err_name(rc),
               sc_client_last_error(c));
    int k = 0;
    while (k < NJ && j[k] != e)
      k++;
    ASSERT_MSG(k < NJ, "wait_any returned a job that was not submitted");
    EXPECT_MSG(!seen[k], "job %d returned twice", k);
    seen[k] = 1;
    EXPECT_EQ(rc, 0);
    char what[64];
    snprintf(what, sizeof what, "job %d of %d", k, NJ);
    scct_check_mesh(what, surf[k], xyz[k], n[k], e);
  }
  sc_client_job_t *e = NULL;
  EXPECT_EQ(sc_client_wait_any(c, 0, &e), SC_CLIENT_ESTATE);
  EXPECT_MSG(e == NULL, "wait_any with nothing under way gave a job");
  for (int k = 0; k < NJ; k++) {
    sc_client_job_free(j[k]);
    free(xyz[k]);
  }
  sc_client_free(c);
}

static void ping_and_stats(void) {
  sc_client_t *c = scct_open(d.sock, 0);
  double rtt = -1;
  EXPECT_EQ(sc_client_ping(c, SCCT_WAIT_MS, &rtt), 0);
  EXPECT_MSG(rtt >= 0 && rtt < 60, "round trip %g s", rtt);
  sc_client_info_t info;
  sc_client_get_info(c, &info);
  EXPECT_EQ(info.version, 1);
  EXPECT_EQ(info.max_jobs, 16);
  EXPECT_MSG(strcmp(info.socket_path, d.sock) == 0, "socket %s",
             info.socket_path);
  sc_client_value_t *v = NULL;
  size_t nv = 0;
  EXPECT_EQ(sc_client_stats(c, SCCT_WAIT_MS, &v, &nv), 0);
  const sc_client_value_t *done =
      sc_client_value_find(v, nv, "jobs_done_total");
  /* Two from an array, two from files, six in flight. */
  EXPECT_MSG(done && done->kind == SC_CLIENT_U64 && done->v.u == 10,
             "jobs_done_total %llu",
             done ? (unsigned long long)done->v.u : 0ull);
  EXPECT_EQ(sc_client_value_get(v, nv, "connections", -1), 1);
  EXPECT_EQ(sc_client_value_get(v, nv, "no_such_counter", -7), -7);
  free(v);
  sc_client_free(c);

  /* The default socket follows the daemon's rule. */
  char buf[256];
  setenv("XDG_RUNTIME_DIR", "/run/user/4242", 1);
  EXPECT_MSG(strcmp(sc_client_default_socket(buf, sizeof buf),
                    "/run/user/4242/shortcrust.sock") == 0,
             "default %s", buf);
  setenv("XDG_RUNTIME_DIR", "relative", 1);
  EXPECT_MSG(strcmp(sc_client_default_socket(buf, sizeof buf),
                    "/run/shortcrust/shortcrust.sock") == 0,
             "default %s", buf);
  unsetenv("XDG_RUNTIME_DIR");
  EXPECT_MSG(strcmp(sc_client_default_socket(buf, sizeof buf),
                    "/run/shortcrust/shortcrust.sock") == 0,
             "default %s", buf);
}

int main(int argc, char **argv) {
  scdt_init(argc, argv);
  ASSERT_MSG(argc > 2, "usage: %s DAEMON DATADIR", argv[0]);
  datadir = argv[2];
  const char *args[] = {"--workers", "2", NULL};
  ASSERT_MSG(scdt_daemon_start(&d, args) == 0, "daemon did not start");
  from_array();
  from_file();
  many_in_flight();
  ping_and_stats();
  EXPECT_EQ(scdt_daemon_stop(&d), 0);
  return scdt_finish();
}
