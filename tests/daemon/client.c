/*
 * The tests' blocking client; see client.h.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "client.h"

#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <poll.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <time.h>
#include <unistd.h>

uint64_t scdt_now_ms(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (uint64_t)ts.tv_sec * 1000u + (uint64_t)ts.tv_nsec / 1000000u;
}

/* A TCP connection to an IPv4 literal and port: the fd, or -errno. */
static int connect_tcp(const char *text) {
  scp_address_t a;
  struct sockaddr_in sin;
  memset(&sin, 0, sizeof sin);
  sin.sin_family = AF_INET;
  if (scp_address_parse(text, &a) != 0 || a.kind != SCP_ADDR_TCP ||
      inet_pton(AF_INET, a.host, &sin.sin_addr) != 1)
    return -EINVAL;
  sin.sin_port = htons(a.port);
  int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0)
    return -errno;
  if (connect(fd, (struct sockaddr *)&sin, sizeof sin) != 0) {
    int e = errno;
    close(fd);
    return -e;
  }
  return fd;
}

int scdt_connect(const char *path, scdt_conn_t **out) {
  *out = NULL;
  int fd;
  if (strncmp(path, "tcp://", 6) == 0) {
    fd = connect_tcp(path);
    if (fd < 0)
      return fd;
    goto connected;
  }
  struct sockaddr_un sa;
  memset(&sa, 0, sizeof sa);
  sa.sun_family = AF_UNIX;
  if (strlen(path) >= sizeof sa.sun_path)
    return -ENAMETOOLONG;
  memcpy(sa.sun_path, path, strlen(path) + 1);
  fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0)
    return -errno;
  if (connect(fd, (struct sockaddr *)&sa, sizeof sa) != 0) {
    int e = errno;
    close(fd);
    return -e;
  }
connected:;
  scdt_conn_t *c = calloc(1, sizeof *c);
  scp_limits_t lim;
  scp_limits_init(&lim);
  lim.role = SCP_ROLE_CLIENT;
  if (c)
    c->dec = scp_decoder_new(&lim);
  if (!c || !c->dec) {
    close(fd);
    free(c);
    return -ENOMEM;
  }
  c->fd = fd;
  scp_buf_init(&c->out, SCP_FRAME_MIN);
  *out = c;
  return 0;
}

void scdt_close(scdt_conn_t *c) {
  if (!c)
    return;
  close(c->fd);
  scp_decoder_free(c->dec);
  scp_buf_free(&c->out);
  while (c->qhead) {
    scdt_frame_t *f = c->qhead;
    c->qhead = f->next;
    free(f);
  }
  free(c);
}

/* Reads once and queues every whole frame. 1 when bytes came, 0 at end of
 * stream, -1 on an error. */
static int read_some(scdt_conn_t *c) {
  uint8_t buf[65536];
  ssize_t n = recv(c->fd, buf, sizeof buf, 0);
  if (n < 0 && (errno == EINTR || errno == EAGAIN))
    return 1;
  if (n <= 0) {
    c->eof = 1;
    return 0;
  }
  if (scp_decoder_feed(c->dec, buf, (size_t)n) != 0) {
    c->dec_err = scp_decoder_error(c->dec);
    return -1;
  }
  scp_frame_t f;
  int rc;
  while ((rc = scp_decoder_next(c->dec, &f)) == 1) {
    scdt_frame_t *q = malloc(sizeof *q + f.length);
    if (!q)
      return -1;
    q->next = NULL;
    q->type = f.type;
    q->length = f.length;
    memcpy(q->payload, f.payload, f.length);
    if (c->qtail)
      c->qtail->next = q;
    else
      c->qhead = q;
    c->qtail = q;
  }
  if (rc < 0) {
    c->dec_err = rc;
    return -1;
  }
  return 1;
}

