/*
 * Encoders: each checks its message like the parser would, then appends one
 * whole frame to the buffer. Nothing is appended when a check fails, so a
 * caller never has to undo half a frame.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "scproto.h"
#include "wire.h"

void scp_buf_init(scp_buf_t *b, uint32_t max_frame) {
  b->data = NULL;
  b->len = 0;
  b->cap = 0;
  b->max_frame = max_frame ? max_frame : SCP_FRAME_MIN;
}

void scp_buf_free(scp_buf_t *b) {
  if (!b)
    return;
  free(b->data);
  b->data = NULL;
  b->len = 0;
  b->cap = 0;
}

void scp_buf_consume(scp_buf_t *b, size_t n) {
  if (n >= b->len) {
    b->len = 0;
    return;
  }
  memmove(b->data, b->data + n, b->len - n);
  b->len -= n;
}

/* Makes room for n more bytes. */
static int buf_reserve(scp_buf_t *b, size_t n) {
  if (b->cap - b->len >= n)
    return 0;
  if (n > SIZE_MAX - b->len)
    return SCP_ENOMEM;
  size_t need = b->len + n;
  size_t cap = b->cap ? b->cap : 256;
  while (cap < need)
    cap = cap > SIZE_MAX / 2 ? need : cap * 2;
  uint8_t *p = realloc(b->data, cap);
  if (!p)
    return SCP_ENOMEM;
  b->data = p;
  b->cap = cap;
  return 0;
}

/*
 * Checks that a payload of the given size fits the frame limit, reserves the
 * frame, writes its header and returns where the payload goes through *out.
 * The size is 64-bit so that callers can pass sums that would overflow a
 * 32-bit length.
 */
static int frame_begin(scp_buf_t *b, uint16_t type, uint64_t payload,
                       uint8_t **out) {
  if (b->max_frame < SCP_HEADER_SIZE ||
      payload > (uint64_t)b->max_frame - SCP_HEADER_SIZE)
    return SCP_ETOOBIG;
  size_t total = SCP_HEADER_SIZE + (size_t)payload;
  int rc = buf_reserve(b, total);
  if (rc)
    return rc;
  uint8_t *p = b->data + b->len;
  scp__st16(p, type);
  scp__st16(p + 2, 0);
  scp__st32(p + 4, (uint32_t)payload);
  memset(p + SCP_HEADER_SIZE, 0, (size_t)payload);
  b->len += total;
  *out = p + SCP_HEADER_SIZE;
  return 0;
}

int scp_enc_hello(scp_buf_t *b, const scp_hello_t *m) {
  int rc = scp__check_hello(m);
  uint8_t *p;
  int token = (m->features & SCP_FEATURE_TOKEN) != 0;
  uint64_t len = SCP_HELLO_FIXED + (token ? 4 + (uint64_t)m->token_len : 0);
  if (rc || (rc = frame_begin(b, SCP_HELLO, len, &p)))
    return rc;
  memcpy(p, SCP_MAGIC, SCP_MAGIC_LEN);
  scp__st16(p + 4, m->version_min);
  scp__st16(p + 6, m->version_max);
  scp__st64(p + 8, m->features);
  scp__st32(p + 16, m->max_frame);
  if (token) {
    scp__st32(p + SCP_HELLO_FIXED, m->token_len);
    if (m->token_len)
      memcpy(p + SCP_HELLO_FIXED + 4, m->token, m->token_len);
  }
  return 0;
}

int scp_enc_welcome(scp_buf_t *b, const scp_welcome_t *m) {
  int rc = scp__check_welcome(m);
  uint8_t *p;
  if (rc || (rc = frame_begin(b, SCP_WELCOME, 32, &p)))
    return rc;
  memcpy(p, SCP_MAGIC, SCP_MAGIC_LEN);
  scp__st16(p + 4, m->version);
  scp__st64(p + 8, m->features);
  scp__st32(p + 16, m->max_frame);
  scp__st32(p + 20, m->max_jobs);
  scp__st64(p + 24, m->max_points);
  return 0;
}

