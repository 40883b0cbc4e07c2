/*
 * Connections: the protocol of PROTOCOL.md from the server's side. Bytes
 * are read into the connection's decoder, each whole frame is read,
 * validated and carried out, and replies are appended to a bounded output
 * queue; meshes go out chunk by chunk only while that queue has room.
 *
 * This file holds the connection itself: accepting, the handshake, reading,
 * writing, the dispatch of frames, timeouts and closing. Jobs are in
 * jobs.c, their frames in job_frames.c and their results in results.c
 * (conn.h).
 *
 * DESIGN. Everything here runs on the loop thread. A connection owns its
 * jobs; a job owns its task until it lets go of it (cancel, failure,
 * disconnect), after which the task finishes on its own in the pool and is
 * freed when it comes back (task->owner is then NULL). Workers never see a
 * connection or a job.
 *
 * Output is throttled, never unbounded: above cfg.out_soft queued bytes a
 * connection stops reading its socket and stops emitting mesh chunks (the
 * parse state stays in the decoder, so parsing resumes where it stopped);
 * above cfg.out_hard, or when nothing has been written for cfg.stall_ms
 * while above out_soft, the connection is closed.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "conn.h"
#include "daemon.h"
#include "log.h"

#include <arpa/inet.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void process(scd_conn_t *c);

double scd_ms_between(uint64_t t0, uint64_t t1) {
  return t0 && t1 > t0 ? (double)(t1 - t0) / 1e6 : 0.0;
}

static size_t queued(const scd_conn_t *c) {
  return c->out.len + (c->writing ? c->wbuf.len : 0);
}

size_t scd_conn_queued(const scd_conn_t *c) { return queued(c); }

static int live(const scd_conn_t *c) {
  return c->state == SCD_CONN_HANDSHAKE || c->state == SCD_CONN_READY;
}

static void set_reading(scd_conn_t *c, int on);

/* Counts an encoder's result. A failure to encode a reply we built
 * ourselves means we are out of memory, and the connection cannot go on;
 * it is closed by the next scd_conn_flush(), not here, because the caller
 * may still hold one of its jobs. */
int scd_conn_sent(scd_conn_t *c, int rc) {
  if (rc == 0) {
    c->srv->n.frames_out_total++;
    return 0;
  }
  scd_error("conn %llu: cannot encode a frame: %s", (ull)c->id,
            scp_strerror(rc));
  c->broken = 1;
  return rc;
}

void scd_vformat(char *buf, size_t len, const char *fmt, va_list ap) {
  int n = vsnprintf(buf, len, fmt, ap);
  if (n < 0)
    buf[0] = '\0';
}

/* A non-fatal ERROR: the request is refused and the connection goes on. */
void scd_conn_reply_error(scd_conn_t *c, uint32_t code, uint32_t job_id,
                          uint16_t ref_type, const char *fmt, ...) {
  scp_error_t e;
  memset(&e, 0, sizeof e);
  e.code = code;
  e.job_id = job_id;
  e.ref_type = ref_type;
  va_list ap;
  va_start(ap, fmt);
  scd_vformat(e.message, sizeof e.message, fmt, ap);
  va_end(ap);
  scd_debug("conn %llu: ERROR %s job %u: %s", (ull)c->id, scp_wire_name(code),
            job_id, e.message);
  c->invalid_streak++;
  if (scd_conn_sent(c, scp_enc_error(&c->out, &e)) != 0)
    return;
  if (c->invalid_streak >= c->srv->cfg.max_invalid)
    scd_conn_fatal(c, SCP_WIRE_PROTOCOL, 0, 0,
                   "%u invalid requests in a row; closing", c->invalid_streak);
}

/* Closing. */

static void on_closed(uv_handle_t *h) {
  scd_conn_t *c = h->data;
  scd_server_t *srv = c->srv;
  if (c->prev)
    c->prev->next = c->next;
  else
    srv->conns = c->next;
  if (c->next)
    c->next->prev = c->prev;
  scp_decoder_free(c->dec);
  scp_buf_free(&c->out);
  scp_buf_free(&c->wbuf);
  free(c);
  scd_server_maybe_finish(srv);
}

