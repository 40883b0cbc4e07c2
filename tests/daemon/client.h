/*
 * A small blocking client for the daemon's integration tests, over
 * sc_proto. It checks everything the protocol lets a client check (chunk
 * order, index ranges, JOB_DONE totals, frames for unknown jobs), so that a
 * test only has to look at the results.
 *
 * Writes never deadlock against a server that is writing too: while a
 * client flushes, it reads whatever arrives and queues the frames.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SCDT_CLIENT_H
#define SCDT_CLIENT_H

#include <stddef.h>
#include <stdint.h>

#include "scproto.h"

typedef struct scdt_frame {
  struct scdt_frame *next;
  uint16_t type;
  uint32_t length;
  uint8_t payload[];
} scdt_frame_t;

typedef struct scdt_conn {
  int fd;
  scp_decoder_t *dec;
  scp_buf_t out;
  scp_welcome_t welcome;
  scdt_frame_t *qhead, *qtail; /* frames read, not yet taken */
  int eof;                     /* the server closed (or reset) */
  int dec_err;                 /* the decoder's sticky error */
  /* Feature bits the handshake offers (default none), and with
   * SCP_FEATURE_TOKEN among them the token HELLO carries. */
  uint64_t features;
  const uint8_t *token;
  uint32_t token_len;
  /* The last ERROR frame seen by scdt_collect(). */
  int got_error;
  scp_error_t last_error;
} scdt_conn_t;

/* Connects (no handshake) to a Unix socket at path, or to
 * "tcp://IPV4:PORT". 0 or -errno. */
int scdt_connect(const char *path, scdt_conn_t **out);
/* HELLO with the given versions and frame limit, then waits for WELCOME:
 * 0, the wire code of the ERROR the server answered with (> 0), or -1. */
int scdt_handshake_v(scdt_conn_t *c, uint16_t vmin, uint16_t vmax,
                     uint32_t max_frame, int timeout_ms);
int scdt_handshake(scdt_conn_t *c, uint32_t max_frame);
/* Connect and handshake; 0 or as above. */
int scdt_open(const char *path, uint32_t max_frame, scdt_conn_t **out);
void scdt_close(scdt_conn_t *c);

/* Writes out everything encoded into c->out, reading meanwhile. 0 or -1
 * (the server closed, or timeout). */
int scdt_flush(scdt_conn_t *c, int timeout_ms);
/* Writes raw bytes (after flushing c->out). 0 or -1. */
int scdt_send_raw(scdt_conn_t *c, const void *bytes, size_t len,
                  int timeout_ms);
/* The next frame, or NULL at end of stream (c->eof), on a decoder error
 * (c->dec_err) or after timeout_ms. */
scdt_frame_t *scdt_recv(scdt_conn_t *c, int timeout_ms);
void scdt_frame_view(const scdt_frame_t *f, scp_frame_t *out);
/* Reads until the server closes: 1 when it did within the time, else 0.
 * Frames read meanwhile are dropped, but a fatal ERROR among them is kept
 * in last_error. */
int scdt_wait_closed(scdt_conn_t *c, int timeout_ms);

/* One job, with what came back for it. */
typedef struct scdt_job {
  uint32_t id;
  const double *xyz;
  uint64_t n;
  uint32_t mode;       /* SCP_MODE_COCONE unless set */
  double r;            /* 0.25 */
  uint32_t flags;      /* SCP_JOB_NORMALS ... */
  uint32_t format;     /* SCP_F64_XYZ unless set */
  int declare;         /* send point_count in JOB_BEGIN (default 1) */
  const scp_value_t *options; /* job options for JOB_BEGIN (default none) */
  uint32_t noptions;
  uint64_t sent;       /* points sent so far */

  int accepted;
  int ended;           /* JOB_DONE or JOB_ERROR arrived */
  int done;            /* JOB_DONE */
  uint32_t error_code; /* JOB_ERROR's */
  char error_msg[SCP_MESSAGE_MAX + 1];
  uint32_t *tri;
  uint64_t ntri;
  double *normals;
  uint64_t nnormals;
  double *vertices; /* VERTICES: the smoothed positions */
  uint64_t nvertices;
  int32_t *genus;
  uint64_t ncomp;
  unsigned progress;   /* PROGRESS frames */
  uint64_t diag_triangles; /* "triangles" from JOB_DONE */
  int64_t diag_genus;
  int diag_mostly_unused; /* "mostly_unused" from JOB_DONE; -1 if absent */
} scdt_job_t;

void scdt_job_init(scdt_job_t *j, uint32_t id, const double *xyz, uint64_t n);
/* Frees what came back; the job can be sent again. */
void scdt_job_reset(scdt_job_t *j);

/* Encode and flush: JOB_BEGIN; `count` more points (as many frames as the
 * frame limit needs); JOB_END; CANCEL. 0 or -1. */
int scdt_job_begin(scdt_conn_t *c, scdt_job_t *j);
int scdt_job_points(scdt_conn_t *c, scdt_job_t *j, uint64_t count);
int scdt_job_end(scdt_conn_t *c, scdt_job_t *j);
int scdt_job_cancel(scdt_conn_t *c, scdt_job_t *j);
/* All three. */
int scdt_job_send(scdt_conn_t *c, scdt_job_t *j);

/*
 * Reads frames until every job in jobs[] has ended (JOB_DONE or JOB_ERROR).
 * Returns 0, or -1 with the reason in why: the server broke the protocol
 * (a frame for a job not in jobs[], a chunk out of order, an index out of range, totals that disagree), closed, or took
 * longer than timeout_ms. Non-fatal ERROR frames are kept in last_error;
 * PONG and STATS are dropped.
 */
int scdt_collect(scdt_conn_t *c, scdt_job_t **jobs, size_t njobs,
                 int timeout_ms, char *why, size_t why_len);
/* The same, but returns once the first nwait jobs of jobs[] have ended;
 * the others are in use and may get frames meanwhile. */
int scdt_collect_some(scdt_conn_t *c, scdt_job_t **jobs, size_t njobs,
                      size_t nwait, int timeout_ms, char *why,
                      size_t why_len);

/* STATS_REQUEST on c, then the value called name: 0 or -1. Frames of
 * other kinds that arrive first are dropped. */
int scdt_stat(scdt_conn_t *c, const char *name, uint64_t *value);

/* Milliseconds from a monotonic clock. */
uint64_t scdt_now_ms(void);

#endif /* SCDT_CLIENT_H */
