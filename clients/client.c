/*
 * The client library; see shortcrust_client.h.
 *
 * DESIGN. No threads and no locks: a handle belongs to one thread at a
 * time, and nothing here is global. Every blocking call funnels into
 * run_io(), which writes what the handle has queued in c->out, reads what
 * the daemon sends and dispatches each frame as it is decoded, until the
 * caller's condition holds, the caller's deadline passes, or the
 * connection dies. Writing and reading always go together, so a daemon
 * that is sending a mesh while we upload the next job's points never waits
 * on us, nor we on it.
 *
 * A job's id is in use (PROTOCOL.md 7.1) from its JOB_BEGIN until both we
 * have sent JOB_END or CANCEL (client_done) and the daemon has sent
 * JOB_DONE or JOB_ERROR (server_done). A job struct lives until the user
 * has freed it and its id is no longer in use; jobs freed by the user while
 * under way are reaped once they end, never from inside a callback.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "shortcrust_client.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <time.h>
#include <unistd.h>

#include "scproto.h"
#include "shortcrust_files.h"

#define SCC_PI 3.14159265358979323846
#define SCC_READ_SIZE (64 * 1024)
#define SCC_MSG_MAX (SCP_MESSAGE_MAX + 256)

struct sc_client_job {
  sc_client_t *c;
  sc_client_job_t *prev, *next; /* every job of the handle */
  sc_client_job_t *enext;       /* ended and not yet reported by a wait */
  int queued_end;               /* in the ended queue */

  uint32_t id;
  int in_use;      /* the id is in use (see DESIGN) */
  int begun;       /* JOB_BEGIN went out */
  int client_done; /* JOB_END or CANCEL went out */
  int server_done; /* JOB_DONE or JOB_ERROR came, or the connection died */
  int cancelled;   /* we asked the daemon to stop it */
  int local_err;   /* why we did, when it was not the user's wish */
  int user_freed;
  int accepted;
  int status; /* SC_CLIENT_PENDING, 0 or an error */
  uint32_t server_code;
  char message[SCC_MSG_MAX];

  sc_client_params_t params;
  uint64_t n;
  double *own_xyz; /* points read from a file */

  uint32_t *tri;
  uint64_t ntri, tri_cap;
  double *normals;
  uint64_t nnormals;
  int32_t *genus;
  uint64_t ncomp, comp_cap;
  sc_client_value_t *values;
  size_t nvalues;

  double t_submit, t_uploaded, t_first_chunk, t_end;
  double last_download_report;
};

struct sc_client {
  int fd;
  char path[sizeof(((struct sockaddr_un *)0)->sun_path)];
  int io_timeout_ms;
  scp_decoder_t *dec;
  scp_buf_t out;
  size_t out_at; /* bytes of out already written */
  uint8_t *rbuf;
  scp_hello_t hello;
  scp_welcome_t welcome;
  int ready; /* 0 handshake, -1 answered, 1 done */

  int err; /* sticky: the connection is gone */
  char errmsg[SCC_MSG_MAX];
  char last[SCC_MSG_MAX];

  sc_client_job_t *jobs;
  sc_client_job_t *ehead, *etail;
  unsigned in_use;
  uint32_t next_id;
  int in_callback;

  uint64_t ping_token;
  int ping_waiting, pong_seen;
  uint32_t stats_tag;
  int stats_waiting, stats_seen;
  sc_client_value_t *stats;
  size_t nstats;
};

static const struct {
  int code;
  const char *name, *text;
} err_table[] = {
#define SC_CLIENT_ERR_ROW_(name, value, text) {value, #name, text},
    SC_CLIENT_ERRNO_MAP(SC_CLIENT_ERR_ROW_)
#undef SC_CLIENT_ERR_ROW_
};

const char *sc_client_strerror(int code) {
  if (code == 0)
    return "success";
  for (size_t i = 0; i < sizeof err_table / sizeof err_table[0]; i++)
    if (err_table[i].code == code)
      return err_table[i].text;
  return "unknown error";
}

const char *sc_client_err_name(int code) {
  if (code == 0)
    return "OK";
  for (size_t i = 0; i < sizeof err_table / sizeof err_table[0]; i++)
    if (err_table[i].code == code)
      return err_table[i].name;
  return "UNKNOWN";
}

const char *sc_client_server_code_name(uint32_t code) {
  return scp_wire_name(code);
}

const char *sc_client_stage_name(uint32_t stage) {
  return scp_stage_name(stage);
}

char *sc_client_default_socket(char *buf, size_t len) {
  const char *xdg = getenv("XDG_RUNTIME_DIR");
  if (xdg && xdg[0] == '/')
    snprintf(buf, len, "%s/shortcrust.sock", xdg);
  else
    snprintf(buf, len, "/run/shortcrust/shortcrust.sock");
  return buf;
}

void sc_client_options_init(sc_client_options_t *o) {
  memset(o, 0, sizeof *o);
  o->io_timeout_ms = 30000;
  o->max_frame = 1u << 20;
}

