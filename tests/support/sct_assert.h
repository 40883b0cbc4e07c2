/*
 * Assertions for every shortcrust test, in C and in C++.
 *
 * Two families with the same checks:
 *
 *   EXPECT_*  records a failure and lets the test go on, so one run shows
 *             every broken expectation;
 *   ASSERT_*  records it and stops the program at once (after the hook
 *             set with sct_on_fatal(), then exit status 1), for checks the
 *             rest of the test cannot do without.
 *
 * Each failure prints file:line, the expressions and both values, e.g.
 *
 *   test_x.c:42: check failed: rc == SCP_OK: -3 vs 0
 *
 * The checks:
 *
 *   EXPECT(cond)                      ASSERT(cond)
 *   EXPECT_MSG(cond, fmt, ...)        ASSERT_MSG(cond, fmt, ...)
 *       printf-style details after the expression, formatted only when
 *       the check fails
 *   EXPECT_EQ / _NE / _LT / _LE / _GT / _GE (a, b)
 *       integers of any type (signed and unsigned compared by value, so
 *       -1 is less than 0u), floating point (exact; NaN fails all but NE)
 *       and pointers
 *   EXPECT_NEAR(a, b, tol)            |a - b| <= tol, as doubles
 *   EXPECT_DBL_SAME(a, b)             the same bits: tells -0 from 0 and
 *                                     holds for the same NaN
 *   EXPECT_STR_EQ / _STR_NE (a, b)    strcmp; NULL equals only NULL
 *   EXPECT_STR_CONTAINS(s, part)      strstr
 *   EXPECT_MEM_EQ(a, alen, b, blen)   lengths, then the first differing byte
 *   EXPECT_NULL(p) / _NOT_NULL(p)
 *   EXPECT_CODE_EQ(a, b, name)        integer codes, printed with name(code)
 *                                     (any const char *name(int))
 *   EXPECT_FAIL(fmt, ...)             a failure, unconditionally
 *
 * and the same with ASSERT_. Every check that passes is counted too.
 * Counting is thread-safe. main() ends with "return sct_finish(name);",
 * which prints "NAME: N checks passed" or "NAME: F of N checks failed" and
 * returns the exit status.
 *
 * The implementation is in assert.c (library sc_testsupport); every name
 * here that is not a check starts with sct_.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SCT_ASSERT_H
#define SCT_ASSERT_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
#include <type_traits>
extern "C" {
#endif

/* One side of a comparison, whatever its type. */
typedef struct sct_value {
  int kind; /* SCT_SIGNED, SCT_UNSIGNED, SCT_FLOAT or SCT_POINTER */
  intmax_t i;
  uintmax_t u;
  long double f;
  const volatile void *p;
} sct_value_t;

enum { SCT_SIGNED, SCT_UNSIGNED, SCT_FLOAT, SCT_POINTER };
enum { SCT_EQ, SCT_NE, SCT_LT, SCT_LE, SCT_GT, SCT_GE };

/* What main() returns: 0 when no check failed, else 1, after one summary
 * line (name may be NULL). */
int sct_finish(const char *name);
/* Failures so far. */
int sct_failures(void);
/* Called (once) when an ASSERT_ fails, before the program exits with
 * status 1: to stop daemons, print logs, remove directories. */
void sct_on_fatal(void (*hook)(void));

/* The machinery behind the macros below. Each returns 1 when the check
 * held; a failure is printed and counted. */
void sct_stop_(void) __attribute__((noreturn));
int sct_cond_(int ok, const char *file, int line, const char *expr);
int sct_msg_(const char *file, int line, const char *expr, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
int sct_cmp_(int op, sct_value_t a, sct_value_t b, const char *file, int line,
             const char *ea, const char *eb);
int sct_near_(double a, double b, double tol, const char *file, int line,
              const char *ea, const char *eb, const char *et);
int sct_same_(double a, double b, const char *file, int line, const char *ea,
              const char *eb);
int sct_str_(int want_equal, const char *a, const char *b, const char *file,
             int line, const char *ea, const char *eb);
int sct_contains_(const char *s, const char *part, const char *file, int line,
                  const char *es, const char *ep);
int sct_mem_(const void *a, size_t alen, const void *b, size_t blen,
             const char *file, int line, const char *ea, const char *eb);
/* The pointer as an integer: a pointer parameter would tell the compiler
 * that the function reads what it points to. */
int sct_null_(int want_null, uintptr_t p, const char *file, int line,
              const char *ep);
int sct_code_(long long a, long long b, const char *(*name)(int),
              const char *file, int line, const char *ea, const char *eb);

static inline sct_value_t sct_value_i_(intmax_t v) {
  sct_value_t r = {SCT_SIGNED, v, 0, 0, NULL};
  return r;
}
static inline sct_value_t sct_value_u_(uintmax_t v) {
  sct_value_t r = {SCT_UNSIGNED, 0, v, 0, NULL};
  return r;
}
static inline sct_value_t sct_value_f_(long double v) {
  sct_value_t r = {SCT_FLOAT, 0, 0, v, NULL};
  return r;
}
static inline sct_value_t sct_value_p_(const volatile void *v) {
  sct_value_t r = {SCT_POINTER, 0, 0, 0, v};
  return r;
}

#ifdef __cplusplus
}

