/*
 * The frames of a job from the client: JOB_BEGIN, POINTS, JOB_END and
 * CANCEL (PROTOCOL.md 6.3 to 6.6, 7). A JOB_BEGIN is checked against every
 * limit before its task is made; points are gathered into batches and
 * handed to the pool as they come.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "conn.h"
#include "daemon.h"
#include "log.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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
/* The row of the core's parameter table that job option name sets, or
 * NULL; *k is its number. */
static const sc_param_info_t *option_row(const char *name, size_t *k) {
  size_t n;
  const sc_param_info_t *rows = sc_param_table(&n);
  for (*k = 0; *k < n; ++*k)
    if (rows[*k].wire == SC_PARAM_OPTION && strcmp(rows[*k].name, name) == 0)
      return &rows[*k];
  return NULL;
}

/* The job options of a JOB_BEGIN (PROTOCOL.md 6.3), applied to *p through
 * the core's parameter table: 0, or the wire code to refuse the job with,
 * and the reason in why. */
static uint32_t apply_options(const scp_values_t *options, sc_params_t *p,
                              char *why, size_t len) {
  uint64_t seen = 0;
  scp_value_iter_t it;
  scp_value_t v;
  scp_values_begin(options, &it);
  while (scp_values_next(&it, &v)) {
    size_t k;
    const sc_param_info_t *row = option_row(v.name, &k);
    if (!row) {
      snprintf(why, len, "job option %s is not supported by this server",
               v.name);
      return SCP_WIRE_UNSUPPORTED;
    }
    if (seen & (1ull << k))
      continue; /* a name given twice takes its first value */
    seen |= 1ull << k;
    int real = row->kind == SC_PARAM_REAL || row->kind == SC_PARAM_ANGLE;
    if (v.kind != (real ? SCP_KIND_F64 : SCP_KIND_U64)) {
      snprintf(why, len, "job option %s must be %s", v.name,
               real ? "a number (f64)" : "an unsigned integer (u64)");
      return SCP_WIRE_INVALID;
    }
    /* On the wire an option is sent only to be used: 0 does not stand for
     * the default there, as it does in the core's struct. */
    double num = real ? v.v.f : (double)v.v.u;
    if (!SC_IN_RANGE(num, row->lo, row->hi,
                     row->range & ~SC_RANGE_ZERO_DEFAULT)) {
      if (real)
        snprintf(why, len, "job option %s out of range: %g", v.name, v.v.f);
      else
        snprintf(why, len, "job option %s out of range: %llu", v.name,
                 (ull)v.v.u);
      return SCP_WIRE_INVALID;
    }
    void *field = (char *)p + row->offset;
    if (real)
      *(double *)field = v.v.f;
    else
      *(int *)field = (int)v.v.u;
  }
  /* Whatever the ranges above let through, the core must take too. */
  if (sc_params_check(p, why, len) != SC_OK)
    return SCP_WIRE_INVALID;
  return 0;
}

/* Whether this server takes the job that JOB_BEGIN m describes, and the
 * job's parameters in *params: 0, or the wire code to refuse it with and
 * the reason in why. */
static uint32_t check_job(const scd_server_t *srv, const scp_job_begin_t *m,
                          sc_params_t *params, char *why, size_t len) {
  if (srv->shutting_down) {
    snprintf(why, len, "server shutting down");
    return SCP_WIRE_SHUTDOWN;
  }
  /* The protocol numbers modes like the core; a mode the core was built
   * without is refused. */
  if (m->mode >= (uint32_t)SC_MODE_COUNT_) {
    snprintf(why, len, "mode %s is not supported by this server",
             scp_mode_name(m->mode));
    return SCP_WIRE_UNSUPPORTED;
  }
  sc_params_init(params);
  params->mode = (sc_mode_t)m->mode;
  params->r = m->r;
  if (m->theta != 0)
    params->cocone_theta = m->theta;
  params->threads = 1;
  uint32_t refused = apply_options(&m->options, params, why, len);
  if (refused)
    return refused;
  if (m->point_count > srv->max_points) {
    snprintf(why, len,
             "job of %llu points; this server takes at most %llu per job",
             (ull)m->point_count, (ull)srv->max_points);
    return SCP_WIRE_LIMIT;
  }
  return 0;
}

/* Makes the task of a job the server takes, reserves its memory and hands
 * it to the pool: ACCEPTED, or JOB_ERROR when the memory is not there. */
