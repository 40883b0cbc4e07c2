/*
 * The client library; see shortcrust_client.h. This file holds the handle:
 * connecting and the handshake, the I/O loop, the connection's end, PING
 * and STATS. Jobs are in client_jobs.c, the frames from the daemon and the
 * results in client_results.c (client_internal.h).
 *
 * A handle remembers its address and token, so that when its connection
 * is lost with jobs whose parameters allow retries, it connects anew and
 * submits them again (scc_recover(), called by the calls that wait for or
 * start jobs; see sc_client_params_t.retries).
 *
 * DESIGN. No threads and no locks: a handle belongs to one thread at a
 * time, and nothing here is global. Every blocking call funnels into
 * scc_run_io(), which writes what the handle has queued in c->out, reads what
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
#include "client_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <time.h>
#include <unistd.h>

#define SCC_READ_SIZE (64 * 1024)

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
  return scp_default_socket(buf, len);
}

void sc_client_options_init(sc_client_options_t *o) {
  memset(o, 0, sizeof *o);
  o->io_timeout_ms = 30000;
  o->max_frame = 1u << 20;
}

double scc_now_s(void) {
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
int scc_fail(sc_client_t *c, int code, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  if (vsnprintf(c->last, sizeof c->last, fmt, ap) < 0)
    c->last[0] = '\0';
  va_end(ap);
  return code;
}

/* Output. */

static size_t out_pending(const sc_client_t *c) {
  return c->out.len - c->out_at;
}


/* The connection is gone: every job in use ends with the error. */
void scc_conn_die(sc_client_t *c, int code, const char *fmt, ...) {
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
      scc_drop_mesh(j);
    }
    j->client_done = j->server_done = 1;
    scc_update_in_use(c, j);
    if (j->resubmit)
      continue;
    if (j->status == SC_CLIENT_PENDING && scc_may_retry(j, code)) {
      j->resubmit = 1;
      continue;
    }
    scc_settle(c, j,
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
    scc_conn_die(c, code, "the daemon broke the protocol: %s", msg);
  else
    scc_conn_die(c, code, "%s", msg);
}

void scc_protocol_error(sc_client_t *c, const char *fmt, ...) {
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


/* Dispatches every whole frame the decoder holds. Until the handshake is
 * done only its answer is taken, and the rest waits for connect. */
static void drain(sc_client_t *c) {
  scp_frame_t f;
  int rc;
  while (!c->err && c->ready >= 0 && (rc = scp_decoder_next(c->dec, &f)) != 0) {
    if (rc < 0) {
      if (rc == SCP_EBADMAGIC || (!c->ready && rc == SCP_EHANDSHAKE))
        scc_protocol_error(c,
                           "the peer on %s does not speak the shortcrust "
                           "protocol (%s)",
                           c->path, scp_strerror(rc));
      else
        scc_protocol_error(c, "%s", scp_strerror(rc));
      return;
    }
    if (c->ready) {
      scc_dispatch(c, &f);
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
        scc_protocol_error(c, "WELCOME frame: %s", scp_strerror(rc));
      return;
    }
    scc_on_error(c, &f);
    if (!c->err)
      scc_protocol_error(c, "a non-fatal ERROR instead of WELCOME");
    return;
  }
}

/* Reads once and dispatches every whole frame. */
static void read_some(sc_client_t *c) {
  ssize_t n = recv(c->fd, c->rbuf, SCC_READ_SIZE, 0);
  if (n < 0) {
    if (errno == EINTR || errno == EAGAIN || errno == EWOULDBLOCK)
      return;
    scc_conn_die(c, SC_CLIENT_ELOST, "connection to the daemon lost: %s",
                 strerror(errno));
    return;
  }
  if (n == 0) {
    int rc = scp_decoder_eof(c->dec);
    scc_conn_die(c, SC_CLIENT_ELOST, "the daemon closed the connection%s",
                 rc < 0 ? " in the middle of a frame" : "");
    return;
  }
  int rc = scp_decoder_feed(c->dec, c->rbuf, (size_t)n);
  if (rc < 0) {
    if (rc == SCP_ENOMEM)
      scc_conn_die(c, SC_CLIENT_ENOMEM,
                   "out of memory for the daemon's frames");
    else
      scc_protocol_error(c, "%s", scp_strerror(rc));
    return;
  }
  drain(c);
}

static int cond_flushed(sc_client_t *c, void *arg) {
  return out_pending(c) == 0;
}

/*
 * The I/O loop: writes out what is queued and reads and dispatches what
 * comes, until cond holds (checked before every wait), the deadline passes
 * (SC_CLIENT_ETIMEOUT; deadline < 0 for none), or the connection dies (its
 * error). A write that cannot go on for io_timeout_ms ends the connection.
 */
int scc_run_io(sc_client_t *c, scc_cond_fn cond, void *arg, double deadline) {
  double write_since = scc_now_s();
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
    double t = scc_now_s();
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
          scc_conn_die(c, SC_CLIENT_ETIMEOUT,
                       "the daemon took no data for %d ms", c->io_timeout_ms);
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
      scc_conn_die(c, SC_CLIENT_ELOST, "poll: %s", strerror(errno));
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
      scc_conn_die(c, SC_CLIENT_ELOST, "connection to the daemon lost");
      return c->err;
    }
    if ((p.revents & POLLOUT) && out_pending(c)) {
      ssize_t n = send(c->fd, c->out.data + c->out_at, out_pending(c),
                       MSG_NOSIGNAL | MSG_DONTWAIT);
      if (n < 0) {
        if (errno == EINTR || errno == EAGAIN || errno == EWOULDBLOCK)
          continue;
        scc_conn_die(c, SC_CLIENT_ELOST, "connection to the daemon lost: %s",
                     strerror(errno));
        return c->err;
      }
      c->out_at += (size_t)n;
    }
  }
}