/* Length of a message kept in a struct's char array, or SCP_ERANGE when the
 * array holds no terminating NUL within SCP_MESSAGE_MAX + 1 bytes. */
static int message_len(const char *text, size_t *len) {
  const char *nul = memchr(text, 0, SCP_MESSAGE_MAX + 1);
  if (!nul)
    return SCP_ERANGE;
  *len = (size_t)(nul - text);
  return 0;
}

int scp_enc_error(scp_buf_t *b, const scp_error_t *m) {
  size_t n;
  int rc = scp__check_error_fields(m);
  uint8_t *p;
  if (rc || (rc = message_len(m->message, &n)) ||
      (rc = frame_begin(b, SCP_ERROR, 20 + (uint64_t)n, &p)))
    return rc;
  scp__st32(p, m->code);
  scp__st32(p + 4, m->flags);
  scp__st32(p + 8, m->job_id);
  scp__st16(p + 12, m->ref_type);
  scp__st32(p + 16, (uint32_t)n);
  memcpy(p + 20, m->message, n);
  return 0;
}

static int enc_token(scp_buf_t *b, uint16_t type, uint64_t token) {
  uint8_t *p;
  int rc = frame_begin(b, type, 8, &p);
  if (rc)
    return rc;
  scp__st64(p, token);
  return 0;
}

int scp_enc_ping(scp_buf_t *b, uint64_t token) {
  return enc_token(b, SCP_PING, token);
}

int scp_enc_pong(scp_buf_t *b, uint64_t token) {
  return enc_token(b, SCP_PONG, token);
}

static void job_begin_write(uint8_t *p, const scp_job_begin_t *m) {
  scp__st32(p, m->job_id);
  scp__st32(p + 4, m->mode);
  scp__stf64(p + 8, m->r);
  scp__stf64(p + 16, m->theta);
  scp__st64(p + 24, m->point_count);
  scp__st32(p + 32, m->flags);
}

int scp_enc_job_begin(scp_buf_t *b, const scp_job_begin_t *m) {
  int rc = scp__check_job_begin(m);
  const scp_values_t *o = &m->options;
  uint8_t *p;
  if (rc)
    return rc;
  if (o->count == 0 && o->len == 0) {
    if ((rc = frame_begin(b, SCP_JOB_BEGIN, 40, &p)))
      return rc;
    job_begin_write(p, m);
    return 0;
  }
  /* A view of options in wire form, as the parser gives it. */
  if (o->count == 0 || !o->data)
    return o->count == 0 ? SCP_ERANGE : SCP_EINVAL;
  if ((rc = scp__values_check(o->data, o->len, o->count)) ||
      (rc = frame_begin(b, SCP_JOB_BEGIN, 48 + (uint64_t)o->len, &p)))
    return rc;
  job_begin_write(p, m);
  scp__st32(p + 40, o->count);
  memcpy(p + 48, o->data, o->len);
  return 0;
}

int scp_enc_job_end(scp_buf_t *b, const scp_job_end_t *m) {
  int rc = scp__check_job_id(m->job_id);
  uint8_t *p;
  if (rc || (rc = frame_begin(b, SCP_JOB_END, 16, &p)))
    return rc;
  scp__st32(p, m->job_id);
  scp__st64(p + 8, m->point_count);
  return 0;
}

int scp_enc_cancel(scp_buf_t *b, uint32_t job_id) {
  int rc = scp__check_job_id(job_id);
  uint8_t *p;
  if (rc || (rc = frame_begin(b, SCP_CANCEL, 8, &p)))
    return rc;
  scp__st32(p, job_id);
  return 0;
}

int scp_enc_stats_request(scp_buf_t *b, uint32_t tag) {
  uint8_t *p;
  int rc = frame_begin(b, SCP_STATS_REQUEST, 8, &p);
  if (rc)
    return rc;
  scp__st32(p, tag);
  return 0;
}

