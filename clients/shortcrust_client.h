/*
 * The shortcrust client library: talks to shortcrustd over its Unix socket
 * or over TCP (proto/PROTOCOL.md) so that a program can have meshes
 * reconstructed
 * without linking the core. Plain C; nothing of libuv, the core or the
 * protocol codec shows through this header.
 *
 * A handle is one connection. Calls block, each for at most the time it is
 * given (poll() underneath), and one handle may carry several jobs at once:
 * submit uploads a job's points and returns, and the results come back
 * while any later call on the handle waits, reads or writes.
 *
 *   sc_client_t *c;
 *   char msg[256];
 *   if (sc_client_connect(NULL, &c, msg, sizeof msg) < 0)   (default socket)
 *     fail(msg);
 *   sc_client_params_t p;  sc_client_params_init(&p);
 *   sc_client_job_t *j;
 *   rc = sc_client_submit(c, &p, xyz, n, &j);
 *   if (rc == 0) rc = sc_client_wait(c, j, -1);
 *   if (rc == 0) { sc_client_mesh_t m; sc_client_job_mesh(j, &m); ... }
 *   else fail(sc_client_job_message(j));
 *   sc_client_job_free(j);
 *   sc_client_free(c);
 *
 * A handle is not thread-safe: use it from one thread at a time. Separate
 * handles are independent, so a program with many threads gives each its
 * own. Callbacks run on the calling thread, inside whichever call on the
 * handle is reading at the time; they must not call functions on the same
 * handle (those return SC_CLIENT_ESTATE), but may read the job they are
 * given.
 *
 * The process must not die of SIGPIPE: the library writes with
 * MSG_NOSIGNAL, so a daemon that goes away shows as SC_CLIENT_ELOST.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SHORTCRUST_CLIENT_H
#define SHORTCRUST_CLIENT_H

#include <stddef.h>
#include <stdint.h>

/* The core's tables of modes and parameters (header only: the client
 * library does not link the core). */
