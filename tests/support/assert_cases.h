/*
 * The cases of test_assert.c and test_assert_cpp.cpp, written in the
 * common subset of C and C++ so the two languages' value capture (_Generic
 * and a template) are held to the same results.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SCT_ASSERT_CASES_H
#define SCT_ASSERT_CASES_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "sct_assert.h"

static int case_problems;

#define CASE(what)                                                             \
  do {                                                                         \
    if (!(what)) {                                                             \
      fprintf(stderr, "%s:%d: case failed: %s\n", __FILE__, __LINE__, #what);  \
      case_problems++;                                                         \
    }                                                                          \
  } while (0)

/* Runs the statement and reports whether it recorded exactly one failure
 * (want 1) or none (want 0). */
#define FAILS(want, stmt)                                                      \
  do {                                                                         \
    int before_ = sct_failures();                                              \
    stmt;                                                                      \
    if (sct_failures() - before_ != (want)) {                                  \
      fprintf(stderr, "%s:%d: %s recorded %d failures, expected %d\n",         \
              __FILE__, __LINE__, #stmt, sct_failures() - before_, (want));    \
      case_problems++;                                                         \
    }                                                                          \
  } while (0)

enum colour { RED = 1, GREEN = 2 };

static const char *code_name(int c) { return c == 0 ? "OK" : "EBAD"; }

static int hook_fd = -1;
static void hook(void) {
  if (hook_fd >= 0 && write(hook_fd, "hook", 4) != 4)
    _exit(3);
}

/* Runs a failing ASSERT in a child: it must print the message to stderr,
 * run the hook, and exit with status 1 without reaching the next line. */
static void fatal_case(void) {
  int err[2], hk[2];
  CASE(pipe(err) == 0 && pipe(hk) == 0);
  pid_t pid = fork();
  if (pid == 0) {
    dup2(err[1], 2);
    hook_fd = hk[1];
    sct_on_fatal(hook);
    int three = 3;
    ASSERT_EQ(three, 4);
    _exit(0);
  }
  close(err[1]);
  close(hk[1]);
  char out[512] = "", hooked[8] = "";
  ssize_t n = read(err[0], out, sizeof out - 1);
  out[n > 0 ? n : 0] = 0;
  n = read(hk[0], hooked, sizeof hooked - 1);
  hooked[n > 0 ? n : 0] = 0;
  int st = 0;
  waitpid(pid, &st, 0);
  CASE(WIFEXITED(st) && WEXITSTATUS(st) == 1);
  CASE(strstr(out, "check failed: three == 4: 3 vs 4") != NULL);
  CASE(strstr(out, ":") != NULL && strstr(out, "assert_cases.h:") != NULL);
  CASE(strcmp(hooked, "hook") == 0);
  close(err[0]);
  close(hk[0]);
}

static int run_cases(void) {
  int i = -1;
  unsigned u = 0;
  uint64_t big = UINT64_MAX;
  int64_t neg = INT64_MIN;
  double d = 0.5, nan_ = NAN, zero = 0.0, mzero = -0.0;
  const char *s = "abc";
  const char *null_s = NULL;
  int x = 7;
  int *px = &x, *pnull = NULL;
  unsigned char bytes1[3] = {1, 2, 3}, bytes2[3] = {1, 2, 4};
  enum colour c = GREEN;

  /* What holds passes. */
  FAILS(0, EXPECT(1 + 1 == 2));
  FAILS(0, EXPECT_MSG(x == 7, "x is %d", x));
  FAILS(0, EXPECT_EQ(x, 7));
  FAILS(0, EXPECT_EQ(big, UINT64_MAX));
  FAILS(0, EXPECT_LT(i, u)); /* by value, not by C's conversion */
  FAILS(0, EXPECT_LT(neg, big));
  FAILS(0, EXPECT_GT(big, neg));
  FAILS(0, EXPECT_NE(i, UINT64_MAX));
  FAILS(0, EXPECT_LE(x, 7));
  FAILS(0, EXPECT_GE(x, 7));
  FAILS(0, EXPECT_EQ(d, 0.5));
  FAILS(0, EXPECT_LT(d, 1));
  FAILS(0, EXPECT_EQ(zero, mzero));
  FAILS(0, EXPECT_NE(nan_, nan_));
  FAILS(0, EXPECT_EQ(c, GREEN));
  FAILS(0, EXPECT_EQ(px, &x));
  FAILS(0, EXPECT_NEAR(0.1 + 0.2, 0.3, 1e-15));
  FAILS(0, EXPECT_DBL_SAME(d, 0.5));
  FAILS(0, EXPECT_STR_EQ(s, "abc"));
  FAILS(0, EXPECT_STR_NE(s, "abd"));
  FAILS(0, EXPECT_STR_EQ(null_s, NULL));
  FAILS(0, EXPECT_STR_CONTAINS(s, "bc"));
  FAILS(0, EXPECT_MEM_EQ(bytes1, 3, bytes1, 3));
  FAILS(0, EXPECT_NULL(pnull));
  FAILS(0, EXPECT_NOT_NULL(px));
  FAILS(0, EXPECT_CODE_EQ(0, 0, code_name));
  FAILS(0, ASSERT_EQ(x, 7));
  FAILS(0, ASSERT_STR_EQ(s, "abc"));

  /* What does not hold fails, once each. */
  FAILS(1, EXPECT(1 + 1 == 3));
  FAILS(1, EXPECT_MSG(x == 8, "x is %d", x));
  FAILS(1, EXPECT_EQ(x, 8));
  FAILS(1, EXPECT_EQ(i, UINT64_MAX));
  FAILS(1, EXPECT_GT(i, u));
  FAILS(1, EXPECT_LT(big, neg));
  FAILS(1, EXPECT_NE(x, 7));
  FAILS(1, EXPECT_LE(x, 6));
  FAILS(1, EXPECT_GE(x, 8));
  FAILS(1, EXPECT_EQ(nan_, nan_));
  FAILS(1, EXPECT_LE(nan_, 1.0));
  FAILS(1, EXPECT_EQ(d, 0.25));
  FAILS(1, EXPECT_EQ(c, RED));
  FAILS(1, EXPECT_EQ(px, pnull));
  FAILS(1, EXPECT_NEAR(1.0, 1.1, 0.05));
  FAILS(1, EXPECT_NEAR(nan_, 1.0, 1e9));
  FAILS(1, EXPECT_DBL_SAME(zero, mzero));
  FAILS(1, EXPECT_STR_EQ(s, "abd"));
  FAILS(1, EXPECT_STR_EQ(s, null_s));
  FAILS(1, EXPECT_STR_NE(s, "abc"));
  FAILS(1, EXPECT_STR_CONTAINS(s, "x"));
  FAILS(1, EXPECT_MEM_EQ(bytes1, 3, bytes2, 3));
  FAILS(1, EXPECT_MEM_EQ(bytes1, 3, bytes1, 2));
  FAILS(1, EXPECT_NULL(px));
  FAILS(1, EXPECT_NOT_NULL(pnull));
  FAILS(1, EXPECT_CODE_EQ(-3, 0, code_name));
  FAILS(1, EXPECT_FAIL("always %d", 1));

  /* Operands are evaluated exactly once. */
  int calls = 0;
  FAILS(0, EXPECT_EQ(++calls, 1));
  CASE(calls == 1);
  FAILS(0, EXPECT_MSG(++calls == 2, "calls %d", calls));
  CASE(calls == 2);

  fatal_case();
  return case_problems;
}

#endif /* SCT_ASSERT_CASES_H */