template <typename T> static inline sct_value_t sct_value_(T v) {
  if constexpr (std::is_enum<T>::value) {
    return sct_value_(static_cast<typename std::underlying_type<T>::type>(v));
  } else if constexpr (std::is_same<T, bool>::value) {
    return sct_value_u_(v ? 1u : 0u);
  } else if constexpr (std::is_integral<T>::value) {
    if constexpr (std::is_signed<T>::value)
      return sct_value_i_(static_cast<intmax_t>(v));
    else
      return sct_value_u_(static_cast<uintmax_t>(v));
  } else if constexpr (std::is_floating_point<T>::value) {
    return sct_value_f_(static_cast<long double>(v));
  } else if constexpr (std::is_null_pointer<T>::value) {
    return sct_value_p_(nullptr);
  } else {
    static_assert(std::is_pointer<T>::value,
                  "compare integers, floating point or pointers");
    return sct_value_p_(static_cast<const volatile void *>(v));
  }
}
#define SCT_VALUE_(x) sct_value_(x)
#else
/* The controlling expression is converted as an operand would be (arrays
 * to pointers, qualifiers dropped); an enum matches its integer type. */
#define SCT_VALUE_(x)                                                          \
  _Generic((x), _Bool                                                          \
           : sct_value_u_, char                                                \
           : sct_value_i_, signed char                                         \
           : sct_value_i_, short                                               \
           : sct_value_i_, int                                                 \
           : sct_value_i_, long                                                \
           : sct_value_i_, long long                                           \
           : sct_value_i_, unsigned char                                       \
           : sct_value_u_, unsigned short                                      \
           : sct_value_u_, unsigned int                                        \
           : sct_value_u_, unsigned long                                       \
           : sct_value_u_, unsigned long long                                  \
           : sct_value_u_, float                                               \
           : sct_value_f_, double                                              \
           : sct_value_f_, long double                                         \
           : sct_value_f_, default                                             \
           : sct_value_p_)(x)
#endif

/* F is 1 for ASSERT_, 0 for EXPECT_: a failed ASSERT_ never returns. The
 * public macros stringify their arguments themselves, so that the message
 * shows them as written, before any macro in them is expanded. */
#define SCT_DO_(F, held)                                                       \
  do {                                                                         \
    if (!(held) && (F))                                                        \
      sct_stop_();                                                             \
  } while (0)

#define SCT_COND_(F, c, ec) SCT_DO_(F, sct_cond_(!!(c), __FILE__, __LINE__, ec))
#define SCT_MSG_(F, c, ec, ...)                                                \
  SCT_DO_(F, (c) ? sct_cond_(1, __FILE__, __LINE__, ec)                        \
                 : sct_msg_(__FILE__, __LINE__, ec, __VA_ARGS__))
#define SCT_CMP_(F, op, a, b, ea, eb)                                          \
  SCT_DO_(F, sct_cmp_(op, SCT_VALUE_(a), SCT_VALUE_(b), __FILE__, __LINE__,    \
                      ea, eb))
#define SCT_NEAR_(F, a, b, tol, ea, eb, et)                                    \
  SCT_DO_(F, sct_near_((a), (b), (tol), __FILE__, __LINE__, ea, eb, et))
#define SCT_SAME_(F, a, b, ea, eb)                                             \
  SCT_DO_(F, sct_same_((a), (b), __FILE__, __LINE__, ea, eb))
#define SCT_STR_(F, eq, a, b, ea, eb)                                          \
  SCT_DO_(F, sct_str_(eq, (a), (b), __FILE__, __LINE__, ea, eb))
#define SCT_CONTAINS_(F, s, part, es, ep)                                      \
  SCT_DO_(F, sct_contains_((s), (part), __FILE__, __LINE__, es, ep))
#define SCT_MEM_(F, a, alen, b, blen, ea, eb)                                  \
  SCT_DO_(F, sct_mem_((a), (alen), (b), (blen), __FILE__, __LINE__, ea, eb))