#include "shortcrust.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * Error codes, in a range of their own (-201 to -216) so that a program can
 * report them next to the core's and the file module's codes. Every call
 * that fails returns one; the handle (or the job, for a job's own end)
 * keeps a one-line message that says more.
 */
#define SC_CLIENT_ERRNO_MAP(X)                                                 \
  X(INVAL, -201, "invalid argument")                                           \
  X(NOMEM, -202, "out of memory")                                              \
  X(NODAEMON, -203, "the daemon is not running")                               \
  X(CONNECT, -204, "cannot connect to the daemon")                             \
  X(VERSION, -205, "the daemon speaks another protocol version")               \
  X(PROTOCOL, -206, "the daemon broke the protocol")                           \
  X(TIMEOUT, -207, "timed out")                                                \
  X(LOST, -208, "connection to the daemon lost")                               \
  X(REFUSED, -209, "the daemon refused the job")                               \
  X(FAILED, -210, "the job failed")                                            \
  X(CANCELLED, -211, "the job was cancelled")                                  \
  X(SHUTDOWN, -212, "the daemon is shutting down")                             \
  X(FILE, -213, "cannot read the point file")                                  \
  X(STATE, -214, "call not allowed now")                                       \
  X(LIMIT, -215, "too many jobs in use on this connection")                    \
  X(AUTH, -216, "the daemon refused the token, or there is none to send")

typedef enum sc_client_err {
  SC_CLIENT_OK = 0,
#define SC_CLIENT_ERR_ENUM_(name, value, text) SC_CLIENT_E##name = (value),
  SC_CLIENT_ERRNO_MAP(SC_CLIENT_ERR_ENUM_)
#undef SC_CLIENT_ERR_ENUM_
} sc_client_err_t;

/* A job still under way, as sc_client_job_status() reports it. */
#define SC_CLIENT_PENDING 1

/* A fixed English description of a code; "unknown error" otherwise. */
const char *sc_client_strerror(int code);
/* The code's name without the prefix, e.g. "NODAEMON"; "UNKNOWN" otherwise. */
const char *sc_client_err_name(int code);
/* The name of an error code the daemon sent (PROTOCOL.md section 9), e.g.
 * "DEGENERATE_INPUT"; "UNKNOWN" for codes this version does not know. */
const char *sc_client_server_code_name(uint32_t code);

/* Candidate tests: the core's modes (SC_MODE_MAP), numbered as on the wire
 * (PROTOCOL.md section 4). */
#define SC_CLIENT_MODE_SHORTCRUST SC_MODE_SHORTCRUST
#define SC_CLIENT_MODE_COCONE SC_MODE_COCONE
#define SC_CLIENT_MODE_BOUNDARY SC_MODE_BOUNDARY
#define SC_CLIENT_MODE_WATERTIGHT SC_MODE_WATERTIGHT
#define SC_CLIENT_MODE_AUTO SC_MODE_AUTO

/* Stages of a job for the progress callback: the daemon's six, numbered as
 * in the core (0 input ... 5 extract), and the client's own two. */
#define SC_CLIENT_STAGE_UPLOAD 0x100
#define SC_CLIENT_STAGE_DOWNLOAD 0x101
/* "input", "delaunay", ..., "upload", "download"; "?" otherwise. */
const char *sc_client_stage_name(uint32_t stage);

/* Where sc_client_connect() goes without a path: the daemon's default,
 * $XDG_RUNTIME_DIR/shortcrust.sock when that variable holds an absolute
 * path, else /run/shortcrust/shortcrust.sock. Writes it to buf (truncated
 * to len - 1 characters) and returns buf. */
char *sc_client_default_socket(char *buf, size_t len);

typedef struct sc_client_options {
  /* The daemon's address: a Unix socket's path, "unix://PATH", or
   * "tcp://HOST:PORT" (HOST a name, an IPv4 address or an IPv6 address in
   * brackets); NULL for the default socket above. */
  const char *socket_path;
  /* How long connecting and the handshake may take, and how long a write
   * may wait for the daemon to take more bytes, in milliseconds. A write
   * that waits longer ends the connection (SC_CLIENT_ETIMEOUT). Default
   * 30000; negative for no limit. */
  int io_timeout_ms;
  /* The largest frame this client accepts, in bytes; the handshake may
   * agree on less. Default 1 MiB; at least 4096. */
  uint32_t max_frame;
  /* The token a daemon on TCP requires (PROTOCOL.md 5.1), from the first
   * of: token (a NUL-terminated string), token_file (its one line, the
   * line end not included; the file must be open to its owner only, as
   * the daemon's), the environment variable SHORTCRUST_TOKEN. Sent over
   * TCP only: a Unix socket needs none. Default NULL for both. */
  const char *token;
  const char *token_file;
} sc_client_options_t;

void sc_client_options_init(sc_client_options_t *o);

typedef struct sc_client sc_client_t;
typedef struct sc_client_job sc_client_job_t;

/*
 * Connects and does the handshake. NULL options means the defaults. On
 * success returns 0 and sets *out. On failure returns a negative code,
 * sets *out to NULL and writes a one-line message to msg: SC_CLIENT_ENODAEMON
 * when nothing listens on the socket (no socket file, or a file left over
 * by a daemon that is gone), SC_CLIENT_ECONNECT for other failures to
 * connect (permissions, a path too long), SC_CLIENT_EVERSION when the daemon
 * has no protocol version in common with this library, SC_CLIENT_ESHUTDOWN
 * when it is shutting down, SC_CLIENT_EPROTOCOL for a peer that does not
 * speak the protocol, SC_CLIENT_EAUTH when a daemon on TCP refused the
 * token (or there was none to send, or the token file cannot be used),
 * SC_CLIENT_EINVAL for an address that is not one, SC_CLIENT_ETIMEOUT,
 * SC_CLIENT_ELOST.
 */
int sc_client_connect(const sc_client_options_t *opts, sc_client_t **out,
                      char *msg, size_t msg_len);

/* Closes the connection (the daemon cancels the jobs still running) and
 * frees the handle together with every job of it not yet freed. Accepts
 * NULL. */
void sc_client_free(sc_client_t *c);

/* 0 while the connection is up; once it is gone, the error that ended it
 * (every later call on the handle returns it too). */
int sc_client_status(const sc_client_t *c);

/* The message of the last call on the handle that failed. */
const char *sc_client_last_error(const sc_client_t *c);

/* What the handshake agreed on. */
typedef struct sc_client_info {
  const char *socket_path; /* the address, as given */
  uint32_t version;
  uint32_t max_frame;
  uint32_t max_jobs;   /* jobs in use at once on this connection */
  uint64_t max_points; /* points in one job */
  int job_options;     /* the daemon takes job options (JOB_OPTIONS) */
} sc_client_info_t;

void sc_client_get_info(const sc_client_t *c, sc_client_info_t *out);

/* One named value: a diagnostic of a job, or a counter of the daemon. */
#define SC_CLIENT_U64 1
#define SC_CLIENT_I64 2
#define SC_CLIENT_F64 3
typedef struct sc_client_value {
  char name[64];
  int kind; /* SC_CLIENT_U64, _I64 or _F64; other kinds may come later */
  union {
    uint64_t u;
    int64_t i;
    double f;
  } v;
} sc_client_value_t;

/* The first value called name, or NULL. */
const sc_client_value_t *sc_client_value_find(const sc_client_value_t *v,
                                              size_t count, const char *name);
/* A value as a double whatever its kind; dflt when it is absent. */
double sc_client_value_get(const sc_client_value_t *v, size_t count,
                           const char *name, double dflt);

/*
 * Progress of a job: stage is one of the daemon's stages (0 to 5) or
 * SC_CLIENT_STAGE_UPLOAD or _DOWNLOAD, fraction the part of it done, in
 * [0, 1]. The download fraction is an estimate until the end (the daemon
 * does not say how large the mesh is; two triangles per point, as on a
 * closed surface). Return 0 to go on, non-zero to cancel the job.
 */
typedef int (*sc_client_progress_fn)(void *user, sc_client_job_t *job,
                                     uint32_t stage, double fraction);

/* Which array a mesh chunk belongs to. */
#define SC_CLIENT_TRIANGLES 1  /* data: 3 * count uint32_t */
#define SC_CLIENT_NORMALS 2    /* data: 3 * count double */
#define SC_CLIENT_COMPONENTS 3 /* data: count int32_t, genus or -1 */
#define SC_CLIENT_VERTICES 4   /* data: 3 * count double, smoothed points */

/*
 * A chunk of the mesh as it arrives: elements first .. first + count - 1 of
 * the array, in order without gaps, already checked (triangle indices are
 * below the job's point count). data is valid during the call only. Return
 * 0 to go on, non-zero to cancel the job.
 */
typedef int (*sc_client_chunk_fn)(void *user, sc_client_job_t *job, int array,
                                  uint64_t first, uint32_t count,
                                  const void *data);

typedef struct sc_client_params {
  /* One of SC_CLIENT_MODE_*; default SC_CLIENT_MODE_COCONE. */
  int mode;
  /* The shortcrust parameter, in (0, 0.5); sent in every mode. Default
   * 0.14, as in the core. */
  double r;
  /* Cocone half-width in radians, in (0, pi/2); 0 (default) for the
   * daemon's default, pi/8. */
  double theta;
  /* Non-zero: have the daemon send one normal per point (as doubles). */
  int normals;
  /* Job options (PROTOCOL.md 6.3): one field per row of the core's
   * parameter table (SC_PARAM_MAP in shortcrust.h) that travels as an
   * option, with that row's name, type, range and meaning, in its order:
   * today paper_pruning, max_hole_edges, boundary_rho (in (0, 10]),
   * boundary_alpha (in (0, pi/2] radians), watertight_labels,
   * watertight_patches, denoise,
   * denoise_scale and smoothed_vertices (the mesh's vertices, below). Each is
   * sent only when not left at its "daemon's default" value, which
   * sc_client_params_init() sets: -1 for an integer, 0 for a number or a
   * flag. A daemon that does not take job options gets no job: it ends
   * SC_CLIENT_EREFUSED at once, with code UNSUPPORTED (see
   * sc_client_info_t.job_options). */
#define SC_CLIENT_PARAM_FIELD_OPTION(field, type) type field;
#define SC_CLIENT_PARAM_FIELD_FIXED(field, type)
#define SC_CLIENT_PARAM_FIELD_LOCAL(field, type)
#define SC_CLIENT_PARAM_FIELD_(field, type, kind, dflt, lo, hi, range, text,  \
                               wire, ...)                                      \
  SC_CLIENT_PARAM_FIELD_##wire(field, type)
  SC_PARAM_MAP(SC_CLIENT_PARAM_FIELD_)
  /* Optional. */
  sc_client_progress_fn progress;
  void *progress_user;
  /* With a chunk callback the mesh goes to it and is not kept; without,
   * the job collects it for sc_client_job_mesh(). */
  sc_client_chunk_fn chunk;
  void *chunk_user;
  /*
   * Retries. A job is a pure function of its points and parameters, so a
   * job whose connection is lost before its end (SC_CLIENT_ELOST: the
   * daemon died, a proxy dropped it) or whose daemon shut down
   * (SC_CLIENT_ESHUTDOWN) can be run again: the handle connects anew to
   * the same address (through a balancer, perhaps to another daemon) and
   * submits it again, up to `retries` times, waiting retry_backoff_ms
   * before the first attempt and twice as long before each next one
   * (capped at 10 s). Every job of the handle with retries left goes
   * along; the others end with the error. A failed attempt to connect
   * counts as a retry. sc_client_job_retries() says how many a job took.
   *
   * Default 0 (no retries) and 100 ms. With retries, the points given to
   * sc_client_submit() must stay valid and unchanged until the job has
   * ended (sc_client_submit_file() keeps its own), and the callbacks may
   * see the job again from the start: progress from the upload on, and
   * chunks from the first one.
   */
  int retries;
  int retry_backoff_ms;
} sc_client_params_t;