/* The connection no longer counts among the TCP ones before WELCOME. */
static void stop_waiting(scd_conn_t *c) {
  if (c->waiting) {
    c->srv->tcp_waiting--;
    c->waiting = 0;
  }
}

void scd_conn_close_now(scd_conn_t *c, const char *reason) {
  if (c->state == SCD_CONN_CLOSED)
    return;
  /* Callers that saved a reason already pass it back in. */
  if (!c->close_reason[0] && reason != c->close_reason)
    snprintf(c->close_reason, sizeof c->close_reason, "%s", reason);
  scd_conn_end_jobs(c, c->close_reason);
  c->state = SCD_CONN_CLOSED;
  c->reading = 0;
  if (c->counted) {
    c->srv->conns_open--;
    c->counted = 0;
  }
  stop_waiting(c);
  /* A balancer's health check opens a TCP connection every second or so,
   * and runs no job: those come and go at debug level, so that the log
   * keeps the clients' connections (a refused token is a warning). */
  int quiet = c->tcp && c->jobs_total == 0 &&
              strcmp(c->close_reason, "closed by the client") == 0;
  scd_log(quiet ? SCD_LOG_DEBUG : SCD_LOG_INFO,
          "conn %llu: closed (%s): %s%s%llu bytes in, %llu bytes out, %llu "
          "jobs, %.1f s",
          (ull)c->id, c->close_reason, c->tcp ? c->peer : "",
          c->tcp ? " over TCP, " : "", (ull)c->bytes_in, (ull)c->bytes_out,
          (ull)c->jobs_total, scd_ms_between(c->open_ns, uv_hrtime()) / 1e3);
  uv_close(&c->h.handle, on_closed);
}

static void on_shutdown(uv_shutdown_t *req, int status) {
  scd_conn_t *c = req->data;
  (void)status;
  scd_conn_close_now(c, c->close_reason);
}

/* The last frames are out: end our half, then close. */
static void finish_closing(scd_conn_t *c) {
  if (c->state != SCD_CONN_CLOSING || c->writing || c->out.len)
    return;
  c->sreq.data = c;
  if (uv_shutdown(&c->sreq, &c->h.stream, on_shutdown) != 0)
    scd_conn_close_now(c, c->close_reason);
}

/* A fatal ERROR, then the connection closes once it is written. */
void scd_conn_fatal(scd_conn_t *c, uint32_t code, uint32_t job_id,
                    uint16_t ref_type, const char *fmt, ...) {
  if (!live(c))
    return;
  scp_error_t e;
  memset(&e, 0, sizeof e);
  e.code = code;
  e.flags = SCP_ERROR_FATAL;
  e.job_id = job_id;
  e.ref_type = ref_type;
  va_list ap;
  va_start(ap, fmt);
  scd_vformat(e.message, sizeof e.message, fmt, ap);
  va_end(ap);
  if (code == SCP_WIRE_AUTH)
    c->srv->n.auth_refused_total++;
  else if (code != SCP_WIRE_SHUTDOWN)
    c->srv->n.protocol_errors_total++;
  scd_log(code == SCP_WIRE_SHUTDOWN ? SCD_LOG_INFO : SCD_LOG_WARN,
          "conn %llu: fatal ERROR %s: %s", (ull)c->id, scp_wire_name(code),
          e.message);
  snprintf(c->close_reason, sizeof c->close_reason, "%s: %s",
           scp_wire_name(code), e.message);
  scd_conn_end_jobs(c, c->close_reason);
  if (scd_conn_sent(c, scp_enc_error(&c->out, &e)) != 0) {
    scd_conn_flush(c);
    return;
  }
  c->state = SCD_CONN_CLOSING;
  c->deadline_ns = uv_hrtime() + c->srv->cfg.close_ms * 1000000u;
  set_reading(c, 0);
  scd_conn_flush(c);
  finish_closing(c);
}

