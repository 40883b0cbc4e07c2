/*
 * Jobs of a connection: their records, their ends (JOB_ERROR, refusals,
 * the closing of the connection), the one log line each writes, and what
 * a shutdown does to them.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "conn.h"
#include "daemon.h"
#include "log.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void send_job_error(scd_conn_t *c, uint32_t job_id, uint32_t code,
                           const char *msg) {
  scp_job_error_t e;
  memset(&e, 0, sizeof e);
  e.job_id = job_id;
  e.code = code;
  snprintf(e.message, sizeof e.message, "%s", msg);
  scd_conn_sent(c, scp_enc_job_error(&c->out, &e));
}

scd_job_t *scd_job_find(scd_conn_t *c, uint32_t id) {
  for (scd_job_t *j = c->jobs; j; j = j->next)
    if (j->id == id)
      return j;
  return NULL;
}

scd_job_t *scd_job_new(scd_conn_t *c, uint32_t id) {
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

void scd_job_unqueue_send(scd_conn_t *c, scd_job_t *j) {
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

void scd_job_free(scd_conn_t *c, scd_job_t *j) {
  drop_task(c, j);
  scd_job_unqueue_send(c, j);
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

const char *scd_job_phase_name(int phase) {
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
void scd_job_log(scd_conn_t *c, scd_job_t *j, const char *outcome,
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
          scd_ms_between(j->begin_ns, j->end_ns ? j->end_ns : now),
          t && t->start_ns ? scd_ms_between(t->start_ns, t->end_ns) : 0.0,
          scd_ms_between(j->done_ns, j->done_ns ? now : 0),
          scd_ms_between(j->begin_ns, now), stages);
}

/* A job that is still uploading fails: JOB_ERROR, and the id drains until
 * the client sends JOB_END or CANCEL. */
void scd_job_fail_upload(scd_conn_t *c, scd_job_t *j, uint32_t code,
                         const char *fmt, ...) {
  char msg[SCP_MESSAGE_MAX + 1];
  va_list ap;
  va_start(ap, fmt);
  scd_vformat(msg, sizeof msg, fmt, ap);
  va_end(ap);
  send_job_error(c, j->id, code, msg);
  c->srv->n.jobs_failed_total++;
  char detail[SCP_MESSAGE_MAX + 32];
  snprintf(detail, sizeof detail, "%s (%s)", scp_wire_name(code), msg);
  scd_job_log(c, j, "failed", detail);
  drop_task(c, j);
  free(j->staging);
  j->staging = NULL;
  j->phase = SCD_JOB_DRAINING;
}

/* A job ends for good with JOB_ERROR and its id is free again. */
void scd_job_fail(scd_conn_t *c, scd_job_t *j, uint32_t code,
                  const char *outcome, const char *msg) {
  send_job_error(c, j->id, code, msg);
  if (code == SCP_WIRE_CANCELLED)
    c->srv->n.jobs_cancelled_total++;
  else
    c->srv->n.jobs_failed_total++;
  char detail[SCP_MESSAGE_MAX + 32];
  snprintf(detail, sizeof detail, "%s (%s)", scp_wire_name(code), msg);
  scd_job_log(c, j, outcome, detail);
  scd_job_free(c, j);
}

/* Every job of a closing connection stops; nothing more is sent. */
void scd_conn_end_jobs(scd_conn_t *c, const char *why) {
  while (c->jobs) {
    scd_job_t *j = c->jobs;
    if (j->phase != SCD_JOB_DRAINING) {
      c->srv->n.jobs_cancelled_total++;
      scd_job_log(c, j, "cancelled", why);
    }
    scd_job_free(c, j);
  }
}

/* Refuses a JOB_BEGIN that claimed a free id: JOB_ERROR, and the id
 * drains. */
void scd_job_refuse(scd_conn_t *c, uint32_t id, uint32_t code, const char *fmt,
                    ...) {
  char msg[SCP_MESSAGE_MAX + 1];
  va_list ap;
  va_start(ap, fmt);
  scd_vformat(msg, sizeof msg, fmt, ap);
  va_end(ap);
  scd_job_t *j = scd_job_new(c, id);
  if (!j) {
    scd_conn_close_now(c, "out of memory");
    return;
  }
  j->phase = SCD_JOB_DRAINING;
  send_job_error(c, id, code, msg);
  c->srv->n.jobs_refused_total++;
  char detail[SCP_MESSAGE_MAX + 32];
  snprintf(detail, sizeof detail, "%s (%s)", scp_wire_name(code), msg);
  scd_job_log(c, j, "refused", detail);
}

/* Shutdown. */

static int has_active_jobs(const scd_conn_t *c) {
  for (const scd_job_t *j = c->jobs; j; j = j->next)
    if (j->phase != SCD_JOB_DRAINING)
      return 1;
  return 0;
}

void scd_conn_check_shutdown(scd_conn_t *c) {
  if (c->srv->shutting_down && c->state == SCD_CONN_READY &&
      !has_active_jobs(c))
    scd_conn_fatal(c, SCP_WIRE_SHUTDOWN, 0, 0, "server shutting down");
}

void scd_conn_shutdown(scd_conn_t *c) {
  scd_server_t *srv = c->srv;
  if (c->state == SCD_CONN_HANDSHAKE) {
    scd_conn_fatal(c, SCP_WIRE_SHUTDOWN, 0, 0, "server shutting down");
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
      /* Jobs still uploading end now, whether or not a worker is
       * inserting a batch of their points at this moment: their points
       * may never all come (PROTOCOL.md 8.5). Of the others, only those
       * that no worker has started end now. */
      int withdrawn = j->task && j->task->submitted &&
                      scd_pool_withdraw(srv->pool, j->task);
      if (withdrawn)
        srv->tasks_in_pool--;
      else if (j->phase != SCD_JOB_UPLOADING)
        continue;
      msg = withdrawn ? "server shutting down; the job had not started"
                      : "server shutting down; the job was still uploading";
    } else {
      msg = "server shutting down; grace period over";
    }
    if (j->phase == SCD_JOB_UPLOADING)
      scd_job_fail_upload(c, j, SCP_WIRE_SHUTDOWN, "%s", msg);
    else
      scd_job_fail(c, j, SCP_WIRE_SHUTDOWN, "failed", msg);
  }
  scd_conn_flush(c);
  scd_conn_check_shutdown(c);
}
