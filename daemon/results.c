/*
 * Results: what comes back from the pool goes out to the client.
 * Progress is sent while there is room for it; a finished mesh goes out
 * as chunks, one job after the other in turn, then JOB_DONE with the
 * mesh's values; a failure is a JOB_ERROR.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "conn.h"
#include "daemon.h"
#include "log.h"

#include <stdio.h>
#include <string.h>

/* Sending meshes. */

static uint64_t mesh_bytes(const sc_mesh_t *m) {
  uint64_t xyz = m->point_count * 3 * sizeof(double);
  return sizeof *m + m->triangle_count * 3 * sizeof(uint32_t) + xyz +
         (m->smoothed ? xyz : 0) + m->component_count * sizeof(int32_t);
}

/* The diagnostics of the core's table, as JOB_DONE values (PROTOCOL.md
 * 6.12) in the table's order; the arrays' element names go into names. */
#define SCD_DONE_NAME_MAX 40
static uint32_t diag_values(const sc_diag_t *d, scp_value_t *v, uint32_t cap,
                            char (*names)[SCD_DONE_NAME_MAX]) {
  size_t nrows;
  const sc_diag_info_t *rows = sc_diag_table(&nrows);
  uint32_t n = 0;
  for (size_t r = 0; r < nrows; ++r) {
    const char *field = (const char *)d + rows[r].offset;
    for (size_t i = 0; i < rows[r].count && n < cap; ++i, ++n) {
      const char *suffix = sc_diag_element_name(&rows[r], i);
      v[n].name = rows[r].wire;
      if (suffix) {
        snprintf(names[n], SCD_DONE_NAME_MAX, "%s.%s", rows[r].wire, suffix);
        v[n].name = names[n];
      }
      switch (rows[r].kind) {
      case SC_DIAG_COUNT:
      case SC_DIAG_LOOPS:
        v[n].kind = SCP_KIND_U64;
        v[n].v.u = ((const uint64_t *)field)[i];
        break;
      case SC_DIAG_BOOL:
        v[n].kind = SCP_KIND_U64;
        v[n].v.u = *(const int *)field ? 1 : 0;
        break;
      case SC_DIAG_PATH:
        v[n].kind = SCP_KIND_U64;
        v[n].v.u = (uint64_t)*(const int *)field;
        break;
      case SC_DIAG_INT:
        v[n].kind = SCP_KIND_I64;
        v[n].v.i = *(const int64_t *)field;
        break;
      case SC_DIAG_REAL:
      case SC_DIAG_SECONDS:
      case SC_DIAG_STAGE_SECONDS:
        v[n].kind = SCP_KIND_F64;
        v[n].v.f = ((const double *)field)[i];
        break;
      }
    }
  }
  return n;
}

static void send_job_done(scd_conn_t *c, scd_job_t *j) {
  enum { CAP = 96 };
  scp_value_t v[CAP];
  char names[CAP][SCD_DONE_NAME_MAX];
  uint32_t n = diag_values(&j->task->mesh->diag, v, CAP - 2, names);
  /* The server's own, about the job rather than the reconstruction. */
  v[n++] = (scp_value_t){
      .name = "seconds.upload",
      .kind = SCP_KIND_F64,
      .v.f = scd_ms_between(j->begin_ns, j->end_ns) / 1e3};
  v[n++] = (scp_value_t){
      .name = "seconds.server",
      .kind = SCP_KIND_F64,
      .v.f = scd_ms_between(j->begin_ns, uv_hrtime()) / 1e3};
  scp_job_done_t done;
  memset(&done, 0, sizeof done);
  done.job_id = j->id;
  done.triangles = j->cursor.triangles;
  done.normals = j->cursor.normals;
  done.components = j->cursor.components;
  scd_conn_sent(c, scp_enc_job_done(&c->out, &done, v, n));
}

/* Emits mesh chunks, one job after the other in turn, while the output
 * queue has room. */
void scd_conn_pump(scd_conn_t *c) {
  while (c->state == SCD_CONN_READY && c->shead &&
         scd_conn_queued(c) < c->srv->cfg.out_soft) {
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
    /* The core keeps the smoothed positions only when the job asked for
     * them (the smoothed_vertices option) and was denoised: exactly when
     * PROTOCOL.md 6.4 sends VERTICES. */
    if (m->smoothed) {
      view.vertices = m->smoothed;
      view.vertex_count = m->point_count;
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
    scd_job_unqueue_send(c, j);
    if (rc == 0) {
      send_job_done(c, j);
      c->srv->n.jobs_done_total++;
      c->srv->n.triangles_out_total += m->triangle_count;
      scd_job_log(c, j, "done", NULL);
      scd_job_free(c, j);
    } else {
      char msg[128];
      snprintf(msg, sizeof msg, "cannot encode the mesh: %s",
               scp_strerror(rc));
      scd_job_fail(c, j, SCP_WIRE_INTERNAL, "failed", msg);
    }
  }
  scd_conn_check_shutdown(c);
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
    if (c->state != SCD_CONN_READY || scd_conn_queued(c) >= srv->cfg.out_soft ||
        stage >= SCP_STAGE_COUNT)
      return;
    scp_progress_t p = {.job_id = j->id, .stage = stage, .fraction = fraction};
    if (scd_conn_sent(c, scp_enc_progress(&c->out, &p)) == 0)
      scd_conn_flush(c);
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
    scd_conn_pump(c);
  } else {
    uint32_t code = wire_code(t->rc);
    char msg[SCP_MESSAGE_MAX + 1];
    snprintf(msg, sizeof msg, "%s", t->msg[0] ? t->msg : sc_strerror(t->rc));
    if (j->phase == SCD_JOB_UPLOADING)
      scd_job_fail_upload(c, j, code, "%s", msg);
    else
      scd_job_fail(c, j, code, "failed", msg);
    scd_conn_check_shutdown(c);
  }
  scd_conn_flush(c);
}
