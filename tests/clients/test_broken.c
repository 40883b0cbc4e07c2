/*
 * The client library against peers the real daemon cannot play: a fake
 * daemon in a thread, on a private socket, answers with a scripted stream.
 * A version mismatch (by ERROR and by WELCOME), a peer that speaks another
 * protocol, a silent one; a daemon that breaks the protocol in the middle
 * of a job (an index out of range, a chunk out of order, totals that
 * disagree, a frame for a job not in use, smoothed vertices a job did not
 * ask for or too few of them), each costing the connection with a fatal
 * ERROR PROTOCOL sent back; a daemon that closes mid-job; and
 * the parts of the protocol a client must handle that the daemon does not
 * use (PING from the server, unknown frame types); and a daemon without
 * job options, to which a job that has some is never sent.
 *
 *   test_clients_broken DAEMON   (the daemon is not used; the harness
 *                                 wants its path)
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <errno.h>
#include <poll.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include "common.h"
#include "scproto.h"

/* The fake daemon's scripts. */
enum {
  S_VERSION_ERROR, /* fatal ERROR VERSION for HELLO */
  S_WELCOME_V2,    /* WELCOME with version 2 */
  S_NOT_SCRU,      /* an HTTP answer */
  S_SILENT,        /* reads, never answers */
  S_BAD_INDEX,     /* a triangle index equal to the point count */
  S_BAD_ORDER,     /* a TRIANGLES chunk that skips ahead */
  S_BAD_TOTALS,    /* JOB_DONE counts a triangle that never came */
  S_UNKNOWN_JOB,   /* ACCEPTED for a job id not in use */
  S_CLOSE_MID_JOB, /* closes after ACCEPTED */
  S_GOOD,          /* PING, unknown types, then the mesh */
  S_NO_OPTIONS,    /* WELCOME without JOB_OPTIONS, then reads to the end */
  S_VERT_UNASKED,  /* VERTICES for a job without smoothed_vertices */
  S_VERT_SHORT,    /* 3 VERTICES for 4 points of a job denoised */
  S_VERT           /* the mesh over 4 VERTICES, as asked */
};

/* The scripts whose job asks for smoothed vertices (and denoise). */
static int asks_vertices(int script) {
  return script == S_VERT_SHORT || script == S_VERT;
}

typedef struct fake {
  char dir[128], sock[160];
  int lfd, fd;
  int script;
  pthread_t thread;
  scp_decoder_t *dec;
  /* What the fake saw from the client. */
  int got_fatal_protocol;
  int got_unknown_type_error;
  int got_pong;
  int got_job_begin;
} fake_t;

static const double tetra[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
static const uint32_t tetra_tris[12] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};

static void send_buf(fake_t *f, scp_buf_t *b) {
  size_t at = 0;
  while (at < b->len) {
    ssize_t n = send(f->fd, b->data + at, b->len - at, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR)
      continue;
    if (n <= 0)
      break;
    at += (size_t)n;
  }
  b->len = 0;
}

/* The next frame from the client: 1, or 0 at end of stream or after 10 s.
 * The frame's payload is valid until the next call. */
static int next_frame(fake_t *f, scp_frame_t *fr) {
  uint8_t buf[65536];
  for (;;) {
    int rc = scp_decoder_next(f->dec, fr);
    if (rc != 0)
      return rc == 1;
    struct pollfd p = {.fd = f->fd, .events = POLLIN};
    if (poll(&p, 1, 10000) <= 0)
      return 0;
    ssize_t n = recv(f->fd, buf, sizeof buf, 0);
    if (n <= 0)
      return 0;
    if (scp_decoder_feed(f->dec, buf, (size_t)n) != 0)
      return 0;
  }
}

