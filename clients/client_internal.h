/*
 * Internals of the client library shared by its files: client.c (the
 * handle, the connection and its I/O), client_jobs.c (submitting, waiting,
 * cancelling) and client_results.c (the frames from the daemon and what
 * the user reads of them). Nothing here is installed.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SCC_CLIENT_INTERNAL_H
#define SCC_CLIENT_INTERNAL_H

#include <stddef.h>
#include <stdint.h>
#include <sys/un.h>

#include "scproto.h"
#include "shortcrust_client.h"

#define SCC_MSG_MAX (SCP_MESSAGE_MAX + 256)

struct sc_client_job {
  sc_client_t *c;
  sc_client_job_t *prev, *next; /* every job of the handle */
  sc_client_job_t *enext;       /* ended and not yet reported by a wait */
  int queued_end;               /* in the ended queue */

  uint32_t id;
  int in_use;      /* the id is in use (client.c, DESIGN) */
  int begun;       /* JOB_BEGIN went out */
  int client_done; /* JOB_END or CANCEL went out */
  int server_done; /* JOB_DONE or JOB_ERROR came, or the connection died */
  int cancelled;   /* we asked the daemon to stop it */
  int local_err;   /* why we did, when it was not the user's wish */
  int user_freed;
  int accepted;
  int status; /* SC_CLIENT_PENDING, 0 or an error */
  uint32_t server_code;
  char message[SCC_MSG_MAX];

  sc_client_params_t params;
  uint64_t n;
  double *own_xyz;   /* points read from a file */
  const double *xyz; /* the points, kept for a retry */
  unsigned retries_used;
  int resubmit; /* its connection is gone; waits to be submitted again */

  uint32_t *tri;
  uint64_t ntri, tri_cap;
  double *normals;
  uint64_t nnormals;
  double *vertices; /* VERTICES, when params.smoothed_vertices */
  uint64_t nvertices;
  int32_t *genus;
  uint64_t ncomp, comp_cap;
  sc_client_value_t *values;
  size_t nvalues;

  double t_submit, t_uploaded, t_first_chunk, t_end;
  double last_download_report;
};

struct sc_client {
  int fd;
  char path[SCP_ADDR_HOST_MAX + 128]; /* the address, as given */
  scp_address_t addr;
  uint8_t token[SCP_TOKEN_MAX]; /* sent over TCP only */
  size_t token_len;
  int has_token;
  uint32_t max_frame_opt;
  int recovering; /* scc_recover() is under way */
  int io_timeout_ms;
  scp_decoder_t *dec;
  scp_buf_t out;
  size_t out_at; /* bytes of out already written */
  uint8_t *rbuf;
  scp_hello_t hello;
  scp_welcome_t welcome;
  int ready; /* 0 handshake, -1 answered, 1 done */

  int err; /* sticky: the connection is gone */
  char errmsg[SCC_MSG_MAX];
  char last[SCC_MSG_MAX];

  sc_client_job_t *jobs;
  sc_client_job_t *ehead, *etail;
  unsigned in_use;
  uint32_t next_id;
  int in_callback;

  uint64_t ping_token;
  int ping_waiting, pong_seen;
  uint32_t stats_tag;
  int stats_waiting, stats_seen;
  sc_client_value_t *stats;
  size_t nstats;
};

/* client.c */
double scc_now_s(void);
/* Records a failed call's message on the handle and returns its code. */
int scc_fail(sc_client_t *c, int code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* The connection is gone: every job in use ends with the error. */
void scc_conn_die(sc_client_t *c, int code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* The daemon broke the protocol: tell it, and close. */
void scc_protocol_error(sc_client_t *c, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));
/* Common checks of the public calls on a handle. */
int scc_usable(sc_client_t *c);
/* The I/O loop, until cond holds, the deadline passes or the connection
 * dies; see client.c. */
typedef int (*scc_cond_fn)(sc_client_t *c, void *arg);
int scc_run_io(sc_client_t *c, scc_cond_fn cond, void *arg, double deadline);
double scc_deadline_after(int timeout_ms);
/* Writes out everything queued. */
int scc_flush_out(sc_client_t *c);
/* 1 when some job waits to be submitted again on a new connection. */
int scc_waiting(const sc_client_t *c);
/* The connection is gone and jobs wait for a retry: connects anew, with
 * the back-off of their parameters, and submits them again. 0 once the
 * connection is up again (c->err 0), else the error (the jobs that ran out
 * of retries have ended with it). */
int scc_recover(sc_client_t *c);
/* Whether a job whose connection ended with code may be run again. */
int scc_may_retry(const sc_client_job_t *j, int code);

/* client_jobs.c */
sc_client_job_t *scc_find_in_use(sc_client_t *c, uint32_t id);
void scc_job_destroy(sc_client_job_t *j);
void scc_unqueue_end(sc_client_t *c, sc_client_job_t *j);
/* Frees the jobs the user let go of whose ids are free again. */
void scc_reap(sc_client_t *c);
void scc_update_in_use(sc_client_t *c, sc_client_job_t *j);
/* The job's end as the user sees it. */
void scc_settle(sc_client_t *c, sc_client_job_t *j, int status);
void scc_drop_mesh(sc_client_job_t *j);
/* A CANCEL for the job, unless one went out already or its id is free. */
void scc_queue_cancel(sc_client_t *c, sc_client_job_t *j);
/* Submits a job that waits for a retry again, on the new connection. */
void scc_resubmit(sc_client_t *c, sc_client_job_t *j);

/* client_params.c */
/* The most job options one job sends: the option rows of the table. */
#define SCC_MAX_OPTIONS 32
/* SC_CLIENT_EINVAL, with the reason, for a parameter out of range. */
int scc_check_params(sc_client_t *c, const sc_client_params_t *p);
/* The job options of p that are set, into opts (cap entries); returns how
 * many, in the table's order. */
uint32_t scc_job_options(const sc_client_params_t *p, scp_value_t *opts,
                         uint32_t cap);

/* client_results.c */
/* Calls the job's progress callback; non-zero when it asked to stop. */
int scc_call_progress(sc_client_t *c, sc_client_job_t *j, uint32_t stage,
                      double fraction);
void scc_on_error(sc_client_t *c, const scp_frame_t *f);
/* Carries out one frame from the daemon after the handshake. */
void scc_dispatch(sc_client_t *c, const scp_frame_t *f);

#endif /* SCC_CLIENT_INTERNAL_H */