/* A stream error from the decoder: fatal, with the wire code it maps to. */
void scd_conn_protocol_fatal(scd_conn_t *c, int rc, uint32_t job_id,
                             uint16_t ref_type) {
  scd_conn_fatal(c, scp_err_to_wire(rc), job_id, ref_type, "%s",
                 scp_strerror(rc));
}

/* Reading and writing. */

static void on_alloc(uv_handle_t *h, size_t suggested, uv_buf_t *buf) {
  scd_conn_t *c = h->data;
  (void)suggested;
  /* One buffer serves every connection: libuv calls on_read right after
   * this, and the decoder copies what it keeps. */
  buf->base = c->srv->readbuf;
  buf->len = sizeof c->srv->readbuf;
}

static void on_read(uv_stream_t *s, ssize_t nread, const uv_buf_t *buf) {
  scd_conn_t *c = s->data;
  if (nread > 0) {
    c->bytes_in += (uint64_t)nread;
    c->srv->n.bytes_in_total += (uint64_t)nread;
    if (!live(c))
      return;
    int rc = scp_decoder_feed(c->dec, buf->base, (size_t)nread);
    if (rc != 0)
      scd_conn_protocol_fatal(c, rc, 0, 0);
    else
      process(c);
  } else if (nread == UV_EOF) {
    if (c->state == SCD_CONN_CLOSING) {
      scd_conn_close_now(c, c->close_reason);
      return;
    }
    int rc = scp_decoder_eof(c->dec);
    scd_conn_close_now(c, rc == SCP_ETRUNCATED
                              ? "closed by the client inside a frame"
                              : "closed by the client");
  } else if (nread < 0) {
    char why[96];
    snprintf(why, sizeof why, "read: %s", uv_strerror((int)nread));
    scd_conn_close_now(c, why);
  }
}

static void set_reading(scd_conn_t *c, int on) {
  if (on && !c->reading && live(c)) {
    if (uv_read_start(&c->h.stream, on_alloc, on_read) == 0)
      c->reading = 1;
  } else if (!on && c->reading) {
    uv_read_stop(&c->h.stream);
    c->reading = 0;
  }
}

static void on_write(uv_write_t *req, int status) {
  scd_conn_t *c = req->data;
  c->writing = 0;
  if (status < 0) {
    if (c->state != SCD_CONN_CLOSED) {
      char why[96];
      snprintf(why, sizeof why, "write: %s", uv_strerror(status));
      scd_conn_close_now(c, why);
    }
    return;
  }
  c->bytes_out += c->wbuf.len;
  c->srv->n.bytes_out_total += c->wbuf.len;
  c->wbuf.len = 0;
  c->stall_since_ns = 0;
  /* Keep a small buffer for the next write, not the largest one ever. */
  if (c->wbuf.cap > (256u << 10))
    scp_buf_free(&c->wbuf);
  if (c->state == SCD_CONN_CLOSED)
    return;
  scd_conn_pump(c);
  scd_conn_flush(c);
  finish_closing(c);
  if (c->state == SCD_CONN_READY && !c->reading &&
      queued(c) <= c->srv->cfg.out_soft / 2)
    process(c);
}

void scd_conn_flush(scd_conn_t *c) {
  if (c->state == SCD_CONN_CLOSED)
    return;
  if (c->broken) {
    scd_conn_close_now(c, "out of memory for output");
    return;
  }
  if (queued(c) > c->srv->cfg.out_hard) {
    c->srv->n.slow_readers_closed_total++;
    scd_warn("conn %llu: %zu bytes of output queued, over the hard cap of %zu",
             (ull)c->id, queued(c), c->srv->cfg.out_hard);
    scd_conn_close_now(c, "output queue over its hard cap");
    return;
  }
  if (c->writing || c->out.len == 0)
    return;
  scp_buf_t b = c->wbuf;
  c->wbuf = c->out;
  c->out = b;
  c->out.len = 0;
  uv_buf_t ub = uv_buf_init((char *)c->wbuf.data, (unsigned)c->wbuf.len);
  c->wreq.data = c;
  c->writing = 1;
  int rc = uv_write(&c->wreq, &c->h.stream, &ub, 1, on_write);
  if (rc != 0) {
    c->writing = 0;
    char why[96];
    snprintf(why, sizeof why, "write: %s", uv_strerror(rc));
    scd_conn_close_now(c, why);
  }
}

