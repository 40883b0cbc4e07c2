/*
 * Assertions for the core tests: each failure prints both sides and the
 * line, and the test goes on so one run shows every failure.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SC_CORE_CHECK_H
#define SC_CORE_CHECK_H

#include <stdio.h>

static int check_failures;

#define CHECK(cond)                                                            \
  do {                                                                         \
    if (!(cond)) {                                                             \
      fprintf(stderr, "%s:%d: FAIL: %s\n", __FILE__, __LINE__, #cond);         \
      ++check_failures;                                                        \
    }                                                                          \
  } while (0)

#define CHECK_EQ_INT(a, b)                                                     \
  do {                                                                         \
    long long a_ = (long long)(a), b_ = (long long)(b);                        \
    if (a_ != b_) {                                                            \
      fprintf(stderr, "%s:%d: FAIL: %s == %s: %lld != %lld\n", __FILE__,       \
              __LINE__, #a, #b, a_, b_);                                       \
      ++check_failures;                                                        \
    }                                                                          \
  } while (0)

/* The counts a reconstruction reports in its diagnostics (d, an
 * sc_diag_t) against those the mesh checker finds in the mesh (c, an
 * scs_meshcheck_t); the core keeps some of them up to date as it edits the
 * surface instead of counting again. */
#define CHECK_DIAG_COUNTS(d, c)                                                \
  do {                                                                         \
    CHECK_EQ_INT((d).triangles, (c).faces);                                    \
    CHECK_EQ_INT((d).components, (c).components);                              \
    CHECK_EQ_INT((d).closed_components, (c).closed_components);                \
    CHECK_EQ_INT((d).boundary_edges, (c).boundary_edges);                      \
    CHECK_EQ_INT((d).euler, (c).euler);                                        \
    CHECK_EQ_INT((d).genus, (c).genus_total);                                  \
    CHECK_EQ_INT((d).samples_unused, (c).samples_unused);                      \
  } while (0)

#define CHECK_DONE()                                                           \
  (check_failures ? (fprintf(stderr, "%d check(s) failed\n", check_failures), \
                     1)                                                        \
                  : 0)

#endif /* SC_CORE_CHECK_H */