int scdt_flush(scdt_conn_t *c, int timeout_ms) {
  size_t at = 0;
  uint64_t deadline = scdt_now_ms() + (uint64_t)timeout_ms;
  while (at < c->out.len) {
    uint64_t now = scdt_now_ms();
    if (now >= deadline)
      return -1;
    struct pollfd p = {.fd = c->fd, .events = POLLOUT | POLLIN};
    if (c->eof || c->dec_err)
      p.events = POLLOUT;
    int rc = poll(&p, 1, (int)(deadline - now));
    if (rc < 0 && errno == EINTR)
      continue;
    if (rc <= 0)
      return -1;
    if (p.revents & POLLIN) {
      if (read_some(c) < 0)
        return -1;
    }
    if (p.revents & (POLLOUT | POLLERR | POLLHUP)) {
      ssize_t n = send(c->fd, c->out.data + at, c->out.len - at,
                       MSG_NOSIGNAL | MSG_DONTWAIT);
      if (n < 0 && (errno == EAGAIN || errno == EINTR))
        continue;
      if (n < 0) {
        c->eof = 1;
        return -1;
      }
      at += (size_t)n;
    }
  }
  c->out.len = 0;
  return 0;
}

int scdt_send_raw(scdt_conn_t *c, const void *bytes, size_t len,
                  int timeout_ms) {
  if (scdt_flush(c, timeout_ms) != 0)
    return -1;
  const uint8_t *p = bytes;
  while (len) {
    ssize_t n = send(c->fd, p, len, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR)
      continue;
    if (n < 0)
      return -1;
    p += n;
    len -= (size_t)n;
  }
  return 0;
}

scdt_frame_t *scdt_recv(scdt_conn_t *c, int timeout_ms) {
  uint64_t deadline = scdt_now_ms() + (uint64_t)timeout_ms;
  while (!c->qhead) {
    if (c->eof || c->dec_err)
      return NULL;
    uint64_t now = scdt_now_ms();
    if (now >= deadline)
      return NULL;
    struct pollfd p = {.fd = c->fd, .events = POLLIN};
    int rc = poll(&p, 1, (int)(deadline - now));
    if (rc < 0 && errno == EINTR)
      continue;
    if (rc <= 0)
      return NULL;
    if (read_some(c) < 0 && !c->qhead)
      return NULL;
  }
  scdt_frame_t *f = c->qhead;
  c->qhead = f->next;
  if (!c->qhead)
    c->qtail = NULL;
  f->next = NULL;
  return f;
}

void scdt_frame_view(const scdt_frame_t *f, scp_frame_t *out) {
  out->type = f->type;
  out->length = f->length;
  out->payload = f->payload;
}

int scdt_wait_closed(scdt_conn_t *c, int timeout_ms) {
  uint64_t deadline = scdt_now_ms() + (uint64_t)timeout_ms;
  for (;;) {
    uint64_t now = scdt_now_ms();
    if (now >= deadline)
      return 0;
    scdt_frame_t *f = scdt_recv(c, (int)(deadline - now));
    if (!f)
      return c->eof || c->dec_err;
    if (f->type == SCP_ERROR) {
      scp_frame_t v;
      scdt_frame_view(f, &v);
      if (scp_parse_error(&v, &c->last_error) == 0)
        c->got_error = 1;
    }
    free(f);
  }
}

int scdt_handshake_v(scdt_conn_t *c, uint16_t vmin, uint16_t vmax,
                     uint32_t max_frame, int timeout_ms) {
  scp_hello_t h = {.version_min = vmin,
                   .version_max = vmax,
                   .features = c->features,
                   .max_frame = max_frame,
                   .token = c->token,
                   .token_len = c->token_len};
  if (scp_enc_hello(&c->out, &h) != 0)
    return -1;
  /* A server that refuses us may close before it reads the HELLO; its
   * ERROR is still there to read. */
  scdt_flush(c, timeout_ms);
  scdt_frame_t *f = scdt_recv(c, timeout_ms);
  if (!f)
    return -1;
  scp_frame_t v;
  scdt_frame_view(f, &v);
  int rc = -1;
  if (f->type == SCP_WELCOME && scp_parse_welcome(&v, &c->welcome) == 0 &&
      c->welcome.max_frame <= max_frame) {
    scp_decoder_set_max_frame(c->dec, c->welcome.max_frame);
    c->out.max_frame = c->welcome.max_frame;
    rc = 0;
  } else if (f->type == SCP_ERROR &&
             scp_parse_error(&v, &c->last_error) == 0) {
    c->got_error = 1;
    rc = (int)c->last_error.code;
  }
  free(f);
  return rc;
}

