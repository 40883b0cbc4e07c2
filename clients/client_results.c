/*
 * Results: the frames the daemon sends, dispatched as they are decoded
 * (progress, mesh chunks, JOB_DONE, JOB_ERROR, ERROR, PONG, STATS), and
 * what the user reads of a finished job: its mesh and its values.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "client_internal.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Frames from the daemon. */

int scc_call_progress(sc_client_t *c, sc_client_job_t *j, uint32_t stage,
                      double fraction) {
  if (!j->params.progress || j->cancelled || j->user_freed)
    return 0;
  c->in_callback++;
  int stop = j->params.progress(j->params.progress_user, j, stage, fraction);
  c->in_callback--;
  if (stop)
    scc_queue_cancel(c, j);
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

/* Which of the job's arrays a chunk frame fills (SC_CLIENT_TRIANGLES,
 * SC_CLIENT_NORMALS, SC_CLIENT_VERTICES or SC_CLIENT_COMPONENTS), with the
 * elements of it that came before in *have; -1 after a protocol error. */
static int chunk_array(sc_client_t *c, sc_client_job_t *j, uint16_t type,
                       const scp_chunk_t *ch, uint64_t *have) {
  switch (type) {
  case SCP_TRIANGLES:
    *have = j->ntri;
    return SC_CLIENT_TRIANGLES;
  case SCP_NORMALS:
    *have = j->nnormals;
    if (!j->params.normals || ch->format != SCP_F64_XYZ) {
      scc_protocol_error(c, "NORMALS for job %u, which asked for %s", j->id,
                         j->params.normals ? "F64_XYZ normals" : "none");
      return -1;
    }
    if (ch->first + ch->count > j->n) {
      scc_protocol_error(c, "job %u: more normals than its %llu points", j->id,
                         (unsigned long long)j->n);
      return -1;
    }
    return SC_CLIENT_NORMALS;
  case SCP_VERTICES:
    *have = j->nvertices;
    /* The parser let only F64_XYZ through. */
    if (!j->params.smoothed_vertices) {
      scc_protocol_error(c, "VERTICES for job %u, which did not ask for them",
                         j->id);
      return -1;
    }
    if (ch->first + ch->count > j->n) {
      scc_protocol_error(c, "job %u: more vertices than its %llu points", j->id,
                         (unsigned long long)j->n);
      return -1;
    }
    return SC_CLIENT_VERTICES;
  default:
    *have = j->ncomp;
    return SC_CLIENT_COMPONENTS;
  }
}

/* Where a chunk of count elements of the array decodes to: the job's
 * buffer, grown as needed, or scratch space (also in *scratch, for the
 * caller to free) when a chunk callback takes the mesh. NULL when out of
 * memory. */
static void *chunk_dest(sc_client_job_t *j, int array, uint64_t have,
                        uint32_t count, void **scratch) {
  size_t esize = array == SC_CLIENT_TRIANGLES ? 3 * sizeof(uint32_t)
                 : array == SC_CLIENT_NORMALS || array == SC_CLIENT_VERTICES
                     ? 3 * sizeof(double)
                     : sizeof(int32_t);
  *scratch = NULL;
  if (j->params.chunk)
    return *scratch = malloc((size_t)count * esize);
  if (array == SC_CLIENT_TRIANGLES) {
    uint32_t *t = grow(j->tri, &j->tri_cap, have + count, esize);
    if (t)
      j->tri = t;
    return t ? t + 3 * have : NULL;
  }
  if (array == SC_CLIENT_NORMALS) {
    if (!j->normals)
      j->normals = malloc((size_t)j->n * esize);
    return j->normals ? j->normals + 3 * have : NULL;
  }
  if (array == SC_CLIENT_VERTICES) {
    if (!j->vertices)
      j->vertices = malloc((size_t)j->n * esize);
    return j->vertices ? j->vertices + 3 * have : NULL;
  }
  int32_t *g = grow(j->genus, &j->comp_cap, have + count, esize);
  if (g)
    j->genus = g;
  return g ? g + have : NULL;
}

/* Decodes the chunk into dst and checks its elements against the job;
 * the job's count of the array grows. -1 after a protocol error. */
static int store_chunk(sc_client_t *c, sc_client_job_t *j, int array,
                       const scp_chunk_t *ch, uint64_t have, void *dst) {
  if (array == SC_CLIENT_TRIANGLES) {
    uint32_t *t = dst;
    scp_chunk_copy_triangles(ch, t);
    for (uint64_t i = 0; i < 3 * (uint64_t)ch->count; i++) {
      if (t[i] >= j->n) {
        scc_protocol_error(c,
                           "job %u: triangle %llu has index %u, but the job "
                           "has %llu points",
                           j->id, (unsigned long long)(have + i / 3), t[i],
                           (unsigned long long)j->n);
        return -1;
      }
    }
    j->ntri += ch->count;
  } else if (array == SC_CLIENT_NORMALS) {
    scp_chunk_copy_xyz(ch, dst);
    j->nnormals += ch->count;
  } else if (array == SC_CLIENT_VERTICES) {
    scp_chunk_copy_xyz(ch, dst);
    j->nvertices += ch->count;
  } else {
    int32_t *g = dst;
    scp_chunk_copy_i32(ch, g);
    for (uint32_t i = 0; i < ch->count; i++) {
      if (g[i] < -1) {
        scc_protocol_error(c, "job %u: component genus %d", j->id, g[i]);
        return -1;
      }
    }
    j->ncomp += ch->count;
  }
  return 0;
}

/* TRIANGLES, NORMALS, VERTICES and COMPONENTS: kept in the job, or handed
 * to its chunk callback. */
static void on_chunk(sc_client_t *c, const scp_frame_t *f) {
  scp_chunk_t ch;
  int rc = scp_parse_chunk(f, &ch);
  if (rc < 0) {
    scc_protocol_error(c, "%s frame: %s", scp_type_name(f->type),
                       scp_strerror(rc));
    return;
  }
  sc_client_job_t *j = scc_find_in_use(c, ch.job_id);
  if (!j || j->server_done) {
    scc_protocol_error(c, "%s for job %u, which is not in use",
                       scp_type_name(f->type), ch.job_id);
    return;
  }
  if (j->cancelled)
    return;
  if (!j->t_first_chunk)
    j->t_first_chunk = scc_now_s();
  uint64_t have;
  int array = chunk_array(c, j, f->type, &ch, &have);
  if (array < 0)
    return;
  if (ch.first != have) {
    scc_protocol_error(c, "job %u: %s chunk starts at %llu, expected %llu",
                       j->id, scp_type_name(f->type),
                       (unsigned long long)ch.first, (unsigned long long)have);
    return;
  }
  void *scratch;
  void *dst = chunk_dest(j, array, have, ch.count, &scratch);
  if (!dst) {
    /* The stream is fine, but we cannot hold this job's mesh. */
    snprintf(j->message, sizeof j->message,
             "out of memory for the mesh after %llu triangles",
             (unsigned long long)j->ntri);
    j->local_err = SC_CLIENT_ENOMEM;
    scc_queue_cancel(c, j);
    free(scratch);
    return;
  }
  if (store_chunk(c, j, array, &ch, have, dst) != 0) {
    free(scratch);
    return;
  }
  if (j->params.chunk) {
    c->in_callback++;
    int stop = j->params.chunk(j->params.chunk_user, j, array, ch.first,
                               ch.count, scratch);
    c->in_callback--;
    free(scratch);
    if (stop) {
      scc_queue_cancel(c, j);
      return;
    }
  }
  if (array == SC_CLIENT_TRIANGLES) {
    double t = scc_now_s();
    if (t - j->last_download_report >= 0.05) {
      j->last_download_report = t;
      double est = 2.0 * (double)j->n;
      double frac = est > 0 ? (double)j->ntri / est : 1;
      scc_call_progress(c, j, SC_CLIENT_STAGE_DOWNLOAD,
                        frac > 0.99 ? 0.99 : frac);
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

/* Whether the job got the VERTICES it should have (PROTOCOL.md 6.4):
 * every point's when it asked and the daemon denoised it, none otherwise.
 * JOB_DONE does not count them, so the diagnostic "denoised" says which;
 * from a daemon that leaves it out, all or none will do. */
static int vertices_ok(const sc_client_job_t *j, const scp_values_t *values) {
  if (!j->params.smoothed_vertices)
    return j->nvertices == 0;
  scp_value_iter_t it;
  scp_value_t v;
  if (!scp_values_find(values, "denoised", &it, &v))
    return j->nvertices == 0 || j->nvertices == j->n;
  return j->nvertices == (v.kind == SCP_KIND_U64 && v.v.u == 1 ? j->n : 0);
}

static void on_job_done(sc_client_t *c, const scp_frame_t *f) {
  scp_job_done_t m;
  int rc = scp_parse_job_done(f, &m);
  if (rc < 0) {
    scc_protocol_error(c, "JOB_DONE frame: %s", scp_strerror(rc));
    return;
  }
  sc_client_job_t *j = scc_find_in_use(c, m.job_id);
  if (!j || j->server_done) {
    scc_protocol_error(c, "JOB_DONE for job %u, which is not in use", m.job_id);
    return;
  }
  if (!j->accepted) {
    scc_protocol_error(c, "JOB_DONE for job %u before ACCEPTED", m.job_id);
    return;
  }
  if (!j->client_done) {
    scc_protocol_error(c, "JOB_DONE for job %u before all its points came",
                       m.job_id);
    return;
  }
  j->server_done = 1;
  scc_update_in_use(c, j);
  if (j->cancelled) {
    /* The result crossed our CANCEL; what came of it was not kept. */
    scc_drop_mesh(j);
    if (!j->local_err)
      snprintf(j->message, sizeof j->message, "cancelled");
    scc_settle(c, j, j->local_err ? j->local_err : SC_CLIENT_ECANCELLED);
    return;
  }
  uint64_t want_normals = j->params.normals ? j->n : 0;
  if (m.triangles != j->ntri || m.normals != j->nnormals ||
      m.components != j->ncomp || j->nnormals != want_normals) {
    scc_protocol_error(
        c,
        "JOB_DONE for job %u counts %llu triangles, %llu normals "
        "and %llu components; %llu, %llu and %llu came",
        j->id, (unsigned long long)m.triangles, (unsigned long long)m.normals,
        (unsigned long long)m.components, (unsigned long long)j->ntri,
        (unsigned long long)j->nnormals, (unsigned long long)j->ncomp);
    return;
  }
  if (!vertices_ok(j, &m.values)) {
    scc_protocol_error(c,
                       "job %u ended with %llu smoothed vertices for its "
                       "%llu points",
                       j->id, (unsigned long long)j->nvertices,
                       (unsigned long long)j->n);
    return;
  }
  copy_values(&m.values, &j->values, &j->nvalues);
  scc_call_progress(c, j, SC_CLIENT_STAGE_DOWNLOAD, 1.0);
  scc_settle(c, j, 0);
}

static void on_job_error(sc_client_t *c, const scp_frame_t *f) {
  scp_job_error_t m;
  int rc = scp_parse_job_error(f, &m);
  if (rc < 0) {
    scc_protocol_error(c, "JOB_ERROR frame: %s", scp_strerror(rc));
    return;
  }
  sc_client_job_t *j = scc_find_in_use(c, m.job_id);
  if (!j || j->server_done) {
    scc_protocol_error(c, "JOB_ERROR for job %u, which is not in use",
                       m.job_id);
    return;
  }
  j->server_done = 1;
  scc_update_in_use(c, j);
  scc_drop_mesh(j);
  if (j->local_err) {
    scc_settle(c, j, j->local_err);
    return;
  }
  if (m.code == SCP_WIRE_SHUTDOWN && scc_may_retry(j, SC_CLIENT_ESHUTDOWN)) {
    /* The daemon is going away: the job runs again elsewhere once this
     * connection is gone. The daemon closes it when its last job is over
     * (PROTOCOL.md 8.5); with none left here, there is nothing to wait
     * for. */
    j->server_code = m.code;
    j->resubmit = 1;
    if (c->in_use == 0)
      scc_conn_die(c, SC_CLIENT_ESHUTDOWN, "the daemon is shutting down: %s",
                   m.message);
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
  scc_settle(c, j, code);
}

void scc_on_error(sc_client_t *c, const scp_frame_t *f) {
  scp_error_t e;
  int rc = scp_parse_error(f, &e);
  if (rc < 0) {
    scc_protocol_error(c, "ERROR frame: %s", scp_strerror(rc));
    return;
  }
  if (e.flags & SCP_ERROR_FATAL) {
    int code = e.code == SCP_WIRE_VERSION    ? SC_CLIENT_EVERSION
               : e.code == SCP_WIRE_SHUTDOWN ? SC_CLIENT_ESHUTDOWN
               : e.code == SCP_WIRE_TIMEOUT  ? SC_CLIENT_ETIMEOUT
               : e.code == SCP_WIRE_AUTH     ? SC_CLIENT_EAUTH
                                             : SC_CLIENT_ELOST;
    scc_conn_die(c, code, "the daemon closed the connection: %s: %s",
                 scp_wire_name(e.code), e.message);
    return;
  }
  /* The daemon rejected one of our frames. That should not happen; when
   * it names a job, stop the job rather than wait for it forever. */
  snprintf(c->last, sizeof c->last, "the daemon rejected a %s frame: %s: %s",
           e.ref_type ? scp_type_name(e.ref_type) : "", scp_wire_name(e.code),
           e.message);
  sc_client_job_t *j = e.job_id ? scc_find_in_use(c, e.job_id) : NULL;
  if (j && !j->cancelled && j->status == SC_CLIENT_PENDING) {
    snprintf(j->message, sizeof j->message, "%s", c->last);
    j->local_err = SC_CLIENT_EPROTOCOL;
    scc_queue_cancel(c, j);
  }
}

void scc_dispatch(sc_client_t *c, const scp_frame_t *f) {
  int rc;
  switch (f->type) {
  case SCP_ERROR:
    scc_on_error(c, f);
    return;
  case SCP_PING: {
    uint64_t token;
    if ((rc = scp_parse_ping(f, &token)) < 0)
      break;
    if (scp_enc_pong(&c->out, token) < 0)
      scc_conn_die(c, SC_CLIENT_ENOMEM, "out of memory for a PONG");
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
    sc_client_job_t *j = scc_find_in_use(c, a.job_id);
    if (!j || j->server_done || j->accepted) {
      scc_protocol_error(c, "ACCEPTED for job %u, which is not waiting for it",
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
    sc_client_job_t *j = scc_find_in_use(c, p.job_id);
    if (!j || j->server_done) {
      scc_protocol_error(c, "PROGRESS for job %u, which is not in use",
                         p.job_id);
      return;
    }
    scc_call_progress(c, j, p.stage, p.fraction);
    return;
  }
  case SCP_TRIANGLES:
  case SCP_NORMALS:
  case SCP_VERTICES:
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
        scc_conn_die(c, SC_CLIENT_ENOMEM, "out of memory for an ERROR");
    }
    return;
  }
  scc_protocol_error(c, "%s frame: %s", scp_type_name(f->type),
                     scp_strerror(rc));
}

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

/* What the user reads of a job. */

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
  out->vertices = job->vertices;
  out->vertex_count = job->nvertices;
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
