/*
 * Assertions that print both sides, and a private temporary directory, for
 * the file-format and command-line tests.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SC_TESTS_CHECK_H
#define SC_TESTS_CHECK_H

#include <dirent.h>
#include <inttypes.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define CHECK_FAIL_(...)                                                       \
  do {                                                                         \
    fprintf(stderr, "%s:%d: ", __FILE__, __LINE__);                            \
    fprintf(stderr, __VA_ARGS__);                                              \
    fputc('\n', stderr);                                                       \
    exit(1);                                                                   \
  } while (0)

#define CHECK(cond)                                                            \
  do {                                                                         \
    if (!(cond))                                                               \
      CHECK_FAIL_("check failed: %s", #cond);                                  \
  } while (0)

#define CHECK_INT_EQ(a, b)                                                     \
  do {                                                                         \
    long long a_ = (long long)(a), b_ = (long long)(b);                        \
    if (a_ != b_)                                                              \
      CHECK_FAIL_("%s == %s failed: %lld != %lld", #a, #b, a_, b_);            \
  } while (0)

#define CHECK_U64_EQ(a, b)                                                     \
  do {                                                                         \
    uint64_t a_ = (uint64_t)(a), b_ = (uint64_t)(b);                           \
    if (a_ != b_)                                                              \
      CHECK_FAIL_("%s == %s failed: %" PRIu64 " != %" PRIu64, #a, #b, a_, b_); \
  } while (0)

/* Equal as bit patterns, so that it also holds for NaN and tells -0 from 0. */
#define CHECK_DBL_SAME(a, b)                                                   \
  do {                                                                         \
    double a_ = (a), b_ = (b);                                                 \
    if (memcmp(&a_, &b_, sizeof a_) != 0)                                      \
      CHECK_FAIL_("%s == %s failed: %.17g != %.17g", #a, #b, a_, b_);          \
  } while (0)

#define CHECK_DBL_NEAR(a, b, tol)                                              \
  do {                                                                         \
    double a_ = (a), b_ = (b);                                                 \
    if (!(a_ - b_ <= (tol) && b_ - a_ <= (tol)))                               \
      CHECK_FAIL_("%s ~= %s failed: %.17g != %.17g (tolerance %g)", #a, #b,    \
                  a_, b_, (double)(tol));                                      \
  } while (0)

#define CHECK_STR_EQ(a, b)                                                     \
  do {                                                                         \
    const char *a_ = (a), *b_ = (b);                                           \
    if (strcmp(a_, b_) != 0)                                                   \
      CHECK_FAIL_("%s == %s failed: \"%s\" != \"%s\"", #a, #b, a_, b_);        \
  } while (0)

#define CHECK_CONTAINS(hay, needle)                                            \
  do {                                                                         \
    const char *h_ = (hay), *n_ = (needle);                                    \
    if (strstr(h_, n_) == NULL)                                                \
      CHECK_FAIL_("\"%s\" does not contain \"%s\"", h_, n_);                   \
  } while (0)

/* The private directory of this test process, made by tmp_init(). */
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
    CHECK_FAIL_("mkdtemp(%s) failed", tmp_dir_);
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
    CHECK_FAIL_("cannot write %s", path);
}

static inline void write_text(const char *path, const char *text) {
  write_bytes(path, text, strlen(text));
}

/* The whole file, NUL-terminated; the caller frees it. */
static inline char *read_all(const char *path, size_t *len) {
  FILE *f = fopen(path, "rb");
  if (f == NULL)
    CHECK_FAIL_("cannot open %s", path);
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
    CHECK_FAIL_("out of memory reading %s", path);
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

#endif /* SC_TESTS_CHECK_H */