int scdt_handshake(scdt_conn_t *c, uint32_t max_frame) {
  return scdt_handshake_v(c, 1, 1, max_frame, 60000);
}

int scdt_open(const char *path, uint32_t max_frame, scdt_conn_t **out) {
  int rc = scdt_connect(path, out);
  if (rc != 0)
    return rc;
  rc = scdt_handshake(*out, max_frame);
  if (rc != 0) {
    scdt_close(*out);
    *out = NULL;
  }
  return rc;
}

void scdt_job_init(scdt_job_t *j, uint32_t id, const double *xyz,
                   uint64_t n) {
  memset(j, 0, sizeof *j);
  j->id = id;
  j->xyz = xyz;
  j->n = n;
  j->mode = SCP_MODE_COCONE;
  j->r = 0.25;
  j->format = SCP_F64_XYZ;
  j->declare = 1;
  j->diag_mostly_unused = -1;
}

void scdt_job_reset(scdt_job_t *j) {
  free(j->tri);
  free(j->normals);
  free(j->vertices);
  free(j->genus);
  scdt_job_t keep = *j;
  scdt_job_init(j, keep.id, keep.xyz, keep.n);
  j->mode = keep.mode;
  j->r = keep.r;
  j->flags = keep.flags;
  j->format = keep.format;
  j->declare = keep.declare;
  j->options = keep.options;
  j->noptions = keep.noptions;
}

#define SCDT_IO_MS 60000

int scdt_job_begin(scdt_conn_t *c, scdt_job_t *j) {
  scp_job_begin_t m = {.job_id = j->id,
                       .mode = j->mode,
                       .r = j->r,
                       .theta = 0,
                       .point_count = j->declare ? j->n : 0,
                       .flags = j->flags};
  j->sent = 0;
  if (scp_enc_job_begin_options(&c->out, &m, j->options, j->noptions) != 0)
    return -1;
  return scdt_flush(c, SCDT_IO_MS);
}

int scdt_job_points(scdt_conn_t *c, scdt_job_t *j, uint64_t count) {
  uint64_t end = j->sent + count;
  if (end > j->n)
    end = j->n;
  uint32_t cap = scp_chunk_capacity(j->format, c->out.max_frame);
  while (j->sent < end) {
    uint64_t k = end - j->sent;
    if (k > cap)
      k = cap;
    int rc = scp_enc_points(&c->out, j->id, j->sent, j->format,
                            j->xyz + 3 * j->sent, (uint32_t)k);
    if (rc != 0)
      return -1;
    j->sent += k;
    if (c->out.len >= (1u << 20) && scdt_flush(c, SCDT_IO_MS) != 0)
      return -1;
  }
  return scdt_flush(c, SCDT_IO_MS);
}

int scdt_job_end(scdt_conn_t *c, scdt_job_t *j) {
  scp_job_end_t m = {.job_id = j->id, .point_count = j->sent};
  if (scp_enc_job_end(&c->out, &m) != 0)
    return -1;
  return scdt_flush(c, SCDT_IO_MS);
}

int scdt_job_cancel(scdt_conn_t *c, scdt_job_t *j) {
  if (scp_enc_cancel(&c->out, j->id) != 0)
    return -1;
  return scdt_flush(c, SCDT_IO_MS);
}

int scdt_job_send(scdt_conn_t *c, scdt_job_t *j) {
  if (scdt_job_begin(c, j) || scdt_job_points(c, j, j->n) ||
      scdt_job_end(c, j))
    return -1;
  return 0;
}

static int fail(char *why, size_t len, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static int fail(char *why, size_t len, const char *fmt, ...) {
  if (why && len) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(why, len, fmt, ap);
    va_end(ap);
  }
  return -1;
}

static int grow(void **p, uint64_t count, size_t size) {
  void *q = realloc(*p, (size_t)(count ? count : 1) * size);
  if (!q)
    return -1;
  *p = q;
  return 0;
}

