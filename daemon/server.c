/*
 * The server: the libuv loop, the listener, signals, the once-a-second tick,
 * the memory budget, STATS, and shutdown.
 *
 * DESIGN. Everything in this file runs on the loop thread, which owns every
 * handle and connection; the only other threads are the pool's workers,
 * reached through pool.h. There are no locks here.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "daemon.h"
#include "log.h"

#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void scd_config_init(scd_config_t *cfg) {
  memset(cfg, 0, sizeof *cfg);
  cfg->socket_mode = 0660;
  cfg->workers = uv_available_parallelism();
  cfg->max_connections = 64;
  cfg->max_jobs = 16;
  cfg->max_points = 10000000;
  uint64_t total = uv_get_total_memory();
  uint64_t limit = uv_get_constrained_memory();
  if (limit && limit < total)
    total = limit;
  cfg->memory_budget = total / 2;
  cfg->grace = 30;
  cfg->log_level = SCD_LOG_INFO;
  cfg->max_frame = 1u << 20;
  cfg->out_soft = 4u << 20;
  cfg->out_hard = 16u << 20;
  cfg->handshake_ms = 10000;
  cfg->stall_ms = 60000;
  cfg->close_ms = 5000;
  cfg->batch_points = 16384;
  cfg->max_invalid = 100;
}

int scd_budget_reserve(scd_server_t *srv, scd_task_t *t, uint64_t bytes) {
  /* Meshes are accounted at their real size, which may in principle go
   * over the budget; nothing more is admitted then. */
  if (srv->budget_used > srv->cfg.memory_budget ||
      bytes > srv->cfg.memory_budget - srv->budget_used)
    return -1;
  srv->budget_used += bytes;
  t->reserved += bytes;
  return 0;
}

void scd_budget_set(scd_server_t *srv, scd_task_t *t, uint64_t bytes) {
  srv->budget_used -= t->reserved;
  srv->budget_used += bytes;
  t->reserved = bytes;
}

/* The allocators keep freed memory (glibc in per-thread arenas, TBB's in
 * its pools); hand it back to the system when the daemon has been idle for
 * a moment, so that its size returns to where it was after a burst. The
 * delay keeps the trim (a walk over every arena) off the path of a client
 * that sends one job after another. */
static void on_trim(uv_timer_t *h) {
  scd_server_t *srv = h->data;
  if (srv->tasks_live == 0)
    sc_release_memory();
}

void scd_server_free_task(scd_server_t *srv, scd_task_t *t) {
  scd_budget_set(srv, t, 0);
  scd_task_free(t);
  srv->tasks_live--;
  if (srv->tasks_live == 0 && !uv_is_closing((uv_handle_t *)&srv->trim))
    uv_timer_start(&srv->trim, on_trim, 250, 0);
}

/*
 * STATS, all u64 (PROTOCOL.md 6.13 leaves the names to the server):
 *
 *   connections                 connections open now (refused ones aside)
 *   connections_total           connections accepted, refused ones included
 *   connections_refused_total   refused for --max-connections, or for
 *                               too many TCP connections before WELCOME
 *   jobs_active                 jobs holding memory: queued, running, or
 *                               sending their mesh
 *   jobs_accepted_total         JOB_BEGINs answered with ACCEPTED
 *   jobs_refused_total          JOB_BEGINs answered with JOB_ERROR
 *   jobs_done_total             jobs that ended with JOB_DONE
 *   jobs_failed_total           accepted jobs that ended with JOB_ERROR
 *                               other than CANCELLED
 *   jobs_cancelled_total        jobs stopped by CANCEL or by their client
 *                               going away
 *   points_in_total             points received
 *   triangles_out_total         triangles of the meshes delivered
 *   bytes_in_total, bytes_out_total, frames_in_total, frames_out_total
 *   protocol_errors_total       fatal ERRORs sent, SHUTDOWN and AUTH aside
 *   slow_readers_closed_total   connections closed for not reading
 *   queue_depth                 jobs waiting for a worker
 *   workers, workers_busy       the pool, and the workers running a job
 *   workers_lent                idle workers whose cores a job's tiles use
 *   jobs_tiled_total            jobs run in tiles on idle workers' cores
 *   memory_jobs_bytes           memory held by jobs, as estimated for
 *                               admission (meshes at their real size)
 *   memory_budget_bytes         --memory-budget
 *   output_queued_bytes         output waiting to be written, all
 *                               connections together
 *   shutting_down               1 once SIGTERM or SIGINT came
 *   auth_refused_total          TCP connections refused with AUTH: no
 *                               token, or a wrong one
 */
