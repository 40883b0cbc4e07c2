/*
 * Jobs: checking the parameters, submitting (JOB_BEGIN, the points,
 * JOB_END), waiting, cancelling, and the records of jobs, whose ids
 * are in use until both sides are done with them.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "client_internal.h"
#include "shortcrust_files.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

sc_client_job_t *scc_find_in_use(sc_client_t *c, uint32_t id) {
  for (sc_client_job_t *j = c->jobs; j; j = j->next)
    if (j->in_use && j->id == id)
      return j;
  return NULL;
}

void scc_job_destroy(sc_client_job_t *j) {
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
  free(j->vertices);
  free(j->genus);
  free(j->values);
  free(j);
}

void scc_unqueue_end(sc_client_t *c, sc_client_job_t *j) {
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
void scc_reap(sc_client_t *c) {
  if (c->in_callback)
    return;
  sc_client_job_t *j = c->jobs;
  while (j) {
    sc_client_job_t *next = j->next;
    if (j->user_freed && !j->in_use)
      scc_job_destroy(j);
    j = next;
  }
}

void scc_update_in_use(sc_client_t *c, sc_client_job_t *j) {
  if (j->in_use && j->client_done && j->server_done) {
    j->in_use = 0;
    c->in_use--;
  }
}

/* The job's end as the user sees it: its status is settled and it joins
 * the queue of sc_client_wait_any(). */
