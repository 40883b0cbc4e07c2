/*
 * The worker pool; see pool.h.
 *
 * DESIGN. Threads: the loop thread and N workers. One mutex, pool->mu,
 * guards the run queue, the outbox, the counters and the fields of every
 * task marked "under the pool mutex" in pool.h; no other lock exists here,
 * so there is no lock order to keep. A worker takes a task off the run
 * queue (state RUNNING) together with its pending points, drops the mutex,
 * runs CGAL through the core, and takes the mutex again to park, requeue or
 * hand back the task. The fields a worker touches without the mutex
 * (recon, rc, msg, mesh, timings) belong to whoever holds the task in
 * state RUNNING (a worker) or DONE (the loop thread); the state changes
 * under the mutex, which orders those accesses. cancel is an atomic flag
 * the loop thread sets and the core's progress callback polls. Tasks going
 * back to the loop thread are put in the outbox and the loop is woken with
 * uv_async_send(), the one libuv call workers make.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "pool.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum {
  SCD_T_NEW = 0, /* not submitted */
  SCD_T_PARKED,  /* waiting for points */
  SCD_T_QUEUED,  /* waiting for a worker */
  SCD_T_RUNNING, /* a worker runs a slice */
  SCD_T_DONE     /* handed back (or on its way back) to the loop thread */
};

/* At most this often per task, the progress callback reports to the loop
 * thread (the protocol asks for no more than about ten a second). */
#define SCD_PROGRESS_NS (100u * 1000u * 1000u)

struct scd_pool {
  uv_mutex_t mu;
  uv_cond_t cv;           /* workers wait here for the run queue */
  scd_task_t *qhead, *qtail;
  uint64_t queued;
  scd_task_t *ohead, *otail;
  unsigned busy;
  unsigned lent; /* idle workers' cores that tiled tasks use */
  int stopping;
  uint64_t batch;
  uint64_t tile_points;
  uint64_t tiled;

  uv_async_t async;       /* the loop's; workers only call uv_async_send() */
  scd_pool_event_fn fn;
  void *arg;

  unsigned nthreads;
  uv_thread_t *threads;
};

scd_chunk_t *scd_chunk_new(size_t capacity) {
  if (capacity == 0)
    capacity = 1;
  if (capacity > (SIZE_MAX - sizeof(scd_chunk_t)) / (3 * sizeof(double)))
    return NULL;
  scd_chunk_t *c =
      malloc(sizeof(scd_chunk_t) + capacity * 3 * sizeof(double));
  if (!c)
    return NULL;
  c->next = NULL;
  c->count = 0;
  c->capacity = capacity;
  return c;
}

void scd_chunk_free_list(scd_chunk_t *c) {
  while (c) {
    scd_chunk_t *next = c->next;
    free(c);
    c = next;
  }
}

scd_task_t *scd_task_new(void) {
  scd_task_t *t = calloc(1, sizeof *t);
  if (!t)
    return NULL;
  sc_params_init(&t->params);
  atomic_init(&t->cancel, 0);
  t->state = SCD_T_NEW;
  return t;
}

void scd_task_free(scd_task_t *t) {
  if (!t)
    return;
  scd_chunk_free_list(t->head);
  sc_mesh_free(t->mesh);
  /* A task only comes back without its reconstruction (the worker frees it
   * when the task ends), so nothing of CGAL is freed here. */
  free(t);
}

/* Run queue and outbox; the caller holds p->mu. */

/* Started tasks go first when they become runnable again: their
 * triangulation is half built, holds memory, and is warm in the caches;
 * new tasks wait behind them. */
static void queue_push(scd_pool_t *p, scd_task_t *t, int front) {
  t->state = SCD_T_QUEUED;
  t->qprev = t->qnext = NULL;
  if (!p->qhead) {
    p->qhead = p->qtail = t;
  } else if (front) {
    t->qnext = p->qhead;
    p->qhead->qprev = t;
    p->qhead = t;
  } else {
    t->qprev = p->qtail;
    p->qtail->qnext = t;
    p->qtail = t;
  }
  p->queued++;
  uv_cond_signal(&p->cv);
}