static void start_job(scd_conn_t *c, uint32_t id, const scp_job_begin_t *m,
                      const sc_params_t *params) {
  scd_server_t *srv = c->srv;
  scd_task_t *t = scd_task_new();
  if (!t) {
    scd_job_refuse(c, id, SCP_WIRE_NO_MEMORY, "out of memory");
    return;
  }
  srv->tasks_live++;
  uint64_t need = sc_estimate_bytes(m->point_count);
  if (scd_budget_reserve(srv, t, need) != 0) {
    char a[32], b[32], d[32];
    fmt_bytes(a, sizeof a, need);
    fmt_bytes(b, sizeof b, budget_left(srv));
    fmt_bytes(d, sizeof d, srv->cfg.memory_budget);
    scd_server_free_task(srv, t);
    scd_job_refuse(c, id, SCP_WIRE_BUSY,
                   "memory budget: the job needs about %s, %s of %s free; "
                   "try later",
                   a, b, d);
    return;
  }
  scd_job_t *j = scd_job_new(c, id);
  if (!j) {
    scd_server_free_task(srv, t);
    scd_conn_close_now(c, "out of memory");
    return;
  }
  t->params = *params;
  t->declared = m->point_count;
  t->owner = j;
  j->task = t;
  j->phase = SCD_JOB_UPLOADING;
  j->declared = m->point_count;
  j->flags = m->flags;
  scd_pool_stats_t ps;
  scd_pool_get_stats(srv->pool, &ps);
  scd_pool_submit(srv->pool, t);
  srv->tasks_in_pool++;
  srv->n.jobs_accepted_total++;
  scp_accepted_t a = {.job_id = id,
                      .queue_position = ps.busy + ps.lent < ps.workers
                                            ? 0
                                            : (uint32_t)ps.queued + 1};
  scd_conn_sent(c, scp_enc_accepted(&c->out, &a));
  scd_debug("job %llu:%u accepted: mode %s, %llu points announced, %u job "
            "options",
            (ull)c->id, id, scp_mode_name(m->mode), (ull)m->point_count,
            m->options.count);
}

/* JOB_BEGIN, PROTOCOL.md 7.3; each check is made once, and their order
 * decides the reply. A frame that cannot be trusted costs the connection,
 * one that names no id is answered with ERROR INVALID, an id in use with
 * ERROR DUPLICATE_JOB, and an id beyond max_jobs with a fatal LIMIT. From
 * then on the id is claimed: a refusal, of an invalid frame or of a job
 * this server does not take, is a JOB_ERROR after which the id drains. */
void scd_on_job_begin(scd_conn_t *c, const scp_frame_t *f) {
  scd_server_t *srv = c->srv;
  scp_job_begin_t m;
  memset(&m, 0, sizeof m);
  /* Options are only for connections that agreed on them. */
  int rc = scp_parse_job_begin_features(f, c->features, &m);
  if (rc != 0 && scp_err_is_fatal(rc)) {
    scd_conn_protocol_fatal(c, rc, 0, f->type);
    return;
  }
  uint32_t id = m.job_id;
  if (rc != 0 && (!scp_frame_job_id(f, &id) || id == 0)) {
    scd_conn_reply_error(c, SCP_WIRE_INVALID, 0, f->type, "JOB_BEGIN: %s",
                         scp_strerror(rc));
    return;
  }
  if (scd_job_find(c, id)) {
    scd_conn_reply_error(c, SCP_WIRE_DUPLICATE_JOB, id, f->type,
                         "job %u is in use", id);
    return;
  }
  if (c->njobs >= srv->cfg.max_jobs) {
    /* A fatal ERROR ends every job, so it names none (PROTOCOL.md 6.1). */
    scd_conn_fatal(c, SCP_WIRE_LIMIT, 0, f->type,
                   "more than %u jobs in use on one connection",
                   srv->cfg.max_jobs);
    return;
  }
  if (rc != 0) {
    scd_job_refuse(c, id, scp_err_to_wire(rc), "JOB_BEGIN: %s",
                   scp_strerror(rc));
    return;
  }
  sc_params_t params;
  char why[SCP_MESSAGE_MAX + 1];
  uint32_t refused = check_job(srv, &m, &params, why, sizeof why);
  if (refused) {
    scd_job_refuse(c, id, refused, "%s", why);
    return;
  }
  start_job(c, id, &m, &params);
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
    scd_conn_reply_error(c, SCP_WIRE_INVALID, 0, f->type, "%s: %s",
                         scp_type_name(f->type), scp_strerror(rc));
    return;
  }
  scd_job_t *j = scd_job_find(c, id);
  if (!j) {
    if (f->type != SCP_CANCEL)
      scd_conn_reply_error(c, SCP_WIRE_UNKNOWN_JOB, id, f->type, "no job %u",
                           id);
    return;
  }
  char msg[SCP_MESSAGE_MAX + 1];
  snprintf(msg, sizeof msg, "%s: %s", scp_type_name(f->type),
           scp_strerror(rc));
  switch (j->phase) {
  case SCD_JOB_UPLOADING:
    if (f->type == SCP_POINTS) {
      scd_job_fail_upload(c, j, scp_err_to_wire(rc), "%s", msg);
    } else {
      /* JOB_END or CANCEL: the client will send nothing more for it. */
      scd_job_fail(c, j, scp_err_to_wire(rc), "failed", msg);
    }
    break;
  case SCD_JOB_DRAINING:
    if (f->type != SCP_POINTS)
      scd_job_free(c, j);
    break;
  default:
    scd_conn_reply_error(c, SCP_WIRE_STATE, id, f->type, "job %u is %s", id,
                         scd_job_phase_name(j->phase));
  }
}