void sc_client_params_init(sc_client_params_t *p) {
  memset(p, 0, sizeof *p);
  p->mode = SC_CLIENT_MODE_COCONE;
  p->r = 0.18;
  p->max_hole_edges = -1;
}

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void set_msg(char *buf, size_t len, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static void set_msg(char *buf, size_t len, const char *fmt, ...) {
  if (!buf || len == 0)
    return;
  va_list ap;
  va_start(ap, fmt);
  if (vsnprintf(buf, len, fmt, ap) < 0)
    buf[0] = '\0';
  va_end(ap);
}

/* Records a failed call's message on the handle and returns its code. */
static int fail(sc_client_t *c, int code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static int fail(sc_client_t *c, int code, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  if (vsnprintf(c->last, sizeof c->last, fmt, ap) < 0)
    c->last[0] = '\0';
  va_end(ap);
  return code;
}

/* Jobs. */

static sc_client_job_t *find_in_use(sc_client_t *c, uint32_t id) {
  for (sc_client_job_t *j = c->jobs; j; j = j->next)
    if (j->in_use && j->id == id)
      return j;
  return NULL;
}

static void job_destroy(sc_client_job_t *j) {
  sc_client_t *c = j->c;
  if (j->prev)
    j->prev->next = j->next;
  else
    c->jobs = j->next;
  if (j->next)
    j->next->prev = j->prev;
  free(j->own_xyz);
  free(j->tri);
  free(j->normals);
  free(j->genus);
  free(j->values);
  free(j);
}

static void unqueue_end(sc_client_t *c, sc_client_job_t *j) {
  if (!j->queued_end)
    return;
  sc_client_job_t **pp = &c->ehead;
  c->etail = NULL;
  while (*pp) {
    if (*pp == j) {
      *pp = j->enext;
      continue;
    }
    c->etail = *pp;
    pp = &(*pp)->enext;
  }
  j->enext = NULL;
  j->queued_end = 0;
}

/* Frees the jobs the user let go of whose ids are free again. */
static void reap(sc_client_t *c) {
  if (c->in_callback)
    return;
  sc_client_job_t *j = c->jobs;
  while (j) {
    sc_client_job_t *next = j->next;
    if (j->user_freed && !j->in_use)
      job_destroy(j);
    j = next;
  }
}

static void update_in_use(sc_client_t *c, sc_client_job_t *j) {
  if (j->in_use && j->client_done && j->server_done) {
    j->in_use = 0;
    c->in_use--;
  }
}

/* The job's end as the user sees it: its status is settled and it joins
 * the queue of sc_client_wait_any(). */
static void settle(sc_client_t *c, sc_client_job_t *j, int status) {
  if (j->status != SC_CLIENT_PENDING)
    return;
  j->status = status;
  j->t_end = now_s();
  if (!j->user_freed) {
    j->enext = NULL;
    if (c->etail)
      c->etail->enext = j;
    else
      c->ehead = j;
    c->etail = j;
    j->queued_end = 1;
  }
}

/* The mesh collected so far is of no use once a job has failed. */
static void drop_mesh(sc_client_job_t *j) {
  free(j->tri);
  free(j->normals);
  free(j->genus);
  j->tri = NULL;
  j->normals = NULL;
  j->genus = NULL;
  j->tri_cap = j->comp_cap = 0;
}

/* Output. */

static size_t out_pending(const sc_client_t *c) {
  return c->out.len - c->out_at;
}

/* A CANCEL for the job, unless one went out already or its id is free.
 * It may follow JOB_END (the daemon then stops the work) and JOB_ERROR
 * (the id drains on the daemon until JOB_END or CANCEL comes). */
static void queue_cancel(sc_client_t *c, sc_client_job_t *j) {
  if (j->cancelled || c->err)
    return;
  j->cancelled = 1;
  if (!j->in_use)
    return;
  if (scp_enc_cancel(&c->out, j->id) == 0) {
    j->client_done = 1;
    update_in_use(c, j);
  }
}

/* The connection is gone: every job in use ends with the error. */
static void conn_die(sc_client_t *c, int code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static void conn_die(sc_client_t *c, int code, const char *fmt, ...) {
  if (c->err)
    return;
  c->err = code;
  va_list ap;
  va_start(ap, fmt);
  if (vsnprintf(c->errmsg, sizeof c->errmsg, fmt, ap) < 0)
    c->errmsg[0] = '\0';
  va_end(ap);
  snprintf(c->last, sizeof c->last, "%s", c->errmsg);
  if (c->fd >= 0) {
    close(c->fd);
    c->fd = -1;
  }
  for (sc_client_job_t *j = c->jobs; j; j = j->next) {
    if (!j->in_use && j->status != SC_CLIENT_PENDING)
      continue;
    if (j->status == SC_CLIENT_PENDING) {
      snprintf(j->message, sizeof j->message, "%s", c->errmsg);
      drop_mesh(j);
    }
    j->client_done = j->server_done = 1;
    update_in_use(c, j);
    settle(c, j,
           j->local_err   ? j->local_err
           : j->cancelled ? SC_CLIENT_ECANCELLED
                          : code);
  }
  c->ping_waiting = c->stats_waiting = 0;
}

/* The daemon broke the protocol: tell it (when no frame of ours is half
 * written) and close. code is SC_CLIENT_EPROTOCOL, or SC_CLIENT_EVERSION
 * for a WELCOME with a version we did not offer. */
static void vbroken(sc_client_t *c, int code, const char *fmt, va_list ap) {
  if (c->err)
    return;
  char msg[SCC_MSG_MAX];
  if (vsnprintf(msg, sizeof msg, fmt, ap) < 0)
    msg[0] = '\0';
  if (c->fd >= 0 && (c->out_at == 0 || out_pending(c) == 0)) {
    scp_error_t e;
    memset(&e, 0, sizeof e);
    e.code = SCP_WIRE_PROTOCOL;
    e.flags = SCP_ERROR_FATAL;
    snprintf(e.message, sizeof e.message, "%.*s", SCP_MESSAGE_MAX - 1, msg);
    scp_buf_t b;
    scp_buf_init(&b, SCP_FRAME_MIN);
    if (scp_enc_error(&b, &e) == 0)
      (void)!send(c->fd, b.data, b.len, MSG_NOSIGNAL | MSG_DONTWAIT);
    scp_buf_free(&b);
  }
  if (code == SC_CLIENT_EPROTOCOL)
    conn_die(c, code, "the daemon broke the protocol: %s", msg);
  else
    conn_die(c, code, "%s", msg);
}

static void protocol_error(sc_client_t *c, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));
static void protocol_error(sc_client_t *c, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vbroken(c, SC_CLIENT_EPROTOCOL, fmt, ap);
  va_end(ap);
}

static void version_error(sc_client_t *c, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));
static void version_error(sc_client_t *c, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vbroken(c, SC_CLIENT_EVERSION, fmt, ap);
  va_end(ap);
}

/* Frames from the daemon. */

static int call_progress(sc_client_t *c, sc_client_job_t *j, uint32_t stage,
                         double fraction) {
  if (!j->params.progress || j->cancelled || j->user_freed)
    return 0;
  c->in_callback++;
  int stop = j->params.progress(j->params.progress_user, j, stage, fraction);
  c->in_callback--;
  if (stop)
    queue_cancel(c, j);
  return stop;
}

/* Room for need elements of size bytes in the block p, which holds *cap:
 * the block (perhaps moved, *cap updated), or NULL with p left as it was. */
static void *grow(void *p, uint64_t *cap, uint64_t need, size_t size) {
  if (need <= *cap)
    return p;
  uint64_t ncap = *cap ? *cap : 1024;
  while (ncap < need)
    ncap *= 2;
  if (ncap > SIZE_MAX / size)
    return NULL;
  void *q = realloc(p, (size_t)(ncap * size));
  if (q)
    *cap = ncap;
  return q;
}

static void on_chunk(sc_client_t *c, const scp_frame_t *f) {
  scp_chunk_t ch;
  int rc = scp_parse_chunk(f, &ch);
  if (rc < 0) {
    protocol_error(c, "%s frame: %s", scp_type_name(f->type), scp_strerror(rc));
    return;
  }
  sc_client_job_t *j = find_in_use(c, ch.job_id);
  if (!j || j->server_done) {
    protocol_error(c, "%s for job %u, which is not in use",
                   scp_type_name(f->type), ch.job_id);
    return;
  }
  if (j->cancelled)
    return;
  if (!j->t_first_chunk)
    j->t_first_chunk = now_s();
  int array;
  uint64_t have;
  switch (f->type) {
  case SCP_TRIANGLES:
    array = SC_CLIENT_TRIANGLES;
    have = j->ntri;
    break;
  case SCP_NORMALS:
    array = SC_CLIENT_NORMALS;
    have = j->nnormals;
    if (!j->params.normals || ch.format != SCP_F64_XYZ) {
      protocol_error(c, "NORMALS for job %u, which asked for %s", j->id,
                     j->params.normals ? "F64_XYZ normals" : "none");
      return;
    }
    if (ch.first + ch.count > j->n) {
      protocol_error(c, "job %u: more normals than its %llu points", j->id,
                     (unsigned long long)j->n);
      return;
    }
    break;
  default:
    array = SC_CLIENT_COMPONENTS;
    have = j->ncomp;
    break;
  }
  if (ch.first != have) {
    protocol_error(c, "job %u: %s chunk starts at %llu, expected %llu", j->id,
                   scp_type_name(f->type), (unsigned long long)ch.first,
                   (unsigned long long)have);
    return;
  }
  /* Decoded into the job's buffer, or into scratch space for a callback. */
  void *dst;
  void *scratch = NULL;
  size_t esize = array == SC_CLIENT_TRIANGLES ? 3 * sizeof(uint32_t)
                 : array == SC_CLIENT_NORMALS ? 3 * sizeof(double)
                                              : sizeof(int32_t);
  if (j->params.chunk) {
    dst = scratch = malloc((size_t)ch.count * esize);
  } else if (array == SC_CLIENT_TRIANGLES) {
    uint32_t *t = grow(j->tri, &j->tri_cap, have + ch.count, esize);
    if (t)
      j->tri = t;
    dst = t ? t + 3 * have : NULL;
  } else if (array == SC_CLIENT_NORMALS) {
    if (!j->normals)
      j->normals = malloc((size_t)j->n * esize);
    dst = j->normals ? j->normals + 3 * have : NULL;
  } else {
    int32_t *g = grow(j->genus, &j->comp_cap, have + ch.count, esize);
    if (g)
      j->genus = g;
    dst = g ? g + have : NULL;
  }
  if (!dst) {
    /* The stream is fine, but we cannot hold this job's mesh. */
    snprintf(j->message, sizeof j->message,
             "out of memory for the mesh after %llu triangles",
             (unsigned long long)j->ntri);
    j->local_err = SC_CLIENT_ENOMEM;
    queue_cancel(c, j);
    free(scratch);
    return;
  }
  if (array == SC_CLIENT_TRIANGLES) {
    uint32_t *t = dst;
    scp_chunk_copy_triangles(&ch, t);
    for (uint64_t i = 0; i < 3 * (uint64_t)ch.count; i++) {
      if (t[i] >= j->n) {
        free(scratch);
        protocol_error(c,
                       "job %u: triangle %llu has index %u, but the job "
                       "has %llu points",
                       j->id, (unsigned long long)(have + i / 3), t[i],
                       (unsigned long long)j->n);
        return;
      }
    }
    j->ntri += ch.count;
  } else if (array == SC_CLIENT_NORMALS) {
    scp_chunk_copy_xyz(&ch, dst);
    j->nnormals += ch.count;
  } else {
    int32_t *g = dst;
    scp_chunk_copy_i32(&ch, g);
    for (uint32_t i = 0; i < ch.count; i++) {
      if (g[i] < -1) {
        free(scratch);
        protocol_error(c, "job %u: component genus %d", j->id, g[i]);
        return;
      }
    }
    j->ncomp += ch.count;
  }
  if (j->params.chunk) {
    c->in_callback++;
    int stop = j->params.chunk(j->params.chunk_user, j, array, ch.first,
                               ch.count, scratch);
    c->in_callback--;
    free(scratch);
    if (stop) {
      queue_cancel(c, j);
      return;
    }
  }
  if (array == SC_CLIENT_TRIANGLES) {
    double t = now_s();
    if (t - j->last_download_report >= 0.05) {
      j->last_download_report = t;
      double est = 2.0 * (double)j->n;
      double frac = est > 0 ? (double)j->ntri / est : 1;
      call_progress(c, j, SC_CLIENT_STAGE_DOWNLOAD, frac > 0.99 ? 0.99 : frac);
    }
  }
}

static void copy_values(const scp_values_t *in, sc_client_value_t **out,
                        size_t *count) {
  *out = NULL;
  *count = 0;
  if (in->count == 0)
    return;
  sc_client_value_t *v = calloc(in->count, sizeof *v);
  if (!v)
    return;
  scp_value_iter_t it;
  scp_value_t e;
  size_t k = 0;
  scp_values_begin(in, &it);
  while (k < in->count && scp_values_next(&it, &e) == 1) {
    snprintf(v[k].name, sizeof v[k].name, "%s", e.name);
    v[k].kind = (int)e.kind;
    v[k].v.u = e.v.u;
    k++;
  }
  *out = v;
  *count = k;
}

static void on_job_done(sc_client_t *c, const scp_frame_t *f) {
  scp_job_done_t m;
  int rc = scp_parse_job_done(f, &m);
  if (rc < 0) {
    protocol_error(c, "JOB_DONE frame: %s", scp_strerror(rc));
    return;
  }
  sc_client_job_t *j = find_in_use(c, m.job_id);
  if (!j || j->server_done) {
    protocol_error(c, "JOB_DONE for job %u, which is not in use", m.job_id);
    return;
  }
  if (!j->accepted) {
    protocol_error(c, "JOB_DONE for job %u before ACCEPTED", m.job_id);
    return;
  }
  if (!j->client_done) {
    protocol_error(c, "JOB_DONE for job %u before all its points came",
                   m.job_id);
    return;
  }
  j->server_done = 1;
  update_in_use(c, j);
  if (j->cancelled) {
    /* The result crossed our CANCEL; what came of it was not kept. */
    drop_mesh(j);
    if (!j->local_err)
      snprintf(j->message, sizeof j->message, "cancelled");
    settle(c, j, j->local_err ? j->local_err : SC_CLIENT_ECANCELLED);
    return;
  }
  uint64_t want_normals = j->params.normals ? j->n : 0;
  if (m.triangles != j->ntri || m.normals != j->nnormals ||
      m.components != j->ncomp || j->nnormals != want_normals) {
    protocol_error(
        c,
        "JOB_DONE for job %u counts %llu triangles, %llu normals "
        "and %llu components; %llu, %llu and %llu came",
        j->id, (unsigned long long)m.triangles, (unsigned long long)m.normals,
        (unsigned long long)m.components, (unsigned long long)j->ntri,
        (unsigned long long)j->nnormals, (unsigned long long)j->ncomp);
    return;
  }
  copy_values(&m.values, &j->values, &j->nvalues);
  call_progress(c, j, SC_CLIENT_STAGE_DOWNLOAD, 1.0);
  settle(c, j, 0);
}

static void on_job_error(sc_client_t *c, const scp_frame_t *f) {
  scp_job_error_t m;
  int rc = scp_parse_job_error(f, &m);
  if (rc < 0) {
    protocol_error(c, "JOB_ERROR frame: %s", scp_strerror(rc));
    return;
  }
  sc_client_job_t *j = find_in_use(c, m.job_id);
  if (!j || j->server_done) {
    protocol_error(c, "JOB_ERROR for job %u, which is not in use", m.job_id);
    return;
  }
  j->server_done = 1;
  update_in_use(c, j);
  drop_mesh(j);
  if (j->local_err) {
    settle(c, j, j->local_err);
    return;
  }
  int code;
  if (j->cancelled || m.code == SCP_WIRE_CANCELLED)
    code = SC_CLIENT_ECANCELLED;
  else if (m.code == SCP_WIRE_SHUTDOWN)
    code = SC_CLIENT_ESHUTDOWN;
  else if (!j->accepted)
    code = SC_CLIENT_EREFUSED;
  else
    code = SC_CLIENT_EFAILED;
  j->server_code = m.code;
  snprintf(j->message, sizeof j->message, "%s: %s", scp_wire_name(m.code),
           m.message);
  settle(c, j, code);
}

static void on_error(sc_client_t *c, const scp_frame_t *f) {
  scp_error_t e;
  int rc = scp_parse_error(f, &e);
  if (rc < 0) {
    protocol_error(c, "ERROR frame: %s", scp_strerror(rc));
    return;
  }
  if (e.flags & SCP_ERROR_FATAL) {
    int code = e.code == SCP_WIRE_VERSION    ? SC_CLIENT_EVERSION
               : e.code == SCP_WIRE_SHUTDOWN ? SC_CLIENT_ESHUTDOWN
               : e.code == SCP_WIRE_TIMEOUT  ? SC_CLIENT_ETIMEOUT
                                             : SC_CLIENT_ELOST;
    conn_die(c, code, "the daemon closed the connection: %s: %s",
             scp_wire_name(e.code), e.message);
    return;
  }
  /* The daemon rejected one of our frames. That should not happen; when
   * it names a job, stop the job rather than wait for it forever. */
  snprintf(c->last, sizeof c->last, "the daemon rejected a %s frame: %s: %s",
           e.ref_type ? scp_type_name(e.ref_type) : "", scp_wire_name(e.code),
           e.message);
  sc_client_job_t *j = e.job_id ? find_in_use(c, e.job_id) : NULL;
  if (j && !j->cancelled && j->status == SC_CLIENT_PENDING) {
    snprintf(j->message, sizeof j->message, "%s", c->last);
    j->local_err = SC_CLIENT_EPROTOCOL;
    queue_cancel(c, j);
  }
}

static void dispatch(sc_client_t *c, const scp_frame_t *f) {
  int rc;
  switch (f->type) {
  case SCP_ERROR:
    on_error(c, f);
    return;
  case SCP_PING: {
    uint64_t token;
    if ((rc = scp_parse_ping(f, &token)) < 0)
      break;
    if (scp_enc_pong(&c->out, token) < 0)
      conn_die(c, SC_CLIENT_ENOMEM, "out of memory for a PONG");
    return;
  }
  case SCP_PONG: {
    uint64_t token;
    if ((rc = scp_parse_pong(f, &token)) < 0)
      break;
    if (c->ping_waiting && token == c->ping_token)
      c->pong_seen = 1;
    return;
  }
  case SCP_STATS: {
    scp_stats_t s;
    if ((rc = scp_parse_stats(f, &s)) < 0)
      break;
    if (c->stats_waiting && !c->stats_seen && s.tag == c->stats_tag) {
      copy_values(&s.values, &c->stats, &c->nstats);
      c->stats_seen = 1;
    }
    return;
  }
  case SCP_ACCEPTED: {
    scp_accepted_t a;
    if ((rc = scp_parse_accepted(f, &a)) < 0)
      break;
    sc_client_job_t *j = find_in_use(c, a.job_id);
    if (!j || j->server_done || j->accepted) {
      protocol_error(c, "ACCEPTED for job %u, which is not waiting for it",
                     a.job_id);
      return;
    }
    j->accepted = 1;
    return;
  }
  case SCP_PROGRESS: {
    scp_progress_t p;
    if ((rc = scp_parse_progress(f, &p)) < 0)
      break;
    sc_client_job_t *j = find_in_use(c, p.job_id);
    if (!j || j->server_done) {
      protocol_error(c, "PROGRESS for job %u, which is not in use", p.job_id);
      return;
    }
    call_progress(c, j, p.stage, p.fraction);
    return;
  }
  case SCP_TRIANGLES:
  case SCP_NORMALS:
  case SCP_COMPONENTS:
    on_chunk(c, f);
    return;
  case SCP_JOB_DONE:
    on_job_done(c, f);
    return;
  case SCP_JOB_ERROR:
    on_job_error(c, f);
    return;
  default:
    /* A type a server does not send, or one this version does not know:
     * skipped, with the ERROR the protocol asks for (PROTOCOL.md 3.2). */
    {
      scp_error_t e;
      memset(&e, 0, sizeof e);
      e.code = SCP_WIRE_UNKNOWN_TYPE;
      e.ref_type = f->type;
      snprintf(e.message, sizeof e.message,
               "frame type 0x%04x is not one a server sends", f->type);
      if (scp_enc_error(&c->out, &e) < 0)
        conn_die(c, SC_CLIENT_ENOMEM, "out of memory for an ERROR");
    }
    return;
  }
  protocol_error(c, "%s frame: %s", scp_type_name(f->type), scp_strerror(rc));
}

/* Dispatches every whole frame the decoder holds. Until the handshake is
 * done only its answer is taken, and the rest waits for connect. */
static void drain(sc_client_t *c) {
  scp_frame_t f;
  int rc;
  while (!c->err && c->ready >= 0 && (rc = scp_decoder_next(c->dec, &f)) != 0) {
    if (rc < 0) {
      if (rc == SCP_EBADMAGIC || (!c->ready && rc == SCP_EHANDSHAKE))
        protocol_error(c,
                       "the peer on %s does not speak the shortcrust "
                       "protocol (%s)",
                       c->path, scp_strerror(rc));
      else
        protocol_error(c, "%s", scp_strerror(rc));
      return;
    }
    if (c->ready) {
      dispatch(c, &f);
      continue;
    }
    /* The decoder lets only WELCOME or ERROR through first. */
    c->ready = -1;
    if (f.type == SCP_WELCOME) {
      rc = scp_parse_welcome(&f, &c->welcome);
      if (rc == 0)
        rc = scp_handshake_check(&c->hello, &c->welcome);
      if (rc == SCP_EVERSION && f.length >= 6)
        version_error(c,
                      "the daemon on %s answered with protocol version "
                      "%u; this client speaks version %u",
                      c->path, (unsigned)(f.payload[4] | f.payload[5] << 8),
                      SCP_VERSION);
      else if (rc < 0)
        protocol_error(c, "WELCOME frame: %s", scp_strerror(rc));
      return;
    }
    on_error(c, &f);
    if (!c->err)
      protocol_error(c, "a non-fatal ERROR instead of WELCOME");
    return;
  }
}

/* Reads once and dispatches every whole frame. */
static void read_some(sc_client_t *c) {
  ssize_t n = recv(c->fd, c->rbuf, SCC_READ_SIZE, 0);
  if (n < 0) {
    if (errno == EINTR || errno == EAGAIN || errno == EWOULDBLOCK)
      return;
    conn_die(c, SC_CLIENT_ELOST, "connection to the daemon lost: %s",
             strerror(errno));
    return;
  }
  if (n == 0) {
    int rc = scp_decoder_eof(c->dec);
    conn_die(c, SC_CLIENT_ELOST, "the daemon closed the connection%s",
             rc < 0 ? " in the middle of a frame" : "");
    return;
  }
  int rc = scp_decoder_feed(c->dec, c->rbuf, (size_t)n);
  if (rc < 0) {
    if (rc == SCP_ENOMEM)
      conn_die(c, SC_CLIENT_ENOMEM, "out of memory for the daemon's frames");
    else
      protocol_error(c, "%s", scp_strerror(rc));
    return;
  }
  drain(c);
}

typedef int (*cond_fn)(sc_client_t *c, void *arg);

static int cond_flushed(sc_client_t *c, void *arg) {
  return out_pending(c) == 0;
}

/*
 * The I/O loop: writes out what is queued and reads and dispatches what
 * comes, until cond holds (checked before every wait), the deadline passes
 * (SC_CLIENT_ETIMEOUT; deadline < 0 for none), or the connection dies (its
 * error). A write that cannot go on for io_timeout_ms ends the connection.
 */
static int run_io(sc_client_t *c, cond_fn cond, void *arg, double deadline) {
  double write_since = now_s();
  size_t last_at = c->out_at;
  for (;;) {
    if (c->err)
      return c->err;
    if (out_pending(c) == 0) {
      c->out.len = 0;
      c->out_at = 0;
    }
    if (cond(c, arg))
      return 0;
    double t = now_s();
    if (c->out_at != last_at || out_pending(c) == 0) {
      last_at = c->out_at;
      write_since = t;
    }
    double until = deadline;
    int write_limit = 0;
    if (out_pending(c) && c->io_timeout_ms >= 0) {
      double w = write_since + c->io_timeout_ms / 1000.0;
      if (until < 0 || w < until) {
        until = w;
        write_limit = 1;
      }
    }
    int ms = -1;
    if (until >= 0) {
      if (t >= until) {
        if (write_limit) {
          conn_die(c, SC_CLIENT_ETIMEOUT, "the daemon took no data for %d ms",
                   c->io_timeout_ms);
          return c->err;
        }
        return SC_CLIENT_ETIMEOUT;
      }
      double d = (until - t) * 1000.0 + 1;
      ms = d > 60000 ? 60000 : (int)d;
    }
    struct pollfd p = {.fd = c->fd, .events = POLLIN};
    if (out_pending(c))
      p.events |= POLLOUT;
    int rc = poll(&p, 1, ms);
    if (rc < 0) {
      if (errno == EINTR)
        continue;
      conn_die(c, SC_CLIENT_ELOST, "poll: %s", strerror(errno));
      return c->err;
    }
    if (rc == 0)
      continue;
    if (p.revents & POLLIN) {
      read_some(c);
      if (c->err)
        return c->err;
    } else if (p.revents & (POLLERR | POLLHUP | POLLNVAL)) {
      /* Whatever the daemon sent before it went is read first, above. */
      conn_die(c, SC_CLIENT_ELOST, "connection to the daemon lost");
      return c->err;
    }
    if ((p.revents & POLLOUT) && out_pending(c)) {
      ssize_t n = send(c->fd, c->out.data + c->out_at, out_pending(c),
                       MSG_NOSIGNAL | MSG_DONTWAIT);
      if (n < 0) {
        if (errno == EINTR || errno == EAGAIN || errno == EWOULDBLOCK)
          continue;
        conn_die(c, SC_CLIENT_ELOST, "connection to the daemon lost: %s",
                 strerror(errno));
        return c->err;
      }
      c->out_at += (size_t)n;
    }
  }
}

static double deadline_after(int timeout_ms) {
  return timeout_ms < 0 ? -1.0 : now_s() + timeout_ms / 1000.0;
}

static int flush_out(sc_client_t *c) {
  return run_io(c, cond_flushed, NULL, -1.0);
}

/* Connecting. */

static int cond_ready(sc_client_t *c, void *arg) { return c->ready != 0; }

int sc_client_connect(const sc_client_options_t *opts, sc_client_t **out,
                      char *msg, size_t msg_len) {
  if (out)
    *out = NULL;
  set_msg(msg, msg_len, "%s", "");
  sc_client_options_t o;
  if (opts)
    o = *opts;
  else
    sc_client_options_init(&o);
  if (!out || (o.max_frame && o.max_frame < SCP_FRAME_MIN)) {
    set_msg(msg, msg_len, "invalid argument");
    return SC_CLIENT_EINVAL;
  }
  sc_client_t *c = calloc(1, sizeof *c);
  if (!c) {
    set_msg(msg, msg_len, "out of memory");
    return SC_CLIENT_ENOMEM;
  }
  c->fd = -1;
  c->io_timeout_ms = o.io_timeout_ms;
  c->next_id = 1;
  if (o.socket_path)
    snprintf(c->path, sizeof c->path, "%s", o.socket_path);
  else
    sc_client_default_socket(c->path, sizeof c->path);
  scp_limits_t lim;
  scp_limits_init(&lim);
  lim.role = SCP_ROLE_CLIENT;
  c->dec = scp_decoder_new(&lim);
  c->rbuf = malloc(SCC_READ_SIZE);
  scp_buf_init(&c->out, SCP_FRAME_MIN);
  if (!c->dec || !c->rbuf) {
    sc_client_free(c);
    set_msg(msg, msg_len, "out of memory");
    return SC_CLIENT_ENOMEM;
  }

  const char *path = o.socket_path ? o.socket_path : c->path;
  struct sockaddr_un sa;
  memset(&sa, 0, sizeof sa);
  sa.sun_family = AF_UNIX;
  if (strlen(path) >= sizeof sa.sun_path) {
    set_msg(msg, msg_len, "socket path too long (at most %zu bytes): %s",
            sizeof sa.sun_path - 1, path);
    sc_client_free(c);
    return SC_CLIENT_ECONNECT;
  }
  memcpy(sa.sun_path, path, strlen(path) + 1);
  c->fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (c->fd < 0) {
    set_msg(msg, msg_len, "socket: %s", strerror(errno));
    sc_client_free(c);
    return SC_CLIENT_ECONNECT;
  }
  int rc;
  do
    rc = connect(c->fd, (struct sockaddr *)&sa, sizeof sa);
  while (rc != 0 && errno == EINTR);
  if (rc != 0) {
    int e = errno;
    int code = (e == ENOENT || e == ECONNREFUSED) ? SC_CLIENT_ENODAEMON
                                                  : SC_CLIENT_ECONNECT;
    if (code == SC_CLIENT_ENODAEMON)
      set_msg(msg, msg_len,
              "the daemon is not running: nothing listens on %s (%s); start "
              "shortcrustd or give its socket",
              path, strerror(e));
    else
      set_msg(msg, msg_len, "cannot connect to the daemon on %s: %s", path,
              strerror(e));
    sc_client_free(c);
    return code;
  }
  int fl = fcntl(c->fd, F_GETFL);
  if (fl < 0 || fcntl(c->fd, F_SETFL, fl | O_NONBLOCK) < 0) {
    set_msg(msg, msg_len, "fcntl: %s", strerror(errno));
    sc_client_free(c);
    return SC_CLIENT_ECONNECT;
  }

  c->hello = (scp_hello_t){.version_min = SCP_VERSION,
                           .version_max = SCP_VERSION,
                           .features = SCP_FEATURE_JOB_OPTIONS,
                           .max_frame = o.max_frame ? o.max_frame : 1u << 20};
  if (scp_enc_hello(&c->out, &c->hello) < 0)
    conn_die(c, SC_CLIENT_ENOMEM, "out of memory");
  rc = run_io(c, cond_ready, NULL, deadline_after(o.io_timeout_ms));
  if (rc == SC_CLIENT_ETIMEOUT && !c->err)
    conn_die(c, SC_CLIENT_ETIMEOUT, "no answer from the daemon on %s in %d ms",
             path, o.io_timeout_ms);
  if (c->err) {
    set_msg(msg, msg_len, "%s", c->errmsg);
    rc = c->err;
    sc_client_free(c);
    return rc;
  }
  c->ready = 1;
  scp_decoder_set_max_frame(c->dec, c->welcome.max_frame);
  c->out.max_frame = c->welcome.max_frame;
  /* Frames that came right behind WELCOME. */
  drain(c);
  *out = c;
  return 0;
}

void sc_client_free(sc_client_t *c) {
  if (!c)
    return;
  if (c->fd >= 0)
    close(c->fd);
  while (c->jobs)
    job_destroy(c->jobs);
  scp_decoder_free(c->dec);
  scp_buf_free(&c->out);
  free(c->rbuf);
  free(c->stats);
  free(c);
}

int sc_client_status(const sc_client_t *c) {
  return c ? c->err : SC_CLIENT_EINVAL;
}

const char *sc_client_last_error(const sc_client_t *c) {
  return c ? c->last : "no handle";
}

void sc_client_get_info(const sc_client_t *c, sc_client_info_t *out) {
  memset(out, 0, sizeof *out);
  out->socket_path = c->path;
  out->version = c->welcome.version;
  out->max_frame = c->welcome.max_frame;
  out->max_jobs = c->welcome.max_jobs;
  out->max_points = c->welcome.max_points;
  out->job_options = (c->welcome.features & SCP_FEATURE_JOB_OPTIONS) != 0;
}

unsigned sc_client_jobs_in_use(const sc_client_t *c) { return c->in_use; }

/* Values. */

const sc_client_value_t *sc_client_value_find(const sc_client_value_t *v,
                                              size_t count, const char *name) {
  for (size_t i = 0; v && i < count; i++)
    if (strcmp(v[i].name, name) == 0)
      return &v[i];
  return NULL;
}

double sc_client_value_get(const sc_client_value_t *v, size_t count,
                           const char *name, double dflt) {
  const sc_client_value_t *e = sc_client_value_find(v, count, name);
  if (!e)
    return dflt;
  switch (e->kind) {
  case SC_CLIENT_U64:
    return (double)e->v.u;
  case SC_CLIENT_I64:
    return (double)e->v.i;
  case SC_CLIENT_F64:
    return e->v.f;
  }
  return dflt;
}

/* Jobs. */

/* Common checks of the public calls on a handle. */
static int usable(sc_client_t *c) {
  if (c->in_callback)
    return fail(c, SC_CLIENT_ESTATE,
                "a callback may not call the library on its own handle");
  if (c->err) {
    snprintf(c->last, sizeof c->last, "%s", c->errmsg);
    return c->err;
  }
  return 0;
}

static int check_params(sc_client_t *c, const sc_client_params_t *p) {
  if (p->mode < 0 || p->mode >= SCP_MODE_COUNT)
    return fail(c, SC_CLIENT_EINVAL, "unknown mode %d", p->mode);
  if (!isfinite(p->r) || p->r <= 0 || p->r >= 0.5)
    return fail(c, SC_CLIENT_EINVAL, "r must be in (0, 0.5), got %g", p->r);
  if (!isfinite(p->theta) || p->theta < 0 || p->theta >= SCC_PI / 2)
    return fail(c, SC_CLIENT_EINVAL,
                "theta must be in (0, pi/2) radians, or 0 for the default; "
                "got %g",
                p->theta);
  if (p->max_hole_edges < -1 || p->max_hole_edges > 100000)
    return fail(c, SC_CLIENT_EINVAL,
                "max_hole_edges must be in [0, 100000], or -1 for the "
                "default; got %d",
                p->max_hole_edges);
  if (!(p->boundary_rho >= 0 && p->boundary_rho <= 10))
    return fail(c, SC_CLIENT_EINVAL,
                "boundary_rho must be in (0, 10], or 0 for the default; got "
                "%g",
                p->boundary_rho);
  if (!(p->boundary_alpha >= 0 && p->boundary_alpha <= SCC_PI / 2))
    return fail(c, SC_CLIENT_EINVAL,
                "boundary_alpha must be in (0, pi/2] radians, or 0 for the "
                "default; got %g",
                p->boundary_alpha);
  if (p->paper_pruning != 0 && p->paper_pruning != 1)
    return fail(c, SC_CLIENT_EINVAL, "paper_pruning must be 0 or 1, got %d",
                p->paper_pruning);
  if (p->watertight_labels != 0 && p->watertight_labels != 1)
    return fail(c, SC_CLIENT_EINVAL,
                "watertight_labels must be 0 or 1, got %d",
                p->watertight_labels);
  return 0;
}

/* The job options of p that differ from the daemon's defaults, into
 * opts[5]; returns how many. */
static uint32_t job_options(const sc_client_params_t *p, scp_value_t *opts) {
  uint32_t n = 0;
  if (p->max_hole_edges >= 0)
    opts[n++] = (scp_value_t){.name = SCP_OPT_MAX_HOLE_EDGES,
                              .kind = SCP_KIND_U64,
                              .v.u = (uint64_t)p->max_hole_edges};
  if (p->boundary_rho > 0)
    opts[n++] = (scp_value_t){.name = SCP_OPT_BOUNDARY_RHO,
                              .kind = SCP_KIND_F64,
                              .v.f = p->boundary_rho};
  if (p->boundary_alpha > 0)
    opts[n++] = (scp_value_t){.name = SCP_OPT_BOUNDARY_ALPHA,
                              .kind = SCP_KIND_F64,
                              .v.f = p->boundary_alpha};
  if (p->paper_pruning)
    opts[n++] = (scp_value_t){
        .name = SCP_OPT_PAPER_PRUNING, .kind = SCP_KIND_U64, .v.u = 1};
  if (p->watertight_labels)
    opts[n++] = (scp_value_t){
        .name = SCP_OPT_WATERTIGHT_LABELS, .kind = SCP_KIND_U64, .v.u = 1};
  return n;
}

static uint32_t free_id(sc_client_t *c) {
  for (;;) {
    uint32_t id = c->next_id++;
    if (c->next_id == 0)
      c->next_id = 1;
    if (id != 0 && !find_in_use(c, id))
      return id;
  }
}

static sc_client_job_t *job_new(sc_client_t *c, const sc_client_params_t *p,
                                uint64_t n) {
  sc_client_job_t *j = calloc(1, sizeof *j);
  if (!j)
    return NULL;
  j->c = c;
  j->params = *p;
  j->n = n;
  j->status = SC_CLIENT_PENDING;
  j->t_submit = now_s();
  j->next = c->jobs;
  if (c->jobs)
    c->jobs->prev = j;
  c->jobs = j;
  return j;
}

/* Uploads the job's points; the job is linked to the handle already. */
static int upload(sc_client_t *c, sc_client_job_t *j, const double *xyz) {
  if (j->n > c->welcome.max_points) {
    snprintf(j->message, sizeof j->message,
             "LIMIT: job of %llu points; the daemon takes at most %llu per "
             "job",
             (unsigned long long)j->n,
             (unsigned long long)c->welcome.max_points);
    j->server_code = SCP_WIRE_LIMIT;
    j->client_done = j->server_done = 1;
    settle(c, j, SC_CLIENT_EREFUSED);
    return 0;
  }
  const sc_client_params_t *p = &j->params;
  scp_value_t opts[5];
  const uint32_t nopts = job_options(p, opts);
  if (nopts && !(c->welcome.features & SCP_FEATURE_JOB_OPTIONS)) {
    snprintf(j->message, sizeof j->message,
             "UNSUPPORTED: the daemon does not take job options (%s); "
             "leave them at their defaults or update the daemon",
             opts[0].name);
    j->server_code = SCP_WIRE_UNSUPPORTED;
    j->client_done = j->server_done = 1;
    settle(c, j, SC_CLIENT_EREFUSED);
    return 0;
  }
  scp_job_begin_t b = {
      .job_id = j->id,
      .mode = (uint32_t)p->mode,
      .r = p->r,
      .theta = p->theta,
      .point_count = j->n,
      .flags = p->normals ? SCP_JOB_NORMALS | SCP_JOB_NORMALS_F64 : 0};
  if (scp_enc_job_begin_options(&c->out, &b, opts, nopts) < 0)
    return fail(c, SC_CLIENT_ENOMEM, "out of memory");
  j->in_use = j->begun = 1;
  c->in_use++;
  uint64_t next = 0;
  int rc = 0;
  while (next < j->n && !j->server_done && !j->cancelled) {
    rc = scp_enc_points_next(&c->out, j->id, SCP_F64_XYZ, xyz, j->n, &next);
    if (rc < 0) {
      rc = fail(c, SC_CLIENT_ENOMEM, "out of memory");
      break;
    }
    rc = flush_out(c);
    if (rc < 0)
      break;
    call_progress(c, j, SC_CLIENT_STAGE_UPLOAD, (double)next / (double)j->n);
  }
  if (c->err)
    return 0; /* the job ended with the connection */
  if (rc < 0) {
    /* Out of memory with a JOB_BEGIN out: give the id back. */
    queue_cancel(c, j);
  } else if (!j->client_done) {
    /* A CANCEL went out already when a callback cancelled the job. */
    if (j->server_done) {
      /* Refused or failed during the upload: the id drains on the daemon
       * until this CANCEL. */
      queue_cancel(c, j);
    } else {
      scp_job_end_t e = {.job_id = j->id, .point_count = j->n};
      if (scp_enc_job_end(&c->out, &e) < 0)
        return fail(c, SC_CLIENT_ENOMEM, "out of memory");
      j->client_done = 1;
      update_in_use(c, j);
    }
  }
  j->t_uploaded = now_s();
  int frc = flush_out(c);
  if (rc == 0 && frc < 0 && !c->err)
    rc = frc;
  return rc < 0 && !c->err ? rc : 0;
}

static int submit(sc_client_t *c, const sc_client_params_t *params,
                  const double *xyz, uint64_t n, double *own,
                  sc_client_job_t **job) {
  sc_client_params_t def;
  if (!params) {
    sc_client_params_init(&def);
    params = &def;
  }
  int rc = check_params(c, params);
  if (rc < 0)
    return rc;
  if (!xyz && n)
    return fail(c, SC_CLIENT_EINVAL, "no points");
  if (c->in_use >= c->welcome.max_jobs)
    return fail(c, SC_CLIENT_ELIMIT,
                "%u jobs are in use on this connection, the most the daemon "
                "allows; wait for one to end",
                c->in_use);
  sc_client_job_t *j = job_new(c, params, n);
  if (!j)
    return fail(c, SC_CLIENT_ENOMEM, "out of memory");
  j->own_xyz = own;
  j->id = free_id(c);
  rc = upload(c, j, xyz);
  if (rc == 0 && c->err)
    rc = fail(c, c->err, "%s", c->errmsg);
  if (rc < 0) {
    /* Nothing of the job is the user's: it is reaped once its id is free. */
    j->own_xyz = NULL;
    j->user_freed = 1;
    unqueue_end(c, j);
    reap(c);
    return rc;
  }
  *job = j;
  reap(c);
  return 0;
}

int sc_client_submit(sc_client_t *c, const sc_client_params_t *params,
                     const double *xyz, uint64_t n, sc_client_job_t **job) {
  if (job)
    *job = NULL;
  if (!c || !job)
    return SC_CLIENT_EINVAL;
  int rc = usable(c);
  if (rc < 0)
    return rc;
  return submit(c, params, xyz, n, NULL, job);
}

int sc_client_submit_file(sc_client_t *c, const sc_client_params_t *params,
                          const char *path, sc_client_job_t **job) {
  if (job)
    *job = NULL;
  if (!c || !job || !path)
    return SC_CLIENT_EINVAL;
  int rc = usable(c);
  if (rc < 0)
    return rc;
  scf_points_t pts;
  char msg[SCC_MSG_MAX];
  rc = scf_points_read(path, &pts, msg, sizeof msg);
  if (rc < 0)
    return fail(c, rc == SCF_ENOMEM ? SC_CLIENT_ENOMEM : SC_CLIENT_EFILE, "%s",
                msg);
  rc = submit(c, params, pts.xyz, pts.count, pts.xyz, job);
  if (rc < 0)
    scf_points_free(&pts);
  return rc;
}

static int cond_job_ended(sc_client_t *c, void *arg) {
  const sc_client_job_t *j = arg;
  return j->status != SC_CLIENT_PENDING;
}

int sc_client_wait(sc_client_t *c, sc_client_job_t *job, int timeout_ms) {
  if (!c || !job || job->c != c || job->user_freed)
    return SC_CLIENT_EINVAL;
  if (c->in_callback)
    return fail(c, SC_CLIENT_ESTATE,
                "a callback may not call the library on its own handle");
  int rc = 0;
  if (job->status == SC_CLIENT_PENDING)
    rc = run_io(c, cond_job_ended, job, deadline_after(timeout_ms));
  reap(c);
  if (job->status == SC_CLIENT_PENDING)
    return fail(c, rc < 0 ? rc : SC_CLIENT_ETIMEOUT,
                "job %u still under way after %d ms", job->id, timeout_ms);
  unqueue_end(c, job);
  if (job->status < 0)
    snprintf(c->last, sizeof c->last, "%s", job->message);
  return job->status;
}

static int cond_any_ended(sc_client_t *c, void *arg) {
  return c->ehead != NULL || c->in_use == 0;
}

int sc_client_wait_any(sc_client_t *c, int timeout_ms, sc_client_job_t **job) {
  if (job)
    *job = NULL;
  if (!c || !job)
    return SC_CLIENT_EINVAL;
  if (c->in_callback)
    return fail(c, SC_CLIENT_ESTATE,
                "a callback may not call the library on its own handle");
  if (!c->ehead && c->in_use == 0)
    return fail(c, SC_CLIENT_ESTATE, "no job under way");
  int rc = run_io(c, cond_any_ended, NULL, deadline_after(timeout_ms));
  reap(c);
  sc_client_job_t *j = c->ehead;
  if (!j) {
    if (rc == 0)
      return fail(c, SC_CLIENT_ESTATE, "no job under way");
    return fail(c, rc, "no job ended within %d ms", timeout_ms);
  }
  unqueue_end(c, j);
  *job = j;
  if (j->status < 0)
    snprintf(c->last, sizeof c->last, "%s", j->message);
  return j->status;
}

int sc_client_cancel(sc_client_t *c, sc_client_job_t *job) {
  if (!c || !job || job->c != c)
    return SC_CLIENT_EINVAL;
  if (c->in_callback)
    return fail(c, SC_CLIENT_ESTATE,
                "a callback may not call the library on its own handle; "
                "return non-zero from it to cancel");
  if (job->status != SC_CLIENT_PENDING || c->err)
    return 0;
  queue_cancel(c, job);
  flush_out(c);
  reap(c);
  return 0;
}

int sc_client_job_status(const sc_client_job_t *job) {
  return job ? job->status : SC_CLIENT_EINVAL;
}

const char *sc_client_job_message(const sc_client_job_t *job) {
  if (!job)
    return "no job";
  return job->status == 0 ? "" : job->message;
}

uint32_t sc_client_job_server_code(const sc_client_job_t *job) {
  return job ? job->server_code : 0;
}

const double *sc_client_job_points(const sc_client_job_t *job, uint64_t *n) {
  if (n)
    *n = job && job->own_xyz ? job->n : 0;
  return job ? job->own_xyz : NULL;
}

int sc_client_job_mesh(const sc_client_job_t *job, sc_client_mesh_t *out) {
  memset(out, 0, sizeof *out);
  if (!job)
    return SC_CLIENT_EINVAL;
  if (job->status != 0)
    return job->status;
  out->point_count = job->n;
  out->triangles = job->tri;
  out->triangle_count = job->ntri;
  out->normals = job->normals;
  out->normal_count = job->nnormals;
  out->genus = job->genus;
  out->component_count = job->ncomp;
  out->values = job->values;
  out->value_count = job->nvalues;
  out->seconds_upload = job->t_uploaded - job->t_submit;
  out->seconds_download =
      job->t_first_chunk ? job->t_end - job->t_first_chunk : 0;
  out->seconds_total = job->t_end - job->t_submit;
  return 0;
}

void sc_client_job_free(sc_client_job_t *job) {
  if (!job || job->user_freed)
    return;
  sc_client_t *c = job->c;
  job->user_freed = 1;
  unqueue_end(c, job);
  if (job->in_use) {
    /* The CANCEL goes out with the next call that writes. */
    if (job->status == SC_CLIENT_PENDING)
      queue_cancel(c, job);
    return;
  }
  reap(c);
}

/* PING and STATS. */

static int cond_pong(sc_client_t *c, void *arg) { return c->pong_seen; }

int sc_client_ping(sc_client_t *c, int timeout_ms, double *rtt) {
  if (!c)
    return SC_CLIENT_EINVAL;
  int rc = usable(c);
  if (rc < 0)
    return rc;
  double t0 = now_s();
  c->ping_token++;
  if (scp_enc_ping(&c->out, c->ping_token) < 0)
    return fail(c, SC_CLIENT_ENOMEM, "out of memory");
  c->ping_waiting = 1;
  c->pong_seen = 0;
  rc = run_io(c, cond_pong, NULL, deadline_after(timeout_ms));
  c->ping_waiting = 0;
  reap(c);
  if (rc < 0)
    return c->err ? usable(c)
                  : fail(c, rc, "no PONG from the daemon in %d ms", timeout_ms);
  if (rtt)
    *rtt = now_s() - t0;
  return 0;
}

static int cond_stats(sc_client_t *c, void *arg) { return c->stats_seen; }

int sc_client_stats(sc_client_t *c, int timeout_ms, sc_client_value_t **values,
                    size_t *count) {
  if (values)
    *values = NULL;
  if (count)
    *count = 0;
  if (!c || !values || !count)
    return SC_CLIENT_EINVAL;
  int rc = usable(c);
  if (rc < 0)
    return rc;
  c->stats_tag++;
  if (scp_enc_stats_request(&c->out, c->stats_tag) < 0)
    return fail(c, SC_CLIENT_ENOMEM, "out of memory");
  free(c->stats);
  c->stats = NULL;
  c->nstats = 0;
  c->stats_waiting = 1;
  c->stats_seen = 0;
  rc = run_io(c, cond_stats, NULL, deadline_after(timeout_ms));
  c->stats_waiting = 0;
  reap(c);
  if (rc < 0)
    return c->err
               ? usable(c)
               : fail(c, rc, "no STATS from the daemon in %d ms", timeout_ms);
  *values = c->stats;
  *count = c->nstats;
  c->stats = NULL;
  c->nstats = 0;
  return 0;
}