/* One chunk for job j, checked and appended. */
static int take_chunk(scdt_job_t *j, const scp_chunk_t *ch, char *why,
                      size_t len) {
  uint64_t have = ch->type == SCP_TRIANGLES  ? j->ntri
                  : ch->type == SCP_NORMALS  ? j->nnormals
                  : ch->type == SCP_VERTICES ? j->nvertices
                                             : j->ncomp;
  if (ch->first != have)
    return fail(why, len, "job %u: %s chunk at %llu, expected %llu", j->id,
                scp_type_name(ch->type), (unsigned long long)ch->first,
                (unsigned long long)have);
  uint64_t total = have + ch->count;
  switch (ch->type) {
  case SCP_TRIANGLES:
    if (grow((void **)&j->tri, 3 * total, sizeof(uint32_t)))
      return fail(why, len, "out of memory");
    scp_chunk_copy_triangles(ch, j->tri + 3 * have);
    for (uint64_t i = 3 * have; i < 3 * total; i++)
      if (j->tri[i] >= j->n)
        return fail(why, len, "job %u: index %u out of range (%llu points)",
                    j->id, j->tri[i], (unsigned long long)j->n);
    j->ntri = total;
    break;
  case SCP_NORMALS:
    if (!(j->flags & SCP_JOB_NORMALS))
      return fail(why, len, "job %u: normals nobody asked for", j->id);
    if (ch->format != ((j->flags & SCP_JOB_NORMALS_F64) ? SCP_F64_XYZ
                                                        : SCP_F32_XYZ))
      return fail(why, len, "job %u: normals in the wrong format", j->id);
    if (total > j->n)
      return fail(why, len, "job %u: more normals than points", j->id);
    if (grow((void **)&j->normals, 3 * total, sizeof(double)))
      return fail(why, len, "out of memory");
    scp_chunk_copy_xyz(ch, j->normals + 3 * have);
    j->nnormals = total;
    break;
  case SCP_VERTICES:
    if (total > j->n)
      return fail(why, len, "job %u: more vertices than points", j->id);
    if (grow((void **)&j->vertices, 3 * total, sizeof(double)))
      return fail(why, len, "out of memory");
    scp_chunk_copy_xyz(ch, j->vertices + 3 * have);
    j->nvertices = total;
    break;
  case SCP_COMPONENTS:
    if (grow((void **)&j->genus, total, sizeof(int32_t)))
      return fail(why, len, "out of memory");
    scp_chunk_copy_i32(ch, j->genus + have);
    j->ncomp = total;
    break;
  }
  return 0;
}

static scdt_job_t *find(scdt_job_t **jobs, size_t n, uint32_t id) {
  for (size_t i = 0; i < n; i++)
    if (jobs[i]->id == id)
      return jobs[i];
  return NULL;
}

/* Handles one frame for scdt_collect(): 0, or -1 with why. */
static int collect_one(scdt_conn_t *c, scdt_job_t **jobs, size_t njobs,
                       const scdt_frame_t *fr, char *why, size_t len) {
  scp_frame_t f;
  scdt_frame_view(fr, &f);
  scp_msg_t m;
  int rc = scp_parse(&f, &m);
  if (rc != 0)
    return fail(why, len, "server sent a bad %s frame: %s",
                scp_type_name(f.type), scp_strerror(rc));
  uint32_t id = 0;
  scdt_job_t *j = NULL;
  if (scp_frame_job_id(&f, &id)) {
    j = find(jobs, njobs, id);
    if (!j || j->ended)
      return fail(why, len, "server sent %s for job %u, which is not in use",
                  scp_type_name(f.type), id);
  }
  switch (f.type) {
  case SCP_ERROR:
    c->last_error = m.u.error;
    c->got_error = 1;
    if (m.u.error.flags & SCP_ERROR_FATAL)
      return fail(why, len, "fatal ERROR %s: %s",
                  scp_wire_name(m.u.error.code), m.u.error.message);
    return 0;
  case SCP_PONG:
  case SCP_STATS:
    return 0;
  case SCP_ACCEPTED:
    if (j->accepted)
      return fail(why, len, "job %u accepted twice", id);
    j->accepted = 1;
    return 0;
  case SCP_PROGRESS:
    j->progress++;
    return 0;
  case SCP_TRIANGLES:
  case SCP_NORMALS:
  case SCP_VERTICES:
  case SCP_COMPONENTS:
    return take_chunk(j, &m.u.chunk, why, len);
  case SCP_JOB_DONE: {
    const scp_job_done_t *d = &m.u.job_done;
    if (d->triangles != j->ntri || d->normals != j->nnormals ||
        d->components != j->ncomp)
      return fail(why, len,
                  "job %u: JOB_DONE says %llu/%llu/%llu, got %llu/%llu/%llu",
                  id, (unsigned long long)d->triangles,
                  (unsigned long long)d->normals,
                  (unsigned long long)d->components,
                  (unsigned long long)j->ntri,
                  (unsigned long long)j->nnormals,
                  (unsigned long long)j->ncomp);
    if ((j->flags & SCP_JOB_NORMALS) && j->nnormals != j->n)
      return fail(why, len, "job %u: %llu normals for %llu points", id,
                  (unsigned long long)j->nnormals, (unsigned long long)j->n);
    /* JOB_DONE does not count them (PROTOCOL.md 6.4): all or none. */
    if (j->nvertices != 0 && j->nvertices != j->n)
      return fail(why, len, "job %u: %llu vertices for %llu points", id,
                  (unsigned long long)j->nvertices, (unsigned long long)j->n);
    scp_value_iter_t it;
    scp_value_t v;
    if (scp_values_find(&d->values, "triangles", &it, &v))
      j->diag_triangles = v.v.u;
    if (scp_values_find(&d->values, "genus", &it, &v))
      j->diag_genus = v.v.i;
    if (scp_values_find(&d->values, "mostly_unused", &it, &v))
      j->diag_mostly_unused = (int)v.v.u;
    j->done = 1;
    j->ended = 1;
    return 0;
  }
  case SCP_JOB_ERROR:
    j->ended = 1;
    j->error_code = m.u.job_error.code;
    snprintf(j->error_msg, sizeof j->error_msg, "%s", m.u.job_error.message);
    return 0;
  }
  return fail(why, len, "unexpected %s frame", scp_type_name(f.type));
}

