/*
 * scproto: the shortcrust wire protocol (proto/PROTOCOL.md) in plain C.
 *
 * This module does no I/O. The caller reads bytes from its socket and feeds
 * them to a decoder, which hands back whole frames; scp_parse_*() turn a
 * frame's payload into a typed struct after checking every field. Encoders
 * append whole frames to a growable buffer that the caller writes out.
 *
 * A server, per connection:
 *
 *   scp_limits_t lim;  scp_limits_init(&lim);  lim.role = SCP_ROLE_SERVER;
 *   scp_decoder_t *d = scp_decoder_new(&lim);
 *   scp_buf_t out;  scp_buf_init(&out, 0);
 *   on read:  scp_decoder_feed(d, bytes, n);
 *     while ((rc = scp_decoder_next(d, &frame)) == 1) {
 *       prc = scp_parse_as(&frame, SCP_ROLE_SERVER, &msg);
 *       if (prc < 0 && scp_err_is_fatal(prc))  fatal ERROR, close
 *       else if (prc < 0)  ERROR or JOB_ERROR with scp_err_to_wire(prc),
 *                          naming scp_frame_job_id() (PROTOCOL.md 7.3, 8.3)
 *       else switch (msg.type) ...
 *     }
 *     if (rc < 0)  fatal ERROR with scp_err_to_wire(rc), close
 *   HELLO:  scp_handshake_answer(&msg.u.hello, &mine, &w);
 *           scp_enc_welcome(&out, &w);  out.max_frame = w.max_frame;
 *           scp_decoder_set_max_frame(d, w.max_frame);
 *   mesh:   while (scp_enc_mesh_next(&out, &view, &cursor) == 1) flush;
 *           scp_enc_job_done(&out, &done, values, n);
 *
 * A client is the same with SCP_ROLE_CLIENT: scp_enc_hello() first, then
 * scp_handshake_check() on WELCOME before raising both limits, POINTS with
 * scp_enc_points_next(), and any error from the server is fatal.
 *
 * Every function that can fail returns 0 (or a count, where documented) or
 * a negative SCP_E* code; scp_strerror() and scp_err_name() describe them.
 * Nothing here keeps global state; distinct objects may be used from
 * distinct threads at once.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SCPROTO_H
#define SCPROTO_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The version this library speaks, and the bytes that open a handshake. */
#define SCP_VERSION 1
#define SCP_MAGIC "SCRU"
#define SCP_MAGIC_LEN 4

/* Every frame starts with an 8-byte header: u16 type, u16 flags, u32 length. */
#define SCP_HEADER_SIZE 8
/* The frame size limit until the handshake is done, and the smallest limit a
 * handshake may agree on. */
#define SCP_FRAME_MIN 4096u
/* The largest frame size limit the protocol allows. */
#define SCP_FRAME_CEILING (1u << 30)
/* Longest message text in ERROR and JOB_ERROR, in bytes. */
#define SCP_MESSAGE_MAX 1024
/* Longest name in a value list, in bytes. */
#define SCP_NAME_MAX 63
/* Fixed part of every chunk frame (POINTS, TRIANGLES, NORMALS, VERTICES,
 * COMPONENTS). */
#define SCP_CHUNK_HEADER 24
/* Fixed part of JOB_BEGIN; job options follow it, where the JOB_OPTIONS
 * feature is in force, from byte SCP_JOB_BEGIN_FIXED + 8 on. */
#define SCP_JOB_BEGIN_FIXED 40

/*
 * Error codes of this library. Each row gives the name, the value, the wire
 * code (section 9 of PROTOCOL.md) a receiver sends when a frame from its
 * peer fails this way, whether that error is fatal for the connection
 * (section 8.2: the receiver sends a fatal ERROR and closes), and a message.
 */
#define SCP_ERRNO_MAP(X)                                                       \
  X(INVAL, -1, INTERNAL, 1, "invalid argument")                                \
  X(NOMEM, -2, NO_MEMORY, 1, "out of memory")                                  \
  X(TOOBIG, -3, LIMIT, 1, "frame larger than the frame size limit")            \
  X(RESERVED, -4, PROTOCOL, 1, "a reserved field or header flag is not zero")  \
  X(BADMAGIC, -5, PROTOCOL, 1,                                                 \
    "bad magic: the peer does not speak this protocol")                        \
  X(HANDSHAKE, -6, PROTOCOL, 1,                                                \
    "handshake frame missing at the start or repeated later")                  \
  X(VERSION, -7, VERSION, 1, "no protocol version in common")                  \
  X(TRUNCATED, -8, PROTOCOL, 1, "the stream ended inside a frame")             \
  X(SHORT, -9, PROTOCOL, 1, "payload shorter than its message's fixed part")   \
  X(LENGTH, -10, PROTOCOL, 1,                                                  \
    "payload length disagrees with the counts or lengths it carries")          \
  X(UNKNOWN_TYPE, -11, UNKNOWN_TYPE, 0, "unknown frame type")                  \
  X(RANGE, -12, INVALID, 0, "a field is out of range")                         \
  X(FLAGS, -13, INVALID, 0, "unknown flag bits are set")