static void queue_remove(scd_pool_t *p, scd_task_t *t) {
  if (t->qprev)
    t->qprev->qnext = t->qnext;
  else
    p->qhead = t->qnext;
  if (t->qnext)
    t->qnext->qprev = t->qprev;
  else
    p->qtail = t->qprev;
  t->qprev = t->qnext = NULL;
  p->queued--;
}

/* Returns 1 when the loop must be woken. */
static int outbox_post(scd_pool_t *p, scd_task_t *t, unsigned ev) {
  if (t->events) {
    t->events |= ev;
    return 0;
  }
  t->events = ev;
  t->onext = NULL;
  if (p->otail)
    p->otail->onext = t;
  else
    p->ohead = t;
  p->otail = t;
  return 1;
}

/* A task's first slice waits this long after its first points, unless
 * its input ends sooner: points that all arrive within it go into the
 * triangulation in one call, as a local run inserts them (the Delaunay
 * stage of 100k points started on the first batch and finished on the rest
 * took 1.2 to 1.4 times as long), and an upload slower than that loses
 * little of its overlap. */
#define SCD_HOLD_NS (250u * 1000u * 1000u)

/* Whether the task may run its tiles on idle workers' cores: it then waits
 * for all of its points (tiles split them all at once). */
static int tiles_on_idle(const scd_pool_t *p, const scd_task_t *t) {
  return p->tile_points && t->declared >= p->tile_points &&
         sc_params_can_tile(&t->params) && t->params.tile_count == 0;
}

static int runnable(const scd_pool_t *p, scd_task_t *t) {
  if (t->input_ended || atomic_load_explicit(&t->cancel, memory_order_relaxed))
    return 1;
  if (tiles_on_idle(p, t))
    return 0;
  return t->pending >= p->batch &&
         (t->started || uv_hrtime() - t->first_ns >= SCD_HOLD_NS);
}

/* The core's progress callback, on a worker thread. */
static int on_progress(void *user, sc_stage_t stage, double fraction) {
  scd_task_t *t = user;
  if (atomic_load_explicit(&t->cancel, memory_order_relaxed))
    return 1;
  uint64_t now = uv_hrtime();
  if (now - t->progress_ns >= SCD_PROGRESS_NS) {
    scd_pool_t *p = t->pool;
    t->progress_ns = now;
    uv_mutex_lock(&p->mu);
    t->stage = (uint32_t)stage;
    t->fraction = fraction < 0 ? 0 : fraction > 1 ? 1 : fraction;
    int wake = outbox_post(p, t, SCD_EV_PROGRESS);
    uv_mutex_unlock(&p->mu);
    if (wake)
      uv_async_send(&p->async);
  }
  return 0;
}

/*
 * One slice of a task, without the mutex: inserts the points taken from the
 * task and finishes when the input has ended. Returns 1 when the task is
 * over (mesh, error or cancelled).
 */
static int run_slice(scd_task_t *t, scd_chunk_t *chunks, uint64_t n,
                     int ended) {
  int rc = 0;
  if (atomic_load_explicit(&t->cancel, memory_order_relaxed)) {
    rc = SC_ECANCELLED;
    snprintf(t->msg, sizeof t->msg, "cancelled");
  }
  if (!rc && !t->recon) {
    /* On lent cores: one tile per thread. */
    sc_params_t params = t->params;
    if (t->lent) {
      params.threads = (int)(1 + t->lent);
      params.tiles = 0;
    }
    rc = sc_recon_new(&params, &t->recon);
    if (rc)
      snprintf(t->msg, sizeof t->msg, "%s", sc_strerror(rc));
  }
  if (!rc && n) {
    const double *xyz = chunks->xyz;
    double *joined = NULL;
    /* One call for everything pending: the core sorts each call's points
     * spatially, so fewer, larger calls insert faster. */
    if (chunks->next) {
      joined = malloc((size_t)n * 3 * sizeof(double));
      if (!joined) {
        rc = SC_ENO_MEMORY;
        snprintf(t->msg, sizeof t->msg, "%s", sc_strerror(rc));
      } else {
        size_t at = 0;
        for (scd_chunk_t *c = chunks; c; c = c->next) {
          memcpy(joined + 3 * at, c->xyz, c->count * 3 * sizeof(double));
          at += c->count;
        }
        xyz = joined;
      }
    }
    if (!rc) {
      rc = sc_recon_add(t->recon, xyz, (size_t)n, t->msg, sizeof t->msg);
      if (!rc)
        t->added += n;
    }
    free(joined);
  }
  scd_chunk_free_list(chunks);
  if (!rc && ended)
    rc = sc_recon_finish(t->recon, &t->mesh, t->msg, sizeof t->msg);
  if (rc || ended) {
    sc_recon_free(t->recon);
    t->recon = NULL;
  }
  t->rc = rc;
  return rc || ended;
}

