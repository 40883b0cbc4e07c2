/*
 * Job options (PROTOCOL.md 6.3): the daemon grants the JOB_OPTIONS feature
 * to a client that offers it, runs a job with its options exactly as the
 * core does with the same parameters, sends the smoothed positions of a
 * denoised job that asks for them (VERTICES), refuses a job whose options
 * it does not know or that are out of range, treats options on a
 * connection without the feature as a malformed frame, and serves on
 * regardless.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <stdlib.h>
#include <string.h>

#include "daemontest.h"
#include "shortcrust.h"
#include "synth.h"

#define T_MS 120000
#define N 3000

static scdt_daemon_t d;
static double *sphere;
/* Uneven: extraction leaves small holes here, which the default fills and
 * max_hole_edges 0 does not. */
static double *torus;

static scdt_conn_t *open_conn(uint64_t features) {
  scdt_conn_t *c;
  ASSERT_MSG(scdt_connect(d.sock, &c) == 0, "connect");
  c->features = features;
  ASSERT_MSG(scdt_handshake(c, 1u << 20) == 0, "handshake");
  return c;
}

/* Runs a job on c and collects it. */
static void run(scdt_conn_t *c, scdt_job_t *j) {
  char why[512] = "";
  ASSERT_MSG(scdt_job_send(c, j) == 0, "job %u: send", j->id);
  scdt_job_t *js[1] = {j};
  EXPECT_MSG(scdt_collect(c, js, 1, T_MS, why, sizeof why) == 0, "job %u: %s",
             j->id, why);
}

/* The core's mesh of the torus with these parameters, the threads the
 * daemon's. */
static sc_mesh_t *direct(sc_params_t p) {
  sc_mesh_t *m = NULL;
  char msg[256];
  p.threads = 1;
  ASSERT_MSG(sc_reconstruct(torus, N, &p, &m, msg, sizeof msg) == SC_OK, "%s",
             msg);
  return m;
}

static int same_mesh(const scdt_job_t *j, const sc_mesh_t *m) {
  return j->done && j->ntri == m->triangle_count &&
         memcmp(j->tri, m->triangles, 3 * sizeof(uint32_t) * j->ntri) == 0;
}

static void features(void) {
  scdt_conn_t *a = open_conn(SCP_FEATURE_JOB_OPTIONS | (1ull << 40));
  EXPECT_EQ(a->welcome.features, SCP_FEATURE_JOB_OPTIONS);
  scdt_close(a);
  scdt_conn_t *b = open_conn(0);
  EXPECT_EQ(b->welcome.features, 0);
  scdt_close(b);
}

static void options_apply(void) {
  scdt_conn_t *c = open_conn(SCP_FEATURE_JOB_OPTIONS);
  const scp_value_t opts[] = {
      {.name = "boundary_rho", .kind = SCP_KIND_F64, .v.f = 0.05},
      {.name = "max_hole_edges", .kind = SCP_KIND_U64, .v.u = 0},
      {.name = "boundary_alpha", .kind = SCP_KIND_F64, .v.f = 0.3},
      {.name = "paper_pruning", .kind = SCP_KIND_U64, .v.u = 1},
      {.name = "watertight_labels", .kind = SCP_KIND_U64, .v.u = 1},
      /* Given twice: the first value counts. */
      {.name = "boundary_rho", .kind = SCP_KIND_F64, .v.f = 5}};
  scdt_job_t with, without;
  scdt_job_init(&with, 1, torus, N);
  with.mode = SCP_MODE_BOUNDARY;
  with.options = opts;
  with.noptions = sizeof opts / sizeof opts[0];
  scdt_job_init(&without, 2, torus, N);
  without.mode = SCP_MODE_BOUNDARY;
  run(c, &with);
  run(c, &without);

  sc_params_t p;
  sc_params_init(&p);
  p.mode = SC_MODE_BOUNDARY;
  p.r = 0.25; /* the test client's r */
  sc_mesh_t *plain = direct(p);
  p.boundary_rho = 0.05;
  p.max_hole_edges = 0;
  p.boundary_alpha = 0.3;
  p.paper_pruning = 1;
  p.watertight_labels = 1;
  sc_mesh_t *optioned = direct(p);
  EXPECT_MSG(plain->triangle_count != optioned->triangle_count,
             "the options change nothing here (%zu triangles either way)",
             plain->triangle_count);
  EXPECT_MSG(same_mesh(&with, optioned),
             "job with options: %llu triangles, the core with them %zu",
             (unsigned long long)with.ntri, optioned->triangle_count);
  EXPECT_MSG(same_mesh(&without, plain),
             "job without options: %llu triangles, the core %zu",
             (unsigned long long)without.ntri, plain->triangle_count);
  printf("boundary mode: %zu triangles by default, %zu with the options\n",
         plain->triangle_count, optioned->triangle_count);
  sc_mesh_free(plain);
  sc_mesh_free(optioned);
  scdt_job_reset(&with);
  scdt_job_reset(&without);
  scdt_close(c);
}