void sc_client_params_init(sc_client_params_t *p);

/*
 * Starts a job of n points (xyz: 3n doubles) and uploads them, in chunks
 * as large as a frame allows, exactly: as floats (F32_XYZ) when every
 * coordinate is exactly a float, as doubles otherwise. Returns once every point
 * is written, or earlier when the job ends before (refused, cancelled);
 * the points are not used after that. The job is then under way: wait for
 * it with sc_client_wait() or sc_client_wait_any(), and free it with
 * sc_client_job_free().
 *
 * Returns 0 with *job set, or a negative code with *job NULL:
 * SC_CLIENT_EINVAL for parameters out of range (with the reason in
 * sc_client_last_error()), SC_CLIENT_ELIMIT when max_jobs jobs are in use
 * on the connection (wait for one first), SC_CLIENT_ELOST and the other
 * connection errors. A job the daemon refuses or that fails during the
 * upload is not an error of this call: it returns 0, and the job's status
 * says what happened. So does a job of more points than the daemon takes
 * (WELCOME's max_points), which is refused here without sending anything.
 */
int sc_client_submit(sc_client_t *c, const sc_client_params_t *params,
                     const double *xyz, uint64_t n, sc_client_job_t **job);

/*
 * The same for the points of a file, read by the point-file module (every
 * input format of `shortcrust reconstruct`). The job keeps the points
 * (sc_client_job_points()). A file that cannot be read gives
 * SC_CLIENT_EFILE, with the reader's message in sc_client_last_error().
 */
