/*
 * Field checks, one place for both directions: the encoder refuses to write
 * what the parser would refuse to read.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "scproto.h"
#include "wire.h"

/* The double nearest pi/2. theta must stay below it, so M_PI / 2 as a
 * caller would write it is refused like the open interval says. */
#define SCP_HALF_PI 1.5707963267948966

int scp__check_hello(const scp_hello_t *m) {
  if (m->version_min < 1 || m->version_min > m->version_max)
    return SCP_EVERSION;
  if (m->max_frame < SCP_FRAME_MIN)
    return SCP_ERANGE;
  if ((m->features & SCP_FEATURE_TOKEN) &&
      (m->token_len > SCP_TOKEN_MAX || (m->token_len && !m->token)))
    return SCP_ERANGE;
  return 0;
}

int scp__check_welcome(const scp_welcome_t *m) {
  if (m->version != SCP_VERSION)
    return SCP_EVERSION;
  if (m->max_frame < SCP_FRAME_MIN || m->max_frame > SCP_FRAME_CEILING)
    return SCP_ERANGE;
  if (m->max_jobs < 1 || m->max_points < 1)
    return SCP_ERANGE;
  return 0;
}

int scp__check_error_fields(const scp_error_t *m) {
  if (m->code == 0)
    return SCP_ERANGE;
  if (m->flags & ~SCP_ERROR_FATAL)
    return SCP_EFLAGS;
  return 0;
}

int scp__check_job_id(uint32_t job_id) {
  return job_id == 0 ? SCP_ERANGE : 0;
}

int scp__check_job_begin(const scp_job_begin_t *m) {
  if (m->job_id == 0 || m->mode >= SCP_MODE_COUNT)
    return SCP_ERANGE;
  /* Written so that NaN fails every comparison and is refused too. */
  if (!(m->r > 0.0 && m->r < 0.5))
    return SCP_ERANGE;
  if (!(m->theta == 0.0 || (m->theta > 0.0 && m->theta < SCP_HALF_PI)))
    return SCP_ERANGE;
  if (m->flags & ~(SCP_JOB_NORMALS | SCP_JOB_NORMALS_F64))
    return SCP_EFLAGS;
  if ((m->flags & SCP_JOB_NORMALS_F64) && !(m->flags & SCP_JOB_NORMALS))
    return SCP_EFLAGS;
  return 0;
}

int scp__check_progress(const scp_progress_t *m) {
  if (m->job_id == 0 || m->stage >= SCP_STAGE_COUNT)
    return SCP_ERANGE;
  if (!(m->fraction >= 0.0 && m->fraction <= 1.0))
    return SCP_ERANGE;
  return 0;
}

int scp__check_job_error_fields(const scp_job_error_t *m) {
  if (m->job_id == 0 || m->code == 0)
    return SCP_ERANGE;
  return 0;
}

int scp__check_chunk_fields(uint16_t type, uint32_t job_id, uint32_t count,
                            uint64_t first, uint32_t format) {
  if (job_id == 0 || count == 0)
    return SCP_ERANGE;
  if (!scp__chunk_format_ok(type, format))
    return SCP_ERANGE;
  if (first > UINT64_MAX - count)
    return SCP_ERANGE;
  return 0;
}