int scp_enc_accepted(scp_buf_t *b, const scp_accepted_t *m) {
  int rc = scp__check_job_id(m->job_id);
  uint8_t *p;
  if (rc || (rc = frame_begin(b, SCP_ACCEPTED, 8, &p)))
    return rc;
  scp__st32(p, m->job_id);
  scp__st32(p + 4, m->queue_position);
  return 0;
}

int scp_enc_progress(scp_buf_t *b, const scp_progress_t *m) {
  int rc = scp__check_progress(m);
  uint8_t *p;
  if (rc || (rc = frame_begin(b, SCP_PROGRESS, 16, &p)))
    return rc;
  scp__st32(p, m->job_id);
  scp__st32(p + 4, m->stage);
  scp__stf64(p + 8, m->fraction);
  return 0;
}

/* Checks a value list and returns its encoded size through *size. */
static int values_size(const scp_value_t *values, uint32_t n,
                       uint64_t *size) {
  uint64_t total = 0;
  if (n > 0 && !values)
    return SCP_EINVAL;
  for (uint32_t i = 0; i < n; i++) {
    const char *name = values[i].name;
    if (!name)
      return SCP_EINVAL;
    size_t len = strnlen(name, SCP_NAME_MAX + 1);
    if (!scp__name_ok(name, len))
      return SCP_ERANGE;
    if (values[i].kind == 0 || values[i].kind > UINT8_MAX)
      return SCP_ERANGE;
    total += 10 + len;
  }
  *size = total;
  return 0;
}

static void values_write(uint8_t *p, const scp_value_t *values, uint32_t n) {
  for (uint32_t i = 0; i < n; i++) {
    size_t len = strlen(values[i].name);
    p[0] = (uint8_t)values[i].kind;
    p[1] = (uint8_t)len;
    memcpy(p + 2, values[i].name, len);
    switch (values[i].kind) {
    case SCP_KIND_I64:
      scp__st64(p + 2 + len, (uint64_t)values[i].v.i);
      break;
    case SCP_KIND_F64:
      scp__stf64(p + 2 + len, values[i].v.f);
      break;
    default:
      /* U64, and kinds this version does not know, whose eight bytes the
       * caller put in v.u. */
      scp__st64(p + 2 + len, values[i].v.u);
      break;
    }
    p += 10 + len;
  }
}

int scp_enc_job_begin_options(scp_buf_t *b, const scp_job_begin_t *m,
                              const scp_value_t *options, uint32_t count) {
  scp_job_begin_t plain = *m;
  plain.options = (scp_values_t){0, NULL, 0};
  if (count == 0)
    return scp_enc_job_begin(b, &plain);
  uint64_t size;
  uint8_t *p;
  int rc = scp__check_job_begin(m);
  if (rc || (rc = values_size(options, count, &size)) ||
      (rc = frame_begin(b, SCP_JOB_BEGIN, 48 + size, &p)))
    return rc;
  job_begin_write(p, m);
  scp__st32(p + 40, count);
  values_write(p + 48, options, count);
  return 0;
}

int scp_enc_job_done(scp_buf_t *b, const scp_job_done_t *m,
                     const scp_value_t *values, uint32_t value_count) {
  uint64_t size;
  uint8_t *p;
  int rc = scp__check_job_id(m->job_id);
  if (rc || (rc = values_size(values, value_count, &size)) ||
      (rc = frame_begin(b, SCP_JOB_DONE, 32 + size, &p)))
    return rc;
  scp__st32(p, m->job_id);
  scp__st32(p + 4, value_count);
  scp__st64(p + 8, m->triangles);
  scp__st64(p + 16, m->normals);
  scp__st64(p + 24, m->components);
  values_write(p + 32, values, value_count);
  return 0;
}

