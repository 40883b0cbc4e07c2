/*
 * Parsers: a whole frame in, a typed message out.
 *
 * Each parser checks the layout before any field, so that a frame that
 * cannot be trusted (SCP_ESHORT, SCP_ELENGTH, SCP_ERESERVED: fatal) is never
 * reported as merely invalid (SCP_ERANGE, SCP_EFLAGS: an error reply). Every
 * field is read with the byte-wise loads of wire.h, so payloads need no
 * alignment, and nothing is allocated: variable parts stay in the frame and
 * are handed out as views.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <float.h>
#include <math.h>
#include <string.h>

#include "scproto.h"
#include "wire.h"

/* A message whose payload length is exactly n. */
static int exact(const scp_frame_t *f, uint16_t type, uint32_t n) {
  if (f->type != type)
    return SCP_EINVAL;
  if (f->length < n)
    return SCP_ESHORT;
  if (f->length != n)
    return SCP_ELENGTH;
  return 0;
}

/* A message with a fixed part of n bytes and more after it. */
static int at_least(const scp_frame_t *f, uint16_t type, uint32_t n) {
  if (f->type != type)
    return SCP_EINVAL;
  if (f->length < n)
    return SCP_ESHORT;
  return 0;
}

static int parse_values(const uint8_t *p, size_t len, uint32_t count,
                        scp_values_t *out);

static int zero32(const uint8_t *p) {
  return scp__ld32(p) == 0 ? 0 : SCP_ERESERVED;
}

static int zero16(const uint8_t *p) {
  return scp__ld16(p) == 0 ? 0 : SCP_ERESERVED;
}

/* The opening of HELLO and WELCOME: the magic first, since a frame from a
 * peer speaking another protocol is more usefully called that than short. */
static int handshake_start(const scp_frame_t *f, uint16_t type, uint32_t n) {
  if (f->type != type)
    return SCP_EINVAL;
  if (f->length >= SCP_MAGIC_LEN &&
      memcmp(f->payload, SCP_MAGIC, SCP_MAGIC_LEN) != 0)
    return SCP_EBADMAGIC;
  return at_least(f, type, n);
}

int scp_parse_hello(const scp_frame_t *f, scp_hello_t *out) {
  const uint8_t *p = f->payload;
  int rc = handshake_start(f, SCP_HELLO, SCP_HELLO_FIXED);
  if (rc || (rc = zero32(p + 20)))
    return rc;
  out->version_min = scp__ld16(p + 4);
  out->version_max = scp__ld16(p + 6);
  out->features = scp__ld64(p + 8);
  out->max_frame = scp__ld32(p + 16);
  out->token = NULL;
  out->token_len = 0;
  /* Without the TOKEN bit whatever follows the fixed part is a later
   * version's tail, and ignored (PROTOCOL.md 3.3). */
  if (out->features & SCP_FEATURE_TOKEN) {
    if (f->length < SCP_HELLO_FIXED + 4)
      return SCP_ESHORT;
    uint32_t n = scp__ld32(p + SCP_HELLO_FIXED);
    if (n > SCP_TOKEN_MAX)
      return SCP_ERANGE;
    if ((uint64_t)SCP_HELLO_FIXED + 4 + n > f->length)
      return SCP_ELENGTH;
    out->token_len = n;
    out->token = n ? p + SCP_HELLO_FIXED + 4 : NULL;
  }
  return scp__check_hello(out);
}

int scp_parse_welcome(const scp_frame_t *f, scp_welcome_t *out) {
  const uint8_t *p = f->payload;
  int rc = handshake_start(f, SCP_WELCOME, 32);
  if (rc || (rc = zero16(p + 6)))
    return rc;
  out->version = scp__ld16(p + 4);
  out->features = scp__ld64(p + 8);
  out->max_frame = scp__ld32(p + 16);
  out->max_jobs = scp__ld32(p + 20);
  out->max_points = scp__ld64(p + 24);
  return scp__check_welcome(out);
}

/* Checks and copies the text of ERROR or JOB_ERROR, whose length field the
 * caller has already matched against the payload length. */
static int copy_text(char *dst, const uint8_t *src, uint32_t len) {
  if (!scp__text_ok((const char *)src, len))
    return SCP_ERANGE;
  memcpy(dst, src, len);
  dst[len] = '\0';
  return 0;
}