/* Reads until a frame of the type; 1 when it came. */
static int read_until(fake_t *f, uint16_t type, scp_frame_t *fr) {
  while (next_frame(f, fr)) {
    if (fr->type == SCP_ERROR) {
      scp_error_t e;
      if (scp_parse_error(fr, &e) == 0) {
        if (e.code == SCP_WIRE_PROTOCOL && (e.flags & SCP_ERROR_FATAL))
          f->got_fatal_protocol = 1;
        if (e.code == SCP_WIRE_UNKNOWN_TYPE && !(e.flags & SCP_ERROR_FATAL))
          f->got_unknown_type_error = 1;
      }
    }
    if (fr->type == SCP_PONG) {
      uint64_t token;
      if (scp_parse_pong(fr, &token) == 0 && token == 4242)
        f->got_pong = 1;
    }
    if (fr->type == SCP_JOB_BEGIN)
      f->got_job_begin = 1;
    if (fr->type == type)
      return 1;
  }
  return 0;
}

static void welcome(fake_t *f, scp_buf_t *b) {
  scp_welcome_t w = {.version = 1,
                     .features =
                         asks_vertices(f->script) ? SCP_FEATURE_JOB_OPTIONS : 0,
                     .max_frame = 4096,
                     .max_jobs = 4,
                     .max_points = 1000};
  scp_enc_welcome(b, &w);
  b->max_frame = 4096;
  scp_decoder_set_max_frame(f->dec, 4096);
}

static void run_script(fake_t *f) {
  scp_buf_t b;
  scp_buf_init(&b, 0);
  scp_frame_t fr;
  if (f->script == S_NOT_SCRU) {
    const char *http = "HTTP/1.1 400 Bad Request\r\n\r\n";
    (void)!send(f->fd, http, strlen(http), MSG_NOSIGNAL);
    scp_buf_free(&b);
    return;
  }
  if (!read_until(f, SCP_HELLO, &fr)) {
    scp_buf_free(&b);
    return;
  }
  switch (f->script) {
  case S_VERSION_ERROR: {
    scp_error_t e;
    memset(&e, 0, sizeof e);
    e.code = SCP_WIRE_VERSION;
    e.flags = SCP_ERROR_FATAL;
    e.ref_type = SCP_HELLO;
    snprintf(e.message, sizeof e.message,
             "client speaks versions 1 to 1; server speaks versions 2 to 3");
    scp_enc_error(&b, &e);
    send_buf(f, &b);
    break;
  }
  case S_WELCOME_V2:
    welcome(f, &b);
    b.data[SCP_HEADER_SIZE + 4] = 2; /* the version field */
    send_buf(f, &b);
    read_until(f, SCP_ERROR, &fr);
    break;
  case S_NO_OPTIONS:
    welcome(f, &b);
    send_buf(f, &b);
    /* Until the client closes. */
    read_until(f, 0xFFFF, &fr);
    break;
  case S_SILENT:
    /* Until the client gives up. */
    while (next_frame(f, &fr))
      ;
    break;
  default: {
    welcome(f, &b);
    send_buf(f, &b);
    if (!read_until(f, SCP_JOB_END, &fr))
      break;
    scp_accepted_t a = {.job_id = 1, .queue_position = 0};
    if (f->script == S_UNKNOWN_JOB)
      a.job_id = 99;
    scp_enc_accepted(&b, &a);
    if (f->script == S_CLOSE_MID_JOB) {
      send_buf(f, &b);
      break;
    }
    if (f->script == S_GOOD) {
      /* A PING the client must answer, an ignorable type it must skip
       * silently, and an unknown one it must answer with ERROR. */
      scp_enc_ping(&b, 4242);
      static const uint8_t ignorable[] = {0x23, 0x81, 0, 0, 2, 0, 0, 0, 7, 7};
      static const uint8_t unknown[] = {0x40, 0x00, 0, 0, 1, 0, 0, 0, 9};
      send_buf(f, &b);
      (void)!send(f->fd, ignorable, sizeof ignorable, MSG_NOSIGNAL);
      (void)!send(f->fd, unknown, sizeof unknown, MSG_NOSIGNAL);
      scp_progress_t p = {.job_id = 1, .stage = 1, .fraction = 0.5};
      scp_enc_progress(&b, &p);
    }
    uint32_t tri[12];
    memcpy(tri, tetra_tris, sizeof tri);
    uint64_t first = 0;
    if (f->script == S_BAD_INDEX)
      tri[7] = 4;
    if (f->script == S_BAD_ORDER)
      first = 1;
    scp_enc_triangles(&b, 1, first, tri, 4);
    if (f->script == S_VERT_UNASKED || asks_vertices(f->script))
      scp_enc_vertices(&b, 1, 0, tetra, f->script == S_VERT_SHORT ? 3 : 4);
    int32_t genus = 0;
    scp_enc_components(&b, 1, 0, &genus, 1);
    /* JOB_DONE does not count the vertices; "denoised" says how many. */
    scp_value_t v[2] = {{.name = "triangles", .kind = SCP_KIND_U64, .v.u = 4},
                        {.name = "denoised", .kind = SCP_KIND_U64, .v.u = 1}};
    scp_job_done_t done = {
        .job_id = 1, .triangles = 4, .normals = 0, .components = 1};
    if (f->script == S_BAD_TOTALS)
      done.triangles = 5;
    scp_enc_job_done(&b, &done, v, asks_vertices(f->script) ? 2 : 1);
    send_buf(f, &b);
    /* What the client says to that: a fatal ERROR, or for the good
     * script the answers to PING and to the unknown type, then its
     * closing. */
    read_until(f, 0xFFFF, &fr);
  }
  }
  scp_buf_free(&b);
}