int sc_client_submit_file(sc_client_t *c, const sc_client_params_t *params,
                          const char *path, sc_client_job_t **job);

/*
 * Reads and dispatches what the daemon sends until the job has ended or
 * timeout_ms pass (negative: no limit). Returns the job's status: 0 when
 * it is done, or its error; SC_CLIENT_ETIMEOUT when the time ran out (the
 * job goes on, and may be waited for again).
 */
int sc_client_wait(sc_client_t *c, sc_client_job_t *job, int timeout_ms);

/*
 * Waits until some job of the handle has ended that no wait call has
 * returned yet, and sets *job to it (jobs in the order they ended).
 * Returns that job's status, SC_CLIENT_ETIMEOUT (*job NULL), or
 * SC_CLIENT_ESTATE when the handle has no job under way or unreported.
 */
int sc_client_wait_any(sc_client_t *c, int timeout_ms, sc_client_job_t **job);

/*
 * Asks the daemon to stop the job, and returns 0 once the request is
 * written. The job then ends with SC_CLIENT_ECANCELLED, even when its
 * result crossed the request on the wire: what arrives for a job after it
 * was cancelled is dropped. Cancelling a job that has ended does nothing.
 */
int sc_client_cancel(sc_client_t *c, sc_client_job_t *job);

/* Jobs the handle has in use (submitted and not yet ended). */
unsigned sc_client_jobs_in_use(const sc_client_t *c);