int scp_parse_error(const scp_frame_t *f, scp_error_t *out) {
  const uint8_t *p = f->payload;
  int rc = at_least(f, SCP_ERROR, 20);
  if (rc || (rc = zero16(p + 14)))
    return rc;
  uint32_t n = scp__ld32(p + 16);
  if ((uint64_t)20 + n != f->length)
    return SCP_ELENGTH;
  out->code = scp__ld32(p);
  out->flags = scp__ld32(p + 4);
  out->job_id = scp__ld32(p + 8);
  out->ref_type = scp__ld16(p + 12);
  out->message[0] = '\0';
  if ((rc = scp__check_error_fields(out)))
    return rc;
  return copy_text(out->message, p + 20, n);
}

static int parse_token(const scp_frame_t *f, uint16_t type, uint64_t *token) {
  int rc = exact(f, type, 8);
  if (rc)
    return rc;
  *token = scp__ld64(f->payload);
  return 0;
}

int scp_parse_ping(const scp_frame_t *f, uint64_t *token) {
  return parse_token(f, SCP_PING, token);
}

int scp_parse_pong(const scp_frame_t *f, uint64_t *token) {
  return parse_token(f, SCP_PONG, token);
}

int scp_parse_job_begin(const scp_frame_t *f, scp_job_begin_t *out) {
  const uint8_t *p = f->payload;
  /* The fixed part, or that, 8 bytes of count and reserved, and a list of
   * job options (PROTOCOL.md 6.3). */
  const uint32_t fixed = SCP_JOB_BEGIN_FIXED, list = SCP_JOB_BEGIN_FIXED + 8;
  int rc = f->length > fixed && f->length < list
               ? exact(f, SCP_JOB_BEGIN, fixed)
               : at_least(f, SCP_JOB_BEGIN, fixed);
  if (rc || (rc = zero32(p + 36)))
    return rc;
  out->job_id = scp__ld32(p);
  out->mode = scp__ld32(p + 4);
  out->r = scp__ldf64(p + 8);
  out->theta = scp__ldf64(p + 16);
  out->point_count = scp__ld64(p + 24);
  out->flags = scp__ld32(p + 32);
  out->options = (scp_values_t){0, NULL, 0};
  if (f->length > fixed) {
    if ((rc = zero32(p + fixed + 4)) ||
        (rc = parse_values(p + list, f->length - list, scp__ld32(p + fixed),
                           &out->options)))
      return rc;
    if (out->options.count == 0)
      return SCP_ERANGE;
  }
  return scp__check_job_begin(out);
}

int scp_parse_job_begin_features(const scp_frame_t *f, uint64_t features,
                                 scp_job_begin_t *out) {
  if (f->type == SCP_JOB_BEGIN && f->length > SCP_JOB_BEGIN_FIXED &&
      !(features & SCP_FEATURE_JOB_OPTIONS))
    return SCP_ELENGTH;
  return scp_parse_job_begin(f, out);
}

int scp_parse_job_end(const scp_frame_t *f, scp_job_end_t *out) {
  const uint8_t *p = f->payload;
  int rc = exact(f, SCP_JOB_END, 16);
  if (rc || (rc = zero32(p + 4)))
    return rc;
  out->job_id = scp__ld32(p);
  out->point_count = scp__ld64(p + 8);
  return scp__check_job_id(out->job_id);
}

int scp_parse_cancel(const scp_frame_t *f, uint32_t *job_id) {
  const uint8_t *p = f->payload;
  int rc = exact(f, SCP_CANCEL, 8);
  if (rc || (rc = zero32(p + 4)))
    return rc;
  *job_id = scp__ld32(p);
  return scp__check_job_id(*job_id);
}

int scp_parse_stats_request(const scp_frame_t *f, uint32_t *tag) {
  const uint8_t *p = f->payload;
  int rc = exact(f, SCP_STATS_REQUEST, 8);
  if (rc || (rc = zero32(p + 4)))
    return rc;
  *tag = scp__ld32(p);
  return 0;
}