/* Frames. */

static void on_hello(scd_conn_t *c, const scp_frame_t *f) {
  scd_server_t *srv = c->srv;
  scp_hello_t h;
  memset(&h, 0, sizeof h);
  int rc = scp_parse_hello(f, &h);
  if (rc == 0 && (h.version_min > SCP_VERSION || h.version_max < SCP_VERSION)) {
    scd_conn_fatal(c, SCP_WIRE_VERSION, 0, f->type,
                   "client speaks versions %u to %u; server speaks versions %u "
                   "to %u",
                   h.version_min, h.version_max, SCP_VERSION, SCP_VERSION);
    return;
  }
  if (rc == SCP_EVERSION) {
    scd_conn_fatal(c, SCP_WIRE_VERSION, 0, f->type,
                   "server speaks versions %u to %u", SCP_VERSION, SCP_VERSION);
    return;
  }
  if (rc != 0) {
    scd_conn_fatal(c, scp_err_to_wire(rc), 0, f->type, "HELLO: %s",
                   scp_strerror(rc));
    return;
  }
  if (!scd_auth_hello(c, &h))
    return;
  if (srv->shutting_down) {
    scd_conn_fatal(c, SCP_WIRE_SHUTDOWN, 0, 0, "server shutting down");
    return;
  }
  scp_welcome_t w;
  memset(&w, 0, sizeof w);
  w.version = SCP_VERSION;
  w.features = h.features & (SCP_FEATURE_JOB_OPTIONS | SCP_FEATURE_TOKEN);
  w.max_frame = h.max_frame < srv->cfg.max_frame ? h.max_frame
                                                 : srv->cfg.max_frame;
  w.max_jobs = srv->cfg.max_jobs;
  w.max_points = srv->max_points;
  if (scd_conn_sent(c, scp_enc_welcome(&c->out, &w)) != 0)
    return;
  c->max_frame = w.max_frame;
  c->features = w.features;
  scp_decoder_set_max_frame(c->dec, w.max_frame);
  c->out.max_frame = c->wbuf.max_frame = w.max_frame;
  c->state = SCD_CONN_READY;
  c->deadline_ns = 0;
  stop_waiting(c);
  scd_log(c->tcp ? SCD_LOG_DEBUG : SCD_LOG_INFO,
          "conn %llu: ready (version %u, max_frame %u)", (ull)c->id, w.version,
          w.max_frame);
}

