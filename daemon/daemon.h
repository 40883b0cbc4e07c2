/*
 * Internals of shortcrustd shared by its files: the configuration, the
 * server, connections and jobs. Everything here belongs to the loop thread;
 * what workers see is in pool.h.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SCD_DAEMON_H
#define SCD_DAEMON_H

#include <stddef.h>
#include <stdint.h>

#include <uv.h>

#include "pool.h"
#include "scproto.h"
#include "shortcrust.h"

/* TCP listeners one daemon may have (--listen, repeated). */
#define SCD_MAX_LISTEN 8

typedef struct scd_config {
  /* Flags. */
  const char *socket_path;  /* never NULL once main() is done with it */
  unsigned socket_mode;     /* default 0660 */
  const char *listen[SCD_MAX_LISTEN]; /* --listen tcp://HOST:PORT */
  unsigned nlisten;
  const char *token_file;   /* --token-file; required with --listen */
  unsigned workers;         /* default: available cores */
  unsigned max_connections; /* default 64 */
  unsigned max_jobs;        /* per connection; default 16 */
  uint64_t max_points;      /* per job; default 10,000,000 */
  uint64_t memory_budget;   /* bytes; default half of the memory */
  uint64_t tile_points;     /* --tile-points; 0 (default) never tiles */
  double grace;             /* seconds; default 30 */
  int log_level;            /* default info */

  /* Fixed limits, not flags. */
  uint32_t max_frame;          /* the largest frame we accept or send */
  size_t out_soft;             /* output queued: stop reading above this */
  size_t out_hard;             /* output queued: close above this */
  uint64_t handshake_ms;       /* time allowed for HELLO */
  uint64_t stall_ms;           /* output over out_soft and not moving */
  uint64_t close_ms;           /* flushing the last frames before close */
  uint64_t batch_points;       /* points a parked job gathers to run again */
  unsigned max_invalid;        /* invalid requests in a row before close */
} scd_config_t;

/* Fills in every default. */
void scd_config_init(scd_config_t *cfg);

/* Counters for STATS; those ending in _total only grow. */
typedef struct scd_counters {
  uint64_t connections_total;
  uint64_t connections_refused_total;
  uint64_t jobs_accepted_total;
  uint64_t jobs_refused_total;
  uint64_t jobs_done_total;
  uint64_t jobs_failed_total;
  uint64_t jobs_cancelled_total;
  uint64_t points_in_total;
  uint64_t triangles_out_total;
  uint64_t bytes_in_total;
  uint64_t bytes_out_total;
  uint64_t frames_in_total;
  uint64_t frames_out_total;
  uint64_t protocol_errors_total;
  uint64_t slow_readers_closed_total;
  uint64_t auth_refused_total;
} scd_counters_t;

typedef struct scd_conn scd_conn_t;
typedef struct scd_job scd_job_t;

/* A TCP listener: its handle and the address it is bound to. */
typedef struct scd_tcp_listener {
  uv_tcp_t tcp;
  struct scd_server *srv;
  int open;
  char name[SCP_ADDR_HOST_MAX + 16]; /* tcp://HOST:PORT, the port bound */
} scd_tcp_listener_t;

typedef struct scd_server {
  uv_loop_t *loop;
  scd_config_t cfg;

  uv_pipe_t listener;
  int listener_open;
  scd_tcp_listener_t tcp[SCD_MAX_LISTEN];
  unsigned ntcp;
  /* The token TCP clients must send (PROTOCOL.md 5.1); token_len 0 when
   * there is none, which is only allowed without TCP listeners. */
  uint8_t token[SCP_TOKEN_MAX];
  size_t token_len;
  char socket_path[256];   /* as bound or as systemd gave it */
  int unlink_at_exit;      /* we created the socket file */
  int lock_fd;             /* held for the daemon's life; -1 when none */
  char lock_path[272];

  uv_signal_t sigterm, sigint;
  uv_timer_t tick;         /* once a second: timeouts */
  uv_timer_t grace;        /* ends the grace period of a shutdown */
  uv_timer_t trim;         /* gives memory back once idle */
  scd_pool_t *pool;

  scd_conn_t *conns;       /* every open connection */
  unsigned conns_open;     /* counted against --max-connections */
  unsigned tcp_waiting;    /* of those, TCP ones before their WELCOME */
  uint64_t next_conn_id;

  uint64_t tasks_in_pool;  /* submitted and not yet handed back */
  uint64_t tasks_live;     /* created and not yet freed */
  uint64_t budget_used;    /* bytes reserved by live tasks */
  uint64_t max_points;     /* what WELCOME offers: flag and budget both */

  int shutting_down;
  int grace_over;
  uint64_t grace_deadline_ns;
  uint64_t final_deadline_ns;
  int exit_code;

  scd_counters_t n;
  char readbuf[64 * 1024];
  int reading;             /* readbuf is lent to libuv */
} scd_server_t;