int scp_enc_job_error(scp_buf_t *b, const scp_job_error_t *m) {
  size_t n;
  int rc = scp__check_job_error_fields(m);
  uint8_t *p;
  if (rc || (rc = message_len(m->message, &n)) ||
      (rc = frame_begin(b, SCP_JOB_ERROR, 16 + (uint64_t)n, &p)))
    return rc;
  scp__st32(p, m->job_id);
  scp__st32(p + 4, m->code);
  scp__st32(p + 8, (uint32_t)n);
  memcpy(p + 16, m->message, n);
  return 0;
}

int scp_enc_stats(scp_buf_t *b, uint32_t tag, const scp_value_t *values,
                  uint32_t value_count) {
  uint64_t size;
  uint8_t *p;
  int rc = values_size(values, value_count, &size);
  if (rc || (rc = frame_begin(b, SCP_STATS, 8 + size, &p)))
    return rc;
  scp__st32(p, tag);
  scp__st32(p + 4, value_count);
  values_write(p + 8, values, value_count);
  return 0;
}

/* Checks a chunk and starts its frame; returns where the elements go. */
static int chunk_begin(scp_buf_t *b, uint16_t type, uint32_t job_id,
                       uint64_t first, uint32_t format, const void *src,
                       uint32_t count, uint8_t **data) {
  uint8_t *p;
  int rc = scp__check_chunk_fields(type, job_id, count, first, format);
  if (rc)
    return rc;
  if (!src)
    return SCP_EINVAL;
  uint64_t size = SCP_CHUNK_HEADER + (uint64_t)count * scp_format_size(format);
  if ((rc = frame_begin(b, type, size, &p)))
    return rc;
  scp__st32(p, job_id);
  scp__st32(p + 4, count);
  scp__st64(p + 8, first);
  scp__st32(p + 16, format);
  *data = p + SCP_CHUNK_HEADER;
  return 0;
}

/*
 * Rounds a double to float. Finite values beyond the float range become
 * infinities explicitly, since C leaves that conversion undefined; the
 * server then refuses them as non-finite, as it should.
 */
static float to_f32(double x) {
  if (x > FLT_MAX)
    return INFINITY;
  if (x < -FLT_MAX)
    return -INFINITY;
  return (float)x;
}

static int enc_xyz(scp_buf_t *b, uint16_t type, uint32_t job_id,
                   uint64_t first, uint32_t format, const double *xyz,
                   uint32_t count) {
  uint8_t *p;
  int rc = chunk_begin(b, type, job_id, first, format, xyz, count, &p);
  if (rc)
    return rc;
  size_t n = 3 * (size_t)count;
  if (format == SCP_F32_XYZ) {
    for (size_t i = 0; i < n; i++)
      scp__stf32(p + 4 * i, to_f32(xyz[i]));
  } else {
    for (size_t i = 0; i < n; i++)
      scp__stf64(p + 8 * i, xyz[i]);
  }
  return 0;
}

int scp_enc_points(scp_buf_t *b, uint32_t job_id, uint64_t first,
                   uint32_t format, const double *xyz, uint32_t count) {
  return enc_xyz(b, SCP_POINTS, job_id, first, format, xyz, count);
}

int scp_enc_normals(scp_buf_t *b, uint32_t job_id, uint64_t first,
                    uint32_t format, const double *xyz, uint32_t count) {
  return enc_xyz(b, SCP_NORMALS, job_id, first, format, xyz, count);
}

int scp_enc_vertices(scp_buf_t *b, uint32_t job_id, uint64_t first,
                     const double *xyz, uint32_t count) {
  return enc_xyz(b, SCP_VERTICES, job_id, first, SCP_F64_XYZ, xyz, count);
}

int scp_enc_points_f32(scp_buf_t *b, uint32_t job_id, uint64_t first,
                       const float *xyz, uint32_t count) {
  uint8_t *p;
  int rc = chunk_begin(b, SCP_POINTS, job_id, first, SCP_F32_XYZ, xyz, count,
                       &p);
  if (rc)
    return rc;
  for (size_t i = 0; i < 3 * (size_t)count; i++)
    scp__stf32(p + 4 * i, xyz[i]);
  return 0;
}