typedef enum scp_err {
  SCP_OK = 0,
#define SCP_ERR_ENUM_(name, value, wire, fatal, msg) SCP_E##name = (value),
  SCP_ERRNO_MAP(SCP_ERR_ENUM_)
#undef SCP_ERR_ENUM_
} scp_err_t;

/* A fixed English message for a code; "unknown error" for other values. */
const char *scp_strerror(int code);
/* The code's name without the prefix, e.g. "TOOBIG"; "UNKNOWN" otherwise. */
const char *scp_err_name(int code);
/* The wire code to put in the ERROR or JOB_ERROR that answers a frame which
 * failed with this library code; SCP_WIRE_INTERNAL for unknown codes. */
uint32_t scp_err_to_wire(int code);
/* 1 when a frame failing with this code must cost the connection (a fatal
 * ERROR, then close), 0 when an error reply is enough. This is the server's
 * view of a client frame after the handshake; during the handshake, and in
 * a client reading the server, every error is fatal (PROTOCOL.md 5, 6.1). */
int scp_err_is_fatal(int code);

/* Wire error codes, PROTOCOL.md section 9. */
#define SCP_WIRE_MAP(X)                                                        \
  X(PROTOCOL, 1, "malformed frame or protocol violation")                      \
  X(VERSION, 2, "no protocol version in common")                               \
  X(UNKNOWN_TYPE, 3, "unknown frame type")                                     \
  X(INVALID, 4, "invalid field in a request")                                  \
  X(UNKNOWN_JOB, 5, "no job with this id")                                     \
  X(DUPLICATE_JOB, 6, "job id already in use")                                 \
  X(STATE, 7, "not allowed in the job's current state")                        \
  X(LIMIT, 8, "a limit from the handshake was exceeded")                       \
  X(UNSUPPORTED, 9, "mode or option not supported by this server")             \
  X(BUSY, 10, "server busy; try later")                                        \
  X(NO_MEMORY, 11, "server out of memory for this job")                        \
  X(CANCELLED, 12, "cancelled")                                                \
  X(SHUTDOWN, 13, "server shutting down")                                      \
  X(TIMEOUT, 14, "timed out")                                                  \
  X(DEGENERATE_INPUT, 15,                                                      \
    "degenerate input: fewer than 4 distinct points, or all coplanar")         \
  X(NONFINITE, 16, "non-finite coordinate (NaN or Inf) in the input")          \
  X(INTERNAL, 17, "internal error")                                            \
  X(AUTH, 18, "authentication failed: wrong or missing token")

typedef enum scp_wire_err {
#define SCP_WIRE_ENUM_(name, value, msg) SCP_WIRE_##name = (value),
  SCP_WIRE_MAP(SCP_WIRE_ENUM_)
#undef SCP_WIRE_ENUM_
} scp_wire_err_t;

/* Message and name of a wire code; "unknown error" and "UNKNOWN" for codes
 * this version does not define, which a peer must still accept. */
const char *scp_wire_strerror(uint32_t code);
const char *scp_wire_name(uint32_t code);

/* Frame types, PROTOCOL.md section 3.2. */
typedef enum scp_type {
  SCP_HELLO = 0x0001,
  SCP_WELCOME = 0x0002,
  SCP_ERROR = 0x0003,
  SCP_PING = 0x0004,
  SCP_PONG = 0x0005,
  SCP_JOB_BEGIN = 0x0010,
  SCP_POINTS = 0x0011,
  SCP_JOB_END = 0x0012,
  SCP_CANCEL = 0x0013,
  SCP_STATS_REQUEST = 0x0014,
  SCP_ACCEPTED = 0x0020,
  SCP_PROGRESS = 0x0021,
  SCP_TRIANGLES = 0x0022,
  SCP_NORMALS = 0x0023,
  SCP_COMPONENTS = 0x0024,
  SCP_JOB_DONE = 0x0025,
  SCP_JOB_ERROR = 0x0026,
  SCP_STATS = 0x0027,
  /* Ignorable (below): a client that does not know it, or did not ask for
   * the smoothed positions, loses nothing by skipping it. */
  SCP_VERTICES = 0x8001
} scp_type_t;

/* Types with this bit are skipped silently by a receiver that does not know
 * them, or that is not the side they go to; other unknown types earn an
 * ERROR UNKNOWN_TYPE. */
#define SCP_TYPE_IGNORABLE 0x8000u

/* Who may send a type: a mask of these, or 0 for a type version 1 lacks. */
#define SCP_FROM_CLIENT 1
#define SCP_FROM_SERVER 2
int scp_type_senders(uint16_t type);
/* Upper-case name of a type ("JOB_BEGIN"); "?" for unknown types. */
const char *scp_type_name(uint16_t type);