static void *fake_main(void *arg) {
  fake_t *f = arg;
  struct pollfd p = {.fd = f->lfd, .events = POLLIN};
  if (poll(&p, 1, 10000) == 1) {
    f->fd = accept(f->lfd, NULL, NULL);
    if (f->fd >= 0) {
      run_script(f);
      close(f->fd);
    }
  }
  return NULL;
}

static void fake_start(fake_t *f, int script) {
  memset(f, 0, sizeof *f);
  f->script = script;
  f->fd = -1;
  snprintf(f->dir, sizeof f->dir, "/tmp/scc-fake.XXXXXX");
  ASSERT_MSG(mkdtemp(f->dir), "mkdtemp: %s", strerror(errno));
  snprintf(f->sock, sizeof f->sock, "%s/f.sock", f->dir);
  f->lfd = socket(AF_UNIX, SOCK_STREAM, 0);
  struct sockaddr_un sa;
  memset(&sa, 0, sizeof sa);
  sa.sun_family = AF_UNIX;
  memcpy(sa.sun_path, f->sock, strlen(f->sock) + 1);
  ASSERT_MSG(f->lfd >= 0 &&
                 bind(f->lfd, (struct sockaddr *)&sa, sizeof sa) == 0 &&
                 listen(f->lfd, 4) == 0,
             "listen on %s: %s", f->sock, strerror(errno));
  scp_limits_t lim;
  scp_limits_init(&lim);
  lim.role = SCP_ROLE_SERVER;
  f->dec = scp_decoder_new(&lim);
  ASSERT_MSG(f->dec, "decoder");
  ASSERT_MSG(pthread_create(&f->thread, NULL, fake_main, f) == 0, "thread");
}

static void fake_finish(fake_t *f) {
  pthread_join(f->thread, NULL);
  close(f->lfd);
  scp_decoder_free(f->dec);
  unlink(f->sock);
  rmdir(f->dir);
}

static int connect_fake(fake_t *f, int timeout_ms, sc_client_t **c, char *msg,
                        size_t len) {
  sc_client_options_t o;
  sc_client_options_init(&o);
  o.socket_path = f->sock;
  o.io_timeout_ms = timeout_ms;
  return sc_client_connect(&o, c, msg, len);
}