static void handle_frame(scd_conn_t *c, const scp_frame_t *f) {
  unsigned streak = c->invalid_streak;
  if (c->state == SCD_CONN_HANDSHAKE) {
    /* The decoder lets only HELLO through first. */
    on_hello(c, f);
    return;
  }
  int rc;
  switch (f->type) {
  case SCP_PING: {
    uint64_t token;
    rc = scp_parse_ping(f, &token);
    if (rc == 0)
      scd_conn_sent(c, scp_enc_pong(&c->out, token));
    break;
  }
  case SCP_PONG: {
    uint64_t token;
    rc = scp_parse_pong(f, &token);
    break;
  }
  case SCP_ERROR: {
    scp_error_t e;
    rc = scp_parse_error(f, &e);
    if (rc == 0) {
      scd_info("conn %llu: client sent %sERROR %s: %s", (ull)c->id,
               (e.flags & SCP_ERROR_FATAL) ? "fatal " : "",
               scp_wire_name(e.code), e.message);
      if (e.flags & SCP_ERROR_FATAL) {
        char why[SCP_MESSAGE_MAX + 64];
        snprintf(why, sizeof why, "client gave up: %s",
                 scp_wire_name(e.code));
        scd_conn_close_now(c, why);
        return;
      }
    }
    break;
  }
  case SCP_JOB_BEGIN:
    scd_on_job_begin(c, f);
    rc = 0;
    break;
  case SCP_POINTS:
    scd_on_points(c, f);
    rc = 0;
    break;
  case SCP_JOB_END:
    scd_on_job_end(c, f);
    rc = 0;
    break;
  case SCP_CANCEL:
    scd_on_cancel(c, f);
    rc = 0;
    break;
  case SCP_STATS_REQUEST: {
    uint32_t tag;
    rc = scp_parse_stats_request(f, &tag);
    if (rc == 0) {
      size_t before = c->out.len;
      scd_server_stats(c->srv, &c->out, tag);
      if (c->out.len > before)
        c->srv->n.frames_out_total++;
    }
    break;
  }
  default:
    /* Unknown types, and types only a server sends. The decoder already
     * skipped unknown ignorable ones. */
    scd_conn_reply_error(c, SCP_WIRE_UNKNOWN_TYPE, 0, f->type,
                         "frame type 0x%04x is not one a client sends",
                         f->type);
    return;
  }
  if (rc != 0 && live(c)) {
    if (scp_err_is_fatal(rc))
      scd_conn_protocol_fatal(c, rc, 0, f->type);
    else
      scd_conn_reply_error(c, scp_err_to_wire(rc), 0, f->type, "%s: %s",
                           scp_type_name(f->type), scp_strerror(rc));
  }
  if (c->invalid_streak == streak)
    c->invalid_streak = 0;
}

/* Reads frames from the decoder while the output queue has room. */
static void process(scd_conn_t *c) {
  while (live(c)) {
    if (queued(c) >= c->srv->cfg.out_soft) {
      scd_debug("conn %llu: %zu bytes queued; not reading until the client "
                "catches up",
                (ull)c->id, queued(c));
      break;
    }
    scp_frame_t f;
    int rc = scp_decoder_next(c->dec, &f);
    if (rc == 0)
      break;
    if (rc < 0) {
      scd_conn_protocol_fatal(c, rc, 0, 0);
      break;
    }
    c->srv->n.frames_in_total++;
    handle_frame(c, &f);
  }
  scd_conn_flush(c);
  scd_conn_check_shutdown(c);
  set_reading(c, live(c) && queued(c) < c->srv->cfg.out_soft);
}

void scd_conn_tick(scd_conn_t *c, uint64_t now) {
  const scd_config_t *cfg = &c->srv->cfg;
  switch (c->state) {
  case SCD_CONN_HANDSHAKE:
    if (now >= c->deadline_ns)
      scd_conn_fatal(c, SCP_WIRE_TIMEOUT, 0, 0, "no HELLO within %.3g s",
                     (double)cfg->handshake_ms / 1e3);
    break;
  case SCD_CONN_CLOSING:
    if (now >= c->deadline_ns)
      scd_conn_close_now(c, "the client did not take the last frames");
    break;
  case SCD_CONN_READY:
    if (queued(c) < cfg->out_soft) {
      c->stall_since_ns = 0;
    } else if (!c->stall_since_ns) {
      c->stall_since_ns = now;
    } else if (now - c->stall_since_ns >= cfg->stall_ms * 1000000u) {
      c->srv->n.slow_readers_closed_total++;
      scd_warn("conn %llu: client read nothing for %.3g s with %zu bytes "
               "queued",
               (ull)c->id, (double)cfg->stall_ms / 1e3, queued(c));
      scd_conn_close_now(c, "slow reader");
    }
    break;
  }
}