/* Modes, numbered like sc_mode_t in core/shortcrust.h (this module does not
 * see the core; the daemon, which sees both, checks at compile time that
 * they agree). A server may refuse a mode it lacks with UNSUPPORTED. */
typedef enum scp_mode {
  SCP_MODE_SHORTCRUST = 0,
  SCP_MODE_COCONE = 1,
  SCP_MODE_BOUNDARY = 2,
  SCP_MODE_WATERTIGHT = 3,
  SCP_MODE_AUTO = 4,
  SCP_MODE_COUNT = 5
} scp_mode_t;
/* Lower-case name of a mode; "?" when out of range. */
const char *scp_mode_name(uint32_t mode);

/* Stages, numbered like sc_stage_t. UPLOAD and DOWNLOAD are for a client's
 * own progress display; they never appear on the wire, and the encoder
 * refuses them. */
typedef enum scp_stage {
  SCP_STAGE_INPUT = 0,
  SCP_STAGE_DELAUNAY = 1,
  SCP_STAGE_POLES = 2,
  SCP_STAGE_CANDIDATES = 3,
  SCP_STAGE_PRUNE = 4,
  SCP_STAGE_EXTRACT = 5,
  SCP_STAGE_COUNT = 6,
  SCP_STAGE_UPLOAD = 0x100,
  SCP_STAGE_DOWNLOAD = 0x101
} scp_stage_t;
/* Lower-case name of a stage, local ones included; "?" otherwise. */
const char *scp_stage_name(uint32_t stage);

/* Where a daemon listens and a client connects when not told otherwise:
 * $XDG_RUNTIME_DIR/shortcrust.sock when that variable holds an absolute
 * path, else /run/shortcrust/shortcrust.sock (the system service's). Writes
 * the path into buf (cut to len - 1 bytes) and returns buf. */
char *scp_default_socket(char *buf, size_t len);

/*
 * Addresses, as the daemon's --listen and a client's --connect take them
 * (PROTOCOL.md 2): "unix://PATH" or a plain PATH (no "://" in it) for a
 * Unix socket, "tcp://HOST:PORT" for TCP, HOST a name, an IPv4 address or
 * an IPv6 address in brackets ("tcp://[::1]:7341"). PORT is 0 to 65535; 0
 * lets a listener choose one.
 */
typedef enum scp_addr_kind {
  SCP_ADDR_UNIX = 1,
  SCP_ADDR_TCP = 2
} scp_addr_kind_t;
/* sun_path of Linux: the longest path is one byte less. */
#define SCP_ADDR_PATH_MAX 108
#define SCP_ADDR_HOST_MAX 255
typedef struct scp_address {
  int kind;                         /* scp_addr_kind_t */
  char path[SCP_ADDR_PATH_MAX];     /* SCP_ADDR_UNIX */
  char host[SCP_ADDR_HOST_MAX + 1]; /* SCP_ADDR_TCP, without brackets */
  uint16_t port;                    /* SCP_ADDR_TCP */
} scp_address_t;
/* 0 with *out filled; SCP_ERANGE for text that is not an address (an
 * unknown scheme, an empty or too long path or host, a bad port), and
 * SCP_EINVAL for NULL. */
int scp_address_parse(const char *text, scp_address_t *out);
/* The address as text ("unix://PATH", "tcp://HOST:PORT", brackets around an
 * IPv6 host), cut to len - 1 bytes; returns buf. */
char *scp_address_format(const scp_address_t *a, char *buf, size_t len);

/* A size in bytes as the daemon's --memory-budget and the command's
 * --memory-limit take it: digits, then optionally K, M, G or T (powers of
 * 1024; k too), optionally followed by B or iB ("512M", "2GiB"); with a
 * unit, the digits may have a fraction ("24.5M", "1.5G": rounded up to
 * the byte, to a millionth of the unit). 0 with *out set (never 0 bytes);
 * SCP_ERANGE for anything else, an overflow included; SCP_EINVAL for
 * NULL. */
int scp_bytes_parse(const char *text, uint64_t *out);

/* Element formats of chunk frames. */
typedef enum scp_format {
  SCP_F32_XYZ = 1,
  SCP_F64_XYZ = 2,
  SCP_U32_TRIANGLE = 3,
  SCP_I32 = 4
} scp_format_t;
/* Bytes per element of a format; 0 for an unknown format. */
size_t scp_format_size(uint32_t format);

/* Feature bits (PROTOCOL.md 5). JOB_OPTIONS: JOB_BEGIN may carry job
 * options after its fixed part. TOKEN: HELLO carries the token field after
 * its fixed part (a shared secret; a server that listens on TCP requires
 * it there). */
#define SCP_FEATURE_JOB_OPTIONS 0x1u
#define SCP_FEATURE_TOKEN 0x2u
/* Fixed part of HELLO, and where the token field starts with TOKEN. */
#define SCP_HELLO_FIXED 24
/* The longest token HELLO carries, in bytes: the handshake's frames stay
 * within SCP_FRAME_MIN. */