int scp_enc_triangles(scp_buf_t *b, uint32_t job_id, uint64_t first,
                      const uint32_t *tri, uint32_t count) {
  uint8_t *p;
  int rc = chunk_begin(b, SCP_TRIANGLES, job_id, first, SCP_U32_TRIANGLE, tri,
                       count, &p);
  if (rc)
    return rc;
  for (size_t i = 0; i < 3 * (size_t)count; i++)
    scp__st32(p + 4 * i, tri[i]);
  return 0;
}

int scp_enc_components(scp_buf_t *b, uint32_t job_id, uint64_t first,
                       const int32_t *genus, uint32_t count) {
  /* Checked before the frame is started, so that a bad value leaves the
   * buffer untouched. */
  if (genus) {
    for (uint32_t i = 0; i < count; i++)
      if (genus[i] < -1)
        return SCP_ERANGE;
  }
  uint8_t *p;
  int rc = chunk_begin(b, SCP_COMPONENTS, job_id, first, SCP_I32, genus, count,
                       &p);
  if (rc)
    return rc;
  for (uint32_t i = 0; i < count; i++)
    scp__st32(p + 4 * (size_t)i, (uint32_t)genus[i]);
  return 0;
}

uint32_t scp_chunk_capacity(uint32_t format, uint32_t max_frame) {
  size_t size = scp_format_size(format);
  if (size == 0 || max_frame < SCP_FRAME_MIN)
    return 0;
  return (uint32_t)((max_frame - SCP_HEADER_SIZE - SCP_CHUNK_HEADER) / size);
}

/* The size of the next chunk of an array, or 0 when none is left. */
static uint32_t next_count(const scp_buf_t *b, uint32_t format, uint64_t total,
                           uint64_t next) {
  uint64_t left = total - next;
  uint32_t cap = scp_chunk_capacity(format, b->max_frame);
  return left < cap ? (uint32_t)left : cap;
}

int scp_enc_points_next(scp_buf_t *b, uint32_t job_id, uint32_t format,
                        const double *xyz, uint64_t total, uint64_t *next) {
  if (*next > total || scp_format_size(format) == 0)
    return SCP_EINVAL;
  if (*next == total)
    return 0;
  uint32_t k = next_count(b, format, total, *next);
  if (k == 0)
    return SCP_ETOOBIG;
  int rc = scp_enc_points(b, job_id, *next, format, xyz + 3 * *next, k);
  if (rc)
    return rc;
  *next += k;
  return 1;
}

int scp_enc_mesh_next(scp_buf_t *b, const scp_mesh_view_t *m,
                      scp_mesh_cursor_t *c) {
  uint32_t k;
  int rc;
  if (c->triangles < m->triangle_count) {
    k = next_count(b, SCP_U32_TRIANGLE, m->triangle_count, c->triangles);
    rc = k ? scp_enc_triangles(b, m->job_id, c->triangles,
                               m->triangles + 3 * c->triangles, k)
           : SCP_ETOOBIG;
    if (rc)
      return rc;
    c->triangles += k;
    return 1;
  }
  if (m->normals && c->normals < m->normal_count) {
    k = next_count(b, m->normal_format, m->normal_count, c->normals);
    rc = k ? scp_enc_normals(b, m->job_id, c->normals, m->normal_format,
                             m->normals + 3 * c->normals, k)
           : SCP_ETOOBIG;
    if (rc)
      return rc;
    c->normals += k;
    return 1;
  }
  if (m->vertices && c->vertices < m->vertex_count) {
    k = next_count(b, SCP_F64_XYZ, m->vertex_count, c->vertices);
    rc = k ? scp_enc_vertices(b, m->job_id, c->vertices,
                              m->vertices + 3 * c->vertices, k)
           : SCP_ETOOBIG;
    if (rc)
      return rc;
    c->vertices += k;
    return 1;
  }
  if (c->components < m->component_count) {
    k = next_count(b, SCP_I32, m->component_count, c->components);
    rc = k ? scp_enc_components(b, m->job_id, c->components,
                                m->genus + c->components, k)
           : SCP_ETOOBIG;
    if (rc)
      return rc;
    c->components += k;
    return 1;
  }
  return 0;
}

