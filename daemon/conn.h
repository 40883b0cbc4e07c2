/*
 * Internals shared by the files of a connection: conn.c (the connection,
 * its I/O and its frames), jobs.c (job records and how jobs end),
 * job_frames.c (JOB_BEGIN, POINTS, JOB_END, CANCEL) and results.c (meshes,
 * JOB_DONE and progress going out). All of it runs on the loop thread.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SCD_CONN_H
#define SCD_CONN_H

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include "daemon.h"

typedef unsigned long long ull;

/* conn.c */
/* Milliseconds from t0 to t1 (uv_hrtime()), 0 when either is unknown. */
double scd_ms_between(uint64_t t0, uint64_t t1);
void scd_vformat(char *buf, size_t len, const char *fmt, va_list ap);
/* Counts an encoder's result; a failure marks the connection broken. */
int scd_conn_sent(scd_conn_t *c, int rc);
/* A non-fatal ERROR: the request is refused and the connection goes on. */
void scd_conn_reply_error(scd_conn_t *c, uint32_t code, uint32_t job_id,
                          uint16_t ref_type, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));
/* A fatal ERROR, then the connection closes once it is written. */
void scd_conn_fatal(scd_conn_t *c, uint32_t code, uint32_t job_id,
                    uint16_t ref_type, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));
/* A stream or frame error, fatal, with the wire code it maps to. */
void scd_conn_protocol_fatal(scd_conn_t *c, int rc, uint32_t job_id,
                             uint16_t ref_type);
/* Starts writing what is queued, or closes a connection that cannot go
 * on. */
void scd_conn_flush(scd_conn_t *c);

/* jobs.c */
scd_job_t *scd_job_find(scd_conn_t *c, uint32_t id);
/* A new job under id, linked to the connection; NULL when out of memory. */
scd_job_t *scd_job_new(scd_conn_t *c, uint32_t id);
void scd_job_unqueue_send(scd_conn_t *c, scd_job_t *j);
void scd_job_free(scd_conn_t *c, scd_job_t *j);
const char *scd_job_phase_name(int phase);
void scd_job_log(scd_conn_t *c, scd_job_t *j, const char *outcome,
                 const char *detail);
/* An uploading job fails: JOB_ERROR, and the id drains. */
void scd_job_fail_upload(scd_conn_t *c, scd_job_t *j, uint32_t code,
                         const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
/* A job ends for good with JOB_ERROR and its id is free again. */
void scd_job_fail(scd_conn_t *c, scd_job_t *j, uint32_t code,
                  const char *outcome, const char *msg);
/* A JOB_BEGIN under a free id is refused: JOB_ERROR, and the id drains. */
void scd_job_refuse(scd_conn_t *c, uint32_t id, uint32_t code,
                    const char *fmt, ...) __attribute__((format(printf, 4, 5)));
void scd_conn_end_jobs(scd_conn_t *c, const char *why);
/* In a shutdown, a connection with no job left under way closes. */
void scd_conn_check_shutdown(scd_conn_t *c);

/* job_frames.c */
void scd_on_job_begin(scd_conn_t *c, const scp_frame_t *f);
void scd_on_points(scd_conn_t *c, const scp_frame_t *f);
void scd_on_job_end(scd_conn_t *c, const scp_frame_t *f);
void scd_on_cancel(scd_conn_t *c, const scp_frame_t *f);

/* results.c */
/* Emits mesh chunks while the output queue has room. */
void scd_conn_pump(scd_conn_t *c);

#endif /* SCD_CONN_H */