#define SCP_TOKEN_MAX 1024
/* Job options (PROTOCOL.md 6.3) are named by the reconstruction's
 * parameter table (SC_PARAM_MAP in core/shortcrust.h), which this module
 * does not see: it carries them as a value list. */

/* JOB_BEGIN flags. */
#define SCP_JOB_NORMALS 0x1u
#define SCP_JOB_NORMALS_F64 0x2u
/* ERROR flags. */
#define SCP_ERROR_FATAL 0x1u

/* Kinds of entries in value lists. */
typedef enum scp_kind {
  SCP_KIND_U64 = 1,
  SCP_KIND_I64 = 2,
  SCP_KIND_F64 = 3
} scp_kind_t;

/* Message structs. Each one both feeds its encoder and receives what its
 * parser found; the comments give the ranges the parser checks. */

typedef struct scp_hello {
  uint16_t version_min; /* >= 1 */
  uint16_t version_max; /* >= version_min */
  uint64_t features;    /* any bits */
  uint32_t max_frame;   /* >= SCP_FRAME_MIN */
  /* With SCP_FEATURE_TOKEN in features: the token, token_len bytes (at
   * most SCP_TOKEN_MAX, 0 for none), any bytes. The parser points into the
   * payload; the encoder sends them. Without the bit both are ignored. */
  const uint8_t *token;
  uint32_t token_len;
} scp_hello_t;

typedef struct scp_welcome {
  uint16_t version;     /* == SCP_VERSION */
  uint64_t features;    /* any bits */
  uint32_t max_frame;   /* in [SCP_FRAME_MIN, SCP_FRAME_CEILING] */
  uint32_t max_jobs;    /* >= 1 */
  uint64_t max_points;  /* >= 1 */
} scp_welcome_t;

/* ERROR. The message is kept NUL-terminated in the struct: the encoder
 * sends strlen(message) bytes, and the parser copies the text in. */
typedef struct scp_error {
  uint32_t code;        /* != 0; unknown codes are accepted */
  uint32_t flags;       /* SCP_ERROR_FATAL or 0 */
  uint32_t job_id;      /* 0 when no job */
  uint16_t ref_type;    /* type of the offending frame, or 0 */
  char message[SCP_MESSAGE_MAX + 1];
} scp_error_t;

/* A value list as a view into a payload (see scp_values_begin() below). */
typedef struct scp_values scp_values_t;
struct scp_values {
  uint32_t count;
  const uint8_t *data;
  size_t len;
};

typedef struct scp_job_begin {
  uint32_t job_id;      /* != 0 */
  uint32_t mode;        /* < SCP_MODE_COUNT */
  double r;             /* finite, in (0, 0.5) */
  double theta;         /* 0, or in (0, pi/2) */
  uint64_t point_count; /* 0 when unknown */
  uint32_t flags;       /* SCP_JOB_NORMALS, SCP_JOB_NORMALS_F64 (needs the
                           former) */
  /* Job options (PROTOCOL.md 6.3), only where SCP_FEATURE_JOB_OPTIONS is
   * in force: count 0 for none, else at least one entry. The parser fills
   * it with a view into the payload; scp_enc_job_begin() sends such a view
   * as it is, scp_enc_job_begin_options() an array. */
  scp_values_t options;
} scp_job_begin_t;

typedef struct scp_job_end {
  uint32_t job_id;      /* != 0 */
  uint64_t point_count; /* points sent in total */
} scp_job_end_t;

typedef struct scp_accepted {
  uint32_t job_id;      /* != 0 */
  uint32_t queue_position;
} scp_accepted_t;

typedef struct scp_progress {
  uint32_t job_id;      /* != 0 */
  uint32_t stage;       /* < SCP_STAGE_COUNT */
  double fraction;      /* finite, in [0, 1] */
} scp_progress_t;

/*
 * A chunk frame, parsed: a view into the frame's payload, valid as long as
 * the frame is. The elements are read through the accessors below, which
 * load them byte by byte, so the payload needs no particular alignment.
 */
typedef struct scp_chunk {
  uint16_t type;        /* SCP_POINTS, SCP_TRIANGLES, SCP_NORMALS,
                           SCP_VERTICES or SCP_COMPONENTS */
  uint32_t job_id;      /* != 0 */
  uint32_t count;       /* >= 1 */
  uint64_t first;       /* first + count does not overflow */
  uint32_t format;      /* allowed for the type */
  const uint8_t *data;  /* count * scp_format_size(format) bytes */
} scp_chunk_t;

/* Element i (< count) of an F32_XYZ or F64_XYZ chunk, as doubles. */
void scp_chunk_xyz(const scp_chunk_t *c, uint32_t i, double out[3]);
/* Element i of an F32_XYZ chunk, bit for bit. */
void scp_chunk_xyz_f32(const scp_chunk_t *c, uint32_t i, float out[3]);
/* Element i of a U32_TRIANGLE chunk. */
void scp_chunk_triangle(const scp_chunk_t *c, uint32_t i, uint32_t out[3]);
/* Element i of an I32 chunk. */
int32_t scp_chunk_i32(const scp_chunk_t *c, uint32_t i);
/* All elements at once: 3 * count doubles (F32_XYZ or F64_XYZ), 3 * count
 * uint32_t (U32_TRIANGLE), count int32_t (I32). SCP_EINVAL for a format
 * that does not match the destination type. */
