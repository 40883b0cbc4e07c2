/*
 * Atomic output: the temporary file is ".<name>.tmp.XXXXXX" in the
 * target's directory, so that rename() stays within one file system, and
 * it replaces the target only after everything was written and synced.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "scf_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#define TMP_BASE_MAX 200
/* The umask, read without changing it (umask() would, for all threads). */
static mode_t current_umask(void) {
  mode_t m = 022;
  FILE *f = fopen("/proc/self/status", "r");
  if (f == NULL)
    return m;
  char line[256];
  while (fgets(line, sizeof line, f) != NULL) {
    if (strncmp(line, "Umask:", 6) == 0) {
      m = (mode_t)strtoul(line + 6, NULL, 8);
      break;
    }
  }
  fclose(f);
  return m;
}

int scf__aout_errno(scf__aout_t *o, const char *what) {
  return scf__fail(o->msg, o->msg_len, SCF_EIO, o->path, "%s: %s", what,
                   strerror(errno));
}

void scf__aout_abort(scf__aout_t *o) {
  if (o->fp != NULL)
    fclose(o->fp);
  else if (o->fd >= 0)
    close(o->fd);
  if (o->tmp != NULL) {
    unlink(o->tmp);
    free(o->tmp);
  }
  o->fp = NULL;
  o->fd = -1;
  o->tmp = NULL;
}

/* A buffered stream over o->fd, the last step of opening either kind of
 * output. */
static int open_stream(scf__aout_t *o) {
  o->fp = fdopen(o->fd, "wb");
  if (o->fp == NULL) {
    int rc = scf__aout_errno(o, "fdopen failed");
    scf__aout_abort(o);
    return rc;
  }
  setvbuf(o->fp, NULL, _IOFBF, (size_t)1 << 20);
  return 0;
}

int scf__aout_open(scf__aout_t *o, const char *path, char *msg,
                   size_t msg_len) {
  memset(o, 0, sizeof *o);
  o->fd = -1;
  o->path = path;
  o->msg = msg;
  o->msg_len = msg_len;
  if (scf__is_stdio(path)) {
    /* Standard output: written in place (a pipe cannot be renamed over),
     * through a duplicate that commit closes. */
    o->path = "standard output";
    o->fd = fcntl(STDOUT_FILENO, F_DUPFD_CLOEXEC, 0);
    if (o->fd < 0)
      return scf__aout_errno(o, "cannot duplicate it");
    return open_stream(o);
  }
  const char *slash = strrchr(path, '/');
  const char *base = slash ? slash + 1 : path;
  size_t dirlen = (size_t)(base - path);
  if (*base == '\0')
    return scf__fail(msg, msg_len, SCF_EINVAL, path, "not a file name");
  /* The temporary name adds 12 bytes to the target's; a name near the
   * file system's limit (255 bytes) is cut so the temporary one fits. */
  size_t baselen = strlen(base);
  if (baselen > TMP_BASE_MAX)
    baselen = TMP_BASE_MAX;
  size_t len = dirlen + baselen + sizeof "..tmp.XXXXXX";
  o->tmp = malloc(len);
  if (o->tmp == NULL)
    return scf__fail(msg, msg_len, SCF_ENOMEM, path, "out of memory");
  snprintf(o->tmp, len, "%.*s.%.*s.tmp.XXXXXX", (int)dirlen, path, (int)baselen,
           base);
  o->fd = mkstemp(o->tmp);
  if (o->fd < 0) {
    int rc = scf__aout_errno(o, "cannot create a temporary file beside it");
    free(o->tmp);
    o->tmp = NULL;
    return rc;
  }
  struct stat st;
  mode_t mode = stat(path, &st) == 0 && S_ISREG(st.st_mode)
                    ? (st.st_mode & 07777)
                    : (0666 & ~current_umask());
  if (fchmod(o->fd, mode) != 0) {
    int rc = scf__aout_errno(o, "cannot set the mode of the temporary file");
    scf__aout_abort(o);
    return rc;
  }
  return open_stream(o);
}

int scf__aout_commit(scf__aout_t *o) {
  if (fflush(o->fp) != 0 || ferror(o->fp))
    return scf__aout_errno(o, "write failed");
  if (o->tmp == NULL) { /* standard output */
    FILE *fp = o->fp;
    o->fp = NULL;
    o->fd = -1;
    return fclose(fp) != 0 ? scf__aout_errno(o, "close failed") : 0;
  }
  if (fsync(o->fd) != 0)
    return scf__aout_errno(o, "fsync failed");
  FILE *fp = o->fp;
  o->fp = NULL;
  o->fd = -1;
  if (fclose(fp) != 0)
    return scf__aout_errno(o, "close failed");
  if (rename(o->tmp, o->path) != 0)
    return scf__aout_errno(o, "cannot rename the temporary file over it");
  free(o->tmp);
  o->tmp = NULL;
  /* The rename itself becomes durable when the directory is synced; a
   * failure there leaves a complete file, so it is not reported. */
  const char *slash = strrchr(o->path, '/');
  char *dir = slash ? strdup(o->path) : NULL;
  if (dir != NULL)
    dir[slash - o->path + (slash == o->path)] = '\0';
  int dfd = open(slash ? (dir ? dir : "/") : ".", O_RDONLY | O_CLOEXEC);
  if (dfd >= 0) {
    fsync(dfd);
    close(dfd);
  }
  free(dir);
  return 0;
}

int scf__out_printf(scf__aout_t *o, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  int n = vfprintf(o->fp, fmt, ap);
  va_end(ap);
  return n < 0 ? scf__aout_errno(o, "write failed") : 0;
}

int scf_write_atomic(const char *path, const void *data, size_t len, char *msg,
                     size_t msg_len) {
  if (msg != NULL && msg_len > 0)
    msg[0] = '\0';
  if (path == NULL || (data == NULL && len > 0))
    return scf__fail(msg, msg_len, SCF_EINVAL, path, "NULL argument");
  scf__aout_t o;
  int rc = scf__aout_open(&o, path, msg, msg_len);
  if (rc == 0 && (rc = scf__out_write(&o, data, len)) == 0)
    rc = scf__aout_commit(&o);
  if (rc < 0)
    scf__aout_abort(&o);
  return rc;
}
