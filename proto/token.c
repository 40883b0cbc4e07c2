/*
 * The token file (PROTOCOL.md 5.1), read by the daemon and by the clients
 * by the same rules, so that a file one side refuses is refused by the
 * other too. The file is the secret itself: one that group or others may
 * read (or write) is refused, as ssh refuses a private key anyone can
 * read, rather than trusted with a warning.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "scproto.h"

#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* memset through a volatile pointer: a wipe of memory that is about to be
 * freed or to go out of scope is otherwise a dead store the compiler may
 * drop. */
static void *(*const volatile wipe)(void *, int, size_t) = memset;

void scp_wipe(void *p, size_t n) { wipe(p, 0, n); }

static int fail(char *msg, size_t msg_len, const char *fmt, ...) {
  if (msg_len) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, msg_len, fmt, ap);
    va_end(ap);
  }
  return -1;
}

int scp_token_read(const char *path, size_t min_len, uint8_t *token,
                   size_t *len, char *msg, size_t msg_len) {
  int fd = open(path, O_RDONLY | O_CLOEXEC | O_NOCTTY);
  if (fd < 0)
    return fail(msg, msg_len, "cannot open the token file %s: %s", path,
                strerror(errno));
  struct stat st;
  if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    close(fd);
    return fail(msg, msg_len, "the token file %s is not a regular file", path);
  }
  if (st.st_mode & 077) {
    close(fd);
    return fail(msg, msg_len,
                "the token file %s is open to group or others (mode %04o); "
                "refusing to use it: chmod 600 %s",
                path, (unsigned)(st.st_mode & 07777), path);
  }
  /* One byte more than a token may have, and its line end. */
  uint8_t buf[SCP_TOKEN_MAX + 3];
  size_t n = 0;
  for (;;) {
    ssize_t got = read(fd, buf + n, sizeof buf - n);
    if (got < 0 && errno == EINTR)
      continue;
    if (got < 0) {
      int e = errno;
      close(fd);
      wipe(buf, 0, sizeof buf);
      return fail(msg, msg_len, "cannot read the token file %s: %s", path,
                  strerror(e));
    }
    if (got == 0 || (n += (size_t)got) == sizeof buf)
      break;
  }
  close(fd);
  /* A file written by an editor or by echo ends its one line. */
  if (n && buf[n - 1] == '\n')
    n--;
  if (n && buf[n - 1] == '\r')
    n--;
  if (n < (min_len ? min_len : 1) || n > SCP_TOKEN_MAX) {
    wipe(buf, 0, sizeof buf);
    return fail(msg, msg_len,
                "the token in %s must have %zu to %d bytes (one line; the "
                "line end is not part of it)",
                path, min_len ? min_len : 1, SCP_TOKEN_MAX);
  }
  memcpy(token, buf, n);
  *len = n;
  wipe(buf, 0, sizeof buf);
  return 0;
}