/* The TCP peer's address as text, for the logs. */
static void peer_name(scd_conn_t *c) {
  struct sockaddr_storage ss;
  int len = sizeof ss;
  char host[48] = "?";
  int port = 0;
  if (uv_tcp_getpeername(&c->h.tcp, (struct sockaddr *)&ss, &len) == 0) {
    if (ss.ss_family == AF_INET6) {
      uv_ip6_name((struct sockaddr_in6 *)&ss, host, sizeof host);
      port = ntohs(((struct sockaddr_in6 *)&ss)->sin6_port);
    } else {
      uv_ip4_name((struct sockaddr_in *)&ss, host, sizeof host);
      port = ntohs(((struct sockaddr_in *)&ss)->sin_port);
    }
  }
  snprintf(c->peer, sizeof c->peer, strchr(host, ':') ? "[%s]:%d" : "%s:%d",
           host, port);
}

void scd_conn_accept(scd_server_t *srv, uv_stream_t *listener, int tcp) {
  scd_conn_t *c = calloc(1, sizeof *c);
  if (!c) {
    scd_error("out of memory for a connection");
    return;
  }
  c->srv = srv;
  c->tcp = tcp;
  if (tcp)
    uv_tcp_init(srv->loop, &c->h.tcp);
  else
    uv_pipe_init(srv->loop, &c->h.pipe, 0);
  c->h.handle.data = c;
  c->next = srv->conns;
  if (srv->conns)
    srv->conns->prev = c;
  srv->conns = c;
  c->id = srv->next_conn_id++;
  c->open_ns = uv_hrtime();
  c->state = SCD_CONN_HANDSHAKE;
  c->max_frame = SCP_FRAME_MIN;
  scp_buf_init(&c->out, SCP_FRAME_MIN);
  scp_buf_init(&c->wbuf, SCP_FRAME_MIN);
  int rc = uv_accept(listener, &c->h.stream);
  if (rc != 0) {
    scd_warn("accept: %s", uv_strerror(rc));
    scd_conn_close_now(c, "accept failed");
    return;
  }
  if (tcp) {
    /* Frames are written whole, so Nagle's delay only adds latency to the
     * small ones (ACCEPTED, PROGRESS, PONG). */
    uv_tcp_nodelay(&c->h.tcp, 1);
    uv_tcp_keepalive(&c->h.tcp, 1, 60);
    peer_name(c);
  }
  scp_limits_t lim;
  scp_limits_init(&lim);
  lim.role = SCP_ROLE_SERVER;
  lim.max_frame = SCP_FRAME_MIN;
  c->dec = scp_decoder_new(&lim);
  if (!c->dec) {
    scd_error("out of memory for a connection");
    scd_conn_close_now(c, "out of memory");
    return;
  }
  srv->n.connections_total++;
  if (srv->conns_open >= srv->cfg.max_connections) {
    srv->n.connections_refused_total++;
    scd_conn_fatal(c, SCP_WIRE_BUSY, 0, 0,
                   "too many connections (at most %u); try later",
                   srv->cfg.max_connections);
    return;
  }
  /* A peer that connects and says nothing holds its place until the
   * handshake timeout. On TCP anyone who can reach the port can do that, so
   * connections still before their WELCOME may take at most a quarter of
   * the places, and the rest stay for clients that authenticate (as
   * sshd's MaxStartups does). */
  const unsigned waiting_max =
      srv->cfg.max_connections / 4 ? srv->cfg.max_connections / 4 : 1;
  if (tcp && srv->tcp_waiting >= waiting_max) {
    srv->n.connections_refused_total++;
    scd_conn_fatal(c, SCP_WIRE_BUSY, 0, 0,
                   "too many TCP connections before their handshake (at most "
                   "%u, a quarter of --max-connections); try later",
                   waiting_max);
    return;
  }
  c->counted = 1;
  srv->conns_open++;
  if (tcp) {
    c->waiting = 1;
    srv->tcp_waiting++;
  }
  c->deadline_ns = c->open_ns + srv->cfg.handshake_ms * 1000000u;
  if (tcp)
    scd_debug("conn %llu: accepted from %s over TCP (%u open)", (ull)c->id,
              c->peer, srv->conns_open);
  else
    scd_info("conn %llu: accepted (%u open)", (ull)c->id, srv->conns_open);
  set_reading(c, 1);
}