static void worker_main(void *arg) {
  scd_pool_t *p = arg;
  uv_mutex_lock(&p->mu);
  for (;;) {
    /* A worker whose core a tiled task uses takes nothing. */
    while ((!p->qhead || p->busy + p->lent >= p->nthreads) && !p->stopping)
      uv_cond_wait(&p->cv, &p->mu);
    if (!p->qhead)
      break;
    scd_task_t *t = p->qhead;
    queue_remove(p, t);
    t->state = SCD_T_RUNNING;
    t->started = 1;
    p->busy++;
    /* Its whole input here, and no other task waiting: the workers idle
     * now lend it their cores. */
    if (t->input_ended && tiles_on_idle(p, t) && !p->qhead &&
        p->busy + p->lent < p->nthreads) {
      t->lent = p->nthreads - p->busy - p->lent;
      p->lent += t->lent;
      p->tiled++;
    }
    scd_chunk_t *chunks = t->head;
    uint64_t n = t->pending;
    int ended = t->input_ended;
    t->head = t->tail = NULL;
    t->pending = 0;
    uv_mutex_unlock(&p->mu);

    if (!t->start_ns)
      t->start_ns = uv_hrtime();
    int over = run_slice(t, chunks, n, ended);
    t->end_ns = uv_hrtime();

    uv_mutex_lock(&p->mu);
    p->busy--;
    if (t->lent) {
      p->lent -= t->lent;
      t->lent = 0;
      uv_cond_broadcast(&p->cv);
    }
    int wake = 0;
    if (over) {
      /* Points that came during the slice are not needed any more. */
      scd_chunk_free_list(t->head);
      t->head = t->tail = NULL;
      t->pending = 0;
      t->state = SCD_T_DONE;
      wake = outbox_post(p, t, SCD_EV_DONE);
    } else if (runnable(p, t)) {
      queue_push(p, t, 1);
    } else {
      t->state = SCD_T_PARKED;
    }
    if (wake)
      uv_async_send(&p->async);
  }
  uv_mutex_unlock(&p->mu);
}

/* On the loop thread: hands every task in the outbox to the callback. */
static void on_async(uv_async_t *handle) {
  scd_pool_t *p = handle->data;
  for (;;) {
    uv_mutex_lock(&p->mu);
    scd_task_t *t = p->ohead;
    if (!t) {
      uv_mutex_unlock(&p->mu);
      return;
    }
    p->ohead = t->onext;
    if (!p->ohead)
      p->otail = NULL;
    t->onext = NULL;
    unsigned ev = t->events;
    uint32_t stage = t->stage;
    double fraction = t->fraction;
    t->events = 0;
    uv_mutex_unlock(&p->mu);
    if (ev & SCD_EV_DONE)
      t->submitted = 0;
    p->fn(p->arg, t, ev, stage, fraction);
  }
}

int scd_pool_new(uv_loop_t *loop, unsigned workers, uint64_t batch,
                 uint64_t tile_points, scd_pool_event_fn fn, void *arg,
                 scd_pool_t **out) {
  *out = NULL;
  if (workers == 0 || !fn)
    return UV_EINVAL;
  scd_pool_t *p = calloc(1, sizeof *p);
  if (!p)
    return UV_ENOMEM;
  p->threads = calloc(workers, sizeof *p->threads);
  if (!p->threads) {
    free(p);
    return UV_ENOMEM;
  }
  p->tile_points = tile_points;
  p->batch = batch ? batch : 1;
  p->fn = fn;
  p->arg = arg;
  int rc = uv_mutex_init(&p->mu);
  if (rc)
    goto fail_threads;
  rc = uv_cond_init(&p->cv);
  if (rc)
    goto fail_mutex;
  rc = uv_async_init(loop, &p->async, on_async);
  if (rc)
    goto fail_cond;
  p->async.data = p;
  for (unsigned i = 0; i < workers; i++) {
    rc = uv_thread_create(&p->threads[i], worker_main, p);
    if (rc) {
      /* Stop the ones that started; the caller closes the async handle
       * through scd_pool_close() as usual. */
      p->nthreads = i;
      *out = p;
      return rc;
    }
  }
  p->nthreads = workers;
  *out = p;
  return 0;

fail_cond:
  uv_cond_destroy(&p->cv);
fail_mutex:
  uv_mutex_destroy(&p->mu);
fail_threads:
  free(p->threads);
  free(p);
  return rc;
}