void scc_settle(sc_client_t *c, sc_client_job_t *j, int status) {
  if (j->status != SC_CLIENT_PENDING)
    return;
  j->status = status;
  j->t_end = scc_now_s();
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
void scc_drop_mesh(sc_client_job_t *j) {
  free(j->tri);
  free(j->normals);
  free(j->vertices);
  free(j->genus);
  j->tri = NULL;
  j->normals = NULL;
  j->vertices = NULL;
  j->genus = NULL;
  j->tri_cap = j->comp_cap = 0;
}

/* A CANCEL for the job, unless one went out already or its id is free.
 * It may follow JOB_END (the daemon then stops the work) and JOB_ERROR
 * (the id drains on the daemon until JOB_END or CANCEL comes). */
void scc_queue_cancel(sc_client_t *c, sc_client_job_t *j) {
  if (j->cancelled || c->err)
    return;
  j->cancelled = 1;
  if (!j->in_use)
    return;
  if (scp_enc_cancel(&c->out, j->id) == 0) {
    j->client_done = 1;
    scc_update_in_use(c, j);
  }
}

static uint32_t free_id(sc_client_t *c) {
  for (;;) {
    uint32_t id = c->next_id++;
    if (c->next_id == 0)
      c->next_id = 1;
    if (id != 0 && !scc_find_in_use(c, id))
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
  j->t_submit = scc_now_s();
  j->next = c->jobs;
  if (c->jobs)
    c->jobs->prev = j;
  c->jobs = j;
  return j;
}

/* Whether every coordinate is exactly a float: the points then travel as
 * F32_XYZ, half the bytes, and the daemon gets the very same doubles
 * back. (A non-finite coordinate is not, and goes as F64 for the daemon to
 * refuse.) */
static int scc_float_exact(const double *xyz, uint64_t n) {
  for (uint64_t i = 0; i < 3 * n; i++) {
    /* Beyond the floats' range (or NaN) a conversion is undefined. */
    if (!(fabs(xyz[i]) <= FLT_MAX) || (double)(float)xyz[i] != xyz[i])
      return 0;
  }
  return 1;
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
    scc_settle(c, j, SC_CLIENT_EREFUSED);
    return 0;
  }
  const sc_client_params_t *p = &j->params;
  scp_value_t opts[SCC_MAX_OPTIONS];
  const uint32_t nopts = scc_job_options(p, opts, SCC_MAX_OPTIONS);
  if (nopts && !(c->welcome.features & SCP_FEATURE_JOB_OPTIONS)) {
    snprintf(j->message, sizeof j->message,
             "UNSUPPORTED: the daemon does not take job options (%s); "
             "leave them at their defaults or update the daemon",
             opts[0].name);
    j->server_code = SCP_WIRE_UNSUPPORTED;
    j->client_done = j->server_done = 1;
    scc_settle(c, j, SC_CLIENT_EREFUSED);
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
    return scc_fail(c, SC_CLIENT_ENOMEM, "out of memory");
  j->in_use = j->begun = 1;
  c->in_use++;
  uint64_t next = 0;
  int rc = 0;
  const uint32_t format =
      scc_float_exact(xyz, j->n) ? SCP_F32_XYZ : SCP_F64_XYZ;
  while (next < j->n && !j->server_done && !j->cancelled) {
    rc = scp_enc_points_next(&c->out, j->id, format, xyz, j->n, &next);
    if (rc < 0) {
      rc = scc_fail(c, SC_CLIENT_ENOMEM, "out of memory");
      break;
    }
    rc = scc_flush_out(c);
    if (rc < 0)
      break;
    scc_call_progress(c, j, SC_CLIENT_STAGE_UPLOAD,
                      (double)next / (double)j->n);
  }
  if (c->err)
    return 0; /* the job ended with the connection */
  if (rc < 0) {
    /* Out of memory with a JOB_BEGIN out: give the id back. */
    scc_queue_cancel(c, j);
  } else if (!j->client_done) {
    /* A CANCEL went out already when a callback cancelled the job. */
    if (j->server_done) {
      /* Refused or failed during the upload: the id drains on the daemon
       * until this CANCEL. */
      scc_queue_cancel(c, j);
    } else {
      scp_job_end_t e = {.job_id = j->id, .point_count = j->n};
      if (scp_enc_job_end(&c->out, &e) < 0)
        return scc_fail(c, SC_CLIENT_ENOMEM, "out of memory");
      j->client_done = 1;
      scc_update_in_use(c, j);
    }
  }
  j->t_uploaded = scc_now_s();
  int frc = scc_flush_out(c);
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
  int rc = scc_check_params(c, params);
  if (rc < 0)
    return rc;
  if (!xyz && n)
    return scc_fail(c, SC_CLIENT_EINVAL, "no points");
  if (c->in_use >= c->welcome.max_jobs)
    return scc_fail(
        c, SC_CLIENT_ELIMIT,
        "%u jobs are in use on this connection, the most the daemon "
        "allows; wait for one to end",
        c->in_use);
  sc_client_job_t *j = job_new(c, params, n);
  if (!j)
    return scc_fail(c, SC_CLIENT_ENOMEM, "out of memory");
  j->own_xyz = own;
  j->xyz = xyz;
  j->id = free_id(c);
  rc = upload(c, j, xyz);
  /* Lost during its upload: with retries, the job goes on elsewhere. */
  if (rc == 0 && c->err && j->resubmit)
    scc_recover(c);
  if (rc == 0 && c->err)
    rc = scc_fail(c, c->err, "%s", c->errmsg);
  if (rc < 0) {
    /* Nothing of the job is the user's: it is reaped once its id is free. */
    j->own_xyz = NULL;
    j->user_freed = 1;
    scc_unqueue_end(c, j);
    scc_reap(c);
    return rc;
  }
  *job = j;
  scc_reap(c);
  return 0;
}

int sc_client_submit(sc_client_t *c, const sc_client_params_t *params,
                     const double *xyz, uint64_t n, sc_client_job_t **job) {
  if (job)
    *job = NULL;
  if (!c || !job)
    return SC_CLIENT_EINVAL;
  int rc = scc_usable(c);
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
  int rc = scc_usable(c);
  if (rc < 0)
    return rc;
  scf_points_t pts;
  char msg[SCC_MSG_MAX];
  rc = scf_points_read(path, &pts, msg, sizeof msg);
  if (rc < 0)
    return scc_fail(c,
                    rc == SCF_ENOMEM ? SC_CLIENT_ENOMEM : SC_CLIENT_EFILE,
                    "%s", msg);
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
    return scc_fail(c, SC_CLIENT_ESTATE,
                    "a callback may not call the library on its own handle");
  int rc = 0;
  double deadline = scc_deadline_after(timeout_ms);
  while (job->status == SC_CLIENT_PENDING) {
    rc = scc_run_io(c, cond_job_ended, job, deadline);
    /* The connection is gone and the job waits for a retry. */
    if (job->status != SC_CLIENT_PENDING || !c->err || !job->resubmit ||
        scc_recover(c) != 0)
      break;
  }
  scc_reap(c);
  if (job->status == SC_CLIENT_PENDING)
    return scc_fail(c, rc < 0 ? rc : SC_CLIENT_ETIMEOUT,
                    "job %u still under way after %d ms", job->id, timeout_ms);
  scc_unqueue_end(c, job);
  if (job->status < 0)
    snprintf(c->last, sizeof c->last, "%s", job->message);
  return job->status;
}

static int cond_any_ended(sc_client_t *c, void *arg) {
  return c->ehead != NULL || (c->in_use == 0 && !scc_waiting(c));
}

int sc_client_wait_any(sc_client_t *c, int timeout_ms, sc_client_job_t **job) {
  if (job)
    *job = NULL;
  if (!c || !job)
    return SC_CLIENT_EINVAL;
  if (c->in_callback)
    return scc_fail(c, SC_CLIENT_ESTATE,
                    "a callback may not call the library on its own handle");
  if (!c->ehead && c->in_use == 0 && !scc_waiting(c))
    return scc_fail(c, SC_CLIENT_ESTATE, "no job under way");
  double deadline = scc_deadline_after(timeout_ms);
  int rc;
  for (;;) {
    rc = scc_run_io(c, cond_any_ended, NULL, deadline);
    /* The connection is gone and jobs wait for a retry. */
    if (c->ehead || !c->err || !scc_waiting(c) || scc_recover(c) != 0)
      break;
  }
  scc_reap(c);
  sc_client_job_t *j = c->ehead;
  if (!j) {
    if (rc == 0)
      return scc_fail(c, SC_CLIENT_ESTATE, "no job under way");
    return scc_fail(c, rc, "no job ended within %d ms", timeout_ms);
  }
  scc_unqueue_end(c, j);
  *job = j;
  if (j->status < 0)
    snprintf(c->last, sizeof c->last, "%s", j->message);
  return j->status;
}

int sc_client_cancel(sc_client_t *c, sc_client_job_t *job) {
  if (!c || !job || job->c != c)
    return SC_CLIENT_EINVAL;
  if (c->in_callback)
    return scc_fail(c, SC_CLIENT_ESTATE,
                    "a callback may not call the library on its own handle; "
                    "return non-zero from it to cancel");
  if (job->resubmit) {
    /* Waiting for a retry: it simply does not run again. */
    job->resubmit = 0;
    job->cancelled = 1;
    snprintf(job->message, sizeof job->message, "cancelled");
    scc_settle(c, job, SC_CLIENT_ECANCELLED);
    return 0;
  }
  if (job->status != SC_CLIENT_PENDING || c->err)
    return 0;
  scc_queue_cancel(c, job);
  scc_flush_out(c);
  scc_reap(c);
  return 0;
}

void scc_resubmit(sc_client_t *c, sc_client_job_t *j) {
  j->resubmit = 0;
  j->in_use = j->begun = j->client_done = j->server_done = 0;
  /* A CANCEL that went out for it was ours, to free its id on a daemon
   * that was shutting down; the user's own cancel ends a waiting job. */
  j->cancelled = 0;
  j->accepted = 0;
  j->server_code = 0;
  j->message[0] = '\0';
  scc_drop_mesh(j);
  j->ntri = j->nnormals = j->nvertices = j->ncomp = 0;
  free(j->values);
  j->values = NULL;
  j->nvalues = 0;
  j->t_first_chunk = j->last_download_report = 0;
  if (c->in_use >= c->welcome.max_jobs) {
    snprintf(j->message, sizeof j->message,
             "LIMIT: the daemon reached on the retry takes %u jobs at once",
             c->welcome.max_jobs);
    j->client_done = j->server_done = 1;
    scc_settle(c, j, SC_CLIENT_ELIMIT);
    return;
  }
  j->id = free_id(c);
  if (upload(c, j, j->xyz) < 0 && j->status == SC_CLIENT_PENDING &&
      !j->resubmit) {
    j->client_done = j->server_done = 1;
    scc_settle(c, j, SC_CLIENT_ENOMEM);
  }
}

unsigned sc_client_job_retries(const sc_client_job_t *job) {
  return job ? job->retries_used : 0;
}

void sc_client_job_free(sc_client_job_t *job) {
  if (!job || job->user_freed)
    return;
  sc_client_t *c = job->c;
  job->user_freed = 1;
  scc_unqueue_end(c, job);
  if (job->in_use) {
    /* The CANCEL goes out with the next call that writes. */
    if (job->status == SC_CLIENT_PENDING)
      scc_queue_cancel(c, job);
    return;
  }
  scc_reap(c);
}
