/*
 * Assertions for plain C tests. Each prints the expression and both values
 * when it fails, counts the failure and lets the test go on, so one run
 * shows every broken expectation; main() returns ts_exit_code().
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SC_TSASSERT_H
#define SC_TSASSERT_H

#include <inttypes.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>

static int ts_failures;

static inline int ts_exit_code(void) {
  if (ts_failures)
    fprintf(stderr, "%d check(s) failed\n", ts_failures);
  return ts_failures ? 1 : 0;
}

#define TS_FAIL_(...)                                                          \
  do {                                                                         \
    fprintf(stderr, "%s:%d: ", __FILE__, __LINE__);                            \
    fprintf(stderr, __VA_ARGS__);                                              \
    fputc('\n', stderr);                                                       \
    ts_failures++;                                                             \
  } while (0)

#define TS_TRUE(cond, ...)                                                     \
  do {                                                                         \
    if (!(cond)) {                                                             \
      TS_FAIL_("%s is false", #cond);                                          \
      fprintf(stderr, "  ");                                                   \
      fprintf(stderr, __VA_ARGS__);                                            \
      fputc('\n', stderr);                                                     \
    }                                                                          \
  } while (0)

#define TS_EQ_U64(a, b)                                                        \
  do {                                                                         \
    uint64_t a_ = (uint64_t)(a), b_ = (uint64_t)(b);                           \
    if (a_ != b_)                                                              \
      TS_FAIL_("%s == %s: %" PRIu64 " vs %" PRIu64, #a, #b, a_, b_);           \
  } while (0)

#define TS_EQ_I64(a, b)                                                        \
  do {                                                                         \
    int64_t a_ = (int64_t)(a), b_ = (int64_t)(b);                              \
    if (a_ != b_)                                                              \
      TS_FAIL_("%s == %s: %" PRId64 " vs %" PRId64, #a, #b, a_, b_);           \
  } while (0)

#define TS_NEAR(a, b, tol)                                                     \
  do {                                                                         \
    double a_ = (a), b_ = (b), t_ = (tol);                                     \
    if (!(fabs(a_ - b_) <= t_))                                                \
      TS_FAIL_("|%s - %s| <= %s: %.17g vs %.17g (tolerance %g)", #a, #b,      \
               #tol, a_, b_, t_);                                              \
  } while (0)

#define TS_LE(a, b)                                                            \
  do {                                                                         \
    double a_ = (a), b_ = (b);                                                 \
    if (!(a_ <= b_))                                                           \
      TS_FAIL_("%s <= %s: %.17g vs %.17g", #a, #b, a_, b_);                    \
  } while (0)

#define TS_LT(a, b)                                                            \
  do {                                                                         \
    double a_ = (a), b_ = (b);                                                 \
    if (!(a_ < b_))                                                            \
      TS_FAIL_("%s < %s: %.17g vs %.17g", #a, #b, a_, b_);                     \
  } while (0)

#endif /* SC_TSASSERT_H */
