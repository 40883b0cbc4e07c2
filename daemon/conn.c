/*
 * Connections: the protocol of PROTOCOL.md from the server's side. Bytes
 * are read into the connection's decoder, each whole frame is read,
 * validated and carried out, and replies are appended to a bounded output
 * queue; meshes go out chunk by chunk only while that queue has room.
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
#include "daemon.h"
#include "log.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* pi / 2, the largest boundary_alpha (M_PI is not C11). */
#define SCD_HALF_PI 1.5707963267948966

static void process(scd_conn_t *c);
static void flush(scd_conn_t *c);
static void pump(scd_conn_t *c);
static void check_shutdown(scd_conn_t *c);
static void conn_fatal(scd_conn_t *c, uint32_t code, uint32_t job_id,
                       uint16_t ref_type, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));

typedef unsigned long long ull;

static double ms_between(uint64_t t0, uint64_t t1) {
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
 * it is closed by the next flush(), not here, because the caller may still
 * hold one of its jobs. */
static int sent(scd_conn_t *c, int rc) {
  if (rc == 0) {
    c->srv->n.frames_out_total++;
    return 0;
  }
  scd_error("conn %llu: cannot encode a frame: %s", (ull)c->id,
            scp_strerror(rc));
  c->broken = 1;
  return rc;
}

static void vformat(char *buf, size_t len, const char *fmt, va_list ap) {
  int n = vsnprintf(buf, len, fmt, ap);
  if (n < 0)
    buf[0] = '\0';
}

/* A non-fatal ERROR: the request is refused and the connection goes on. */
static void reply_error(scd_conn_t *c, uint32_t code, uint32_t job_id,
                        uint16_t ref_type, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));
static void reply_error(scd_conn_t *c, uint32_t code, uint32_t job_id,
                        uint16_t ref_type, const char *fmt, ...) {
  scp_error_t e;
  memset(&e, 0, sizeof e);
  e.code = code;
  e.job_id = job_id;
  e.ref_type = ref_type;
  va_list ap;
  va_start(ap, fmt);
  vformat(e.message, sizeof e.message, fmt, ap);
  va_end(ap);
  scd_debug("conn %llu: ERROR %s job %u: %s", (ull)c->id, scp_wire_name(code),
            job_id, e.message);
  c->invalid_streak++;
  if (sent(c, scp_enc_error(&c->out, &e)) != 0)
    return;
  if (c->invalid_streak >= c->srv->cfg.max_invalid)
    conn_fatal(c, SCP_WIRE_PROTOCOL, 0, 0,
               "%u invalid requests in a row; closing", c->invalid_streak);
}

static void send_job_error(scd_conn_t *c, uint32_t job_id, uint32_t code,
                           const char *msg) {
  scp_job_error_t e;
  memset(&e, 0, sizeof e);
  e.job_id = job_id;
  e.code = code;
  snprintf(e.message, sizeof e.message, "%s", msg);
  sent(c, scp_enc_job_error(&c->out, &e));
}

/* Jobs. */

static scd_job_t *find_job(scd_conn_t *c, uint32_t id) {
  for (scd_job_t *j = c->jobs; j; j = j->next)
    if (j->id == id)
      return j;
  return NULL;
}

static scd_job_t *new_job(scd_conn_t *c, uint32_t id) {
  scd_job_t *j = calloc(1, sizeof *j);
  if (!j)
    return NULL;
  j->conn = c;
  j->id = id;
  j->begin_ns = uv_hrtime();
  j->next = c->jobs;
  if (c->jobs)
    c->jobs->prev = j;
  c->jobs = j;
  c->njobs++;
  c->jobs_total++;
  return j;
}

static void unqueue_send(scd_conn_t *c, scd_job_t *j) {
  scd_job_t **pp = &c->shead;
  scd_job_t *prev = NULL;
  while (*pp && *pp != j) {
    prev = *pp;
    pp = &(*pp)->snext;
  }
  if (!*pp)
    return;
  *pp = j->snext;
  if (c->stail == j)
    c->stail = prev;
  j->snext = NULL;
}

/* Lets go of the job's task: freed now when the pool does not hold it, or
 * cancelled and freed when it comes back. */
static void drop_task(scd_conn_t *c, scd_job_t *j) {
  scd_server_t *srv = c->srv;
  scd_task_t *t = j->task;
  if (!t)
    return;
  j->task = NULL;
  t->owner = NULL;
  if (t->submitted) {
    if (!scd_pool_withdraw(srv->pool, t)) {
      scd_pool_cancel(srv->pool, t);
      return;
    }
    srv->tasks_in_pool--;
  }
  scd_server_free_task(srv, t);
}

static void free_job(scd_conn_t *c, scd_job_t *j) {
  drop_task(c, j);
  unqueue_send(c, j);
  if (j->prev)
    j->prev->next = j->next;
  else
    c->jobs = j->next;
  if (j->next)
    j->next->prev = j->prev;
  c->njobs--;
  free(j->staging);
  free(j);
}

static const char *phase_name(int phase) {
  switch (phase) {
  case SCD_JOB_UPLOADING:
    return "uploading";
  case SCD_JOB_WORKING:
    return "working";
  case SCD_JOB_SENDING:
    return "sending";
  case SCD_JOB_DRAINING:
    return "draining";
  }
  return "?";
}

