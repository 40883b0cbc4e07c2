/*
 * Error codes and messages of the point and mesh file module: the public
 * code names and texts, and the "<path>: [line|byte N: ]<what>" messages
 * every failure writes.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "scf_internal.h"

#include <stdio.h>

const char *scf_strerror(int code) {
  switch (code) {
  case SCF_OK:
    return "success";
#define SCF_ERR_TEXT_(name, value, text)                                       \
  case SCF_E##name:                                                            \
    return text;
    SCF_ERRNO_MAP(SCF_ERR_TEXT_)
#undef SCF_ERR_TEXT_
  default:
    return "unknown error";
  }
}

const char *scf_err_name(int code) {
  switch (code) {
  case SCF_OK:
    return "OK";
#define SCF_ERR_NAME_(name, value, text)                                       \
  case SCF_E##name:                                                            \
    return #name;
    SCF_ERRNO_MAP(SCF_ERR_NAME_)
#undef SCF_ERR_NAME_
  default:
    return "UNKNOWN";
  }
}

/*
 * Writes "<path>: [<kind> <where>: ]<message>" to msg and returns code.
 * kind is "line", "byte" or NULL.
 */
int scf__vfail(char *msg, size_t msg_len, int code, const char *path,
               const char *kind, uint64_t where, const char *fmt, va_list ap) {
  if (msg == NULL || msg_len == 0)
    return code;
  int n = kind ? snprintf(msg, msg_len, "%s: %s %llu: ", path, kind,
                          (scf__ull)where)
               : snprintf(msg, msg_len, "%s: ", path);
  if (n >= 0 && (size_t)n < msg_len)
    vsnprintf(msg + n, msg_len - (size_t)n, fmt, ap);
  return code;
}

SCF__PRINTF_LIKE(5, 6)
int scf__fail(char *msg, size_t msg_len, int code, const char *path,
              const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  scf__vfail(msg, msg_len, code, path ? path : "(null)", NULL, 0, fmt, ap);
  va_end(ap);
  return code;
}

/*
 * Tokens from a file go into messages; non-printing bytes are replaced so
 * that a binary file read as text still gives a one-line, readable message.
 */
const char *scf__show(const char *tok, char buf[SCF__SHOW_MAX + 4]) {
  size_t i = 0;
  for (; tok[i] && i < SCF__SHOW_MAX; i++) {
    unsigned char c = (unsigned char)tok[i];
    buf[i] = (c < 0x20 || c == 0x7f) ? '?' : (char)c;
  }
  if (tok[i]) {
    memcpy(buf + i, "...", 3);
    i += 3;
  }
  buf[i] = '\0';
  return buf;
}