double scc_deadline_after(int timeout_ms) {
  return timeout_ms < 0 ? -1.0 : scc_now_s() + timeout_ms / 1000.0;
}

int scc_flush_out(sc_client_t *c) {
  return scc_run_io(c, cond_flushed, NULL, -1.0);
}

/* Connecting. */

static int cond_ready(sc_client_t *c, void *arg) { return c->ready != 0; }

/* Connects c->fd to the daemon's Unix socket at path and makes it
 * non-blocking: 0, or the error code with its message in msg. */
static int connect_unix(sc_client_t *c, const char *path, char *msg,
                        size_t msg_len) {
  struct sockaddr_un sa;
  memset(&sa, 0, sizeof sa);
  sa.sun_family = AF_UNIX;
  if (strlen(path) >= sizeof sa.sun_path) {
    set_msg(msg, msg_len, "socket path too long (at most %zu bytes): %s",
            sizeof sa.sun_path - 1, path);
    return SC_CLIENT_ECONNECT;
  }
  memcpy(sa.sun_path, path, strlen(path) + 1);
  c->fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (c->fd < 0) {
    set_msg(msg, msg_len, "socket: %s", strerror(errno));
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
    return code;
  }
  int fl = fcntl(c->fd, F_GETFL);
  if (fl < 0 || fcntl(c->fd, F_SETFL, fl | O_NONBLOCK) < 0) {
    set_msg(msg, msg_len, "fcntl: %s", strerror(errno));
    return SC_CLIENT_ECONNECT;
  }
  return 0;
}

/* One TCP address: a non-blocking connect that waits at most timeout_ms.
 * The fd, or -errno. */