static void handshakes(void) {
  fake_t f;
  sc_client_t *c;
  char msg[512];

  fake_start(&f, S_VERSION_ERROR);
  EXPECT_EQ(connect_fake(&f, 10000, &c, msg, sizeof msg), SC_CLIENT_EVERSION);
  EXPECT_STR_CONTAINS(msg, "VERSION");
  EXPECT_STR_CONTAINS(msg, "server speaks versions 2 to 3");
  fake_finish(&f);

  fake_start(&f, S_WELCOME_V2);
  EXPECT_EQ(connect_fake(&f, 10000, &c, msg, sizeof msg), SC_CLIENT_EVERSION);
  EXPECT_STR_CONTAINS(msg, "version 2");
  fake_finish(&f);
  EXPECT_MSG(f.got_fatal_protocol, "no fatal ERROR PROTOCOL for a bad WELCOME");

  fake_start(&f, S_NOT_SCRU);
  EXPECT_EQ(connect_fake(&f, 10000, &c, msg, sizeof msg), SC_CLIENT_EPROTOCOL);
  EXPECT_STR_CONTAINS(msg, "does not speak the shortcrust protocol");
  fake_finish(&f);

  fake_start(&f, S_SILENT);
  EXPECT_EQ(connect_fake(&f, 300, &c, msg, sizeof msg), SC_CLIENT_ETIMEOUT);
  EXPECT_STR_CONTAINS(msg, "no answer");
  fake_finish(&f);
}

/* Runs a job of the tetrahedron's four points against a script. */
static int job_against(int script, fake_t *f, char *msg, size_t len) {
  fake_start(f, script);
  sc_client_t *c = NULL;
  int rc = connect_fake(f, 10000, &c, msg, len);
  EXPECT_MSG(rc == 0, "connect: %s", msg);
  if (rc != 0) {
    fake_finish(f);
    return rc;
  }
  sc_client_params_t p;
  sc_client_params_init(&p);
  p.denoise = p.smoothed_vertices = asks_vertices(script);
  sc_client_job_t *j = NULL;
  rc = sc_client_submit(c, &p, tetra, 4, &j);
  EXPECT_MSG(rc == 0, "submit: %s", sc_client_last_error(c));
  if (rc == 0) {
    rc = sc_client_wait(c, j, 10000);
    snprintf(msg, len, "%s", sc_client_job_message(j));
    if (script == S_GOOD && rc == 0) {
      sc_client_mesh_t m;
      sc_client_job_mesh(j, &m);
      EXPECT_EQ(m.triangle_count, 4);
      EXPECT_MSG(m.triangles &&
                     memcmp(m.triangles, tetra_tris, sizeof tetra_tris) == 0,
                 "triangles differ");
      EXPECT_MSG(m.genus && m.component_count == 1 && m.genus[0] == 0,
                 "components");
      /* The PING's answer must go out; a PING of ours flushes it. */
      sc_client_ping(c, 100, NULL);
    }
    if (script == S_VERT && rc == 0) {
      sc_client_mesh_t m;
      sc_client_job_mesh(j, &m);
      EXPECT_EQ(m.vertex_count, 4);
      EXPECT_MSG(m.vertices && memcmp(m.vertices, tetra, sizeof tetra) == 0,
                 "vertices differ");
    }
  }
  sc_client_job_free(j);
  sc_client_free(c);
  fake_finish(f);
  return rc;
}