int scp_chunk_copy_xyz(const scp_chunk_t *c, double *out);
int scp_chunk_copy_triangles(const scp_chunk_t *c, uint32_t *out);
int scp_chunk_copy_i32(const scp_chunk_t *c, int32_t *out);

/* One entry of a value list. */
typedef struct scp_value {
  const char *name;     /* NUL-terminated; see PROTOCOL.md 6.11 */
  uint32_t kind;        /* scp_kind_t; unknown kinds arrive as they are */
  union {
    uint64_t u;
    int64_t i;
    double f;
  } v;
} scp_value_t;

/* A parsed value list (struct scp_values above): a view into the payload,
 * already checked entry by entry. Read it with
 * scp_values_begin()/scp_values_next(). */

typedef struct scp_value_iter {
  const uint8_t *p;
  const uint8_t *end;
  uint32_t left;
  char name[SCP_NAME_MAX + 1];
} scp_value_iter_t;

void scp_values_begin(const scp_values_t *values, scp_value_iter_t *it);
/* Fills *out with the next entry and returns 1, or returns 0 at the end.
 * out->name points into the iterator and is overwritten by the next call. */
int scp_values_next(scp_value_iter_t *it, scp_value_t *out);
/* Finds the first entry called name: 1 and *out filled, or 0. out->name
 * points into the iterator it, which the caller provides. */
int scp_values_find(const scp_values_t *values, const char *name,
                    scp_value_iter_t *it, scp_value_t *out);

/* JOB_DONE. scp_enc_job_done() takes the values as an array and ignores
 * .values; the parser fills .values with a view into the payload, and
 * scp_enc_msg() sends such a view as it is. */
typedef struct scp_job_done {
  uint32_t job_id;      /* != 0 */
  uint64_t triangles;
  uint64_t normals;
  uint64_t components;
  scp_values_t values;
} scp_job_done_t;

typedef struct scp_job_error {
  uint32_t job_id;      /* != 0 */
  uint32_t code;        /* != 0; unknown codes are accepted */
  char message[SCP_MESSAGE_MAX + 1];
} scp_job_error_t;

/* STATS; .values as in JOB_DONE. */
typedef struct scp_stats {
  uint32_t tag;
  scp_values_t values;
} scp_stats_t;

/*
 * A growable output buffer. Every encoder appends one or more whole frames
 * to it, refusing (SCP_ETOOBIG) any frame larger than max_frame, and on any
 * error leaves the buffer as it was.
 */
typedef struct scp_buf {
  uint8_t *data;
  size_t len;
  size_t cap;
  /* The frame size limit in force: SCP_FRAME_MIN until the handshake is
   * done, WELCOME's max_frame afterwards. */
  uint32_t max_frame;
} scp_buf_t;

/* Empty buffer with the given frame limit; 0 means SCP_FRAME_MIN. */
void scp_buf_init(scp_buf_t *b, uint32_t max_frame);
/* Frees the bytes and leaves an empty buffer with the same limit. Accepts
 * NULL. */
void scp_buf_free(scp_buf_t *b);
/* Drops the first n bytes (for example once they are written out). */
void scp_buf_consume(scp_buf_t *b, size_t n);

int scp_enc_hello(scp_buf_t *b, const scp_hello_t *m);
int scp_enc_welcome(scp_buf_t *b, const scp_welcome_t *m);
int scp_enc_error(scp_buf_t *b, const scp_error_t *m);
int scp_enc_ping(scp_buf_t *b, uint64_t token);
int scp_enc_pong(scp_buf_t *b, uint64_t token);
int scp_enc_job_begin(scp_buf_t *b, const scp_job_begin_t *m);
/* JOB_BEGIN with the options given as an array (m->options is ignored);
 * with count 0, the same as scp_enc_job_begin() without options. The names
 * must differ from each other, as in scp_enc_job_done(). */
int scp_enc_job_begin_options(scp_buf_t *b, const scp_job_begin_t *m,
                              const scp_value_t *options, uint32_t count);
int scp_enc_job_end(scp_buf_t *b, const scp_job_end_t *m);
int scp_enc_cancel(scp_buf_t *b, uint32_t job_id);
int scp_enc_stats_request(scp_buf_t *b, uint32_t tag);
int scp_enc_accepted(scp_buf_t *b, const scp_accepted_t *m);
int scp_enc_progress(scp_buf_t *b, const scp_progress_t *m);
/* The names in values must differ from each other (PROTOCOL.md 6.11); the
 * encoder checks each name's spelling but not that they are distinct. */
int scp_enc_job_done(scp_buf_t *b, const scp_job_done_t *m,
                     const scp_value_t *values, uint32_t value_count);