int scp_parse_accepted(const scp_frame_t *f, scp_accepted_t *out) {
  const uint8_t *p = f->payload;
  int rc = exact(f, SCP_ACCEPTED, 8);
  if (rc)
    return rc;
  out->job_id = scp__ld32(p);
  out->queue_position = scp__ld32(p + 4);
  return scp__check_job_id(out->job_id);
}

int scp_parse_progress(const scp_frame_t *f, scp_progress_t *out) {
  const uint8_t *p = f->payload;
  int rc = exact(f, SCP_PROGRESS, 16);
  if (rc)
    return rc;
  out->job_id = scp__ld32(p);
  out->stage = scp__ld32(p + 4);
  out->fraction = scp__ldf64(p + 8);
  return scp__check_progress(out);
}

static int is_chunk_type(uint16_t type) {
  return type == SCP_POINTS || type == SCP_TRIANGLES || type == SCP_NORMALS ||
         type == SCP_VERTICES || type == SCP_COMPONENTS;
}

int scp_parse_chunk(const scp_frame_t *f, scp_chunk_t *out) {
  const uint8_t *p = f->payload;
  if (!is_chunk_type(f->type))
    return SCP_EINVAL;
  int rc = at_least(f, f->type, SCP_CHUNK_HEADER);
  if (rc || (rc = zero32(p + 20)))
    return rc;
  out->type = f->type;
  out->job_id = scp__ld32(p);
  out->count = scp__ld32(p + 4);
  out->first = scp__ld64(p + 8);
  out->format = scp__ld32(p + 16);
  out->data = p + SCP_CHUNK_HEADER;
  /* Without a known element size the layout cannot be checked; the frame
   * is still well framed, so this is an invalid field, not a broken
   * stream. */
  size_t size = scp_format_size(out->format);
  if (size == 0)
    return SCP_ERANGE;
  if (SCP_CHUNK_HEADER + (uint64_t)out->count * size != f->length)
    return SCP_ELENGTH;
  rc = scp__check_chunk_fields(out->type, out->job_id, out->count, out->first,
                               out->format);
  if (rc)
    return rc;
  if (out->type == SCP_COMPONENTS) {
    for (uint32_t i = 0; i < out->count; i++)
      if ((int32_t)scp__ld32(out->data + 4 * (size_t)i) < -1)
        return SCP_ERANGE;
  }
  return 0;
}

int scp__values_check(const uint8_t *p, size_t len, uint32_t count) {
  const uint8_t *end = p + len;
  int bad = 0;
  /* Every entry takes at least 11 bytes, so this loop ends after at most
   * len / 11 rounds whatever count claims. */
  for (uint32_t i = 0; i < count; i++) {
    if (end - p < 2)
      return SCP_ELENGTH;
    uint8_t kind = p[0];
    uint8_t name_len = p[1];
    if (end - p < 10 + (ptrdiff_t)name_len)
      return SCP_ELENGTH;
    /* A bad entry is remembered but the walk goes on: a list that is both
     * invalid and misframed must be reported as misframed. */
    if (!bad && (kind == 0 || !scp__name_ok((const char *)p + 2, name_len)))
      bad = SCP_ERANGE;
    p += 10 + (size_t)name_len;
  }
  if (p != end)
    return SCP_ELENGTH;
  return bad;
}

static int parse_values(const uint8_t *p, size_t len, uint32_t count,
                        scp_values_t *out) {
  out->count = count;
  out->data = p;
  out->len = len;
  return scp__values_check(p, len, count);
}

int scp_parse_job_done(const scp_frame_t *f, scp_job_done_t *out) {
  const uint8_t *p = f->payload;
  int rc = at_least(f, SCP_JOB_DONE, 32);
  if (rc)
    return rc;
  out->job_id = scp__ld32(p);
  out->triangles = scp__ld64(p + 8);
  out->normals = scp__ld64(p + 16);
  out->components = scp__ld64(p + 24);
  rc = parse_values(p + 32, f->length - 32, scp__ld32(p + 4), &out->values);
  if (rc)
    return rc;
  return scp__check_job_id(out->job_id);
}

