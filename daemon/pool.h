/*
 * The worker pool: N threads that run reconstructions, fed from the loop
 * thread and handing every task back to it.
 *
 * A task is one job's work. The loop thread creates it, submits it, then
 * feeds it chunks of points as they arrive; whenever a task has enough new
 * points (or its input has ended, or it was cancelled) it waits in the run
 * queue for a worker. A worker runs one slice of the task: it inserts the
 * pending points with sc_recon_add() and, once the input has ended, finishes
 * the reconstruction. A task whose input has not ended is then parked until
 * more points come, so a client that uploads slowly holds no worker.
 *
 * Every submitted task comes back to the loop thread exactly once, through
 * the event callback with SCD_EV_DONE: with a mesh, with an error, or
 * cancelled. Only then may the loop thread free it. Workers never touch
 * libuv handles (uv_async_send() aside) or connections, and only workers
 * create or free an sc_recon_t, so the loop thread never runs CGAL.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SCD_POOL_H
#define SCD_POOL_H

#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>

#include <uv.h>

#include "shortcrust.h"

/* Points on their way from the loop thread to a worker. */
typedef struct scd_chunk {
  struct scd_chunk *next;
  size_t count;    /* points held */
  size_t capacity; /* points that fit */
  double xyz[];    /* 3 * capacity */
} scd_chunk_t;

/* NULL when out of memory or when the size overflows. */
scd_chunk_t *scd_chunk_new(size_t capacity);
/* Frees a whole list; accepts NULL. */
void scd_chunk_free_list(scd_chunk_t *c);

/* Events delivered to the loop thread. */
#define SCD_EV_PROGRESS 1u
#define SCD_EV_DONE 2u

typedef struct scd_pool scd_pool_t;
typedef struct scd_task scd_task_t;

struct scd_task {
  /* Set by the loop thread before scd_pool_submit(), read-only after. */
  sc_params_t params;
  uint64_t declared; /* points JOB_BEGIN announced, 0 for unknown */
  scd_pool_t *pool;

  /* Loop thread only. */
  void *owner;        /* the job, or NULL once the job let go of the task */
  uint64_t reserved;  /* bytes of the memory budget this task holds */
  int submitted;      /* in the pool: submitted and not yet handed back */

  /* Under the pool mutex. */
  int state;
  int started;        /* a worker has run a slice of it */
  int input_ended;
  scd_chunk_t *head, *tail;
  uint64_t pending;   /* points in head..tail */
  uint64_t first_ns;  /* when the first points came */
  scd_task_t *qprev, *qnext; /* run queue */
  scd_task_t *onext;  /* outbox */
  unsigned lent;      /* idle workers' cores its tiles run on (tile_points) */
  unsigned events;    /* SCD_EV_*; non-zero exactly while in the outbox */
  uint32_t stage;
  double fraction;

  atomic_int cancel;

  /* The running worker's during a slice; the loop thread's once the task is
   * handed back. Passed between threads under the pool mutex. */
  sc_recon_t *recon;
  uint64_t added;        /* points given to sc_recon_add() */
  uint64_t progress_ns;  /* when progress was last reported */
  uint64_t start_ns;     /* start of the first slice */
  uint64_t end_ns;       /* end of the last slice */
  int rc;                /* 0 or an SC_E* code */
  char msg[256];
  sc_mesh_t *mesh;
};

/* Called on the loop thread for each task with news: events is a mask of
 * SCD_EV_*; stage and fraction are the latest progress. After SCD_EV_DONE
 * the task belongs to the loop thread again. */
typedef void (*scd_pool_event_fn)(void *arg, scd_task_t *t, unsigned events,
                                  uint32_t stage, double fraction);

typedef struct scd_pool_stats {
  unsigned workers;
  unsigned busy;    /* workers running a slice */
  unsigned lent;    /* idle workers whose cores a tiled job uses */
  uint64_t queued;  /* tasks waiting for a worker */
  uint64_t tiled;   /* jobs run in tiles on lent cores, in all */
} scd_pool_stats_t;

/*
 * Starts `workers` threads. A parked task goes back to the run queue once
 * it has `batch` points pending. With tile_points (0: never), a job that
 * announced at least that many points, in a mode that tiles (cocone,
 * shortcrust), gathers all its points first and then, when no other task
 * waits, runs its tiles on its worker and on every worker idle at that
 * moment (docs/algorithm.md section 17): those workers take no task until
 * it is done. Returns 0 or a
 * negative libuv error code; when a thread fails to start, *out is still
 * set (with the threads that did start) and the caller closes and frees
 * the pool as usual.
 */
int scd_pool_new(uv_loop_t *loop, unsigned workers, uint64_t batch,
                 uint64_t tile_points, scd_pool_event_fn fn, void *arg,
                 scd_pool_t **out);
/* Closes the async handle; call on the loop thread once every submitted
 * task is back, before the loop ends. */
void scd_pool_close(scd_pool_t *p);
/* Stops and joins the threads and frees the pool; accepts NULL. Every
 * submitted task must be back. */
void scd_pool_free(scd_pool_t *p);

/* The rest is for the loop thread. */

/* A zeroed task with default parameters; NULL when out of memory. */
scd_task_t *scd_task_new(void);
/* Frees a task that is not in the pool, with its points and mesh. */
void scd_task_free(scd_task_t *t);

/* Hands a new task to the pool; it waits, parked, for points. */
void scd_pool_submit(scd_pool_t *p, scd_task_t *t);
/* Appends a chunk of points (the pool takes it). */
void scd_pool_add(scd_pool_t *p, scd_task_t *t, scd_chunk_t *c);
/* No more points will come. */
void scd_pool_end_input(scd_pool_t *p, scd_task_t *t);
/* Asks the task to stop at the next chunk or stage boundary. It still
 * comes back through the event callback. */
void scd_pool_cancel(scd_pool_t *p, scd_task_t *t);
/* Takes back a task that no worker has started: returns 1, and the task is
 * the loop thread's again (no event will come for it); 0 when it has
 * started. */
int scd_pool_withdraw(scd_pool_t *p, scd_task_t *t);

void scd_pool_get_stats(scd_pool_t *p, scd_pool_stats_t *out);

#endif /* SCD_POOL_H */