/* The one log line of a job, written when it ends however it ends. */
static void log_job(scd_conn_t *c, scd_job_t *j, const char *outcome,
                    const char *detail) {
  uint64_t now = uv_hrtime();
  /* A task still in the pool is a worker's: its timings and mesh are not
   * ours to read. */
  const scd_task_t *t = j->task && !j->task->submitted ? j->task : NULL;
  const sc_mesh_t *m = t ? t->mesh : NULL;
  char stages[256] = "";
  if (m) {
    size_t at = 0;
    for (int s = 0; s < SC_STAGE_COUNT && at < sizeof stages; s++) {
      int n = snprintf(stages + at, sizeof stages - at, " %s_ms=%.1f",
                       sc_stage_name(s), m->diag.seconds[s] * 1e3);
      if (n < 0)
        break;
      at += (size_t)n;
    }
  }
  int level = strcmp(outcome, "done") == 0 ? SCD_LOG_INFO : SCD_LOG_WARN;
  if (strcmp(outcome, "cancelled") == 0)
    level = SCD_LOG_INFO;
  scd_log(level,
          "job %llu:%u %s%s%s: points=%llu triangles=%llu upload_ms=%.1f "
          "compute_ms=%.1f send_ms=%.1f total_ms=%.1f%s",
          (ull)c->id, j->id, outcome, detail ? " " : "", detail ? detail : "",
          (ull)j->received, (ull)(m ? m->triangle_count : 0),
          ms_between(j->begin_ns, j->end_ns ? j->end_ns : now),
          t && t->start_ns ? ms_between(t->start_ns, t->end_ns) : 0.0,
          ms_between(j->done_ns, j->done_ns ? now : 0),
          ms_between(j->begin_ns, now), stages);
}

/* A job that is still uploading fails: JOB_ERROR, and the id drains until
 * the client sends JOB_END or CANCEL. */