/* A job frame's payload did not parse: a fatal error closes the
 * connection, any other is answered for the job the frame names. */
static void job_frame_failed(scd_conn_t *c, const scp_frame_t *f, int rc) {
  if (scp_err_is_fatal(rc))
    scd_conn_protocol_fatal(c, rc, 0, f->type);
  else
    bad_job_frame(c, f, rc);
}

/* The connection's job `id`, or NULL after answering UNKNOWN_JOB. */
static scd_job_t *known_job(scd_conn_t *c, const scp_frame_t *f,
                            uint32_t id) {
  scd_job_t *j = scd_job_find(c, id);
  if (!j)
    scd_conn_reply_error(c, SCP_WIRE_UNKNOWN_JOB, id, f->type, "no job %u", id);
  return j;
}

void scd_on_points(scd_conn_t *c, const scp_frame_t *f) {
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
    scd_conn_reply_error(c, SCP_WIRE_STATE, ch.job_id, f->type,
                         "job %u is %s: its points have all come", ch.job_id,
                         scd_job_phase_name(j->phase));
    return;
  }
  if (ch.first != j->received) {
    scd_job_fail_upload(c, j, SCP_WIRE_INVALID,
                        "POINTS chunk starts at point %llu, expected %llu",
                        (ull)ch.first, (ull)j->received);
    return;
  }
  /* Past an announced count the client broke its own word (INVALID);
   * only a job that announced none can reach max_points (LIMIT), since
   * the count was checked against it (PROTOCOL.md 7.3). */
  uint64_t total = j->received + ch.count;
  if (j->declared && total > j->declared) {
    scd_job_fail_upload(c, j, SCP_WIRE_INVALID,
                        "more points than the %llu JOB_BEGIN announced",
                        (ull)j->declared);
    return;
  }
  if (total > srv->max_points) {
    scd_job_fail_upload(
        c, j, SCP_WIRE_LIMIT,
        "more than %llu points; this server takes at most %llu per "
        "job",
        (ull)(total - 1), (ull)srv->max_points);
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
      scd_job_fail_upload(
          c, j, SCP_WIRE_NO_MEMORY,
          "memory budget exhausted at %llu points: the job would "
          "need about %s; %s of the %s budget is left for it",
          (ull)total, a, left, b);
      return;
    }
  }
  if (take_points(c, j, &ch) != 0) {
    scd_job_fail_upload(c, j, SCP_WIRE_NO_MEMORY, "out of memory");
    return;
  }
  j->received = total;
  srv->n.points_in_total += ch.count;
}

void scd_on_job_end(scd_conn_t *c, const scp_frame_t *f) {
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
    scd_job_free(c, j);
    return;
  }
  if (j->phase != SCD_JOB_UPLOADING) {
    scd_conn_reply_error(c, SCP_WIRE_STATE, m.job_id, f->type, "job %u is %s",
                         m.job_id, scd_job_phase_name(j->phase));
    return;
  }
  if (m.point_count != j->received ||
      (j->declared && j->declared != j->received)) {
    char msg[200];
    snprintf(msg, sizeof msg,
             "JOB_END says %llu points, %llu arrived (JOB_BEGIN announced "
             "%llu)",
             (ull)m.point_count, (ull)j->received, (ull)j->declared);
    scd_job_fail(c, j, SCP_WIRE_INVALID, "failed", msg);
    return;
  }
  hand_over(c, j);
  scd_pool_end_input(c->srv->pool, j->task);
  j->phase = SCD_JOB_WORKING;
  j->end_ns = uv_hrtime();
}

void scd_on_cancel(scd_conn_t *c, const scp_frame_t *f) {
  uint32_t id;
  int rc = scp_parse_cancel(f, &id);
  if (rc != 0) {
    job_frame_failed(c, f, rc);
    return;
  }
  scd_job_t *j = scd_job_find(c, id);
  if (!j)
    return; /* crossed the job's end on the wire: not an error */
  if (j->phase == SCD_JOB_DRAINING) {
    scd_job_free(c, j);
    return;
  }
  scd_job_fail(c, j, SCP_WIRE_CANCELLED, "cancelled",
               "cancelled by the client");
}