static int connect_one(const struct addrinfo *ai, int timeout_ms) {
  int fd = socket(ai->ai_family, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (fd < 0)
    return -errno;
  int rc = connect(fd, ai->ai_addr, ai->ai_addrlen);
  int e = rc == 0 ? 0 : errno;
  if (e == EINPROGRESS || e == EINTR) {
    struct pollfd p = {.fd = fd, .events = POLLOUT};
    double deadline = scc_deadline_after(timeout_ms);
    for (;;) {
      int ms = -1;
      if (deadline >= 0) {
        double left = (deadline - scc_now_s()) * 1000.0;
        ms = left <= 0 ? 0 : (int)left + 1;
      }
      rc = poll(&p, 1, ms);
      if (rc < 0 && errno == EINTR)
        continue;
      break;
    }
    socklen_t len = sizeof e;
    if (rc == 0)
      e = ETIMEDOUT;
    else if (rc < 0)
      e = errno;
    else if (getsockopt(fd, SOL_SOCKET, SO_ERROR, &e, &len) != 0)
      e = errno;
  }
  if (e != 0) {
    close(fd);
    return -e;
  }
  /* Frames go out whole: Nagle's delay would only hold back the small
   * ones (JOB_END, PING) behind an acknowledgement. */
  int one = 1;
  setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  return fd;
}

/* Connects c->fd to the daemon's TCP address, trying each address the
 * host name gives: 0, or the error code with its message in msg. */
static int connect_tcp(sc_client_t *c, int timeout_ms, char *msg,
                       size_t msg_len) {
  char port[8];
  snprintf(port, sizeof port, "%u", (unsigned)c->addr.port);
  struct addrinfo hints, *res = NULL;
  memset(&hints, 0, sizeof hints);
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_NUMERICSERV;
  int rc = getaddrinfo(c->addr.host, port, &hints, &res);
  if (rc != 0 || !res) {
    set_msg(msg, msg_len, "cannot resolve %s: %s", c->addr.host,
            gai_strerror(rc));
    return SC_CLIENT_ECONNECT;
  }
  int e = EHOSTUNREACH;
  for (const struct addrinfo *ai = res; ai; ai = ai->ai_next) {
    int fd = connect_one(ai, timeout_ms);
    if (fd >= 0) {
      c->fd = fd;
      freeaddrinfo(res);
      return 0;
    }
    e = -fd;
  }
  freeaddrinfo(res);
  if (e == ECONNREFUSED) {
    set_msg(msg, msg_len,
            "the daemon is not running: nothing listens on %s (%s)", c->path,
            strerror(e));
    return SC_CLIENT_ENODAEMON;
  }
  set_msg(msg, msg_len, "cannot connect to the daemon on %s: %s", c->path,
          strerror(e));
  return e == ETIMEDOUT ? SC_CLIENT_ETIMEOUT : SC_CLIENT_ECONNECT;
}

/* The token file, by the daemon's rules (scp_token_read()), so that a
 * file the daemon would refuse is not used here either. */
static int read_token_file(sc_client_t *c, const char *path, char *msg,
                           size_t msg_len) {
  if (scp_token_read(path, 1, c->token, &c->token_len, msg, msg_len) != 0)
    return SC_CLIENT_EAUTH;
  c->has_token = 1;
  return 0;
}

/* The token for a TCP daemon: the options' own, their file, or
 * SHORTCRUST_TOKEN; none is not an error here (the daemon says AUTH). */
static int load_token(sc_client_t *c, const sc_client_options_t *o, char *msg,
                      size_t msg_len) {
  const char *t = o->token;
  if (!t && o->token_file)
    return read_token_file(c, o->token_file, msg, msg_len);
  if (!t)
    t = getenv("SHORTCRUST_TOKEN");
  if (!t || !*t)
    return 0;
  if (strlen(t) > SCP_TOKEN_MAX) {
    set_msg(msg, msg_len, "the token is longer than %d bytes", SCP_TOKEN_MAX);
    return SC_CLIENT_EAUTH;
  }
  c->token_len = strlen(t);
  memcpy(c->token, t, c->token_len);
  c->has_token = 1;
  return 0;
}

/* Opens the connection and does the handshake, on a handle that is new or
 * whose connection is gone: 0 with the handle ready, or the error code
 * with its message in msg (the handle then has no connection, c->err set). */
static int open_connection(sc_client_t *c, char *msg, size_t msg_len) {
  if (c->fd >= 0) {
    close(c->fd);
    c->fd = -1;
  }
  scp_decoder_free(c->dec);
  scp_limits_t lim;
  scp_limits_init(&lim);
  lim.role = SCP_ROLE_CLIENT;
  c->dec = scp_decoder_new(&lim);
  scp_buf_free(&c->out);
  scp_buf_init(&c->out, SCP_FRAME_MIN);
  c->out_at = 0;
  c->ready = 0;
  c->err = 0;
  c->errmsg[0] = '\0';
  memset(&c->welcome, 0, sizeof c->welcome);
  c->ping_waiting = c->pong_seen = 0;
  c->stats_waiting = c->stats_seen = 0;
  if (!c->dec) {
    set_msg(msg, msg_len, "out of memory");
    c->err = SC_CLIENT_ENOMEM;
    return c->err;
  }
  int tcp = c->addr.kind == SCP_ADDR_TCP;
  int rc = tcp ? connect_tcp(c, c->io_timeout_ms, msg, msg_len)
               : connect_unix(c, c->addr.path[0] ? c->addr.path : c->path, msg,
                              msg_len);
  if (rc != 0) {
    if (c->fd >= 0) {
      close(c->fd);
      c->fd = -1;
    }
    c->err = rc;
    snprintf(c->errmsg, sizeof c->errmsg, "%s", msg ? msg : "");
    return rc;
  }

  /* The token goes over TCP only (PROTOCOL.md 5.1). */
  c->hello = (scp_hello_t){.version_min = SCP_VERSION,
                           .version_max = SCP_VERSION,
                           .features = SCP_FEATURE_JOB_OPTIONS,
                           .max_frame = c->max_frame_opt};
  if (tcp && c->has_token) {
    c->hello.features |= SCP_FEATURE_TOKEN;
    c->hello.token = c->token;
    c->hello.token_len = (uint32_t)c->token_len;
  }
  if (scp_enc_hello(&c->out, &c->hello) < 0)
    scc_conn_die(c, SC_CLIENT_ENOMEM, "out of memory");
  c->hello.token = NULL;
  rc = scc_run_io(c, cond_ready, NULL, scc_deadline_after(c->io_timeout_ms));
  if (rc == SC_CLIENT_ETIMEOUT && !c->err)
    scc_conn_die(c, SC_CLIENT_ETIMEOUT,
                 "no answer from the daemon on %s in %d ms", c->path,
                 c->io_timeout_ms);
  if (c->err == SC_CLIENT_EAUTH && !c->has_token)
    snprintf(c->errmsg + strlen(c->errmsg),
             sizeof c->errmsg - strlen(c->errmsg),
             "; give the daemon's token (a token file, or SHORTCRUST_TOKEN)");
  /* Wipe the HELLO that held the token. */
  if (c->out.data)
    scp_wipe(c->out.data, c->out.cap);
  c->out.len = 0;
  c->out_at = 0;
  if (c->err) {
    set_msg(msg, msg_len, "%s", c->errmsg);
    return c->err;
  }
  c->ready = 1;
  scp_decoder_set_max_frame(c->dec, c->welcome.max_frame);
  c->out.max_frame = c->welcome.max_frame;
  /* Frames that came right behind WELCOME. */
  drain(c);
  return 0;
}

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
  c->max_frame_opt = o.max_frame ? o.max_frame : 1u << 20;
  c->next_id = 1;
  if (o.socket_path)
    snprintf(c->path, sizeof c->path, "%s", o.socket_path);
  else
    sc_client_default_socket(c->path, sizeof c->path);
  if (scp_address_parse(c->path, &c->addr) != 0 && !strstr(c->path, "://")) {
    /* A plain path too long for a socket: connecting says so. */
    c->addr.kind = SCP_ADDR_UNIX;
  } else if (c->addr.kind == 0) {
    set_msg(msg, msg_len,
            "'%s' is not an address: want a socket path, unix://PATH or "
            "tcp://HOST:PORT",
            c->path);
    free(c);
    return SC_CLIENT_EINVAL;
  }
  int rc = c->addr.kind == SCP_ADDR_TCP ? load_token(c, &o, msg, msg_len) : 0;
  c->rbuf = malloc(SCC_READ_SIZE);
  if (rc == 0 && !c->rbuf) {
    set_msg(msg, msg_len, "out of memory");
    rc = SC_CLIENT_ENOMEM;
  }
  if (rc == 0)
    rc = open_connection(c, msg, msg_len);
  if (rc != 0) {
    sc_client_free(c);
    return rc;
  }
  *out = c;
  return 0;
}

