/*
 * The token of TCP clients (PROTOCOL.md 5.1): read once at start-up from
 * --token-file, checked in every HELLO that comes over TCP.
 *
 * The file is the secret itself, so it must be the daemon's alone: one that
 * group or others may read (or write) is refused, as ssh refuses a private
 * key anyone can read, rather than trusted with a warning.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "conn.h"
#include "daemon.h"
#include "log.h"

#include <errno.h>
#include <fcntl.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* The shortest token taken: 16 bytes leave no room for guessing over a
 * network, and any generator of secrets makes more. */
#define SCD_TOKEN_MIN 16

/* memset through a volatile pointer: a wipe of memory that is about to be
 * freed or to go out of scope is otherwise a dead store the compiler may
 * drop. */
static void *(*const volatile wipe)(void *, int, size_t) = memset;

int scd_token_load(scd_server_t *srv, const char *path) {
  int fd = open(path, O_RDONLY | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) {
    scd_error("cannot open the token file %s: %s", path, strerror(errno));
    return -1;
  }
  struct stat st;
  if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    scd_error("the token file %s is not a regular file", path);
    close(fd);
    return -1;
  }
  if (st.st_mode & 077) {
    scd_error("the token file %s is open to group or others (mode %04o); "
              "refusing to use it: chmod 600 %s",
              path, (unsigned)(st.st_mode & 07777), path);
    close(fd);
    return -1;
  }
  /* One byte more than a token may have, and its line end. */
  uint8_t buf[SCP_TOKEN_MAX + 3];
  size_t len = 0;
  for (;;) {
    ssize_t n = read(fd, buf + len, sizeof buf - len);
    if (n < 0 && errno == EINTR)
      continue;
    if (n < 0) {
      scd_error("cannot read the token file %s: %s", path, strerror(errno));
      close(fd);
      return -1;
    }
    if (n == 0 || (len += (size_t)n) == sizeof buf)
      break;
  }
  close(fd);
  /* A file written by an editor or by echo ends its one line. */
  if (len && buf[len - 1] == '\n')
    len--;
  if (len && buf[len - 1] == '\r')
    len--;
  if (len < SCD_TOKEN_MIN || len > SCP_TOKEN_MAX) {
    scd_error("the token in %s must have %d to %d bytes (one line; the line "
              "end is not part of it)",
              path, SCD_TOKEN_MIN, SCP_TOKEN_MAX);
    wipe(buf, 0, sizeof buf);
    return -1;
  }
  memcpy(srv->token, buf, len);
  srv->token_len = len;
  wipe(buf, 0, sizeof buf);
  return 0;
}

void scd_token_forget(scd_server_t *srv) {
  wipe(srv->token, 0, sizeof srv->token);
  srv->token_len = 0;
}

int scd_auth_hello(scd_conn_t *c, const scp_hello_t *h) {
  /* On a Unix socket the file's mode is the access control, and a token
   * sent anyway is ignored (PROTOCOL.md 5.1). */
  if (!c->tcp)
    return 1;
  scd_server_t *srv = c->srv;
  if (srv->token_len && scp_token_equal(h, srv->token, srv->token_len))
    return 1;
  /* Which of the two it was helps whoever configures a client, and says
   * nothing of the token itself. */
  const char *what = (h->features & SCP_FEATURE_TOKEN) && h->token_len
                         ? "wrong token"
                         : "no token";
  scd_warn("conn %llu: refused %s: %s", (ull)c->id, c->peer, what);
  scd_conn_fatal(c, SCP_WIRE_AUTH, 0, SCP_HELLO,
                 "authentication failed: %s (give the daemon's token)", what);
  return 0;
}