/* smoothed_vertices: the core's smoothed positions, bit for bit, when the
 * job was denoised (a given scale smooths even this clean torus), and no
 * VERTICES at all when it was not. */
static void options_vertices(void) {
  scdt_conn_t *c = open_conn(SCP_FEATURE_JOB_OPTIONS);
  const double scale = 0.15;
  const scp_value_t smoothed[] = {
      {.name = "denoise", .kind = SCP_KIND_U64, .v.u = 1},
      {.name = "denoise_scale", .kind = SCP_KIND_F64, .v.f = scale},
      {.name = "smoothed_vertices", .kind = SCP_KIND_U64, .v.u = 1}};
  scdt_job_t with, unsmoothed;
  scdt_job_init(&with, 1, torus, N);
  with.options = smoothed;
  with.noptions = sizeof smoothed / sizeof smoothed[0];
  /* Without denoise nothing is smoothed, so there is nothing to send. */
  scdt_job_init(&unsmoothed, 2, torus, N);
  unsmoothed.options = &smoothed[2];
  unsmoothed.noptions = 1;
  run(c, &with);
  run(c, &unsmoothed);

  sc_params_t p;
  sc_params_init(&p);
  p.r = 0.25; /* the test client's r */
  p.denoise = 1;
  p.denoise_scale = scale;
  p.smoothed_vertices = 1;
  sc_mesh_t *m = direct(p);
  ASSERT_MSG(m->diag.denoised && m->smoothed, "the core did not smooth");
  EXPECT_MSG(same_mesh(&with, m), "smoothed job: %llu triangles, the core %zu",
             (unsigned long long)with.ntri, m->triangle_count);
  EXPECT_MSG(with.nvertices == N && memcmp(with.vertices, m->smoothed,
                                           3 * N * sizeof(double)) == 0,
             "smoothed job: %llu vertices, not the core's %d",
             (unsigned long long)with.nvertices, N);
  EXPECT_MSG(memcmp(with.vertices, torus, 3 * N * sizeof(double)) != 0,
             "the vertices are the points as sent");
  EXPECT_MSG(unsmoothed.done && unsmoothed.nvertices == 0,
             "job without denoise: %llu vertices",
             (unsigned long long)unsmoothed.nvertices);
  sc_mesh_free(m);
  scdt_job_reset(&with);
  scdt_job_reset(&unsmoothed);
  scdt_close(c);
}

/* A job refused at JOB_BEGIN with the code and a message naming text. */
static void expect_refused(scdt_conn_t *c, uint32_t id, scp_value_t opt,
                           uint32_t code, const char *text) {
  scdt_job_t j;
  scdt_job_init(&j, id, sphere, N);
  j.options = &opt;
  j.noptions = 1;
  ASSERT_MSG(scdt_job_begin(c, &j) == 0, "job %u: send", id);
  char why[512] = "";
  scdt_job_t *js[1] = {&j};
  EXPECT_MSG(scdt_collect(c, js, 1, T_MS, why, sizeof why) == 0, "job %u: %s",
             id, why);
  EXPECT_MSG(!j.accepted && j.error_code == code,
             "%s: got %s (%s), want %s before ACCEPTED", opt.name,
             scp_wire_name(j.error_code), j.error_msg, scp_wire_name(code));
  EXPECT_MSG(strstr(j.error_msg, text) != NULL, "%s: message '%s' lacks '%s'",
             opt.name, j.error_msg, text);
  printf("%s: %s: %s\n", opt.name, scp_wire_name(j.error_code), j.error_msg);
  scdt_job_reset(&j);
}