int scc_waiting(const sc_client_t *c) {
  for (const sc_client_job_t *j = c->jobs; j; j = j->next)
    if (j->resubmit)
      return 1;
  return 0;
}

int scc_may_retry(const sc_client_job_t *j, int code) {
  return (code == SC_CLIENT_ELOST || code == SC_CLIENT_ESHUTDOWN) &&
         !j->cancelled && !j->local_err && !j->user_freed && j->xyz &&
         j->retries_used <
             (unsigned)(j->params.retries > 0 ? j->params.retries : 0);
}

static void sleep_ms(int ms) {
  struct timespec ts = {.tv_sec = ms / 1000,
                        .tv_nsec = (long)(ms % 1000) * 1000000L};
  while (nanosleep(&ts, &ts) != 0 && errno == EINTR)
    ;
}

int scc_recover(sc_client_t *c) {
  if (c->recovering || c->in_callback)
    return c->err;
  c->recovering = 1;
  while (c->err && scc_waiting(c)) {
    /* The longest back-off any waiting job asks for at its attempt. */
    int wait = 0;
    for (sc_client_job_t *j = c->jobs; j; j = j->next)
      if (j->resubmit) {
        long ms =
            j->params.retry_backoff_ms > 0 ? j->params.retry_backoff_ms : 0;
        for (unsigned i = 0; i < j->retries_used && ms < 10000; i++)
          ms *= 2;
        if (ms > 10000)
          ms = 10000;
        if (ms > wait)
          wait = (int)ms;
        j->retries_used++;
      }
    if (wait)
      sleep_ms(wait);
    char msg[SCC_MSG_MAX];
    int rc = open_connection(c, msg, sizeof msg);
    if (rc != 0) {
      /* An attempt that failed counts as a retry: the jobs that have none
       * left end with its error. */
      for (sc_client_job_t *j = c->jobs; j; j = j->next)
        if (j->resubmit && j->retries_used >= (unsigned)j->params.retries) {
          j->resubmit = 0;
          snprintf(j->message, sizeof j->message, "%.1200s (after %u retries)",
                   msg, j->retries_used);
          scc_settle(c, j, rc);
        }
      continue;
    }
    for (sc_client_job_t *j = c->jobs; j && !c->err; j = j->next)
      if (j->resubmit)
        scc_resubmit(c, j);
  }
  c->recovering = 0;
  scc_reap(c);
  return c->err;
}