int scp_enc_job_error(scp_buf_t *b, const scp_job_error_t *m);
int scp_enc_stats(scp_buf_t *b, uint32_t tag, const scp_value_t *values,
                  uint32_t value_count);

/* One chunk frame of exactly count elements (which must fit in
 * b->max_frame). POINTS and NORMALS take format SCP_F32_XYZ (the doubles
 * are rounded to float) or SCP_F64_XYZ; VERTICES are always SCP_F64_XYZ. */
int scp_enc_points(scp_buf_t *b, uint32_t job_id, uint64_t first,
                   uint32_t format, const double *xyz, uint32_t count);
int scp_enc_points_f32(scp_buf_t *b, uint32_t job_id, uint64_t first,
                       const float *xyz, uint32_t count);
int scp_enc_normals(scp_buf_t *b, uint32_t job_id, uint64_t first,
                    uint32_t format, const double *xyz, uint32_t count);
int scp_enc_vertices(scp_buf_t *b, uint32_t job_id, uint64_t first,
                     const double *xyz, uint32_t count);
int scp_enc_triangles(scp_buf_t *b, uint32_t job_id, uint64_t first,
                      const uint32_t *tri, uint32_t count);
int scp_enc_components(scp_buf_t *b, uint32_t job_id, uint64_t first,
                       const int32_t *genus, uint32_t count);
/* Any chunk from a view whose data is already in wire form (little-endian
 * elements of c->format), copied as it is; for example a chunk just parsed,
 * or a little-endian host's own array of uint32_t triangles. */
int scp_enc_chunk(scp_buf_t *b, const scp_chunk_t *c);

/* The most elements of a format that one frame of size max_frame holds;
 * 0 for an unknown format or a limit below SCP_FRAME_MIN. */
uint32_t scp_chunk_capacity(uint32_t format, uint32_t max_frame);

/*
 * Splitting helpers. Each call appends the next chunk, as large as
 * b->max_frame allows, and advances *next past it: it returns 1 when it
 * appended a frame and 0 when nothing was left. The caller can flush the
 * buffer between calls to keep its size down:
 *
 *   uint64_t next = 0;
 *   while ((rc = scp_enc_points_next(&b, id, SCP_F64_XYZ, xyz, n, &next)) == 1)
 *     ... write b out when it is large ...
 */
int scp_enc_points_next(scp_buf_t *b, uint32_t job_id, uint32_t format,
                        const double *xyz, uint64_t total, uint64_t *next);

/* A finished mesh as the server holds it. normals and vertices may be NULL
 * (then their counts are ignored); genus may be NULL when component_count
 * is 0. */
typedef struct scp_mesh_view {
  uint32_t job_id;
  const uint32_t *triangles;   /* 3 * triangle_count */
  uint64_t triangle_count;
  const double *normals;       /* 3 * normal_count */
  uint64_t normal_count;
  uint32_t normal_format;      /* SCP_F32_XYZ or SCP_F64_XYZ */
  const double *vertices;      /* 3 * vertex_count, sent as SCP_F64_XYZ */
  uint64_t vertex_count;
  const int32_t *genus;        /* component_count */
  uint64_t component_count;
} scp_mesh_view_t;

/* Where scp_enc_mesh_next() is in a mesh; start from all zeros. */
typedef struct scp_mesh_cursor {
  uint64_t triangles;
  uint64_t normals;
  uint64_t vertices;
  uint64_t components;
} scp_mesh_cursor_t;

/* Appends the mesh's next chunk: all TRIANGLES first, then NORMALS, then
 * VERTICES, then COMPONENTS. Returns 1 when it appended a frame, 0 when the
 * mesh is all sent (JOB_DONE is the caller's to send), or a negative code. */
int scp_enc_mesh_next(scp_buf_t *b, const scp_mesh_view_t *m,
                      scp_mesh_cursor_t *c);

/* A frame out of the decoder. payload points into the decoder and stays
 * valid until the next call of scp_decoder_next(), scp_decoder_feed() or
 * scp_decoder_free() on it. */
typedef struct scp_frame {
  uint16_t type;
  uint32_t length;
  const uint8_t *payload;
} scp_frame_t;

/* Which side the decoder reads for: SCP_ROLE_SERVER decodes what a client
 * sends, so the first frame must be HELLO; SCP_ROLE_CLIENT decodes what a
 * server sends, so it takes only WELCOME or ERROR until WELCOME. In both
 * roles HELLO or WELCOME after the handshake is an error. SCP_ROLE_ANY
 * skips these checks (tests, tools that read captured streams). Frames that
 * travel the wrong way (TRIANGLES to a server) are returned like any other;
 * scp_parse_as() reports them as unknown types. */
typedef enum scp_role {
  SCP_ROLE_ANY = 0,
  SCP_ROLE_SERVER = 1,
  SCP_ROLE_CLIENT = 2
} scp_role_t;