/* Job phases, from the loop thread's view of the id (PROTOCOL.md 7.1). */
enum {
  SCD_JOB_UPLOADING = 1,
  SCD_JOB_WORKING,   /* JOB_END came; the task is in the pool */
  SCD_JOB_SENDING,   /* the mesh is going out */
  SCD_JOB_DRAINING   /* JOB_ERROR sent before JOB_END or CANCEL */
};

struct scd_job {
  scd_conn_t *conn;
  scd_job_t *prev, *next;  /* the connection's jobs */
  scd_job_t *snext;        /* the connection's sending queue */
  uint32_t id;
  int phase;
  uint32_t flags;          /* JOB_BEGIN flags */
  uint64_t declared;       /* JOB_BEGIN's point_count, 0 when unknown */
  uint64_t received;       /* points taken so far */
  scd_task_t *task;        /* NULL when rejected or draining */
  scd_chunk_t *staging;    /* points gathered before going to the pool */
  scp_mesh_cursor_t cursor;
  uint64_t begin_ns, end_ns, done_ns; /* JOB_BEGIN, JOB_END, mesh back */
};

enum {
  SCD_CONN_HANDSHAKE = 1,
  SCD_CONN_READY,
  SCD_CONN_CLOSING,   /* last frames going out, then close */
  SCD_CONN_CLOSED     /* uv_close() called */
};

struct scd_conn {
  /* The client's stream: a Unix socket or TCP. The handle comes first, so
   * libuv's callbacks find the connection through its data field either
   * way. */
  union {
    uv_pipe_t pipe;
    uv_tcp_t tcp;
    uv_stream_t stream;
    uv_handle_t handle;
  } h;
  int tcp;       /* 1: came in over TCP and needs the token */
  char peer[64]; /* the TCP peer's address, for the logs */
  scd_server_t *srv;
  scd_conn_t *prev, *next;
  uint64_t id;
  int state;
  int counted;             /* counts against --max-connections */
  int waiting;             /* counts in tcp_waiting */
  int reading;             /* uv_read_start() in force */
  int broken;              /* out of memory for output: close at flush */
  scp_decoder_t *dec;

  /* Output: frames are appended to out; wbuf is the one being written. */
  scp_buf_t out, wbuf;
  uv_write_t wreq;
  int writing;
  uv_shutdown_t sreq;
  uint32_t max_frame;
  uint64_t features;       /* feature bits in force (WELCOME's) */

  scd_job_t *jobs;
  unsigned njobs;
  scd_job_t *shead, *stail; /* jobs whose mesh is going out, round-robin */

  unsigned invalid_streak;
  uint64_t open_ns, deadline_ns, stall_since_ns;
  uint64_t bytes_in, bytes_out, jobs_total;
  char close_reason[160];
};

/* server.c */
int scd_server_run(const scd_config_t *cfg);
void scd_server_maybe_finish(scd_server_t *srv);
/* The budget: reserve returns 0 or -1 when the bytes do not fit. */
int scd_budget_reserve(scd_server_t *srv, scd_task_t *t, uint64_t bytes);
void scd_budget_set(scd_server_t *srv, scd_task_t *t, uint64_t bytes);
/* Frees a task that is back from the pool (or never went) and its
 * reservation. */
void scd_server_free_task(scd_server_t *srv, scd_task_t *t);
void scd_server_stats(scd_server_t *srv, scp_buf_t *b, uint32_t tag);

/* conn.c */
/* Accepts a client on a listener: the Unix socket (tcp 0) or a TCP one. */
void scd_conn_accept(scd_server_t *srv, uv_stream_t *listener, int tcp);
void scd_conn_task_event(scd_server_t *srv, scd_task_t *t, unsigned events,
                         uint32_t stage, double fraction);
/* Shutdown: stop queued jobs (grace_over 0) or every job (1), and close
 * connections with nothing left to do. */
void scd_conn_shutdown(scd_conn_t *c);
void scd_conn_tick(scd_conn_t *c, uint64_t now);
void scd_conn_close_now(scd_conn_t *c, const char *reason);
/* Output bytes queued on the connection, written or waiting. */
size_t scd_conn_queued(const scd_conn_t *c);

/* listen.c */
int scd_listen_open(scd_server_t *srv);
/* Binds every --listen address; -1 (logged) when one cannot be bound. */
int scd_listen_tcp(scd_server_t *srv);
/* Stops accepting on every listener. */
void scd_listen_close(scd_server_t *srv);
void scd_listen_cleanup(scd_server_t *srv);

/* auth.c */
/* Reads --token-file into srv->token: -1 (logged) when the file is missing,
 * not a regular file, open to group or others, or holds no usable token. */
int scd_token_load(scd_server_t *srv, const char *path);
/* Wipes the token from memory, at exit. */
void scd_token_forget(scd_server_t *srv);
/* Whether HELLO may go on: 1 on a Unix socket (the token is ignored) or
 * with the right token on TCP; 0 after a fatal ERROR AUTH. */
int scd_auth_hello(scd_conn_t *c, const scp_hello_t *h);

#endif /* SCD_DAEMON_H */