void sc_client_free(sc_client_t *c) {
  if (!c)
    return;
  if (c->fd >= 0)
    close(c->fd);
  while (c->jobs)
    scc_job_destroy(c->jobs);
  scp_decoder_free(c->dec);
  scp_buf_free(&c->out);
  free(c->rbuf);
  free(c->stats);
  scp_wipe(c->token, sizeof c->token);
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

/* Common checks of the public calls on a handle. */
int scc_usable(sc_client_t *c) {
  if (c->in_callback)
    return scc_fail(c, SC_CLIENT_ESTATE,
                    "a callback may not call the library on its own handle");
  if (c->err && scc_waiting(c))
    scc_recover(c);
  if (c->err) {
    snprintf(c->last, sizeof c->last, "%s", c->errmsg);
    return c->err;
  }
  return 0;
}

/* PING and STATS. */

static int cond_pong(sc_client_t *c, void *arg) { return c->pong_seen; }

int sc_client_ping(sc_client_t *c, int timeout_ms, double *rtt) {
  if (!c)
    return SC_CLIENT_EINVAL;
  int rc = scc_usable(c);
  if (rc < 0)
    return rc;
  double t0 = scc_now_s();
  c->ping_token++;
  if (scp_enc_ping(&c->out, c->ping_token) < 0)
    return scc_fail(c, SC_CLIENT_ENOMEM, "out of memory");
  c->ping_waiting = 1;
  c->pong_seen = 0;
  rc = scc_run_io(c, cond_pong, NULL, scc_deadline_after(timeout_ms));
  c->ping_waiting = 0;
  scc_reap(c);
  if (rc < 0)
    return c->err ? scc_usable(c)
                  : scc_fail(c, rc, "no PONG from the daemon in %d ms",
                             timeout_ms);
  if (rtt)
    *rtt = scc_now_s() - t0;
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
  int rc = scc_usable(c);
  if (rc < 0)
    return rc;
  c->stats_tag++;
  if (scp_enc_stats_request(&c->out, c->stats_tag) < 0)
    return scc_fail(c, SC_CLIENT_ENOMEM, "out of memory");
  free(c->stats);
  c->stats = NULL;
  c->nstats = 0;
  c->stats_waiting = 1;
  c->stats_seen = 0;
  rc = scc_run_io(c, cond_stats, NULL, scc_deadline_after(timeout_ms));
  c->stats_waiting = 0;
  scc_reap(c);
  if (rc < 0)
    return c->err ? scc_usable(c)
                  : scc_fail(c, rc, "no STATS from the daemon in %d ms",
                             timeout_ms);
  *values = c->stats;
  *count = c->nstats;
  c->stats = NULL;
  c->nstats = 0;
  return 0;
}