#define SCT_NULL_(F, want, p, ep)                                              \
  SCT_DO_(F, sct_null_(want, (uintptr_t)(const volatile void *)(p), __FILE__,  \
                       __LINE__, ep))
#define SCT_CODE_(F, a, b, name, ea, eb)                                       \
  SCT_DO_(F, sct_code_((long long)(a), (long long)(b), (name), __FILE__,       \
                       __LINE__, ea, eb))
#define SCT_FAIL_(F, ...)                                                      \
  do {                                                                         \
    (void)sct_msg_(__FILE__, __LINE__, NULL, __VA_ARGS__);                     \
    if (F)                                                                     \
      sct_stop_();                                                             \
  } while (0)

#define EXPECT(c) SCT_COND_(0, c, #c)
#define EXPECT_MSG(c, ...) SCT_MSG_(0, c, #c, __VA_ARGS__)
#define EXPECT_EQ(a, b) SCT_CMP_(0, SCT_EQ, a, b, #a, #b)
#define EXPECT_NE(a, b) SCT_CMP_(0, SCT_NE, a, b, #a, #b)
#define EXPECT_LT(a, b) SCT_CMP_(0, SCT_LT, a, b, #a, #b)
#define EXPECT_LE(a, b) SCT_CMP_(0, SCT_LE, a, b, #a, #b)
#define EXPECT_GT(a, b) SCT_CMP_(0, SCT_GT, a, b, #a, #b)
#define EXPECT_GE(a, b) SCT_CMP_(0, SCT_GE, a, b, #a, #b)
#define EXPECT_NEAR(a, b, tol) SCT_NEAR_(0, a, b, tol, #a, #b, #tol)
#define EXPECT_DBL_SAME(a, b) SCT_SAME_(0, a, b, #a, #b)
#define EXPECT_STR_EQ(a, b) SCT_STR_(0, 1, a, b, #a, #b)
#define EXPECT_STR_NE(a, b) SCT_STR_(0, 0, a, b, #a, #b)
#define EXPECT_STR_CONTAINS(s, part) SCT_CONTAINS_(0, s, part, #s, #part)
#define EXPECT_MEM_EQ(a, alen, b, blen) SCT_MEM_(0, a, alen, b, blen, #a, #b)
#define EXPECT_NULL(p) SCT_NULL_(0, 1, p, #p)
#define EXPECT_NOT_NULL(p) SCT_NULL_(0, 0, p, #p)
#define EXPECT_CODE_EQ(a, b, name) SCT_CODE_(0, a, b, name, #a, #b)
#define EXPECT_FAIL(...) SCT_FAIL_(0, __VA_ARGS__)

#define ASSERT(c) SCT_COND_(1, c, #c)
#define ASSERT_MSG(c, ...) SCT_MSG_(1, c, #c, __VA_ARGS__)
#define ASSERT_EQ(a, b) SCT_CMP_(1, SCT_EQ, a, b, #a, #b)
#define ASSERT_NE(a, b) SCT_CMP_(1, SCT_NE, a, b, #a, #b)
#define ASSERT_LT(a, b) SCT_CMP_(1, SCT_LT, a, b, #a, #b)
#define ASSERT_LE(a, b) SCT_CMP_(1, SCT_LE, a, b, #a, #b)
#define ASSERT_GT(a, b) SCT_CMP_(1, SCT_GT, a, b, #a, #b)
#define ASSERT_GE(a, b) SCT_CMP_(1, SCT_GE, a, b, #a, #b)
#define ASSERT_NEAR(a, b, tol) SCT_NEAR_(1, a, b, tol, #a, #b, #tol)
#define ASSERT_DBL_SAME(a, b) SCT_SAME_(1, a, b, #a, #b)
#define ASSERT_STR_EQ(a, b) SCT_STR_(1, 1, a, b, #a, #b)
#define ASSERT_STR_NE(a, b) SCT_STR_(1, 0, a, b, #a, #b)
#define ASSERT_STR_CONTAINS(s, part) SCT_CONTAINS_(1, s, part, #s, #part)
#define ASSERT_MEM_EQ(a, alen, b, blen) SCT_MEM_(1, a, alen, b, blen, #a, #b)
#define ASSERT_NULL(p) SCT_NULL_(1, 1, p, #p)
#define ASSERT_NOT_NULL(p) SCT_NULL_(1, 0, p, #p)
#define ASSERT_CODE_EQ(a, b, name) SCT_CODE_(1, a, b, name, #a, #b)
#define ASSERT_FAIL(...) SCT_FAIL_(1, __VA_ARGS__)

#endif /* SCT_ASSERT_H */