void scd_server_stats(scd_server_t *srv, scp_buf_t *b, uint32_t tag) {
  scd_pool_stats_t ps;
  scd_pool_get_stats(srv->pool, &ps);
  const scd_counters_t *n = &srv->n;
  uint64_t out_queued = 0;
  for (const scd_conn_t *c = srv->conns; c; c = c->next)
    out_queued += scd_conn_queued(c);
#define U64(name_, value_)                                                     \
  {.name = name_, .kind = SCP_KIND_U64, .v.u = (uint64_t)(value_)}
  scp_value_t v[] = {
      U64("connections", srv->conns_open),
      U64("connections_total", n->connections_total),
      U64("connections_refused_total", n->connections_refused_total),
      U64("jobs_active", srv->tasks_live),
      U64("jobs_accepted_total", n->jobs_accepted_total),
      U64("jobs_refused_total", n->jobs_refused_total),
      U64("jobs_done_total", n->jobs_done_total),
      U64("jobs_failed_total", n->jobs_failed_total),
      U64("jobs_cancelled_total", n->jobs_cancelled_total),
      U64("points_in_total", n->points_in_total),
      U64("triangles_out_total", n->triangles_out_total),
      U64("bytes_in_total", n->bytes_in_total),
      U64("bytes_out_total", n->bytes_out_total),
      U64("frames_in_total", n->frames_in_total),
      U64("frames_out_total", n->frames_out_total),
      U64("protocol_errors_total", n->protocol_errors_total),
      U64("slow_readers_closed_total", n->slow_readers_closed_total),
      U64("queue_depth", ps.queued),
      U64("workers", ps.workers),
      U64("workers_busy", ps.busy),
      U64("workers_lent", ps.lent),
      U64("jobs_tiled_total", ps.tiled),
      U64("memory_jobs_bytes", srv->budget_used),
      U64("memory_budget_bytes", srv->cfg.memory_budget),
      U64("output_queued_bytes", out_queued),
      U64("shutting_down", srv->shutting_down),
      U64("auth_refused_total", n->auth_refused_total),
  };
#undef U64
  scp_enc_stats(b, tag, v, (uint32_t)(sizeof v / sizeof v[0]));
}

static void close_handle(uv_handle_t *h) {
  if (h->loop && !uv_is_closing(h))
    uv_close(h, NULL);
}

/* Once shutting down, the loop ends when the last connection and the last
 * task are gone: close the handles that keep it alive. */
void scd_server_maybe_finish(scd_server_t *srv) {
  if (!srv->shutting_down || srv->conns || srv->tasks_in_pool)
    return;
  close_handle((uv_handle_t *)&srv->sigterm);
  close_handle((uv_handle_t *)&srv->sigint);
  close_handle((uv_handle_t *)&srv->tick);
  close_handle((uv_handle_t *)&srv->grace);
  close_handle((uv_handle_t *)&srv->trim);
  scd_pool_close(srv->pool);
}

static void end_grace(scd_server_t *srv) {
  if (srv->grace_over)
    return;
  srv->grace_over = 1;
  scd_info("grace period over: stopping the jobs still running");
  for (scd_conn_t *c = srv->conns, *next; c; c = next) {
    next = c->next;
    scd_conn_shutdown(c);
  }
  scd_server_maybe_finish(srv);
}

static void on_grace(uv_timer_t *h) { end_grace(h->data); }

static void begin_shutdown(scd_server_t *srv, const char *why) {
  if (srv->shutting_down) {
    scd_info("%s again: not waiting for the grace period", why);
    end_grace(srv);
    return;
  }
  uint64_t now = uv_hrtime();
  srv->shutting_down = 1;
  srv->grace_deadline_ns = now + (uint64_t)(srv->cfg.grace * 1e9);
  srv->final_deadline_ns =
      srv->grace_deadline_ns + srv->cfg.close_ms * 1000000u;
  scd_info("%s: shutting down (%u connections, %llu jobs; grace %.3g s)", why,
           srv->conns_open, (unsigned long long)srv->tasks_live,
           srv->cfg.grace);
  scd_listen_close(srv);
  scd_listen_cleanup(srv);
  for (scd_conn_t *c = srv->conns, *next; c; c = next) {
    next = c->next;
    scd_conn_shutdown(c);
  }
  if (srv->cfg.grace <= 0)
    end_grace(srv);
  else
    uv_timer_start(&srv->grace, on_grace, (uint64_t)(srv->cfg.grace * 1e3), 0);
  scd_server_maybe_finish(srv);
}

static void on_signal(uv_signal_t *h, int signum) {
  begin_shutdown(h->data, signum == SIGINT ? "SIGINT" : "SIGTERM");
}

static void on_tick(uv_timer_t *h) {
  scd_server_t *srv = h->data;
  uint64_t now = uv_hrtime();
  for (scd_conn_t *c = srv->conns, *next; c; c = next) {
    next = c->next;
    if (srv->shutting_down && now >= srv->final_deadline_ns)
      scd_conn_close_now(c, "shutdown: could not flush in time");
    else
      scd_conn_tick(c, now);
  }
  scd_server_maybe_finish(srv);
}

