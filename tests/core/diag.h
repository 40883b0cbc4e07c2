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

#include <stdio.h>
#include <string.h>

#include "sct_assert.h"
#include "shortcrust.h"
#include "synth.h"

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

/* The mode of that name (sc_mode_name()), or SC_MODE_COUNT_. */
static inline sc_mode_t sct_mode_from_name(const char *name) {
  for (int k = 0; k < SC_MODE_COUNT_; ++k)
    if (strcmp(name, sc_mode_name(k)) == 0)
      return (sc_mode_t)k;
  return SC_MODE_COUNT_;
}

/* Reconstructs the n samples xyz with p and checks the mesh as
 * EXPECT_CLOSED_PIECE does, and that every sample is a vertex when
 * every_sample; prints `what` with the mesh checker's summary. Returns the
 * mesh for further checks (the caller frees it), or NULL where the
 * reconstruction failed. */
static inline sc_mesh_t *sct_expect_closed(const double *xyz, size_t n,
                                           const sc_params_t *p, int genus,
                                           int every_sample, const char *what) {
  char msg[512];
  sc_mesh_t *m = NULL;
  const int rc = sc_reconstruct(xyz, n, p, &m, msg, sizeof msg);
  EXPECT_EQ(rc, 0);
  if (rc != 0) {
    fprintf(stderr, "%s: %s\n", what, msg);
    return NULL;
  }
  scs_meshcheck_t c;
  EXPECT_EQ(scs_meshcheck(n, xyz, m->triangles, m->triangle_count, NULL, &c),
            0);
  char line[512];
  printf("%s: %s; %llu attached, %llu handles cut, %llu small handles cut\n",
         what, scs_meshcheck_summary(&c, line, sizeof line),
         (unsigned long long)m->diag.samples_attached,
         (unsigned long long)m->diag.handles_cut,
         (unsigned long long)m->diag.small_handles_cut);
  EXPECT_CLOSED_PIECE(m->diag, c, genus, n);
  if (every_sample) {
    EXPECT_EQ(m->diag.samples_unused, 0);
    EXPECT_EQ(c.samples_unused, 0);
  }
  scs_meshcheck_free(&c);
  return m;
}

#endif /* SC_TESTS_CORE_DIAG_H */