int scp_parse_job_error(const scp_frame_t *f, scp_job_error_t *out) {
  const uint8_t *p = f->payload;
  int rc = at_least(f, SCP_JOB_ERROR, 16);
  if (rc || (rc = zero32(p + 12)))
    return rc;
  uint32_t n = scp__ld32(p + 8);
  if ((uint64_t)16 + n != f->length)
    return SCP_ELENGTH;
  out->job_id = scp__ld32(p);
  out->code = scp__ld32(p + 4);
  out->message[0] = '\0';
  if ((rc = scp__check_job_error_fields(out)))
    return rc;
  return copy_text(out->message, p + 16, n);
}

int scp_parse_stats(const scp_frame_t *f, scp_stats_t *out) {
  const uint8_t *p = f->payload;
  int rc = at_least(f, SCP_STATS, 8);
  if (rc)
    return rc;
  out->tag = scp__ld32(p);
  return parse_values(p + 8, f->length - 8, scp__ld32(p + 4), &out->values);
}

int scp_parse(const scp_frame_t *f, scp_msg_t *out) {
  out->type = f->type;
  switch (f->type) {
  case SCP_HELLO:
    return scp_parse_hello(f, &out->u.hello);
  case SCP_WELCOME:
    return scp_parse_welcome(f, &out->u.welcome);
  case SCP_ERROR:
    return scp_parse_error(f, &out->u.error);
  case SCP_PING:
    return scp_parse_ping(f, &out->u.token);
  case SCP_PONG:
    return scp_parse_pong(f, &out->u.token);
  case SCP_JOB_BEGIN:
    return scp_parse_job_begin(f, &out->u.job_begin);
  case SCP_POINTS:
  case SCP_TRIANGLES:
  case SCP_NORMALS:
  case SCP_VERTICES:
  case SCP_COMPONENTS:
    return scp_parse_chunk(f, &out->u.chunk);
  case SCP_JOB_END:
    return scp_parse_job_end(f, &out->u.job_end);
  case SCP_CANCEL:
    return scp_parse_cancel(f, &out->u.job_id);
  case SCP_STATS_REQUEST:
    return scp_parse_stats_request(f, &out->u.tag);
  case SCP_ACCEPTED:
    return scp_parse_accepted(f, &out->u.accepted);
  case SCP_PROGRESS:
    return scp_parse_progress(f, &out->u.progress);
  case SCP_JOB_DONE:
    return scp_parse_job_done(f, &out->u.job_done);
  case SCP_JOB_ERROR:
    return scp_parse_job_error(f, &out->u.job_error);
  case SCP_STATS:
    return scp_parse_stats(f, &out->u.stats);
  }
  return SCP_EUNKNOWN_TYPE;
}

int scp_parse_as(const scp_frame_t *f, int role, scp_msg_t *out) {
  int senders = scp_type_senders(f->type);
  out->type = f->type;
  if ((role == SCP_ROLE_SERVER && !(senders & SCP_FROM_CLIENT)) ||
      (role == SCP_ROLE_CLIENT && !(senders & SCP_FROM_SERVER)))
    return SCP_EUNKNOWN_TYPE;
  return scp_parse(f, out);
}

int scp_frame_job_id(const scp_frame_t *f, uint32_t *job_id) {
  switch (f->type) {
  case SCP_JOB_BEGIN:
  case SCP_POINTS:
  case SCP_JOB_END:
  case SCP_CANCEL:
  case SCP_ACCEPTED:
  case SCP_PROGRESS:
  case SCP_TRIANGLES:
  case SCP_NORMALS:
  case SCP_VERTICES:
  case SCP_COMPONENTS:
  case SCP_JOB_DONE:
  case SCP_JOB_ERROR:
    if (f->length < 4)
      return 0;
    *job_id = scp__ld32(f->payload);
    return 1;
  }
  return 0;
}

/*
 * Chunk accessors. A format that does not match the accessor gives zeros
 * rather than reading past the data, since the data holds count elements
 * of the chunk's own size.
 */
void scp_chunk_xyz(const scp_chunk_t *c, uint32_t i, double out[3]) {
  const uint8_t *p;
  switch (c->format) {
  case SCP_F32_XYZ:
    p = c->data + 12 * (size_t)i;
    for (int k = 0; k < 3; k++)
      out[k] = scp__ldf32(p + 4 * k);
    return;
  case SCP_F64_XYZ:
    p = c->data + 24 * (size_t)i;
    for (int k = 0; k < 3; k++)
      out[k] = scp__ldf64(p + 8 * k);
    return;
  }
  out[0] = out[1] = out[2] = 0.0;
}