static void on_connection(uv_stream_t *listener, int status) {
  scd_server_t *srv = listener->data;
  if (status < 0) {
    scd_warn("accept: %s", uv_strerror(status));
    return;
  }
  scd_conn_accept(srv, listener, 0);
}

static void on_task_event(void *arg, scd_task_t *t, unsigned events,
                          uint32_t stage, double fraction) {
  scd_server_t *srv = arg;
  if (events & SCD_EV_DONE)
    srv->tasks_in_pool--;
  scd_conn_task_event(srv, t, events, stage, fraction);
  scd_server_maybe_finish(srv);
}

/* The most points a job may have so that its estimate fits the budget. */
static uint64_t points_in_budget(uint64_t budget) {
  uint64_t lo = 0, hi = 0xFFFFFFFEu;
  while (lo < hi) {
    uint64_t mid = lo + (hi - lo + 1) / 2;
    if (sc_estimate_bytes(mid) <= budget)
      lo = mid;
    else
      hi = mid - 1;
  }
  return lo;
}

int scd_server_run(const scd_config_t *cfg) {
  scd_server_t *srv = calloc(1, sizeof *srv);
  if (!srv) {
    scd_error("out of memory");
    return 1;
  }
  srv->cfg = *cfg;
  srv->lock_fd = -1;
  srv->loop = uv_default_loop();
  srv->next_conn_id = 1;

  uint64_t fit = points_in_budget(cfg->memory_budget);
  if (fit < 4) {
    scd_error("--memory-budget %llu is too small for any job (%llu bytes "
              "for 4 points)",
              (unsigned long long)cfg->memory_budget,
              (unsigned long long)sc_estimate_bytes(4));
    free(srv);
    return 1;
  }
  srv->max_points = cfg->max_points < fit ? cfg->max_points : fit;
  if (cfg->token_file && scd_token_load(srv, cfg->token_file) != 0) {
    free(srv);
    return 1;
  }

  /* A client that goes away while we write must not kill the daemon. */
  signal(SIGPIPE, SIG_IGN);

  int rc = 0;
  if (scd_listen_open(srv) != 0) {
    rc = 1;
    goto out;
  }
  int urc = uv_listen((uv_stream_t *)&srv->listener, SOMAXCONN, on_connection);
  if (urc != 0) {
    scd_error("listen on %s: %s", srv->socket_path, uv_strerror(urc));
    scd_listen_close(srv);
    rc = 1;
    goto out_loop;
  }
  if (scd_listen_tcp(srv) != 0) {
    scd_listen_close(srv);
    rc = 1;
    goto out_loop;
  }
  urc = scd_pool_new(srv->loop, cfg->workers, cfg->batch_points,
                     cfg->tile_points, on_task_event, srv, &srv->pool);
  if (urc != 0) {
    scd_error("cannot start %u workers: %s", cfg->workers, uv_strerror(urc));
    scd_listen_close(srv);
    scd_pool_close(srv->pool);
    rc = 1;
    goto out_loop;
  }
  uv_signal_init(srv->loop, &srv->sigterm);
  uv_signal_init(srv->loop, &srv->sigint);
  srv->sigterm.data = srv->sigint.data = srv;
  uv_signal_start(&srv->sigterm, on_signal, SIGTERM);
  uv_signal_start(&srv->sigint, on_signal, SIGINT);
  uv_timer_init(srv->loop, &srv->tick);
  srv->tick.data = srv;
  uv_timer_start(&srv->tick, on_tick, 1000, 1000);
  uv_timer_init(srv->loop, &srv->grace);
  srv->grace.data = srv;
  uv_timer_init(srv->loop, &srv->trim);
  srv->trim.data = srv;

  char budget[32];
  snprintf(budget, sizeof budget, "%.1f MiB",
           (double)cfg->memory_budget / (1024.0 * 1024.0));
  scd_info("listening on %s (mode %04o): %u workers, at most %u connections, "
           "%u jobs per connection, %llu points per job, memory budget %s, "
           "grace %.3g s",
           srv->socket_path, cfg->socket_mode, cfg->workers,
           cfg->max_connections, cfg->max_jobs,
           (unsigned long long)srv->max_points, budget, cfg->grace);
  for (unsigned i = 0; i < srv->ntcp; i++)
    scd_info("listening on %s (clients must send the token)", srv->tcp[i].name);

out_loop:
  uv_run(srv->loop, UV_RUN_DEFAULT);
  scd_pool_free(srv->pool);
  if (rc == 0)
    scd_info("stopped: %llu connections, %llu jobs done, %llu failed, "
             "%llu cancelled",
             (unsigned long long)srv->n.connections_total,
             (unsigned long long)srv->n.jobs_done_total,
             (unsigned long long)srv->n.jobs_failed_total,
             (unsigned long long)srv->n.jobs_cancelled_total);
out:
  scd_listen_cleanup(srv);
  uv_loop_close(srv->loop);
  scd_token_forget(srv);
  free(srv);
  return rc;
}
