/*
 * The buffered reader every format reads through, and the out-of-line
 * parts of the shared helpers declared in scf_internal.h.
 *
 * scf__rd_t is a fixed buffer over a file descriptor that knows the byte
 * offset and line number of what it hands out, so that every error can say
 * where it happened. Text formats are read line by line, binary ones record
 * by record; nothing depends on the whole file fitting in memory. Counts
 * from headers are checked against the bytes left in the file before
 * anything is allocated for them, and allocation then grows with the data
 * actually read, which also covers inputs of unknown size.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "scf_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

int scf__rd_fail_line(scf__rd_t *r, uint64_t line, int code, const char *fmt,
                      ...) {
  va_list ap;
  va_start(ap, fmt);
  scf__vfail(r->msg, r->msg_len, code, r->path, "line", line, fmt, ap);
  va_end(ap);
  return code;
}

int scf__rd_fail_byte(scf__rd_t *r, uint64_t offset, int code, const char *fmt,
                      ...) {
  va_list ap;
  va_start(ap, fmt);
  scf__vfail(r->msg, r->msg_len, code, r->path, "byte", offset, fmt, ap);
  va_end(ap);
  return code;
}

int scf__rd_open(scf__rd_t *r, const char *path, char *msg, size_t msg_len) {
  memset(r, 0, sizeof *r);
  r->fd = -1;
  r->path = path;
  r->msg = msg;
  r->msg_len = msg_len;
  r->size = UINT64_MAX;
  /* A duplicate, so that closing the reader leaves standard input open. */
  r->fd = scf__is_stdio(path) ? fcntl(STDIN_FILENO, F_DUPFD_CLOEXEC, 0)
                              : open(path, O_RDONLY | O_CLOEXEC);
  if (r->fd < 0) {
    int e = errno;
    return scf__fail(msg, msg_len, e == ENOENT ? SCF_ENOENT : SCF_EIO, path,
                     "cannot open: %s", strerror(e));
  }
  struct stat st;
  if (fstat(r->fd, &st) != 0)
    return scf__fail(msg, msg_len, SCF_EIO, path, "cannot stat: %s",
                     strerror(errno));
  if (S_ISDIR(st.st_mode))
    return scf__fail(msg, msg_len, SCF_EIO, path, "is a directory, not a file");
  if (S_ISREG(st.st_mode))
    r->size = (uint64_t)st.st_size;
  r->buf = malloc(SCF__RD_CAP + 1);
  if (r->buf == NULL)
    return scf__fail(msg, msg_len, SCF_ENOMEM, path,
                     "out of memory for the read buffer");
  return 0;
}

void scf__rd_close(scf__rd_t *r) {
  if (r->fd >= 0)
    close(r->fd);
  free(r->buf);
  r->fd = -1;
  r->buf = NULL;
}

/* Moves the unread bytes to the front and reads once more (sets eof). */
int scf__rd_fill(scf__rd_t *r) {
  if (r->pos > 0) {
    memmove(r->buf, r->buf + r->pos, r->end - r->pos);
    r->base += r->pos;
    r->end -= r->pos;
    r->pos = 0;
  }
  while (!r->eof && r->end < SCF__RD_CAP) {
    ssize_t n = read(r->fd, r->buf + r->end, SCF__RD_CAP - r->end);
    if (n < 0) {
      if (errno == EINTR)
        continue;
      return scf__rd_fail_byte(r, r->base + r->end, SCF_EIO, "read failed: %s",
                               strerror(errno));
    }
    if (n == 0)
      r->eof = 1;
    else
      r->end += (size_t)n;
    break;
  }
  return 0;
}

/* Consumes n bytes, or fewer at the end of the file (*skipped says). */
int scf__rd_skip(scf__rd_t *r, uint64_t n, uint64_t *skipped) {
  uint64_t done = 0;
  while (done < n) {
    if (r->pos == r->end) {
      if (r->eof)
        break;
      int rc = scf__rd_fill(r);
      if (rc < 0)
        return rc;
      continue;
    }
    size_t avail = r->end - r->pos;
    size_t take = (n - done) < avail ? (size_t)(n - done) : avail;
    r->pos += take;
    done += take;
  }
  *skipped = done;
  return 0;
}

int scf__vbuf_reserve(scf__rd_t *r, scf__vbuf_t *v, uint64_t cap) {
  if (cap <= v->cap)
    return 0;
  if (cap > SIZE_MAX / (3 * sizeof(double)))
    return scf__fail(r->msg, r->msg_len, SCF_ENOMEM, r->path,
                     "too many points for memory (%llu)", (scf__ull)cap);
  double *p = realloc(v->xyz, (size_t)cap * 3 * sizeof(double));
  if (p == NULL)
    return scf__fail(r->msg, r->msg_len, SCF_ENOMEM, r->path,
                     "out of memory for %llu points", (scf__ull)cap);
  v->xyz = p;
  v->cap = (size_t)cap;
  return 0;
}

/* The slow path of scf__tbuf_push(): doubles the array. */
int scf__tbuf_grow(scf__rd_t *r, scf__tbuf_t *t) {
  size_t cap = t->cap ? t->cap * 2 : 4096;
  if (cap < t->cap || cap > SIZE_MAX / (3 * sizeof(uint32_t)))
    return scf__fail(r->msg, r->msg_len, SCF_ENOMEM, r->path,
                     "too many triangles for memory");
  uint32_t *p = realloc(t->idx, cap * 3 * sizeof(uint32_t));
  if (p == NULL)
    return scf__fail(r->msg, r->msg_len, SCF_ENOMEM, r->path,
                     "out of memory after %zu triangles", t->count);
  t->idx = p;
  t->cap = cap;
  return 0;
}

int scf__parse_u64(const char *tok, uint64_t *out) {
  int64_t v;
  if (tok[0] == '-' || tok[0] == '+' || scf__parse_i64(tok, &v) < 0)
    return -1;
  *out = (uint64_t)v;
  return 0;
}

int scf__bad_numbers(scf__rd_t *r, const char *what, const char *bad,
                     int ntok) {
  char buf[SCF__SHOW_MAX + 4];
  if (bad != NULL)
    return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                             "expected 3 numbers%s, got '%s'", what,
                             scf__show(bad, buf));
  return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                           "expected 3 numbers%s, got %d", what, ntok);
}