/* Rounds to float, saturating to infinity, since C leaves the conversion of
 * a finite double beyond the float range undefined. */
static float to_f32(double x) {
  if (x > FLT_MAX)
    return INFINITY;
  if (x < -FLT_MAX)
    return -INFINITY;
  return (float)x;
}

void scp_chunk_xyz_f32(const scp_chunk_t *c, uint32_t i, float out[3]) {
  if (c->format == SCP_F32_XYZ) {
    const uint8_t *p = c->data + 12 * (size_t)i;
    for (int k = 0; k < 3; k++)
      out[k] = scp__ldf32(p + 4 * k);
    return;
  }
  double xyz[3];
  scp_chunk_xyz(c, i, xyz);
  for (int k = 0; k < 3; k++)
    out[k] = to_f32(xyz[k]);
}

void scp_chunk_triangle(const scp_chunk_t *c, uint32_t i, uint32_t out[3]) {
  if (c->format != SCP_U32_TRIANGLE) {
    out[0] = out[1] = out[2] = 0;
    return;
  }
  const uint8_t *p = c->data + 12 * (size_t)i;
  for (int k = 0; k < 3; k++)
    out[k] = scp__ld32(p + 4 * k);
}

int32_t scp_chunk_i32(const scp_chunk_t *c, uint32_t i) {
  if (c->format != SCP_I32)
    return 0;
  return (int32_t)scp__ld32(c->data + 4 * (size_t)i);
}

int scp_chunk_copy_xyz(const scp_chunk_t *c, double *out) {
  if (c->format != SCP_F32_XYZ && c->format != SCP_F64_XYZ)
    return SCP_EINVAL;
  for (uint32_t i = 0; i < c->count; i++)
    scp_chunk_xyz(c, i, out + 3 * (size_t)i);
  return 0;
}

int scp_chunk_copy_triangles(const scp_chunk_t *c, uint32_t *out) {
  if (c->format != SCP_U32_TRIANGLE)
    return SCP_EINVAL;
  for (size_t i = 0; i < 3 * (size_t)c->count; i++)
    out[i] = scp__ld32(c->data + 4 * i);
  return 0;
}

int scp_chunk_copy_i32(const scp_chunk_t *c, int32_t *out) {
  if (c->format != SCP_I32)
    return SCP_EINVAL;
  for (uint32_t i = 0; i < c->count; i++)
    out[i] = (int32_t)scp__ld32(c->data + 4 * (size_t)i);
  return 0;
}

void scp_values_begin(const scp_values_t *values, scp_value_iter_t *it) {
  it->p = values->data;
  it->end = values->data + values->len;
  it->left = values->count;
  it->name[0] = '\0';
}

int scp_values_next(scp_value_iter_t *it, scp_value_t *out) {
  /* The list was checked by its parser; these tests only keep a caller's
   * hand-made view from sending the walk past its end. */
  if (it->left == 0 || it->end - it->p < 2)
    return 0;
  uint8_t name_len = it->p[1];
  if (name_len > SCP_NAME_MAX || it->end - it->p < 10 + (ptrdiff_t)name_len)
    return 0;
  uint64_t bits = scp__ld64(it->p + 2 + name_len);
  memcpy(it->name, it->p + 2, name_len);
  it->name[name_len] = '\0';
  out->name = it->name;
  out->kind = it->p[0];
  switch (out->kind) {
  case SCP_KIND_I64:
    memcpy(&out->v.i, &bits, sizeof bits);
    break;
  case SCP_KIND_F64:
    memcpy(&out->v.f, &bits, sizeof bits);
    break;
  default:
    out->v.u = bits;
    break;
  }
  it->p += 10 + (size_t)name_len;
  it->left--;
  return 1;
}

int scp_values_find(const scp_values_t *values, const char *name,
                    scp_value_iter_t *it, scp_value_t *out) {
  scp_values_begin(values, it);
  while (scp_values_next(it, out))
    if (strcmp(out->name, name) == 0)
      return 1;
  return 0;
}