typedef struct scp_limits {
  /* The frame size limit in force, header included. Default SCP_FRAME_MIN;
   * raise it with scp_decoder_set_max_frame() after the handshake. */
  uint32_t max_frame;
  /* Default SCP_ROLE_ANY. */
  int role;
} scp_limits_t;

/* Fills *l with the defaults. */
void scp_limits_init(scp_limits_t *l);

/*
 * The incremental decoder. Feed it bytes split anywhere; it returns whole
 * frames. scp_decoder_next() checks each header as soon as its eight bytes
 * are in, before it waits for the payload: the type against the role
 * (SCP_EHANDSHAKE), the flags (SCP_ERESERVED), and the length against the
 * frame size limit in force (SCP_ETOOBIG); a handshake frame's magic is
 * checked as soon as its first four payload bytes are in (SCP_EBADMAGIC).
 * The payload itself is not parsed here; that is scp_parse_*()'s job.
 *
 * Frames of an ignorable type (0x8000 and above) that this version does
 * not know, or that the other side of the role sends (VERTICES to a
 * server), are skipped silently, as PROTOCOL.md 3.2 requires: their bytes
 * are dropped as they arrive, and they are only counted. Every other frame,
 * including unknown types without the high bit, is returned.
 *
 * Nothing is allocated on the word of a length field. The decoder copies
 * what it is fed; if the caller drains it with scp_decoder_next() until that
 * returns 0 after every feed, it holds at most one partial frame (below the
 * frame size limit) plus the bytes of one feed, and it frees a large buffer
 * once it is empty again.
 *
 * Errors in the stream are sticky: once next(), feed() or eof() has
 * returned one, every later call returns the same code, because nothing
 * after a broken frame can be trusted. "Need more bytes" is not an error:
 * next() returns 0 for it.
 */
typedef struct scp_decoder scp_decoder_t;

/* NULL limits means the defaults. Returns NULL when out of memory or when
 * the limits are out of range. */
scp_decoder_t *scp_decoder_new(const scp_limits_t *limits);
void scp_decoder_free(scp_decoder_t *d);

/* Appends len bytes. Returns 0, the sticky error, SCP_ENOMEM (which then
 * sticks too: the bytes are lost), or SCP_EINVAL for NULL bytes with a
 * non-zero len. */
int scp_decoder_feed(scp_decoder_t *d, const void *bytes, size_t len);
/* 1 with *frame filled when a whole frame is ready, 0 when more bytes are
 * needed, or the sticky error. */
int scp_decoder_next(scp_decoder_t *d, scp_frame_t *frame);
/* The peer closed the stream: 0 when it did so between frames, otherwise
 * SCP_ETRUNCATED (sticky) or the earlier sticky error. */
int scp_decoder_eof(scp_decoder_t *d);
/* The sticky error, or 0. */
int scp_decoder_error(const scp_decoder_t *d);
/* Bytes buffered that are not part of a frame already returned. */
size_t scp_decoder_pending(const scp_decoder_t *d);
/* Changes the frame size limit (in [SCP_FRAME_MIN, SCP_FRAME_CEILING]) for
 * every frame not yet returned. SCP_EINVAL when out of range. Call it with
 * WELCOME's max_frame right after the handshake: frames already fed but not
 * yet returned are judged by the new limit. */
int scp_decoder_set_max_frame(scp_decoder_t *d, uint32_t max_frame);
uint32_t scp_decoder_max_frame(const scp_decoder_t *d);

/* What the decoder has seen, for the caller's statistics and logs. */
typedef struct scp_decoder_counters {
  uint64_t bytes;   /* bytes fed */
  uint64_t frames;  /* frames returned by scp_decoder_next() */
  uint64_t skipped; /* ignorable frames not for this role, dropped */
  uint64_t buffer;  /* bytes allocated for the buffer now */
} scp_decoder_counters_t;
void scp_decoder_get_counters(const scp_decoder_t *d,
                              scp_decoder_counters_t *out);

/*
 * Parsers. Each checks that the frame has its type (SCP_EINVAL otherwise),
 * then the payload's layout (SCP_ESHORT, SCP_ELENGTH, SCP_ERESERVED), then
 * every field (SCP_ERANGE, SCP_EFLAGS, SCP_EVERSION). On an error *out is
 * unspecified; scp_frame_job_id() still tells which job the frame named.
 */
int scp_parse_hello(const scp_frame_t *f, scp_hello_t *out);
int scp_parse_welcome(const scp_frame_t *f, scp_welcome_t *out);
int scp_parse_error(const scp_frame_t *f, scp_error_t *out);
int scp_parse_ping(const scp_frame_t *f, uint64_t *token);
int scp_parse_pong(const scp_frame_t *f, uint64_t *token);
int scp_parse_job_begin(const scp_frame_t *f, scp_job_begin_t *out);
/* JOB_BEGIN on a connection whose handshake agreed on features (WELCOME's):
 * without SCP_FEATURE_JOB_OPTIONS a payload longer than the fixed part is
 * malformed (SCP_ELENGTH, PROTOCOL.md 6.3), whatever else is wrong with it;
 * otherwise the same as scp_parse_job_begin(). */