void scd_pool_close(scd_pool_t *p) {
  if (p && !uv_is_closing((uv_handle_t *)&p->async))
    uv_close((uv_handle_t *)&p->async, NULL);
}

void scd_pool_free(scd_pool_t *p) {
  if (!p)
    return;
  uv_mutex_lock(&p->mu);
  p->stopping = 1;
  uv_cond_broadcast(&p->cv);
  uv_mutex_unlock(&p->mu);
  for (unsigned i = 0; i < p->nthreads; i++)
    uv_thread_join(&p->threads[i]);
  uv_cond_destroy(&p->cv);
  uv_mutex_destroy(&p->mu);
  free(p->threads);
  free(p);
}

void scd_pool_submit(scd_pool_t *p, scd_task_t *t) {
  t->pool = p;
  t->params.progress = on_progress;
  t->params.progress_user = t;
  t->submitted = 1;
  uv_mutex_lock(&p->mu);
  t->state = SCD_T_PARKED;
  uv_mutex_unlock(&p->mu);
}

void scd_pool_add(scd_pool_t *p, scd_task_t *t, scd_chunk_t *c) {
  c->next = NULL;
  uv_mutex_lock(&p->mu);
  if (t->state == SCD_T_DONE) {
    /* Over already (an error in an earlier chunk); the loop thread learns
     * of it from the outbox. */
    uv_mutex_unlock(&p->mu);
    free(c);
    return;
  }
  if (!t->first_ns)
    t->first_ns = uv_hrtime();
  if (t->tail)
    t->tail->next = c;
  else
    t->head = c;
  t->tail = c;
  t->pending += c->count;
  if (t->state == SCD_T_PARKED && runnable(p, t))
    queue_push(p, t, t->started);
  uv_mutex_unlock(&p->mu);
}

void scd_pool_end_input(scd_pool_t *p, scd_task_t *t) {
  uv_mutex_lock(&p->mu);
  t->input_ended = 1;
  if (t->state == SCD_T_PARKED)
    queue_push(p, t, t->started);
  uv_mutex_unlock(&p->mu);
}

void scd_pool_cancel(scd_pool_t *p, scd_task_t *t) {
  atomic_store_explicit(&t->cancel, 1, memory_order_relaxed);
  uv_mutex_lock(&p->mu);
  /* A cancelled task needs a worker only to free what it holds; it goes
   * first so that its memory comes back soon. */
  if (t->state == SCD_T_PARKED) {
    queue_push(p, t, 1);
  } else if (t->state == SCD_T_QUEUED) {
    queue_remove(p, t);
    queue_push(p, t, 1);
  }
  uv_mutex_unlock(&p->mu);
}

int scd_pool_withdraw(scd_pool_t *p, scd_task_t *t) {
  int taken = 0;
  uv_mutex_lock(&p->mu);
  if (!t->started &&
      (t->state == SCD_T_PARKED || t->state == SCD_T_QUEUED)) {
    if (t->state == SCD_T_QUEUED)
      queue_remove(p, t);
    t->state = SCD_T_NEW;
    taken = 1;
  }
  uv_mutex_unlock(&p->mu);
  if (taken)
    t->submitted = 0;
  return taken;
}

void scd_pool_get_stats(scd_pool_t *p, scd_pool_stats_t *out) {
  uv_mutex_lock(&p->mu);
  out->workers = p->nthreads;
  out->busy = p->busy;
  out->lent = p->lent;
  out->queued = p->queued;
  out->tiled = p->tiled;
  uv_mutex_unlock(&p->mu);
}