/* The job's status: SC_CLIENT_PENDING while under way, 0 when done, or the
 * negative code it ended with. */
int sc_client_job_status(const sc_client_job_t *job);
/* What went wrong, one line ("" while under way or when done). For an
 * error the daemon reported, its code name and message. */
const char *sc_client_job_message(const sc_client_job_t *job);
/* The daemon's error code for a job it refused or that failed on it
 * (PROTOCOL.md section 9; sc_client_server_code_name() names it), else 0. */
uint32_t sc_client_job_server_code(const sc_client_job_t *job);
/* How many times the job was submitted again after losing its connection
 * (sc_client_params_t.retries): 0 when its first run ended it. */
unsigned sc_client_job_retries(const sc_client_job_t *job);
/* The points of a job submitted from a file (3 * *n doubles), else NULL. */
const double *sc_client_job_points(const sc_client_job_t *job, uint64_t *n);

/* A finished job's mesh, and its times. */
typedef struct sc_client_mesh {
  uint64_t point_count;
  /* 3 * triangle_count indices into the job's points; NULL when a chunk
   * callback took them. The counts are right either way. */
  const uint32_t *triangles;
  uint64_t triangle_count;
  const double *normals; /* 3 * normal_count, when asked for */
  uint64_t normal_count;
  /* With smoothed_vertices, when the daemon denoised the job (its value
   * "denoised" is 1): the smoothed position of every point, 3 *
   * vertex_count doubles (vertex_count = point_count), to use as the
   * mesh's vertices (NULL, as the triangles, when a chunk callback took
   * them); otherwise NULL and 0. */
  const double *vertices;
  uint64_t vertex_count;
  const int32_t *genus; /* per component, -1 for one with boundary */
  uint64_t component_count;
  /* The daemon's diagnostics (PROTOCOL.md section 6.12). */
  const sc_client_value_t *values;
  size_t value_count;
  /* Seconds: the upload, from submit until the last point was written;
   * the download, from the first mesh chunk until the end; and the whole
   * job, from submit until the end. */
  double seconds_upload;
  double seconds_download;
  double seconds_total;
} sc_client_mesh_t;

/* Fills *out for a job that is done and returns 0; otherwise returns the
 * job's status and leaves *out zeroed. Valid until the job is freed. */
int sc_client_job_mesh(const sc_client_job_t *job, sc_client_mesh_t *out);

/* Frees a job. A job still under way is cancelled first; the handle keeps
 * what it needs to follow it to its end. Accepts NULL. */
void sc_client_job_free(sc_client_job_t *job);

/* PING, and the round trip in seconds (rtt may be NULL). */
int sc_client_ping(sc_client_t *c, int timeout_ms, double *rtt);

/* The daemon's counters (STATS): *values is malloc'd, *count entries; the
 * caller frees it with free(). */
int sc_client_stats(sc_client_t *c, int timeout_ms, sc_client_value_t **values,
                    size_t *count);

#ifdef __cplusplus
}
#endif

#endif /* SHORTCRUST_CLIENT_H */
