/*
 * The assertions of sct_assert.h: comparing, printing and counting.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "sct_assert.h"

#include <inttypes.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Updated from any thread; the builtins work the same in C and C++ code
 * built with GCC or Clang. */
static unsigned long passed;
static int failed;
static void (*fatal_hook)(void);
static int stopping;

static void count_pass(void) {
  __atomic_fetch_add(&passed, 1, __ATOMIC_RELAXED);
}

/* Prints "file:line: " and the rest as one write, so that failures from
 * several threads do not interleave, and counts the failure. */
static int fail(const char *file, int line, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static int vfail(const char *file, int line, const char *fmt, va_list ap) {
  char buf[4096];
  int k = snprintf(buf, sizeof buf, "%s:%d: ", file, line);
  if (k < 0)
    k = 0;
  if ((size_t)k < sizeof buf)
    vsnprintf(buf + k, sizeof buf - (size_t)k, fmt, ap);
  flockfile(stderr);
  fputs(buf, stderr);
  fputc('\n', stderr);
  funlockfile(stderr);
  __atomic_fetch_add(&failed, 1, __ATOMIC_RELAXED);
  return 0;
}

static int fail(const char *file, int line, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vfail(file, line, fmt, ap);
  va_end(ap);
  return 0;
}

int sct_failures(void) { return __atomic_load_n(&failed, __ATOMIC_RELAXED); }

void sct_on_fatal(void (*hook)(void)) { fatal_hook = hook; }

void sct_stop_(void) {
  /* Only the first thread to stop runs the hook; a failure inside the hook
   * goes straight out. */
  if (__atomic_exchange_n(&stopping, 1, __ATOMIC_ACQ_REL) == 0 && fatal_hook)
    fatal_hook();
  exit(1);
}

int sct_finish(const char *name) {
  unsigned long p = __atomic_load_n(&passed, __ATOMIC_RELAXED);
  int f = sct_failures();
  const char *sep = name ? ": " : "";
  if (!name)
    name = "";
  if (f) {
    fprintf(stderr, "%s%s%d of %lu checks failed\n", name, sep, f,
            p + (unsigned long)f);
    return 1;
  }
  printf("%s%s%lu checks passed\n", name, sep, p);
  return 0;
}

int sct_cond_(int ok, const char *file, int line, const char *expr) {
  if (ok) {
    count_pass();
    return 1;
  }
  return fail(file, line, "check failed: %s", expr);
}

int sct_msg_(const char *file, int line, const char *expr, const char *fmt,
             ...) {
  char msg[3072];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  if (expr)
    return fail(file, line, "check failed: %s: %s", expr, msg);
  return fail(file, line, "failed: %s", msg);
}

static void show(char *buf, size_t len, sct_value_t v) {
  switch (v.kind) {
  case SCT_SIGNED:
    snprintf(buf, len, "%" PRIdMAX, v.i);
    break;
  case SCT_UNSIGNED:
    snprintf(buf, len, "%" PRIuMAX, v.u);
    break;
  case SCT_FLOAT:
    snprintf(buf, len, "%.17Lg", v.f);
    break;
  default:
    snprintf(buf, len, "%p", (const void *)v.p);
    break;
  }
}

static long double as_float(sct_value_t v) {
  switch (v.kind) {
  case SCT_SIGNED:
    return (long double)v.i;
  case SCT_UNSIGNED:
    return (long double)v.u;
  case SCT_FLOAT:
    return v.f;
  default:
    return (long double)(uintptr_t)v.p;
  }
}

static uintptr_t as_address(sct_value_t v) {
  switch (v.kind) {
  case SCT_SIGNED:
    return (uintptr_t)v.i;
  case SCT_UNSIGNED:
    return (uintptr_t)v.u;
  default:
    return (uintptr_t)v.p;
  }
}

/* -1, 0 or 1; 2 when unordered (a NaN). Integers compare by value whatever
 * their signedness; anything with a floating-point side compares as long
 * double (exact for 64-bit integers where long double has a 64-bit or
 * longer significand). */
static int order(sct_value_t a, sct_value_t b) {
  if (a.kind == SCT_FLOAT || b.kind == SCT_FLOAT) {
    long double x = as_float(a), y = as_float(b);
    if (isnan(x) || isnan(y))
      return 2;
    return x < y ? -1 : x > y;
  }
  if (a.kind == SCT_POINTER || b.kind == SCT_POINTER) {
    uintptr_t x = as_address(a), y = as_address(b);
    return x < y ? -1 : x > y;
  }
  if (a.kind == SCT_SIGNED && b.kind == SCT_SIGNED)
    return a.i < b.i ? -1 : a.i > b.i;
  if (a.kind == SCT_SIGNED && a.i < 0)
    return -1;
  if (b.kind == SCT_SIGNED && b.i < 0)
    return 1;
  uintmax_t x = a.kind == SCT_SIGNED ? (uintmax_t)a.i : a.u;
  uintmax_t y = b.kind == SCT_SIGNED ? (uintmax_t)b.i : b.u;
  return x < y ? -1 : x > y;
}

int sct_cmp_(int op, sct_value_t a, sct_value_t b, const char *file, int line,
             const char *ea, const char *eb) {
  static const char *const names[] = {"==", "!=", "<", "<=", ">", ">="};
  int o = order(a, b), ok;
  switch (op) {
  case SCT_EQ:
    ok = o == 0;
    break;
  case SCT_NE:
    ok = o != 0;
    break;
  case SCT_LT:
    ok = o == -1;
    break;
  case SCT_LE:
    ok = o == -1 || o == 0;
    break;
  case SCT_GT:
    ok = o == 1;
    break;
  default:
    ok = o == 1 || o == 0;
    break;
  }
  if (ok) {
    count_pass();
    return 1;
  }
  char sa[64], sb[64];
  show(sa, sizeof sa, a);
  show(sb, sizeof sb, b);
  return fail(file, line, "check failed: %s %s %s: %s vs %s", ea,
              names[op >= 0 && op <= SCT_GE ? op : SCT_GE], eb, sa, sb);
}

int sct_near_(double a, double b, double tol, const char *file, int line,
              const char *ea, const char *eb, const char *et) {
  if (fabs(a - b) <= tol) {
    count_pass();
    return 1;
  }
  return fail(file, line,
              "check failed: |%s - %s| <= %s: %.17g vs %.17g (difference "
              "%.3g, tolerance %g)",
              ea, eb, et, a, b, fabs(a - b), tol);
}

int sct_same_(double a, double b, const char *file, int line, const char *ea,
              const char *eb) {
  if (memcmp(&a, &b, sizeof a) == 0) {
    count_pass();
    return 1;
  }
  uint64_t ba, bb;
  memcpy(&ba, &a, sizeof ba);
  memcpy(&bb, &b, sizeof bb);
  return fail(file, line,
              "check failed: %s is bitwise %s: %.17g (0x%016" PRIx64
              ") vs %.17g (0x%016" PRIx64 ")",
              ea, eb, a, ba, b, bb);
}

int sct_str_(int want_equal, const char *a, const char *b, const char *file,
             int line, const char *ea, const char *eb) {
  int equal = (a && b) ? strcmp(a, b) == 0 : a == b;
  if (equal == want_equal) {
    count_pass();
    return 1;
  }
  return fail(file, line, "check failed: %s %s %s: %s%s%s vs %s%s%s", ea,
              want_equal ? "==" : "!=", eb, a ? "\"" : "", a ? a : "NULL",
              a ? "\"" : "", b ? "\"" : "", b ? b : "NULL", b ? "\"" : "");
}

int sct_contains_(const char *s, const char *part, const char *file, int line,
                  const char *es, const char *ep) {
  if (s && part && strstr(s, part)) {
    count_pass();
    return 1;
  }
  return fail(file, line, "check failed: %s contains %s: \"%s\" lacks \"%s\"",
              es, ep, s ? s : "(NULL)", part ? part : "(NULL)");
}

int sct_mem_(const void *a, size_t alen, const void *b, size_t blen,
             const char *file, int line, const char *ea, const char *eb) {
  if (alen != blen)
    return fail(file, line,
                "check failed: %s and %s differ in length: %zu vs "
                "%zu",
                ea, eb, alen, blen);
  const unsigned char *x = a, *y = b;
  for (size_t i = 0; i < alen; i++)
    if (x[i] != y[i])
      return fail(file, line,
                  "check failed: %s and %s differ at byte %zu: %02x vs %02x",
                  ea, eb, i, x[i], y[i]);
  count_pass();
  return 1;
}

int sct_null_(int want_null, uintptr_t p, const char *file, int line,
              const char *ep) {
  if ((p == 0) == want_null) {
    count_pass();
    return 1;
  }
  if (want_null)
    return fail(file, line, "check failed: %s is NULL: it is %p", ep,
                (const void *)p);
  return fail(file, line, "check failed: %s is not NULL", ep);
}

int sct_code_(long long a, long long b, const char *(*name)(int),
              const char *file, int line, const char *ea, const char *eb) {
  if (a == b) {
    count_pass();
    return 1;
  }
  const char *na = name((int)a), *nb = name((int)b);
  return fail(file, line, "check failed: %s == %s: %lld (%s) vs %lld (%s)", ea,
              eb, a, na ? na : "?", b, nb ? nb : "?");
}
