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
      F("seconds.upload", scd_ms_between(j->begin_ns, j->end_ns) / 1e3),
      F("seconds.server", scd_ms_between(j->begin_ns, uv_hrtime()) / 1e3),
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
  scd_conn_sent(c, scp_enc_job_done(&c->out, &done, v,
                                    (uint32_t)(sizeof v / sizeof v[0])));
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
