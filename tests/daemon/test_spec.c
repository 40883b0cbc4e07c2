/*
 * The daemon against the rules of PROTOCOL.md that a client written from
 * the document alone could not settle without them (issue 30): each
 * function checks one decision, named by the section that states it, so
 * that a change of behaviour fails here before a client finds it.
 *
 *   test_spec DAEMON PROTOCOL.md
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>

#include "daemontest.h"
#include "synth.h"

#define T_MS 120000

static scdt_daemon_t d;
static const char *spec_path;

/* The points of the example in section 11, and the triangles it shows. */
static const double tet[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
static const uint32_t tet_tris[12] = {0, 1, 3, 0, 2, 1, 0, 3, 2, 1, 2, 3};

/* Runs one job on c and waits for its end. */
static void run(scdt_conn_t *c, scdt_job_t *j) {
  char why[512] = "";
  EXPECT_MSG(scdt_job_send(c, j) == 0, "job %u: send", j->id);
  EXPECT_MSG(scdt_collect(c, &j, 1, T_MS, why, sizeof why) == 0, "%s", why);
}

/* The next frame on c, which must be of the type; NULL (after a failure)
 * otherwise. The caller frees it. */
static scdt_frame_t *expect_frame(scdt_conn_t *c, uint16_t type,
                                  const char *what) {
  scdt_frame_t *f = scdt_recv(c, T_MS);
  EXPECT_MSG(f && f->type == type, "%s: want %s, got %s", what,
             scp_type_name(type), f ? scp_type_name(f->type) : "nothing");
  if (f && f->type != type) {
    free(f);
    return NULL;
  }
  return f;
}

/* The code of the JOB_ERROR that must come next on c (after ACCEPTED and
 * PROGRESS, which are skipped). */
static uint32_t next_job_error(scdt_conn_t *c, uint32_t id, const char *what) {
  for (;;) {
    scdt_frame_t *f = scdt_recv(c, T_MS);
    if (!f || (f->type != SCP_ACCEPTED && f->type != SCP_PROGRESS)) {
      EXPECT_MSG(f && f->type == SCP_JOB_ERROR, "%s: want JOB_ERROR, got %s",
                 what, f ? scp_type_name(f->type) : "nothing");
      uint32_t code = 0;
      if (f && f->type == SCP_JOB_ERROR) {
        scp_frame_t v;
        scp_job_error_t e;
        scdt_frame_view(f, &v);
        EXPECT_EQ(scp_parse_job_error(&v, &e), 0);
        EXPECT_EQ(e.job_id, id);
        code = e.code;
        printf("%s: %s: %s\n", what, scp_wire_name(e.code), e.message);
      }
      free(f);
      return code;
    }
    free(f);
  }
}

/* Reads until the server closes, and expects the last ERROR to be fatal
 * with the code, job_id 0 and the ref_type. */
static void expect_fatal(scdt_conn_t *c, uint32_t code, uint16_t ref_type,
                         const char *what) {
  EXPECT_MSG(scdt_wait_closed(c, T_MS), "%s: not closed", what);
  EXPECT_MSG(c->got_error && c->last_error.code == code &&
                 (c->last_error.flags & SCP_ERROR_FATAL),
             "%s: want a fatal %s, got %s", what, scp_wire_name(code),
             c->got_error ? scp_wire_name(c->last_error.code) : "nothing");
  EXPECT_EQ(c->last_error.job_id, 0);
  EXPECT_EQ(c->last_error.ref_type, ref_type);
}

/* 6.9 and 11: four points give the four faces of their hull in every
 * mode, in the example's order; a sample with no surface gives JOB_DONE
 * with no triangles, and says so with mostly_unused. */
static void empty_and_tetrahedron(void) {
  scdt_conn_t *c;
  ASSERT_MSG(scdt_open(d.sock, 1u << 20, &c) == 0, "connect");
  for (uint32_t mode = 0; mode <= SCP_MODE_AUTO; mode++) {
    scdt_job_t j;
    scdt_job_init(&j, 7, tet, 4);
    j.mode = mode;
    j.format = SCP_F32_XYZ;
    j.flags = SCP_JOB_NORMALS;
    run(c, &j);
    EXPECT_MSG(j.done && j.ntri == 4, "mode %s: %llu triangles (%s)",
               scp_mode_name(mode), (unsigned long long)j.ntri, j.error_msg);
    if (j.ntri == 4)
      EXPECT_MEM_EQ(j.tri, sizeof tet_tris, tet_tris, sizeof tet_tris);
    EXPECT_EQ(j.ncomp, 1);
    if (j.ncomp == 1)
      EXPECT_EQ(j.genus[0], 0);
    EXPECT_EQ(j.diag_mostly_unused, 0);
    scdt_job_reset(&j);
  }
  /* The tetrahedron and a point inside it: no surface passes the tests. */
  double five[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0.3, 0.3, 0.3};
  scdt_job_t j;
  scdt_job_init(&j, 8, five, 5);
  run(c, &j);
  EXPECT_MSG(j.done, "an empty mesh is a JOB_DONE, got %s",
             scp_wire_name(j.error_code));
  EXPECT_EQ(j.ntri, 0);
  EXPECT_EQ(j.diag_mostly_unused, 1);
  scdt_job_reset(&j);
  scdt_close(c);
}

/* 3.2 and 5: a WELCOME from a client is a second handshake frame, and
 * costs the connection, rather than a misdirected one. */
static void welcome_from_client(void) {
  scdt_conn_t *c;
  ASSERT_MSG(scdt_open(d.sock, SCP_FRAME_MIN, &c) == 0, "connect");
  scp_welcome_t w = {
      .version = 1, .max_frame = SCP_FRAME_MIN, .max_jobs = 1, .max_points = 4};
  EXPECT_EQ(scp_enc_welcome(&c->out, &w), 0);
  scdt_flush(c, T_MS);
  expect_fatal(c, SCP_WIRE_PROTOCOL, 0, "WELCOME from a client");
  scdt_close(c);
}

/* 8.2 and 8.4: a stream that ends inside a frame is an end of stream: the
 * server sends nothing, not even a fatal ERROR, and closes. */
static void truncated(void) {
  scdt_conn_t *c;
  ASSERT_MSG(scdt_open(d.sock, SCP_FRAME_MIN, &c) == 0, "connect");
  scp_buf_t b;
  scp_buf_init(&b, SCP_FRAME_MIN);
  scp_enc_ping(&b, 5);
  EXPECT_EQ(scdt_send_raw(c, b.data, b.len - 3, T_MS), 0);
  shutdown(c->fd, SHUT_WR);
  scdt_frame_t *f = scdt_recv(c, T_MS);
  EXPECT_MSG(!f && c->eof, "want the end of the stream, got %s",
             f ? scp_type_name(f->type) : "a timeout");
  free(f);
  scp_buf_free(&b);
  scdt_close(c);
}

/* 7.3: points past JOB_BEGIN's count are INVALID even when they are past
 * max_points too; LIMIT only for a job that announced no count. The
 * daemon takes at most 1000 points per job (see main()). */
static void beyond_count(void) {
  scdt_conn_t *c;
  ASSERT_MSG(scdt_open(d.sock, 1u << 20, &c) == 0, "connect");
  double *xyz = scdt_sample(SCS_SURF_SPHERE, 1100, 3);
  scdt_job_t j;
  scdt_job_init(&j, 1, xyz, 10);
  EXPECT_EQ(scdt_job_begin(c, &j), 0);
  j.n = 1100;
  EXPECT_EQ(scdt_job_points(c, &j, 1100), 0);
  EXPECT_EQ(next_job_error(c, 1, "past the count and max_points"),
            SCP_WIRE_INVALID);
  scdt_job_init(&j, 2, xyz, 1100);
  j.declare = 0;
  EXPECT_EQ(scdt_job_begin(c, &j), 0);
  EXPECT_EQ(scdt_job_points(c, &j, 1100), 0);
  EXPECT_EQ(next_job_error(c, 2, "past max_points, no count"), SCP_WIRE_LIMIT);
  free(xyz);
  scdt_close(c);
}

/* Runs job id on c over the n points with the options; the caller resets
 * j. */
static void run_options(scdt_conn_t *c, scdt_job_t *j, uint32_t id,
                        const double *xyz, uint64_t n,
                        const scp_value_t *options, uint32_t noptions) {
  scdt_job_init(j, id, xyz, n);
  j->options = options;
  j->noptions = noptions;
  run(c, j);
}

/* 6.3: an option of a kind no value list defines is refused, not skipped;
 * the name is judged first; a repeated name's later entries are not
 * checked at all. */
static void option_kinds(void) {
  scdt_conn_t *c;
  ASSERT_MSG(scdt_connect(d.sock, &c) == 0, "connect");
  c->features = SCP_FEATURE_JOB_OPTIONS;
  ASSERT_MSG(scdt_handshake(c, 1u << 20) == 0, "handshake");
  double *xyz = scdt_sample(SCS_SURF_SPHERE, 500, 4);
  scdt_job_t j;

  scp_value_t twice[2] = {
      {.name = "denoise", .kind = SCP_KIND_U64, .v.u = 1},
      {.name = "denoise", .kind = SCP_KIND_F64, .v.f = 7.5}};
  run_options(c, &j, 1, xyz, 500, twice, 2);
  EXPECT_MSG(j.done, "a repeated name: want JOB_DONE, got %s (%s)",
             scp_wire_name(j.error_code), j.error_msg);
  scdt_job_reset(&j);

  scp_value_t odd = {.name = "denoise", .kind = 4, .v.u = 1};
  run_options(c, &j, 2, xyz, 500, &odd, 1);
  EXPECT_MSG(j.error_code == SCP_WIRE_INVALID, "kind 4: want INVALID, got %s",
             j.done ? "JOB_DONE" : scp_wire_name(j.error_code));
  scdt_job_reset(&j);

  scp_value_t unknown = {.name = "no_such_option", .kind = 4, .v.u = 1};
  run_options(c, &j, 3, xyz, 500, &unknown, 1);
  EXPECT_MSG(j.error_code == SCP_WIRE_UNSUPPORTED,
             "unknown name of kind 4: want UNSUPPORTED, got %s",
             j.done ? "JOB_DONE" : scp_wire_name(j.error_code));
  scdt_job_reset(&j);
  free(xyz);
  scdt_close(c);
}

/* 8.3 and 9: a job of no points is valid, and fails as too few points. */
static void zero_points(void) {
  scdt_conn_t *c;
  ASSERT_MSG(scdt_open(d.sock, SCP_FRAME_MIN, &c) == 0, "connect");
  scdt_job_t j;
  scdt_job_init(&j, 9, tet, 0);
  j.declare = 0;
  EXPECT_EQ(scdt_job_begin(c, &j), 0);
  EXPECT_EQ(scdt_job_end(c, &j), 0);
  EXPECT_EQ(next_job_error(c, 9, "no points"), SCP_WIRE_DEGENERATE_INPUT);
  scdt_close(c);
}

/* 6.7: queue_position is 0 when a worker is free, though the job, still
 * uploading, holds none; behind a running job on the one worker it is 1. */
static void queue_position(void) {
  scdt_daemon_t q;
  const char *args[] = {"--workers", "1", NULL};
  ASSERT_MSG(scdt_daemon_start(&q, args) == 0, "daemon did not start");
  scdt_conn_t *a, *b;
  ASSERT_MSG(scdt_open(q.sock, 1u << 20, &a) == 0, "a");
  ASSERT_MSG(scdt_open(q.sock, 1u << 20, &b) == 0, "b");
  size_t big = 60000;
  double *xyz = scdt_sample_random(SCS_SURF_SPHERE, big, 5);
  scdt_job_t up, run_job, late;
  scdt_job_init(&up, 1, xyz, big);
  EXPECT_EQ(scdt_job_begin(b, &up), 0);
  scdt_frame_t *f = expect_frame(b, SCP_ACCEPTED, "idle");
  scp_frame_t v;
  scp_accepted_t acc = {0};
  if (f) {
    scdt_frame_view(f, &v);
    EXPECT_EQ(scp_parse_accepted(&v, &acc), 0);
    EXPECT_EQ(acc.queue_position, 0);
  }
  free(f);
  uint64_t busy = 99;
  EXPECT_EQ(scdt_stat(a, "workers_busy", &busy), 0);
  EXPECT_EQ(busy, 0);
  EXPECT_EQ(scdt_job_cancel(b, &up), 0);
  EXPECT_EQ(next_job_error(b, 1, "cancelled upload"), SCP_WIRE_CANCELLED);

  scdt_job_init(&run_job, 2, xyz, big);
  EXPECT_EQ(scdt_job_send(a, &run_job), 0);
  EXPECT_EQ(scdt_stat_wait(q.sock, "workers_busy", 1, T_MS), 1);
  scdt_job_init(&late, 3, xyz, 1000);
  EXPECT_EQ(scdt_job_begin(b, &late), 0);
  f = expect_frame(b, SCP_ACCEPTED, "busy");
  if (f) {
    scdt_frame_view(f, &v);
    EXPECT_EQ(scp_parse_accepted(&v, &acc), 0);
    EXPECT_EQ(acc.queue_position, 1);
  }
  free(f);
  scdt_close(a);
  scdt_close(b);
  scdt_daemon_stop(&q);
  free(xyz);
}

/* 8.5: on shutdown a job still uploading ends at once, even one whose
 * points a worker has begun to insert; a running job gets the grace
 * period (test_shutdown checks the rest). */
static void shutdown_uploading(void) {
  scdt_daemon_t s;
  const char *args[] = {"--workers", "1", "--grace", "60", NULL};
  ASSERT_MSG(scdt_daemon_start(&s, args) == 0, "daemon did not start");
  scdt_conn_t *c;
  ASSERT_MSG(scdt_open(s.sock, 1u << 20, &c) == 0, "connect");
  size_t n = 200000;
  double *xyz = scdt_sample_random(SCS_SURF_SPHERE, n, 6);
  scdt_job_t j;
  scdt_job_init(&j, 1, xyz, n);
  EXPECT_EQ(scdt_job_begin(c, &j), 0);
  EXPECT_EQ(scdt_job_points(c, &j, n / 2), 0);
  /* Let the worker take the first batches. */
  EXPECT_EQ(scdt_stat_wait(s.sock, "points_in_total", n / 2, T_MS), n / 2);
  kill(s.pid, SIGTERM);
  uint64_t t0 = scdt_now_ms();
  EXPECT_EQ(next_job_error(c, 1, "uploading at shutdown"), SCP_WIRE_SHUTDOWN);
  EXPECT_LT(scdt_now_ms() - t0, 30000);
  EXPECT_MSG(scdt_wait_closed(c, T_MS), "not closed");
  EXPECT_EQ(scdt_daemon_wait(&s, T_MS), 0);
  scdt_close(c);
  free(xyz);
}

/* 3.1: frames written right after HELLO are judged by WELCOME's max_frame:
 * a POINTS frame over 4096 bytes in the same write goes through. */
static void pipelined(void) {
  scdt_conn_t *c;
  ASSERT_MSG(scdt_connect(d.sock, &c) == 0, "connect");
  double *xyz = scdt_sample(SCS_SURF_SPHERE, 600, 7);
  scp_buf_t b;
  scp_buf_init(&b, 1u << 20);
  scp_hello_t h = {.version_min = 1, .version_max = 1, .max_frame = 1u << 20};
  scp_job_begin_t jb = {
      .job_id = 4, .mode = SCP_MODE_COCONE, .r = 0.25, .point_count = 600};
  scp_job_end_t je = {.job_id = 4, .point_count = 600};
  EXPECT_EQ(scp_enc_hello(&b, &h), 0);
  EXPECT_EQ(scp_enc_job_begin(&b, &jb), 0);
  EXPECT_EQ(scp_enc_points(&b, 4, 0, SCP_F64_XYZ, xyz, 600), 0);
  EXPECT_EQ(scp_enc_job_end(&b, &je), 0);
  EXPECT_GT(b.len, 2 * SCP_FRAME_MIN);
  EXPECT_EQ(scdt_send_raw(c, b.data, b.len, T_MS), 0);
  scdt_frame_t *f = expect_frame(c, SCP_WELCOME, "pipelined");
  if (f) {
    scp_frame_t v;
    scdt_frame_view(f, &v);
    EXPECT_EQ(scp_parse_welcome(&v, &c->welcome), 0);
    scp_decoder_set_max_frame(c->dec, c->welcome.max_frame);
  }
  free(f);
  scdt_job_t j;
  scdt_job_init(&j, 4, xyz, 600);
  j.sent = 600;
  scdt_job_t *pj = &j;
  char why[512] = "";
  EXPECT_MSG(scdt_collect(c, &pj, 1, T_MS, why, sizeof why) == 0, "%s", why);
  EXPECT_MSG(j.done && j.ntri > 0, "pipelined job: %s",
             j.done ? "no triangles" : j.error_msg);
  scdt_job_reset(&j);
  scp_buf_free(&b);
  free(xyz);
  scdt_close(c);
}

/* 6.13: the STATS names are those of the table, in its order, all u64. */
static void stats_table(void) {
  FILE *fp = fopen(spec_path, "r");
  ASSERT_MSG(fp != NULL, "cannot open %s", spec_path);
  char line[512], names[64][64];
  size_t n = 0;
  int in = 0;
  while (fgets(line, sizeof line, fp)) {
    if (strstr(line, "This project's daemon sends these"))
      in = 1;
    else if (in && line[0] == '|' && line[2] != '-' &&
             strncmp(line, "| name ", 7) != 0 && n < 64)
      sscanf(line, "| %63s", names[n++]);
    else if (in && n && line[0] != '|')
      break;
  }
  fclose(fp);
  ASSERT_GT(n, 0);

  scdt_conn_t *c;
  ASSERT_MSG(scdt_open(d.sock, SCP_FRAME_MIN, &c) == 0, "connect");
  EXPECT_EQ(scp_enc_stats_request(&c->out, 77), 0);
  scdt_flush(c, T_MS);
  scdt_frame_t *f = expect_frame(c, SCP_STATS, "STATS");
  if (f) {
    scp_frame_t v;
    scp_stats_t st;
    scdt_frame_view(f, &v);
    EXPECT_EQ(scp_parse_stats(&v, &st), 0);
    EXPECT_EQ(st.values.count, n);
    scp_value_iter_t it;
    scp_value_t val;
    scp_values_begin(&st.values, &it);
    for (size_t i = 0; i < n && scp_values_next(&it, &val); i++) {
      EXPECT_STR_EQ(val.name, names[i]);
      EXPECT_EQ(val.kind, SCP_KIND_U64);
    }
  }
  free(f);
  scdt_close(c);
}

/* 6.1: a non-fatal ERROR from a client gets no reply; a fatal one is a
 * disconnect, after which the server sends nothing, not even JOB_ERROR
 * for the job in flight. A fatal ERROR names no job. */
static void errors_from_client(void) {
  scdt_conn_t *c;
  ASSERT_MSG(scdt_open(d.sock, SCP_FRAME_MIN, &c) == 0, "connect");
  scp_error_t e;
  memset(&e, 0, sizeof e);
  e.code = SCP_WIRE_UNKNOWN_TYPE;
  e.ref_type = 0x0042;
  EXPECT_EQ(scp_enc_error(&c->out, &e), 0);
  EXPECT_EQ(scp_enc_ping(&c->out, 11), 0);
  scdt_flush(c, T_MS);
  free(expect_frame(c, SCP_PONG, "after a non-fatal ERROR"));

  double *xyz = scdt_sample(SCS_SURF_SPHERE, 800, 8);
  scdt_job_t j;
  scdt_job_init(&j, 5, xyz, 800);
  EXPECT_EQ(scdt_job_begin(c, &j), 0);
  free(expect_frame(c, SCP_ACCEPTED, "job before a fatal ERROR"));
  e.code = SCP_WIRE_PROTOCOL;
  e.flags = SCP_ERROR_FATAL;
  EXPECT_EQ(scp_enc_error(&c->out, &e), 0);
  scdt_flush(c, T_MS);
  scdt_frame_t *f = scdt_recv(c, T_MS);
  EXPECT_MSG(!f && c->eof, "after a fatal ERROR: want the end, got %s",
             f ? scp_type_name(f->type) : "a timeout");
  free(f);
  scdt_close(c);

  /* A malformed POINTS of a job in use, and a JOB_BEGIN over max_jobs
   * (--max-jobs 2, see main()): fatal, job_id 0. */
  ASSERT_MSG(scdt_open(d.sock, SCP_FRAME_MIN, &c) == 0, "connect");
  scdt_job_init(&j, 5, xyz, 800);
  EXPECT_EQ(scdt_job_begin(c, &j), 0);
  scp_buf_t b;
  scp_buf_init(&b, SCP_FRAME_MIN);
  scp_enc_points(&b, 5, 0, SCP_F64_XYZ, xyz, 10);
  b.data[8 + 20] = 1; /* the chunk's reserved field */
  EXPECT_EQ(scdt_send_raw(c, b.data, b.len, T_MS), 0);
  expect_fatal(c, SCP_WIRE_PROTOCOL, SCP_POINTS, "malformed POINTS");
  scdt_close(c);
  ASSERT_MSG(scdt_open(d.sock, SCP_FRAME_MIN, &c) == 0, "connect");
  for (uint32_t id = 1; id <= 3; id++) {
    scdt_job_init(&j, id, xyz, 800);
    EXPECT_EQ(scdt_job_begin(c, &j), 0);
  }
  expect_fatal(c, SCP_WIRE_LIMIT, SCP_JOB_BEGIN, "over max_jobs");
  scdt_close(c);
  scp_buf_free(&b);
  free(xyz);
}

/* 5: --memory-budget lowers max_points; a job above it is LIMIT (BUSY is
 * for one that fits but finds the budget taken: test_limits). */
static void budget_lowers_max_points(void) {
  scdt_daemon_t m;
  const char *args[] = {"--memory-budget", "64M", NULL};
  ASSERT_MSG(scdt_daemon_start(&m, args) == 0, "daemon did not start");
  scdt_conn_t *c;
  ASSERT_MSG(scdt_open(m.sock, SCP_FRAME_MIN, &c) == 0, "connect");
  uint64_t max = c->welcome.max_points;
  EXPECT_LT(max, 10000000);
  EXPECT_GE(max, 4);
  scdt_job_t j;
  scdt_job_init(&j, 1, tet, max + 1);
  EXPECT_EQ(scdt_job_begin(c, &j), 0);
  EXPECT_EQ(next_job_error(c, 1, "over the lowered max_points"),
            SCP_WIRE_LIMIT);
  scdt_close(c);
  scdt_daemon_stop(&m);
}

int main(int argc, char **argv) {
  scdt_init(argc, argv);
  ASSERT_MSG(argc == 3, "usage: %s DAEMON PROTOCOL.md", argv[0]);
  spec_path = argv[2];
  const char *args[] = {"--max-points", "1000", "--max-jobs", "2", NULL};
  ASSERT_MSG(scdt_daemon_start(&d, args) == 0, "daemon did not start");
  empty_and_tetrahedron();
  welcome_from_client();
  truncated();
  beyond_count();
  option_kinds();
  zero_points();
  pipelined();
  stats_table();
  errors_from_client();
  budget_lowers_max_points();
  queue_position();
  shutdown_uploading();
  return scdt_finish();
}
