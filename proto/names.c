/*
 * Names and messages: the error tables, types, modes, stages and formats.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "scproto.h"
#include "wire.h"

#include <stdio.h>
#include <stdlib.h>

const char *scp_strerror(int code) {
  switch (code) {
  case SCP_OK:
    return "success";
#define SCP_ERR_MSG_(name, value, wire, fatal, msg)                            \
  case SCP_E##name:                                                            \
    return msg;
    SCP_ERRNO_MAP(SCP_ERR_MSG_)
#undef SCP_ERR_MSG_
  }
  return "unknown error";
}

const char *scp_err_name(int code) {
  switch (code) {
  case SCP_OK:
    return "OK";
#define SCP_ERR_NAME_(name, value, wire, fatal, msg)                           \
  case SCP_E##name:                                                            \
    return #name;
    SCP_ERRNO_MAP(SCP_ERR_NAME_)
#undef SCP_ERR_NAME_
  }
  return "UNKNOWN";
}

uint32_t scp_err_to_wire(int code) {
  switch (code) {
#define SCP_ERR_WIRE_(name, value, wire, fatal, msg)                           \
  case SCP_E##name:                                                            \
    return SCP_WIRE_##wire;
    SCP_ERRNO_MAP(SCP_ERR_WIRE_)
#undef SCP_ERR_WIRE_
  }
  return SCP_WIRE_INTERNAL;
}

int scp_err_is_fatal(int code) {
  switch (code) {
#define SCP_ERR_FATAL_(name, value, wire, fatal, msg)                          \
  case SCP_E##name:                                                            \
    return fatal;
    SCP_ERRNO_MAP(SCP_ERR_FATAL_)
#undef SCP_ERR_FATAL_
  }
  /* A code this table does not know cannot be judged safe to survive. */
  return code != SCP_OK;
}

const char *scp_wire_strerror(uint32_t code) {
  switch (code) {
#define SCP_WIRE_MSG_(name, value, msg)                                        \
  case SCP_WIRE_##name:                                                        \
    return msg;
    SCP_WIRE_MAP(SCP_WIRE_MSG_)
#undef SCP_WIRE_MSG_
  }
  return "unknown error";
}

const char *scp_wire_name(uint32_t code) {
  switch (code) {
#define SCP_WIRE_NAME_(name, value, msg)                                       \
  case SCP_WIRE_##name:                                                        \
    return #name;
    SCP_WIRE_MAP(SCP_WIRE_NAME_)
#undef SCP_WIRE_NAME_
  }
  return "UNKNOWN";
}

int scp_type_senders(uint16_t type) {
  switch (type) {
  case SCP_HELLO:
  case SCP_JOB_BEGIN:
  case SCP_POINTS:
  case SCP_JOB_END:
  case SCP_CANCEL:
  case SCP_STATS_REQUEST:
    return SCP_FROM_CLIENT;
  case SCP_ERROR:
  case SCP_PING:
  case SCP_PONG:
    return SCP_FROM_CLIENT | SCP_FROM_SERVER;
  case SCP_WELCOME:
  case SCP_ACCEPTED:
  case SCP_PROGRESS:
  case SCP_TRIANGLES:
  case SCP_NORMALS:
  case SCP_VERTICES:
  case SCP_COMPONENTS:
  case SCP_JOB_DONE:
  case SCP_JOB_ERROR:
  case SCP_STATS:
    return SCP_FROM_SERVER;
  }
  return 0;
}

const char *scp_type_name(uint16_t type) {
  switch (type) {
  case SCP_HELLO:
    return "HELLO";
  case SCP_WELCOME:
    return "WELCOME";
  case SCP_ERROR:
    return "ERROR";
  case SCP_PING:
    return "PING";
  case SCP_PONG:
    return "PONG";
  case SCP_JOB_BEGIN:
    return "JOB_BEGIN";
  case SCP_POINTS:
    return "POINTS";
  case SCP_JOB_END:
    return "JOB_END";
  case SCP_CANCEL:
    return "CANCEL";
  case SCP_STATS_REQUEST:
    return "STATS_REQUEST";
  case SCP_ACCEPTED:
    return "ACCEPTED";
  case SCP_PROGRESS:
    return "PROGRESS";
  case SCP_TRIANGLES:
    return "TRIANGLES";
  case SCP_NORMALS:
    return "NORMALS";
  case SCP_VERTICES:
    return "VERTICES";
  case SCP_COMPONENTS:
    return "COMPONENTS";
  case SCP_JOB_DONE:
    return "JOB_DONE";
  case SCP_JOB_ERROR:
    return "JOB_ERROR";
  case SCP_STATS:
    return "STATS";
  }
  return "?";
}

const char *scp_mode_name(uint32_t mode) {
  static const char *const names[SCP_MODE_COUNT] = {
      "shortcrust", "cocone", "boundary", "watertight", "auto"};
  return mode < SCP_MODE_COUNT ? names[mode] : "?";
}

const char *scp_stage_name(uint32_t stage) {
  static const char *const names[SCP_STAGE_COUNT] = {
      "input", "delaunay", "poles", "candidates", "prune", "extract"};
  if (stage < SCP_STAGE_COUNT)
    return names[stage];
  if (stage == SCP_STAGE_UPLOAD)
    return "upload";
  if (stage == SCP_STAGE_DOWNLOAD)
    return "download";
  return "?";
}

size_t scp_format_size(uint32_t format) {
  switch (format) {
  case SCP_F32_XYZ:
    return 12;
  case SCP_F64_XYZ:
    return 24;
  case SCP_U32_TRIANGLE:
    return 12;
  case SCP_I32:
    return 4;
  }
  return 0;
}

int scp__chunk_format_ok(uint16_t type, uint32_t format) {
  switch (type) {
  case SCP_POINTS:
  case SCP_NORMALS:
    return format == SCP_F32_XYZ || format == SCP_F64_XYZ;
  case SCP_VERTICES:
    /* Positions for the client to write as they are: never rounded. */
    return format == SCP_F64_XYZ;
  case SCP_TRIANGLES:
    return format == SCP_U32_TRIANGLE;
  case SCP_COMPONENTS:
    return format == SCP_I32;
  }
  return 0;
}

int scp__name_ok(const char *name, size_t len) {
  if (len < 1 || len > SCP_NAME_MAX)
    return 0;
  if (!(name[0] >= 'a' && name[0] <= 'z'))
    return 0;
  for (size_t i = 1; i < len; i++) {
    char c = name[i];
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' ||
          c == '.'))
      return 0;
  }
  return 1;
}

int scp__text_ok(const char *text, size_t len) {
  return len <= SCP_MESSAGE_MAX && memchr(text, 0, len) == NULL;
}

char *scp_default_socket(char *buf, size_t len) {
  const char *xdg = getenv("XDG_RUNTIME_DIR");
  if (xdg && xdg[0] == '/')
    snprintf(buf, len, "%s/shortcrust.sock", xdg);
  else
    snprintf(buf, len, "/run/shortcrust/shortcrust.sock");
  return buf;
}