static void options_refused(void) {
  scdt_conn_t *c = open_conn(SCP_FEATURE_JOB_OPTIONS);
  static const struct {
    scp_value_t opt;
    uint32_t code;
    const char *says;
  } cases[] = {
      {{.name = "smoothing", .kind = SCP_KIND_U64, .v.u = 1},
       SCP_WIRE_UNSUPPORTED,
       "smoothing"},
      {{.name = "max_hole_edges", .kind = SCP_KIND_F64, .v.f = 10},
       SCP_WIRE_INVALID,
       "must be an unsigned integer"},
      {{.name = "max_hole_edges", .kind = SCP_KIND_U64, .v.u = 100001},
       SCP_WIRE_INVALID,
       "out of range"},
      {{.name = "boundary_rho", .kind = SCP_KIND_F64, .v.f = 0},
       SCP_WIRE_INVALID,
       "out of range"},
      {{.name = "boundary_alpha", .kind = SCP_KIND_F64, .v.f = 2},
       SCP_WIRE_INVALID,
       "out of range"},
      {{.name = "paper_pruning", .kind = SCP_KIND_U64, .v.u = 2},
       SCP_WIRE_INVALID,
       "out of range"},
      {{.name = "denoise", .kind = SCP_KIND_U64, .v.u = 2},
       SCP_WIRE_INVALID,
       "out of range"},
      {{.name = "denoise_scale", .kind = SCP_KIND_F64, .v.f = -1},
       SCP_WIRE_INVALID,
       "out of range"},
      {{.name = "denoise_scale", .kind = SCP_KIND_U64, .v.u = 1},
       SCP_WIRE_INVALID,
       "must be"},
      {{.name = "smoothed_vertices", .kind = SCP_KIND_U64, .v.u = 2},
       SCP_WIRE_INVALID,
       "out of range"},
      {{.name = "smoothed_vertices", .kind = SCP_KIND_F64, .v.f = 1},
       SCP_WIRE_INVALID,
       "must be an unsigned integer"},
      {{.name = "tile_count", .kind = SCP_KIND_U64, .v.u = 1},
       SCP_WIRE_INVALID,
       "out of range"},
      {{.name = "tile_count", .kind = SCP_KIND_U64, .v.u = 4097},
       SCP_WIRE_INVALID,
       "out of range"},
      {{.name = "tile_index", .kind = SCP_KIND_U64, .v.u = 3},
       SCP_WIRE_INVALID,
       "tile_index needs tile_count"},
  };
  for (uint32_t i = 0; i < sizeof cases / sizeof cases[0]; i++)
    expect_refused(c, 10 + i, cases[i].opt, cases[i].code, cases[i].says);
  /* An empty option list in the long form: invalid, not malformed. */
  scp_buf_t b;
  scp_buf_init(&b, 1u << 20);
  scp_value_t one = {.name = "x", .kind = SCP_KIND_U64, .v.u = 0};
  scp_job_begin_t m = {.job_id = 26, .mode = SCP_MODE_COCONE, .r = 0.25};
  ASSERT_MSG(scp_enc_job_begin_options(&b, &m, &one, 1) == 0, "encode");
  /* The header, then the payload: count at 40 (little-endian, as is the
   * header's payload length at 4), the entry at 48, cut off. */
  memset(b.data + SCP_HEADER_SIZE + 40, 0, 4);
  b.len = SCP_HEADER_SIZE + 48;
  b.data[4] = 48, b.data[5] = b.data[6] = b.data[7] = 0;
  scdt_send_raw(c, b.data, b.len, T_MS);
  scdt_frame_t *f = scdt_recv(c, T_MS);
  ASSERT_MSG(f != NULL, "no answer to an empty option list");
  scp_frame_t v;
  scdt_frame_view(f, &v);
  scp_job_error_t e;
  EXPECT_MSG(f->type == SCP_JOB_ERROR && scp_parse_job_error(&v, &e) == 0 &&
                 e.job_id == 26 && e.code == SCP_WIRE_INVALID,
             "empty option list: got frame type 0x%04x", f->type);
  free(f);
  scp_buf_free(&b);
  scdt_run_ok(c, 27, SCS_SURF_SPHERE, sphere, N, T_MS, "after refusals");
  scdt_close(c);

  /* Options on a connection that did not agree on them: malformed. */
  scdt_conn_t *old = open_conn(0);
  scdt_job_t j;
  scdt_job_init(&j, 1, sphere, N);
  j.options = &one;
  j.noptions = 1;
  ASSERT_MSG(scdt_job_begin(old, &j) == 0, "send");
  EXPECT_MSG(scdt_wait_closed(old, T_MS), "not closed");
  EXPECT_MSG(old->got_error && (old->last_error.flags & SCP_ERROR_FATAL) &&
                 old->last_error.code == SCP_WIRE_PROTOCOL,
             "want a fatal PROTOCOL, got %s",
             old->got_error ? scp_wire_name(old->last_error.code) : "nothing");
  printf("options without the feature: fatal %s: %s\n",
         scp_wire_name(old->last_error.code), old->last_error.message);
  scdt_close(old);
  scdt_check_serving(d.sock, SCS_SURF_SPHERE, sphere, N, T_MS,
                     "after a malformed JOB_BEGIN");
}

int main(int argc, char **argv) {
  scdt_init(argc, argv);
  sphere = scdt_sample(SCS_SURF_SPHERE, N, 3);
  torus = scdt_sample_random(SCS_SURF_TORUS, N, 3);
  ASSERT_MSG(sphere != NULL && torus != NULL, "sample");
  const char *args[] = {"--workers", "2", NULL};
  ASSERT_MSG(scdt_daemon_start(&d, args) == 0, "daemon");
  features();
  options_apply();
  options_vertices();
  options_refused();
  EXPECT_MSG(scdt_daemon_stop(&d) == 0, "daemon stop: status %d", d.status);
  free(sphere);
  free(torus);
  return scdt_finish();
}
