/*
 * The counts a reconstruction reports in its diagnostics against those the
 * mesh checker finds in the mesh: the core keeps some of them up to date
 * as it edits the surface instead of counting again.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SC_TESTS_CORE_DIAG_H
#define SC_TESTS_CORE_DIAG_H

#include "sct_assert.h"

/* d is an sc_diag_t, c an scs_meshcheck_t. */
#define EXPECT_DIAG_COUNTS(d, c)                                               \
  do {                                                                         \
    EXPECT_EQ((d).triangles, (c).faces);                                       \
    EXPECT_EQ((d).components, (c).components);                                 \
    EXPECT_EQ((d).closed_components, (c).closed_components);                   \
    EXPECT_EQ((d).boundary_edges, (c).boundary_edges);                         \
    EXPECT_EQ((d).euler, (c).euler);                                           \
    EXPECT_EQ((d).genus, (c).genus_total);                                     \
    EXPECT_EQ((d).samples_unused, (c).samples_unused);                         \
  } while (0)

/* d an sc_diag_t, c the scs_meshcheck_t of its mesh over n samples: one
 * closed, oriented (outward: positive volume) 2-manifold of the given
 * genus, with at most one sample in a thousand in no triangle (a stray
 * sample or two far from the surface may stay out), and the diagnostics
 * saying so. */
#define EXPECT_CLOSED_PIECE(d, c, genus, n)                                    \
  do {                                                                         \
    EXPECT((c).manifold);                                                      \
    EXPECT((c).closed);                                                        \
    EXPECT((c).oriented);                                                      \
    EXPECT_EQ((c).components, 1);                                              \
    EXPECT_EQ((c).genus_total, (genus));                                       \
    EXPECT_GT((c).volume, 0);                                                  \
    EXPECT_LE((c).samples_unused * 1000, (n));                                 \
    EXPECT_EQ((d).genus, (genus));                                             \
    EXPECT((d).closed);                                                        \
    EXPECT_DIAG_COUNTS((d), (c));                                              \
  } while (0)

#endif /* SC_TESTS_CORE_DIAG_H */