int scdt_collect(scdt_conn_t *c, scdt_job_t **jobs, size_t njobs,
                 int timeout_ms, char *why, size_t why_len) {
  return scdt_collect_some(c, jobs, njobs, njobs, timeout_ms, why, why_len);
}

int scdt_collect_some(scdt_conn_t *c, scdt_job_t **jobs, size_t njobs,
                      size_t nwait, int timeout_ms, char *why,
                      size_t why_len) {
  uint64_t deadline = scdt_now_ms() + (uint64_t)timeout_ms;
  for (;;) {
    size_t open = 0;
    for (size_t i = 0; i < nwait; i++)
      open += !jobs[i]->ended;
    if (!open)
      return 0;
    uint64_t now = scdt_now_ms();
    if (now >= deadline)
      return fail(why, why_len, "timed out with %zu jobs open", open);
    scdt_frame_t *f = scdt_recv(c, (int)(deadline - now));
    if (!f) {
      if (c->eof)
        return fail(why, why_len, "server closed with %zu jobs open", open);
      if (c->dec_err)
        return fail(why, why_len, "bad stream from the server: %s",
                    scp_strerror(c->dec_err));
      continue;
    }
    int rc = collect_one(c, jobs, njobs, f, why, why_len);
    free(f);
    if (rc != 0)
      return rc;
  }
}

int scdt_stat(scdt_conn_t *c, const char *name, uint64_t *value) {
  static atomic_uint tags;
  uint32_t tag = atomic_fetch_add(&tags, 1) + 1;
  if (scp_enc_stats_request(&c->out, tag) != 0 ||
      scdt_flush(c, SCDT_IO_MS) != 0)
    return -1;
  uint64_t deadline = scdt_now_ms() + SCDT_IO_MS;
  for (;;) {
    uint64_t now = scdt_now_ms();
    if (now >= deadline)
      return -1;
    scdt_frame_t *f = scdt_recv(c, (int)(deadline - now));
    if (!f)
      return -1;
    int found = -1;
    if (f->type == SCP_STATS) {
      scp_frame_t v;
      scp_stats_t s;
      scdt_frame_view(f, &v);
      if (scp_parse_stats(&v, &s) == 0 && s.tag == tag) {
        scp_value_iter_t it;
        scp_value_t val;
        found = scp_values_find(&s.values, name, &it, &val) ? 1 : 0;
        if (found)
          *value = val.v.u;
      }
    }
    free(f);
    if (found >= 0)
      return found ? 0 : -1;
  }
}