int scp_enc_chunk(scp_buf_t *b, const scp_chunk_t *c) {
  uint8_t *p;
  if (c->type == SCP_COMPONENTS && c->format == SCP_I32 && c->data) {
    for (uint32_t i = 0; i < c->count; i++)
      if ((int32_t)scp__ld32(c->data + 4 * (size_t)i) < -1)
        return SCP_ERANGE;
  }
  int rc = chunk_begin(b, c->type, c->job_id, c->first, c->format, c->data,
                       c->count, &p);
  if (rc)
    return rc;
  memcpy(p, c->data, (size_t)c->count * scp_format_size(c->format));
  return 0;
}

/* JOB_DONE or STATS from a value list that is already in wire form. */
static int enc_values_raw(scp_buf_t *b, uint16_t type, uint32_t fixed,
                          const scp_values_t *v, uint8_t **out) {
  if (v->len > 0 && !v->data)
    return SCP_EINVAL;
  int rc = v->len ? scp__values_check(v->data, v->len, v->count)
                  : (v->count ? SCP_ELENGTH : 0);
  if (rc || (rc = frame_begin(b, type, fixed + (uint64_t)v->len, out)))
    return rc;
  scp__st32(*out + 4, v->count);
  if (v->len)
    memcpy(*out + fixed, v->data, v->len);
  return 0;
}

int scp_enc_msg(scp_buf_t *b, const scp_msg_t *m) {
  const scp_job_done_t *jd;
  uint8_t *p;
  int rc;
  switch (m->type) {
  case SCP_HELLO:
    return scp_enc_hello(b, &m->u.hello);
  case SCP_WELCOME:
    return scp_enc_welcome(b, &m->u.welcome);
  case SCP_ERROR:
    return scp_enc_error(b, &m->u.error);
  case SCP_PING:
    return scp_enc_ping(b, m->u.token);
  case SCP_PONG:
    return scp_enc_pong(b, m->u.token);
  case SCP_JOB_BEGIN:
    return scp_enc_job_begin(b, &m->u.job_begin);
  case SCP_JOB_END:
    return scp_enc_job_end(b, &m->u.job_end);
  case SCP_CANCEL:
    return scp_enc_cancel(b, m->u.job_id);
  case SCP_STATS_REQUEST:
    return scp_enc_stats_request(b, m->u.tag);
  case SCP_ACCEPTED:
    return scp_enc_accepted(b, &m->u.accepted);
  case SCP_PROGRESS:
    return scp_enc_progress(b, &m->u.progress);
  case SCP_POINTS:
  case SCP_TRIANGLES:
  case SCP_NORMALS:
  case SCP_VERTICES:
  case SCP_COMPONENTS:
    if (m->u.chunk.type != m->type)
      return SCP_EINVAL;
    return scp_enc_chunk(b, &m->u.chunk);
  case SCP_JOB_DONE:
    jd = &m->u.job_done;
    if ((rc = scp__check_job_id(jd->job_id)) ||
        (rc = enc_values_raw(b, SCP_JOB_DONE, 32, &jd->values, &p)))
      return rc;
    scp__st32(p, jd->job_id);
    scp__st64(p + 8, jd->triangles);
    scp__st64(p + 16, jd->normals);
    scp__st64(p + 24, jd->components);
    return 0;
  case SCP_JOB_ERROR:
    return scp_enc_job_error(b, &m->u.job_error);
  case SCP_STATS:
    if ((rc = enc_values_raw(b, SCP_STATS, 8, &m->u.stats.values, &p)))
      return rc;
    scp__st32(p, m->u.stats.tag);
    return 0;
  }
  return SCP_EUNKNOWN_TYPE;
}