static void fail_upload(scd_conn_t *c, scd_job_t *j, uint32_t code,
                        const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static void fail_upload(scd_conn_t *c, scd_job_t *j, uint32_t code,
                        const char *fmt, ...) {
  char msg[SCP_MESSAGE_MAX + 1];
  va_list ap;
  va_start(ap, fmt);
  vformat(msg, sizeof msg, fmt, ap);
  va_end(ap);
  send_job_error(c, j->id, code, msg);
  c->srv->n.jobs_failed_total++;
  char detail[SCP_MESSAGE_MAX + 32];
  snprintf(detail, sizeof detail, "%s (%s)", scp_wire_name(code), msg);
  log_job(c, j, "failed", detail);
  drop_task(c, j);
  free(j->staging);
  j->staging = NULL;
  j->phase = SCD_JOB_DRAINING;
}

/* A job ends for good with JOB_ERROR and its id is free again. */
static void fail_job(scd_conn_t *c, scd_job_t *j, uint32_t code,
                     const char *outcome, const char *msg) {
  send_job_error(c, j->id, code, msg);
  if (code == SCP_WIRE_CANCELLED)
    c->srv->n.jobs_cancelled_total++;
  else
    c->srv->n.jobs_failed_total++;
  char detail[SCP_MESSAGE_MAX + 32];
  snprintf(detail, sizeof detail, "%s (%s)", scp_wire_name(code), msg);
  log_job(c, j, outcome, detail);
  free_job(c, j);
}

/* Every job of a closing connection stops; nothing more is sent. */
static void end_all_jobs(scd_conn_t *c, const char *why) {
  while (c->jobs) {
    scd_job_t *j = c->jobs;
    if (j->phase != SCD_JOB_DRAINING) {
      c->srv->n.jobs_cancelled_total++;
      log_job(c, j, "cancelled", why);
    }
    free_job(c, j);
  }
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

void scd_conn_close_now(scd_conn_t *c, const char *reason) {
  if (c->state == SCD_CONN_CLOSED)
    return;
  if (!c->close_reason[0])
    snprintf(c->close_reason, sizeof c->close_reason, "%s", reason);
  end_all_jobs(c, c->close_reason);
  c->state = SCD_CONN_CLOSED;
  c->reading = 0;
  if (c->counted) {
    c->srv->conns_open--;
    c->counted = 0;
  }
  scd_info("conn %llu: closed (%s): %llu bytes in, %llu bytes out, %llu "
           "jobs, %.1f s",
           (ull)c->id, c->close_reason, (ull)c->bytes_in, (ull)c->bytes_out,
           (ull)c->jobs_total, ms_between(c->open_ns, uv_hrtime()) / 1e3);
  uv_close((uv_handle_t *)&c->pipe, on_closed);
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
  if (uv_shutdown(&c->sreq, (uv_stream_t *)&c->pipe, on_shutdown) != 0)
    scd_conn_close_now(c, c->close_reason);
}

/* A fatal ERROR, then the connection closes once it is written. */
static void conn_fatal(scd_conn_t *c, uint32_t code, uint32_t job_id,
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
  vformat(e.message, sizeof e.message, fmt, ap);
  va_end(ap);
  if (code != SCP_WIRE_SHUTDOWN)
    c->srv->n.protocol_errors_total++;
  scd_log(code == SCP_WIRE_SHUTDOWN ? SCD_LOG_INFO : SCD_LOG_WARN,
          "conn %llu: fatal ERROR %s: %s", (ull)c->id, scp_wire_name(code),
          e.message);
  snprintf(c->close_reason, sizeof c->close_reason, "%s: %s",
           scp_wire_name(code), e.message);
  end_all_jobs(c, c->close_reason);
  if (sent(c, scp_enc_error(&c->out, &e)) != 0) {
    flush(c);
    return;
  }
  c->state = SCD_CONN_CLOSING;
  c->deadline_ns = uv_hrtime() + c->srv->cfg.close_ms * 1000000u;
  set_reading(c, 0);
  flush(c);
  finish_closing(c);
}

/* A stream error from the decoder: fatal, with the wire code it maps to. */
static void protocol_fatal(scd_conn_t *c, int rc, uint32_t job_id,
                           uint16_t ref_type) {
  conn_fatal(c, scp_err_to_wire(rc), job_id, ref_type, "%s",
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
      protocol_fatal(c, rc, 0, 0);
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
    if (uv_read_start((uv_stream_t *)&c->pipe, on_alloc, on_read) == 0)
      c->reading = 1;
  } else if (!on && c->reading) {
    uv_read_stop((uv_stream_t *)&c->pipe);
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
  pump(c);
  flush(c);
  finish_closing(c);
  if (c->state == SCD_CONN_READY && !c->reading &&
      queued(c) <= c->srv->cfg.out_soft / 2)
    process(c);
}

static void flush(scd_conn_t *c) {
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
  int rc = uv_write(&c->wreq, (uv_stream_t *)&c->pipe, &ub, 1, on_write);
  if (rc != 0) {
    c->writing = 0;
    char why[96];
    snprintf(why, sizeof why, "write: %s", uv_strerror(rc));
    scd_conn_close_now(c, why);
  }
}

/* Sending meshes. */

static uint64_t mesh_bytes(const sc_mesh_t *m) {
  return sizeof *m + m->triangle_count * 3 * sizeof(uint32_t) +
         m->point_count * 3 * sizeof(double) +
         m->component_count * sizeof(int32_t);
}

static void send_job_done(scd_conn_t *c, scd_job_t *j) {
  const sc_mesh_t *m = j->task->mesh;
  const sc_diag_t *d = &m->diag;
#define U(n_, v_) {.name = n_, .kind = SCP_KIND_U64, .v.u = (uint64_t)(v_)}
#define I(n_, v_) {.name = n_, .kind = SCP_KIND_I64, .v.i = (int64_t)(v_)}
#define F(n_, v_) {.name = n_, .kind = SCP_KIND_F64, .v.f = (double)(v_)}
  scp_value_t v[] = {
      U("points_in", d->points_in),
      U("duplicates_merged", d->duplicates_merged),
      U("delaunay_vertices", d->delaunay_vertices),
      U("delaunay_cells", d->delaunay_cells),
      U("delaunay_facets", d->delaunay_facets),
      U("hull_vertices", d->hull_vertices),
      U("degenerate_cells", d->degenerate_cells),
      U("candidates", d->candidates),
      U("pruned", d->pruned),
      U("triangles", d->triangles),
      U("walk_rejected", d->walk_rejected),
      U("holes_filled", d->holes_filled),
      U("hole_triangles", d->hole_triangles),
      U("samples_unused", d->samples_unused),
      U("boundary_edges", d->boundary_edges),
      U("boundary_loops", d->boundary_loops),
      U("nonmanifold_edges", d->nonmanifold_edges),
      U("nonmanifold_vertices", d->nonmanifold_vertices),
      U("components", d->components),
      U("closed_components", d->closed_components),
      U("closed", d->closed ? 1 : 0),
      I("euler", d->euler),
      I("genus", d->genus),
      F("seconds.input", d->seconds[SC_STAGE_INPUT]),
      F("seconds.delaunay", d->seconds[SC_STAGE_DELAUNAY]),
      F("seconds.poles", d->seconds[SC_STAGE_POLES]),
      F("seconds.candidates", d->seconds[SC_STAGE_CANDIDATES]),
      F("seconds.prune", d->seconds[SC_STAGE_PRUNE]),
      F("seconds.extract", d->seconds[SC_STAGE_EXTRACT]),
      F("seconds.total", d->seconds_total),
      U("path", d->path),
      U("boundary_samples", d->boundary_samples),
      U("longest_loop", d->longest_loop),
      U("loops.3_10", d->loops_by_length[0]),
      U("loops.11_100", d->loops_by_length[1]),
      U("loops.101_1000", d->loops_by_length[2]),
      U("loops.over_1000", d->loops_by_length[3]),
      U("cells_relabelled", d->cells_relabelled),
      U("bubbles_dropped", d->bubbles_dropped),
      U("samples_attached", d->samples_attached),
      U("handles_cut", d->handles_cut),
      F("seconds.upload", ms_between(j->begin_ns, j->end_ns) / 1e3),
      F("seconds.server", ms_between(j->begin_ns, uv_hrtime()) / 1e3),
  };
#undef U
#undef I
#undef F
  scp_job_done_t done;
  memset(&done, 0, sizeof done);
  done.job_id = j->id;
  done.triangles = j->cursor.triangles;
  done.normals = j->cursor.normals;
  done.components = j->cursor.components;
  sent(c, scp_enc_job_done(&c->out, &done, v,
                           (uint32_t)(sizeof v / sizeof v[0])));
}

/* Emits mesh chunks, one job after the other in turn, while the output
 * queue has room. */
static void pump(scd_conn_t *c) {
  while (c->state == SCD_CONN_READY && c->shead &&
         queued(c) < c->srv->cfg.out_soft) {
    scd_job_t *j = c->shead;
    const sc_mesh_t *m = j->task->mesh;
    scp_mesh_view_t view;
    memset(&view, 0, sizeof view);
    view.job_id = j->id;
    view.triangles = m->triangles;
    view.triangle_count = m->triangle_count;
    if (j->flags & SCP_JOB_NORMALS) {
      view.normals = m->normals;
      view.normal_count = m->point_count;
      view.normal_format =
          (j->flags & SCP_JOB_NORMALS_F64) ? SCP_F64_XYZ : SCP_F32_XYZ;
    }
    view.genus = m->component_genus;
    view.component_count = m->component_count;
    int rc = scp_enc_mesh_next(&c->out, &view, &j->cursor);
    if (rc == 1) {
      c->srv->n.frames_out_total++;
      if (j->snext) {
        c->shead = j->snext;
        j->snext = NULL;
        c->stail->snext = j;
        c->stail = j;
      }
      continue;
    }
    unqueue_send(c, j);
    if (rc == 0) {
      send_job_done(c, j);
      c->srv->n.jobs_done_total++;
      c->srv->n.triangles_out_total += m->triangle_count;
      log_job(c, j, "done", NULL);
      free_job(c, j);
    } else {
      char msg[128];
      snprintf(msg, sizeof msg, "cannot encode the mesh: %s",
               scp_strerror(rc));
      fail_job(c, j, SCP_WIRE_INTERNAL, "failed", msg);
    }
  }
  check_shutdown(c);
}

/* Results from the pool. */

static uint32_t wire_code(int sc_rc) {
  switch (sc_rc) {
  case SC_EDEGENERATE_INPUT:
    return SCP_WIRE_DEGENERATE_INPUT;
  case SC_ENONFINITE:
    return SCP_WIRE_NONFINITE;
  case SC_ENO_MEMORY:
    return SCP_WIRE_NO_MEMORY;
  case SC_ECANCELLED:
    return SCP_WIRE_CANCELLED;
  case SC_ETOO_MANY_POINTS:
    return SCP_WIRE_LIMIT;
  }
  return SCP_WIRE_INTERNAL;
}

void scd_conn_task_event(scd_server_t *srv, scd_task_t *t, unsigned events,
                         uint32_t stage, double fraction) {
  scd_job_t *j = t->owner;
  if (!(events & SCD_EV_DONE)) {
    if (!j || (j->phase != SCD_JOB_UPLOADING && j->phase != SCD_JOB_WORKING))
      return;
    scd_conn_t *c = j->conn;
    /* Progress is informational: dropped when the client is behind. */
    if (c->state != SCD_CONN_READY || queued(c) >= srv->cfg.out_soft ||
        stage >= SCP_STAGE_COUNT)
      return;
    scp_progress_t p = {.job_id = j->id, .stage = stage, .fraction = fraction};
    if (sent(c, scp_enc_progress(&c->out, &p)) == 0)
      flush(c);
    return;
  }
  if (!j) {
    scd_server_free_task(srv, t);
    return;
  }
  scd_conn_t *c = j->conn;
  j->done_ns = uv_hrtime();
  if (t->rc == 0) {
    scd_budget_set(srv, t, mesh_bytes(t->mesh));
    j->phase = SCD_JOB_SENDING;
    j->snext = NULL;
    if (c->stail)
      c->stail->snext = j;
    else
      c->shead = j;
    c->stail = j;
    pump(c);
  } else {
    uint32_t code = wire_code(t->rc);
    char msg[SCP_MESSAGE_MAX + 1];
    snprintf(msg, sizeof msg, "%s", t->msg[0] ? t->msg : sc_strerror(t->rc));
    if (j->phase == SCD_JOB_UPLOADING)
      fail_upload(c, j, code, "%s", msg);
    else
      fail_job(c, j, code, "failed", msg);
    check_shutdown(c);
  }
  flush(c);
}

/* Frames. */

static void on_hello(scd_conn_t *c, const scp_frame_t *f) {
  scd_server_t *srv = c->srv;
  scp_hello_t h;
  memset(&h, 0, sizeof h);
  int rc = scp_parse_hello(f, &h);
  if (rc == 0 && (h.version_min > SCP_VERSION || h.version_max < SCP_VERSION)) {
    conn_fatal(c, SCP_WIRE_VERSION, 0, f->type,
               "client speaks versions %u to %u; server speaks versions %u "
               "to %u",
               h.version_min, h.version_max, SCP_VERSION, SCP_VERSION);
    return;
  }
  if (rc == SCP_EVERSION) {
    conn_fatal(c, SCP_WIRE_VERSION, 0, f->type,
               "server speaks versions %u to %u", SCP_VERSION, SCP_VERSION);
    return;
  }
  if (rc != 0) {
    conn_fatal(c, scp_err_to_wire(rc), 0, f->type, "HELLO: %s",
               scp_strerror(rc));
    return;
  }
  if (srv->shutting_down) {
    conn_fatal(c, SCP_WIRE_SHUTDOWN, 0, 0, "server shutting down");
    return;
  }
  scp_welcome_t w;
  memset(&w, 0, sizeof w);
  w.version = SCP_VERSION;
  w.features = h.features & SCP_FEATURE_JOB_OPTIONS;
  w.max_frame = h.max_frame < srv->cfg.max_frame ? h.max_frame
                                                 : srv->cfg.max_frame;
  w.max_jobs = srv->cfg.max_jobs;
  w.max_points = srv->max_points;
  if (sent(c, scp_enc_welcome(&c->out, &w)) != 0)
    return;
  c->max_frame = w.max_frame;
  c->features = w.features;
  scp_decoder_set_max_frame(c->dec, w.max_frame);
  c->out.max_frame = c->wbuf.max_frame = w.max_frame;
  c->state = SCD_CONN_READY;
  c->deadline_ns = 0;
  scd_info("conn %llu: ready (version %u, max_frame %u)", (ull)c->id,
           w.version, w.max_frame);
}

/* Refuses a JOB_BEGIN that claimed a free id: JOB_ERROR, and the id
 * drains. */
static void refuse_job(scd_conn_t *c, uint32_t id, uint32_t code,
                       const char *fmt, ...) __attribute__((format(printf, 4, 5)));
static void refuse_job(scd_conn_t *c, uint32_t id, uint32_t code,
                       const char *fmt, ...) {
  char msg[SCP_MESSAGE_MAX + 1];
  va_list ap;
  va_start(ap, fmt);
  vformat(msg, sizeof msg, fmt, ap);
  va_end(ap);
  scd_job_t *j = new_job(c, id);
  if (!j) {
    scd_conn_close_now(c, "out of memory");
    return;
  }
  j->phase = SCD_JOB_DRAINING;
  send_job_error(c, id, code, msg);
  c->srv->n.jobs_refused_total++;
  char detail[SCP_MESSAGE_MAX + 32];
  snprintf(detail, sizeof detail, "%s (%s)", scp_wire_name(code), msg);
  log_job(c, j, "refused", detail);
}

static uint64_t budget_left(const scd_server_t *srv) {
  return srv->budget_used < srv->cfg.memory_budget
             ? srv->cfg.memory_budget - srv->budget_used
             : 0;
}

static void fmt_bytes(char *buf, size_t len, uint64_t b) {
  snprintf(buf, len, "%.1f MiB", (double)b / (1024.0 * 1024.0));
}

/* The job options of a JOB_BEGIN (PROTOCOL.md 6.3), applied to *p: 0, or
 * the wire code to refuse the job with, and the reason in why. */
static uint32_t apply_options(const scp_values_t *options, sc_params_t *p,
                              char *why, size_t len) {
  static const struct {
    const char *name;
    uint32_t kind;
  } known[] = {{SCP_OPT_MAX_HOLE_EDGES, SCP_KIND_U64},
               {SCP_OPT_BOUNDARY_RHO, SCP_KIND_F64},
               {SCP_OPT_BOUNDARY_ALPHA, SCP_KIND_F64},
               {SCP_OPT_PAPER_PRUNING, SCP_KIND_U64},
               {SCP_OPT_WATERTIGHT_LABELS, SCP_KIND_U64}};
  const size_t nknown = sizeof known / sizeof known[0];
  unsigned seen = 0;
  scp_value_iter_t it;
  scp_value_t v;
  scp_values_begin(options, &it);
  while (scp_values_next(&it, &v)) {
    size_t k = 0;
    while (k < nknown && strcmp(v.name, known[k].name) != 0)
      k++;
    if (k == nknown) {
      snprintf(why, len, "job option %s is not supported by this server",
               v.name);
      return SCP_WIRE_UNSUPPORTED;
    }
    if (seen & (1u << k))
      continue; /* a name given twice takes its first value */
    seen |= 1u << k;
    if (v.kind != known[k].kind) {
      snprintf(why, len, "job option %s must be %s", v.name,
               known[k].kind == SCP_KIND_U64 ? "an unsigned integer (u64)"
                                             : "a number (f64)");
      return SCP_WIRE_INVALID;
    }
    int bad = 0;
    switch (k) {
    case 0:
      bad = v.v.u > 100000;
      p->max_hole_edges = bad ? 0 : (int)v.v.u;
      break;
    case 1:
      bad = !(v.v.f > 0 && v.v.f <= 10);
      p->boundary_rho = v.v.f;
      break;
    case 2:
      bad = !(v.v.f > 0 && v.v.f <= SCD_HALF_PI);
      p->boundary_alpha = v.v.f;
      break;
    case 3:
      bad = v.v.u > 1;
      p->paper_pruning = (int)(v.v.u & 1);
      break;
    default:
      bad = v.v.u > 1;
      p->watertight_labels = (int)(v.v.u & 1);
      break;
    }
    if (bad) {
      if (known[k].kind == SCP_KIND_U64)
        snprintf(why, len, "job option %s out of range: %llu", v.name,
                 (ull)v.v.u);
      else
        snprintf(why, len, "job option %s out of range: %g", v.name, v.v.f);
      return SCP_WIRE_INVALID;
    }
  }
  /* Whatever the ranges above let through, the core must take too. */
  if (sc_params_check(p, why, len) != SC_OK)
    return SCP_WIRE_INVALID;
  return 0;
}

static void on_job_begin(scd_conn_t *c, const scp_frame_t *f) {
  scd_server_t *srv = c->srv;
  scp_job_begin_t m;
  memset(&m, 0, sizeof m);
  /* Options are only for connections that agreed on them. */
  int rc = scp_parse_job_begin_features(f, c->features, &m);
  uint32_t id = m.job_id;
  if (rc != 0) {
    if (scp_err_is_fatal(rc)) {
      protocol_fatal(c, rc, 0, f->type);
      return;
    }
    if (!scp_frame_job_id(f, &id) || id == 0)
      reply_error(c, SCP_WIRE_INVALID, 0, f->type, "JOB_BEGIN: %s",
                  scp_strerror(rc));
    else if (find_job(c, id))
      reply_error(c, SCP_WIRE_DUPLICATE_JOB, id, f->type,
                  "job %u is in use", id);
    else if (c->njobs >= srv->cfg.max_jobs)
      conn_fatal(c, SCP_WIRE_LIMIT, id, f->type,
                 "more than %u jobs in use on one connection",
                 srv->cfg.max_jobs);
    else
      refuse_job(c, id, scp_err_to_wire(rc), "JOB_BEGIN: %s",
                 scp_strerror(rc));
    return;
  }
  if (find_job(c, id)) {
    reply_error(c, SCP_WIRE_DUPLICATE_JOB, id, f->type, "job %u is in use",
                id);
    return;
  }
  if (c->njobs >= srv->cfg.max_jobs) {
    conn_fatal(c, SCP_WIRE_LIMIT, id, f->type,
               "more than %u jobs in use on one connection",
               srv->cfg.max_jobs);
    return;
  }
  if (srv->shutting_down) {
    refuse_job(c, id, SCP_WIRE_SHUTDOWN, "server shutting down");
    return;
  }
  /* The protocol numbers modes like the core; a mode the core was built
   * without is refused. */
  if (m.mode >= (uint32_t)SC_MODE_COUNT_) {
    refuse_job(c, id, SCP_WIRE_UNSUPPORTED,
               "mode %s is not supported by this server",
               scp_mode_name(m.mode));
    return;
  }
  sc_params_t params;
  sc_params_init(&params);
  params.mode = (sc_mode_t)m.mode;
  params.r = m.r;
  if (m.theta != 0)
    params.cocone_theta = m.theta;
  params.threads = 1;
  char why[SCP_MESSAGE_MAX + 1];
  uint32_t refused = apply_options(&m.options, &params, why, sizeof why);
  if (refused) {
    refuse_job(c, id, refused, "%s", why);
    return;
  }
  if (m.point_count > srv->max_points) {
    refuse_job(c, id, SCP_WIRE_LIMIT,
               "job of %llu points; this server takes at most %llu per job",
               (ull)m.point_count, (ull)srv->max_points);
    return;
  }
  scd_task_t *t = scd_task_new();
  if (!t) {
    refuse_job(c, id, SCP_WIRE_NO_MEMORY, "out of memory");
    return;
  }
  srv->tasks_live++;
  uint64_t need = sc_estimate_bytes(m.point_count);
  if (scd_budget_reserve(srv, t, need) != 0) {
    char a[32], b[32], d[32];
    fmt_bytes(a, sizeof a, need);
    fmt_bytes(b, sizeof b, budget_left(srv));
    fmt_bytes(d, sizeof d, srv->cfg.memory_budget);
    scd_server_free_task(srv, t);
    refuse_job(c, id, SCP_WIRE_BUSY,
               "memory budget: the job needs about %s, %s of %s free; "
               "try later",
               a, b, d);
    return;
  }
  scd_job_t *j = new_job(c, id);
  if (!j) {
    scd_server_free_task(srv, t);
    scd_conn_close_now(c, "out of memory");
    return;
  }
  t->params = params;
  t->owner = j;
  j->task = t;
  j->phase = SCD_JOB_UPLOADING;
  j->declared = m.point_count;
  j->flags = m.flags;
  scd_pool_stats_t ps;
  scd_pool_get_stats(srv->pool, &ps);
  scd_pool_submit(srv->pool, t);
  srv->tasks_in_pool++;
  srv->n.jobs_accepted_total++;
  scp_accepted_t a = {
      .job_id = id,
      .queue_position = ps.busy < ps.workers ? 0 : (uint32_t)ps.queued + 1};
  sent(c, scp_enc_accepted(&c->out, &a));
  scd_debug("job %llu:%u accepted: mode %s, %llu points announced, %u job "
            "options",
            (ull)c->id, id, scp_mode_name(m.mode), (ull)m.point_count,
            m.options.count);
}

/* Hands the points gathered so far to the pool. */
static void hand_over(scd_conn_t *c, scd_job_t *j) {
  if (j->staging && j->staging->count) {
    scd_pool_add(c->srv->pool, j->task, j->staging);
    j->staging = NULL;
  }
}

/* Copies a chunk's points, gathering small chunks into batches so that
 * the core inserts them in few calls. -1 when out of memory. */
static int take_points(scd_conn_t *c, scd_job_t *j, const scp_chunk_t *ch) {
  uint64_t batch = c->srv->cfg.batch_points;
  size_t k = ch->count;
  scd_chunk_t *s = j->staging;
  if (s && s->capacity - s->count < k) {
    if (s->count + k <= batch) {
      size_t cap = s->capacity * 2;
      if (cap < s->count + k)
        cap = s->count + k;
      if (cap > batch)
        cap = (size_t)batch;
      scd_chunk_t *g = realloc(s, sizeof *s + cap * 3 * sizeof(double));
      if (!g)
        return -1;
      g->capacity = cap;
      s = j->staging = g;
    } else {
      hand_over(c, j);
      s = NULL;
    }
  }
  if (!s) {
    size_t cap = k < 1024 ? 1024 : k;
    if (j->declared && j->declared - j->received < cap)
      cap = (size_t)(j->declared - j->received);
    if (cap < k)
      cap = k;
    s = j->staging = scd_chunk_new(cap);
    if (!s)
      return -1;
  }
  scp_chunk_copy_xyz(ch, s->xyz + 3 * s->count);
  s->count += k;
  if (s->count >= batch)
    hand_over(c, j);
  return 0;
}

/* A job frame that failed to parse but is not fatal: answered as section
 * 7.3 of PROTOCOL.md says for the job it names. */
static void bad_job_frame(scd_conn_t *c, const scp_frame_t *f, int rc) {
  uint32_t id = 0;
  if (!scp_frame_job_id(f, &id) || id == 0) {
    reply_error(c, SCP_WIRE_INVALID, 0, f->type, "%s: %s",
                scp_type_name(f->type), scp_strerror(rc));
    return;
  }
  scd_job_t *j = find_job(c, id);
  if (!j) {
    if (f->type != SCP_CANCEL)
      reply_error(c, SCP_WIRE_UNKNOWN_JOB, id, f->type, "no job %u", id);
    return;
  }
  char msg[SCP_MESSAGE_MAX + 1];
  snprintf(msg, sizeof msg, "%s: %s", scp_type_name(f->type),
           scp_strerror(rc));
  switch (j->phase) {
  case SCD_JOB_UPLOADING:
    if (f->type == SCP_POINTS) {
      fail_upload(c, j, scp_err_to_wire(rc), "%s", msg);
    } else {
      /* JOB_END or CANCEL: the client will send nothing more for it. */
      fail_job(c, j, scp_err_to_wire(rc), "failed", msg);
    }
    break;
  case SCD_JOB_DRAINING:
    if (f->type != SCP_POINTS)
      free_job(c, j);
    break;
  default:
    reply_error(c, SCP_WIRE_STATE, id, f->type, "job %u is %s", id,
                phase_name(j->phase));
  }
}

/* A job frame's payload did not parse: a fatal error closes the
 * connection, any other is answered for the job the frame names. */
static void job_frame_failed(scd_conn_t *c, const scp_frame_t *f, int rc) {
  if (scp_err_is_fatal(rc))
    protocol_fatal(c, rc, 0, f->type);
  else
    bad_job_frame(c, f, rc);
}

/* The connection's job `id`, or NULL after answering UNKNOWN_JOB. */
static scd_job_t *known_job(scd_conn_t *c, const scp_frame_t *f,
                            uint32_t id) {
  scd_job_t *j = find_job(c, id);
  if (!j)
    reply_error(c, SCP_WIRE_UNKNOWN_JOB, id, f->type, "no job %u", id);
  return j;
}

static void on_points(scd_conn_t *c, const scp_frame_t *f) {
  scd_server_t *srv = c->srv;
  scp_chunk_t ch;
  int rc = scp_parse_chunk(f, &ch);
  if (rc != 0) {
    job_frame_failed(c, f, rc);
    return;
  }
  scd_job_t *j = known_job(c, f, ch.job_id);
  if (!j)
    return;
  if (j->phase == SCD_JOB_DRAINING)
    return;
  if (j->phase != SCD_JOB_UPLOADING) {
    reply_error(c, SCP_WIRE_STATE, ch.job_id, f->type,
                "job %u is %s: its points have all come", ch.job_id,
                phase_name(j->phase));
    return;
  }
  if (ch.first != j->received) {
    fail_upload(c, j, SCP_WIRE_INVALID,
                "POINTS chunk starts at point %llu, expected %llu",
                (ull)ch.first, (ull)j->received);
    return;
  }
  uint64_t total = j->received + ch.count;
  if (total > srv->max_points) {
    fail_upload(c, j, SCP_WIRE_LIMIT,
                "more than %llu points; this server takes at most %llu per "
                "job",
                (ull)(total - 1), (ull)srv->max_points);
    return;
  }
  if (j->declared && total > j->declared) {
    fail_upload(c, j, SCP_WIRE_INVALID,
                "more points than the %llu JOB_BEGIN announced",
                (ull)j->declared);
    return;
  }
  if (!j->declared) {
    uint64_t need = sc_estimate_bytes(total);
    if (need > j->task->reserved &&
        scd_budget_reserve(srv, j->task, need - j->task->reserved) != 0) {
      char a[32], b[32], left[32];
      fmt_bytes(a, sizeof a, need);
      fmt_bytes(left, sizeof left,
                j->task->reserved + budget_left(srv));
      fmt_bytes(b, sizeof b, srv->cfg.memory_budget);
      fail_upload(c, j, SCP_WIRE_NO_MEMORY,
                  "memory budget exhausted at %llu points: the job would "
                  "need about %s; %s of the %s budget is left for it",
                  (ull)total, a, left, b);
      return;
    }
  }
  if (take_points(c, j, &ch) != 0) {
    fail_upload(c, j, SCP_WIRE_NO_MEMORY, "out of memory");
    return;
  }
  j->received = total;
  srv->n.points_in_total += ch.count;
}

static void on_job_end(scd_conn_t *c, const scp_frame_t *f) {
  scp_job_end_t m;
  int rc = scp_parse_job_end(f, &m);
  if (rc != 0) {
    job_frame_failed(c, f, rc);
    return;
  }
  scd_job_t *j = known_job(c, f, m.job_id);
  if (!j)
    return;
  if (j->phase == SCD_JOB_DRAINING) {
    free_job(c, j);
    return;
  }
  if (j->phase != SCD_JOB_UPLOADING) {
    reply_error(c, SCP_WIRE_STATE, m.job_id, f->type, "job %u is %s",
                m.job_id, phase_name(j->phase));
    return;
  }
  if (m.point_count != j->received ||
      (j->declared && j->declared != j->received)) {
    char msg[200];
    snprintf(msg, sizeof msg,
             "JOB_END says %llu points, %llu arrived (JOB_BEGIN announced "
             "%llu)",
             (ull)m.point_count, (ull)j->received, (ull)j->declared);
    fail_job(c, j, SCP_WIRE_INVALID, "failed", msg);
    return;
  }
  hand_over(c, j);
  scd_pool_end_input(c->srv->pool, j->task);
  j->phase = SCD_JOB_WORKING;
  j->end_ns = uv_hrtime();
}

static void on_cancel(scd_conn_t *c, const scp_frame_t *f) {
  uint32_t id;
  int rc = scp_parse_cancel(f, &id);
  if (rc != 0) {
    job_frame_failed(c, f, rc);
    return;
  }
  scd_job_t *j = find_job(c, id);
  if (!j)
    return; /* crossed the job's end on the wire: not an error */
  if (j->phase == SCD_JOB_DRAINING) {
    free_job(c, j);
    return;
  }
  fail_job(c, j, SCP_WIRE_CANCELLED, "cancelled", "cancelled by the client");
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
      sent(c, scp_enc_pong(&c->out, token));
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
    on_job_begin(c, f);
    rc = 0;
    break;
  case SCP_POINTS:
    on_points(c, f);
    rc = 0;
    break;
  case SCP_JOB_END:
    on_job_end(c, f);
    rc = 0;
    break;
  case SCP_CANCEL:
    on_cancel(c, f);
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
    reply_error(c, SCP_WIRE_UNKNOWN_TYPE, 0, f->type,
                "frame type 0x%04x is not one a client sends", f->type);
    return;
  }
  if (rc != 0 && live(c)) {
    if (scp_err_is_fatal(rc))
      protocol_fatal(c, rc, 0, f->type);
    else
      reply_error(c, scp_err_to_wire(rc), 0, f->type, "%s: %s",
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
      protocol_fatal(c, rc, 0, 0);
      break;
    }
    c->srv->n.frames_in_total++;
    handle_frame(c, &f);
  }
  flush(c);
  check_shutdown(c);
  set_reading(c, live(c) && queued(c) < c->srv->cfg.out_soft);
}

/* Shutdown. */

static int has_active_jobs(const scd_conn_t *c) {
  for (const scd_job_t *j = c->jobs; j; j = j->next)
    if (j->phase != SCD_JOB_DRAINING)
      return 1;
  return 0;
}

static void check_shutdown(scd_conn_t *c) {
  if (c->srv->shutting_down && c->state == SCD_CONN_READY &&
      !has_active_jobs(c))
    conn_fatal(c, SCP_WIRE_SHUTDOWN, 0, 0, "server shutting down");
}

void scd_conn_shutdown(scd_conn_t *c) {
  scd_server_t *srv = c->srv;
  if (c->state == SCD_CONN_HANDSHAKE) {
    conn_fatal(c, SCP_WIRE_SHUTDOWN, 0, 0, "server shutting down");
    return;
  }
  if (c->state != SCD_CONN_READY)
    return;
  scd_job_t *next;
  for (scd_job_t *j = c->jobs; j; j = next) {
    next = j->next;
    if (j->phase == SCD_JOB_DRAINING)
      continue;
    const char *msg;
    if (!srv->grace_over) {
      /* Only jobs that no worker has started end now. */
      if (!j->task || !j->task->submitted ||
          !scd_pool_withdraw(srv->pool, j->task))
        continue;
      srv->tasks_in_pool--;
      msg = "server shutting down; the job had not started";
    } else {
      msg = "server shutting down; grace period over";
    }
    if (j->phase == SCD_JOB_UPLOADING)
      fail_upload(c, j, SCP_WIRE_SHUTDOWN, "%s", msg);
    else
      fail_job(c, j, SCP_WIRE_SHUTDOWN, "failed", msg);
  }
  flush(c);
  check_shutdown(c);
}

void scd_conn_tick(scd_conn_t *c, uint64_t now) {
  const scd_config_t *cfg = &c->srv->cfg;
  switch (c->state) {
  case SCD_CONN_HANDSHAKE:
    if (now >= c->deadline_ns)
      conn_fatal(c, SCP_WIRE_TIMEOUT, 0, 0, "no HELLO within %.3g s",
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

void scd_conn_accept(scd_server_t *srv) {
  scd_conn_t *c = calloc(1, sizeof *c);
  if (!c) {
    scd_error("out of memory for a connection");
    return;
  }
  c->srv = srv;
  uv_pipe_init(srv->loop, &c->pipe, 0);
  c->pipe.data = c;
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
  int rc = uv_accept((uv_stream_t *)&srv->listener, (uv_stream_t *)&c->pipe);
  if (rc != 0) {
    scd_warn("accept: %s", uv_strerror(rc));
    scd_conn_close_now(c, "accept failed");
    return;
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
    conn_fatal(c, SCP_WIRE_BUSY, 0, 0,
               "too many connections (at most %u); try later",
               srv->cfg.max_connections);
    return;
  }
  c->counted = 1;
  srv->conns_open++;
  c->deadline_ns = c->open_ns + srv->cfg.handshake_ms * 1000000u;
  scd_info("conn %llu: accepted (%u open)", (ull)c->id, srv->conns_open);
  set_reading(c, 1);
}
