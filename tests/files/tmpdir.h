/*
 * A private temporary directory, small file helpers and the check of a
 * failed read for the file-format tests. Failures go through sct_assert.h, like
 * every test's.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SC_TESTS_FILES_TMPDIR_H
#define SC_TESTS_FILES_TMPDIR_H

#include <dirent.h>
#include <inttypes.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "sct_assert.h"
#include "shortcrust_files.h"

static char tmp_dir_[256];

static inline void tmp_remove_tree(const char *path) {
  struct stat st;
  if (lstat(path, &st) != 0)
    return;
  if (S_ISDIR(st.st_mode)) {
    DIR *d = opendir(path);
    struct dirent *e;
    while (d != NULL && (e = readdir(d)) != NULL) {
      if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0)
        continue;
      size_t len = strlen(path) + strlen(e->d_name) + 2;
      char *sub = malloc(len);
      if (sub == NULL)
        break;
      snprintf(sub, len, "%s/%s", path, e->d_name);
      tmp_remove_tree(sub);
      free(sub);
    }
    if (d != NULL)
      closedir(d);
    rmdir(path);
  } else {
    unlink(path);
  }
}

static inline void tmp_cleanup_(void) {
  if (tmp_dir_[0] != '\0')
    tmp_remove_tree(tmp_dir_);
}

static inline void tmp_init(void) {
  const char *base = getenv("TMPDIR");
  snprintf(tmp_dir_, sizeof tmp_dir_, "%s/sc-test-XXXXXX",
           base && *base ? base : "/tmp");
  if (mkdtemp(tmp_dir_) == NULL)
    ASSERT_FAIL("mkdtemp(%s) failed", tmp_dir_);
  atexit(tmp_cleanup_);
}

/* A path in the private directory; eight results stay valid at a time. */
static inline const char *tmp_path(const char *name) {
  static char bufs[8][512];
  static unsigned next;
  char *b = bufs[next++ % 8];
  snprintf(b, sizeof bufs[0], "%s/%s", tmp_dir_, name);
  return b;
}

static inline void write_bytes(const char *path, const void *data,
                               size_t len) {
  FILE *f = fopen(path, "wb");
  if (f == NULL || fwrite(data, 1, len, f) != len || fclose(f) != 0)
    ASSERT_FAIL("cannot write %s", path);
}

static inline void write_text(const char *path, const char *text) {
  write_bytes(path, text, strlen(text));
}

/* The whole file, NUL-terminated; the caller frees it. */
static inline char *read_all(const char *path, size_t *len) {
  FILE *f = fopen(path, "rb");
  if (f == NULL)
    ASSERT_FAIL("cannot open %s", path);
  size_t cap = 4096, n = 0;
  char *buf = malloc(cap);
  size_t got;
  while (buf != NULL && (got = fread(buf + n, 1, cap - n - 1, f)) > 0) {
    n += got;
    if (cap - n - 1 == 0) {
      char *nb = realloc(buf, cap * 2);
      if (nb == NULL)
        free(buf);
      buf = nb;
      cap *= 2;
    }
  }
  fclose(f);
  if (buf == NULL)
    ASSERT_FAIL("out of memory reading %s", path);
  buf[n] = '\0';
  if (len != NULL)
    *len = n;
  return buf;
}

/* The number of entries of a directory whose names contain needle. */
static inline int count_entries(const char *dir, const char *needle) {
  DIR *d = opendir(dir);
  int n = 0;
  struct dirent *e;
  while (d != NULL && (e = readdir(d)) != NULL)
    if (strstr(e->d_name, needle) != NULL)
      n++;
  if (d != NULL)
    closedir(d);
  return n;
}

/* Reads path as points (mesh 0) or as a mesh and expects code rc with a
 * message that starts with the path and contains both fragments. */
static inline void expect_read_fail(const char *path, int mesh, int rc,
                                    const char *frag1, const char *frag2) {
  char msg[512];
  scf_points_t p;
  uint32_t *tri = (uint32_t *)msg;
  size_t nt = 5;
  memset(msg, 'x', sizeof msg);
  int got = mesh ? scf_mesh_read(path, &p, &tri, &nt, msg, sizeof msg)
                 : scf_points_read(path, &p, msg, sizeof msg);
  if (got != rc)
    ASSERT_FAIL("reading %s: %s (%s), expected %s", path, scf_err_name(got),
                got ? msg : "", scf_err_name(rc));
  ASSERT(p.xyz == NULL);
  ASSERT_EQ(p.count, 0);
  if (mesh) {
    ASSERT(tri == NULL);
    ASSERT_EQ(nt, 0);
  }
  ASSERT(memchr(msg, '\0', sizeof msg) != NULL);
  ASSERT(strchr(msg, '\n') == NULL);
  if (strncmp(msg, path, strlen(path)) != 0 || msg[strlen(path)] != ':')
    ASSERT_FAIL("\"%s\" does not start with \"%s:\"", msg, path);
  if (frag1 != NULL)
    ASSERT_STR_CONTAINS(msg, frag1);
  if (frag2 != NULL)
    ASSERT_STR_CONTAINS(msg, frag2);
}

#endif /* SC_TESTS_FILES_TMPDIR_H */