static void broken_jobs(void) {
  fake_t f;
  char msg[1200];
  static const struct {
    int script;
    int want;
    const char *says;
  } cases[] = {
      {S_BAD_INDEX, SC_CLIENT_EPROTOCOL, "index 4"},
      {S_BAD_ORDER, SC_CLIENT_EPROTOCOL, "starts at 1, expected 0"},
      {S_BAD_TOTALS, SC_CLIENT_EPROTOCOL, "counts 5 triangles"},
      {S_UNKNOWN_JOB, SC_CLIENT_EPROTOCOL, "ACCEPTED for job 99"},
      {S_CLOSE_MID_JOB, SC_CLIENT_ELOST, "closed the connection"},
      {S_VERT_UNASKED, SC_CLIENT_EPROTOCOL, "did not ask for them"},
      {S_VERT_SHORT, SC_CLIENT_EPROTOCOL,
       "3 smoothed vertices for its 4 points"},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    int rc = job_against(cases[i].script, &f, msg, sizeof msg);
    EXPECT_MSG(rc == cases[i].want, "case %zu: %s, expected %s: %s", i,
               sc_client_err_name(rc), sc_client_err_name(cases[i].want), msg);
    EXPECT_STR_CONTAINS(msg, cases[i].says);
    if (cases[i].want == SC_CLIENT_EPROTOCOL)
      EXPECT_MSG(f.got_fatal_protocol, "case %zu: no fatal ERROR PROTOCOL sent",
                 i);
  }
  int rc = job_against(S_GOOD, &f, msg, sizeof msg);
  EXPECT_MSG(rc == 0, "good script: %s: %s", sc_client_err_name(rc), msg);
  EXPECT_MSG(f.got_pong, "no PONG for the server's PING");
  EXPECT_MSG(f.got_unknown_type_error, "no ERROR UNKNOWN_TYPE for type 0x0040");
  EXPECT_MSG(!f.got_fatal_protocol, "a fatal ERROR for a good stream");
  rc = job_against(S_VERT, &f, msg, sizeof msg);
  EXPECT_MSG(rc == 0, "smoothed vertices: %s: %s", sc_client_err_name(rc), msg);
  EXPECT_MSG(!f.got_fatal_protocol, "a fatal ERROR for smoothed vertices");
}

/* A job with options against a daemon that does not take them: refused
 * by the library, with nothing sent; the same job without them goes. */
static void no_job_options(void) {
  fake_t f;
  char msg[512];
  fake_start(&f, S_NO_OPTIONS);
  sc_client_t *c = NULL;
  ASSERT_MSG(connect_fake(&f, 10000, &c, msg, sizeof msg) == 0, "connect: %s",
             msg);
  sc_client_info_t info;
  sc_client_get_info(c, &info);
  EXPECT_EQ(info.job_options, 0);
  sc_client_params_t p;
  sc_client_params_init(&p);
  p.mode = SC_CLIENT_MODE_BOUNDARY;
  p.max_hole_edges = 0;
  sc_client_job_t *j = NULL;
  EXPECT_EQ(sc_client_submit(c, &p, tetra, 4, &j), 0);
  EXPECT_EQ(sc_client_wait(c, j, 10000), SC_CLIENT_EREFUSED);
  EXPECT_STR_CONTAINS(sc_client_job_message(j), "UNSUPPORTED");
  EXPECT_STR_CONTAINS(sc_client_job_message(j), "max_hole_edges");
  sc_client_job_free(j);
  /* Out of range: refused before anything else. */
  p.max_hole_edges = -2;
  EXPECT_EQ(sc_client_submit(c, &p, tetra, 4, &j), SC_CLIENT_EINVAL);
  EXPECT_STR_CONTAINS(sc_client_last_error(c), "max_hole_edges");
  p.max_hole_edges = -1;
  p.boundary_alpha = 2;
  EXPECT_EQ(sc_client_submit(c, &p, tetra, 4, &j), SC_CLIENT_EINVAL);
  EXPECT_STR_CONTAINS(sc_client_last_error(c), "boundary_alpha");
  sc_client_free(c);
  fake_finish(&f);
  EXPECT_MSG(!f.got_job_begin, "a JOB_BEGIN went to a daemon without options");
}

int main(int argc, char **argv) {
  scdt_init(argc, argv);
  handshakes();
  broken_jobs();
  no_job_options();
  return scdt_finish();
}