int scp_parse_job_begin_features(const scp_frame_t *f, uint64_t features,
                                 scp_job_begin_t *out);
int scp_parse_job_end(const scp_frame_t *f, scp_job_end_t *out);
int scp_parse_cancel(const scp_frame_t *f, uint32_t *job_id);
int scp_parse_stats_request(const scp_frame_t *f, uint32_t *tag);
int scp_parse_accepted(const scp_frame_t *f, scp_accepted_t *out);
int scp_parse_progress(const scp_frame_t *f, scp_progress_t *out);
int scp_parse_job_done(const scp_frame_t *f, scp_job_done_t *out);
int scp_parse_job_error(const scp_frame_t *f, scp_job_error_t *out);
int scp_parse_stats(const scp_frame_t *f, scp_stats_t *out);
/* Any of the five chunk types. */
int scp_parse_chunk(const scp_frame_t *f, scp_chunk_t *out);

/* Any message, dispatched on the type; SCP_EUNKNOWN_TYPE for a type this
 * version does not define. out->type is always set. */
typedef struct scp_msg {
  uint16_t type;
  union {
    scp_hello_t hello;
    scp_welcome_t welcome;
    scp_error_t error;
    uint64_t token;        /* PING, PONG */
    scp_job_begin_t job_begin;
    scp_job_end_t job_end;
    uint32_t job_id;       /* CANCEL */
    uint32_t tag;          /* STATS_REQUEST */
    scp_accepted_t accepted;
    scp_progress_t progress;
    scp_chunk_t chunk;     /* the five chunk types */
    scp_job_done_t job_done;
    scp_job_error_t job_error;
    scp_stats_t stats;
  } u;
} scp_msg_t;

int scp_parse(const scp_frame_t *f, scp_msg_t *out);
/* Like scp_parse() for a frame received by role (SCP_ROLE_SERVER or
 * SCP_ROLE_CLIENT): a type the other side never sends is SCP_EUNKNOWN_TYPE,
 * as PROTOCOL.md 3.2 requires, whatever its payload. */
int scp_parse_as(const scp_frame_t *f, int role, scp_msg_t *out);

/* Encodes any message, as parsed: what scp_parse() accepts, this writes
 * back byte for byte (HELLO and WELCOME without their unknown tail). Value
 * lists and chunks are taken from their views. */
int scp_enc_msg(scp_buf_t *b, const scp_msg_t *m);

/* For a job frame (JOB_BEGIN, POINTS, JOB_END, CANCEL, ACCEPTED, PROGRESS,
 * TRIANGLES, NORMALS, VERTICES, COMPONENTS, JOB_DONE, JOB_ERROR) whose
 * payload holds at least the job id, stores the id and returns 1, whether or
 * not the rest parses; returns 0 for other frames. */
int scp_frame_job_id(const scp_frame_t *f, uint32_t *job_id);

/*
 * The handshake, PROTOCOL.md section 5.
 *
 * Server: the WELCOME that answers hello, given the server's own limits in
 * *server (its version is ignored; its features are the bits the server
 * supports and its max_frame is the server's own limit). SCP_EVERSION when
 * no version is in common, SCP_ERANGE or SCP_EVERSION for a HELLO out of
 * range, SCP_EINVAL for server limits out of range. Either way the server
 * sends a fatal ERROR (scp_err_to_wire() gives the code) and closes.
 */
int scp_handshake_answer(const scp_hello_t *hello, const scp_welcome_t *server,
                         scp_welcome_t *out);
/* 1 when the token HELLO carried (with SCP_FEATURE_TOKEN) is the
 * expected one, byte for byte, else 0. The time it takes depends on the
 * lengths only, never on where the bytes differ, so that a peer cannot
 * guess a token byte by byte from how fast it is refused. */
int scp_token_equal(const scp_hello_t *hello, const uint8_t *expected,
                    size_t expected_len);
/* Reads the token file at path: a regular file open to its owner only,
 * holding one line of min_len (at least 1) to SCP_TOKEN_MAX bytes, its
 * line end not part of the token. Returns 0 with the token in token
 * (SCP_TOKEN_MAX bytes of room) and its length in *len; -1 with a
 * one-line message in msg that never holds the token. The only I/O of
 * this module: the daemon and the clients read the file by one rule. */
int scp_token_read(const char *path, size_t min_len, uint8_t *token,
                   size_t *len, char *msg, size_t msg_len);
/* Zeroes n bytes at p, also where the memory is about to be freed or go out
 * of scope (a plain memset there is a dead store the compiler may drop). */
void scp_wipe(void *p, size_t n);

/* Client: checks the server's WELCOME against the HELLO it sent. Any error
 * makes WELCOME malformed: fatal ERROR PROTOCOL, then close. */
int scp_handshake_check(const scp_hello_t *sent, const scp_welcome_t *got);

#ifdef __cplusplus
}
#endif

#endif /* SCPROTO_H */
