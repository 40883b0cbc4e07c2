/*
 * The C boundary: error names, the parameter check, streaming against one
 * call, threads, progress and cancellation at every stage, state errors.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sct_assert.h"
#include "shortcrust.h"
#include "synth.h"

enum { N = 6000 };

/* Each triangle rotated to start at its smallest index, then all sorted:
 * the same surface with the same orientation gives the same array. */
static int cmp_tri(const void *a, const void *b) {
  return memcmp(a, b, 3 * sizeof(uint32_t)) < 0   ? -1
         : memcmp(a, b, 3 * sizeof(uint32_t)) > 0 ? 1
                                                  : 0;
}
static uint32_t *canonical(const sc_mesh_t *m) {
  uint32_t *t = malloc(3 * m->triangle_count * sizeof *t + 1);
  for (size_t i = 0; i < m->triangle_count; ++i) {
    const uint32_t *s = m->triangles + 3 * i;
    int k = s[0] < s[1] ? (s[0] < s[2] ? 0 : 2) : (s[1] < s[2] ? 1 : 2);
    for (int j = 0; j < 3; ++j)
      t[3 * i + j] = s[(k + j) % 3];
  }
  /* Sort big-endian-like: compare index by index. */
  for (size_t i = 0; i < 3 * m->triangle_count; ++i) {
    uint32_t v = t[i];
    unsigned char *b = (unsigned char *)&t[i];
    b[0] = (unsigned char)(v >> 24), b[1] = (unsigned char)(v >> 16);
    b[2] = (unsigned char)(v >> 8), b[3] = (unsigned char)v;
  }
  qsort(t, m->triangle_count, 3 * sizeof *t, cmp_tri);
  return t;
}
static int same_surface(const sc_mesh_t *a, const sc_mesh_t *b) {
  if (a->triangle_count != b->triangle_count)
    return 0;
  uint32_t *x = canonical(a), *y = canonical(b);
  int same = memcmp(x, y, 3 * a->triangle_count * sizeof *x) == 0;
  free(x);
  free(y);
  return same;
}

/* The order the core promises: each triangle from its smallest index, the
 * triangles in increasing order, index by index (so none twice). */
static int in_canonical_order(const sc_mesh_t *m) {
  for (size_t i = 0; i < m->triangle_count; ++i) {
    const uint32_t *t = m->triangles + 3 * i;
    if (t[0] > t[1] || t[0] > t[2])
      return 0;
    if (i > 0) {
      const uint32_t *s = t - 3;
      int k = 0;
      while (k < 3 && s[k] == t[k])
        ++k;
      if (k == 3 || s[k] > t[k])
        return 0;
    }
  }
  return 1;
}

typedef struct {
  int cancel_stage; /* cancel at the first call in this stage; -1 never */
  int calls;
  int last_stage;
  int regress; /* stage went backwards, or fraction out of [0, 1] */
} progress_t;

/* Cancels once the input stage is past a fraction (smoothing's
 * iterations, with --denoise). */
static int cancel_late_input(void *user, sc_stage_t stage, double fraction) {
  (void)user;
  return stage == SC_STAGE_INPUT && fraction > 0.6;
}

static int on_progress(void *user, sc_stage_t stage, double fraction) {
  progress_t *p = user;
  ++p->calls;
  if ((int)stage < p->last_stage || !(fraction >= 0 && fraction <= 1))
    p->regress = 1;
  p->last_stage = (int)stage;
  return (int)stage == p->cancel_stage;
}

int main(void) {
  /* Every code has a distinct name and message; unknown codes say so. */
  const int codes[] = {SC_EINVALID_ARGUMENT, SC_EDEGENERATE_INPUT,
                       SC_ENONFINITE,        SC_ENO_MEMORY,
                       SC_ECANCELLED,        SC_ETOO_MANY_POINTS,
                       SC_EINTERNAL,         SC_EBAD_STATE};
  for (size_t i = 0; i < sizeof codes / sizeof codes[0]; ++i) {
    EXPECT_LT(codes[i], 0);
    EXPECT_STR_NE(sc_err_name(codes[i]), "UNKNOWN");
    EXPECT_STR_NE(sc_strerror(codes[i]), "unknown error");
    for (size_t j = 0; j < i; ++j)
      EXPECT_STR_NE(sc_err_name(codes[i]), sc_err_name(codes[j]));
  }
  EXPECT_STR_EQ(sc_err_name(-999), "UNKNOWN");
  EXPECT_STR_EQ(sc_strerror(-999), "unknown error");
  EXPECT_STR_EQ(sc_stage_name(SC_STAGE_DELAUNAY), "delaunay");
  EXPECT_STR_EQ(sc_stage_name(SC_STAGE_COUNT), "?");
  EXPECT_GT(sc_estimate_bytes(2000000), sc_estimate_bytes(1000000));

  /* sc_params_check() takes the defaults and says what is out of range,
   * as sc_reconstruct() would. */
  {
    sc_params_t q;
    char why[256] = "";
    sc_params_init(&q);
    EXPECT_EQ(sc_params_check(&q, why, sizeof why), SC_OK);
    q.boundary_rho = 11;
    EXPECT_EQ(sc_params_check(&q, why, sizeof why), SC_EINVALID_ARGUMENT);
    EXPECT_STR_CONTAINS(why, "boundary_rho");
    sc_params_init(&q);
    q.max_hole_edges = -1;
    EXPECT_EQ(sc_params_check(&q, NULL, 0), SC_EINVALID_ARGUMENT);
    EXPECT_EQ(sc_params_check(NULL, why, sizeof why), SC_EINVALID_ARGUMENT);
  }

  /* Every mode tiles but watertight mode's labelling alone. */
  {
    sc_params_t q;
    sc_params_init(&q);
    EXPECT_EQ(sc_params_can_tile(&q), 1);
    q.mode = SC_MODE_BOUNDARY;
    q.watertight_labels = 1; /* a watertight option: boundary mode tiles */
    EXPECT_EQ(sc_params_can_tile(&q), 1);
    q.mode = SC_MODE_WATERTIGHT;
    EXPECT_EQ(sc_params_can_tile(&q), 0);
    q.watertight_labels = 0;
    EXPECT_EQ(sc_params_can_tile(&q), 1);
    q.memory_limit = 1e9;
    EXPECT_EQ(sc_params_can_tile(&q), 0);
    q.mode = SC_MODE_COCONE;
    EXPECT_EQ(sc_params_can_tile(&q), 1);
    EXPECT_EQ(sc_params_can_tile(NULL), 0);
  }

  double *xyz = malloc(3 * N * sizeof *xyz);
  scs_sample_surface(SCS_SURF_TORUS, SCS_DENSITY_UNIFORM, N, 11, xyz);
  sc_params_t p;
  sc_params_init(&p);
  char msg[256];

  sc_mesh_t *ref = NULL;
  EXPECT_EQ(sc_reconstruct(xyz, N, &p, &ref, msg, sizeof msg), 0);
  if (!ref)
    return sct_finish("core_api");
  EXPECT(ref->diag.closed && ref->diag.genus == 1);
  EXPECT_EQ(ref->point_count, N);
  EXPECT(in_canonical_order(ref));
  /* The order holds in every mode, and for a sample of fewer points than
   * the ranges the sort first splits the vertex numbers into. */
  {
    const size_t counts[] = {N, 1200, 300};
    const sc_mode_t modes[] = {SC_MODE_SHORTCRUST, SC_MODE_COCONE,
                               SC_MODE_BOUNDARY, SC_MODE_WATERTIGHT,
                               SC_MODE_AUTO};
    for (size_t c = 0; c < sizeof counts / sizeof counts[0]; ++c)
      for (size_t k = 0; k < sizeof modes / sizeof modes[0]; ++k) {
        sc_params_t q = p;
        q.mode = modes[k];
        sc_mesh_t *m = NULL;
        EXPECT_EQ(sc_reconstruct(xyz, counts[c], &q, &m, msg, sizeof msg), 0);
        EXPECT(m && m->triangle_count > 0 && in_canonical_order(m));
        sc_mesh_free(m);
      }
  }

  /* Streaming in uneven chunks gives the same surface. */
  sc_recon_t *r = NULL;
  EXPECT_EQ(sc_recon_new(&p, &r), 0);
  for (size_t at = 0; at < N;) {
    size_t k = at == 0 ? 3 : 977; /* a first chunk too small to triangulate */
    if (k > N - at)
      k = N - at;
    EXPECT_EQ(sc_recon_add(r, xyz + 3 * at, k, msg, sizeof msg), 0);
    at += k;
  }
  sc_mesh_t *streamed = NULL;
  EXPECT_EQ(sc_recon_finish(r, &streamed, msg, sizeof msg), 0);
  EXPECT(streamed && same_surface(ref, streamed));
  /* A finished reconstruction takes nothing more. */
  sc_mesh_t *again = NULL;
  EXPECT_EQ(sc_recon_add(r, xyz, 1, msg, sizeof msg), SC_EBAD_STATE);
  EXPECT_EQ(sc_recon_finish(r, &again, msg, sizeof msg), SC_EBAD_STATE);
  EXPECT_NULL(again);
  sc_recon_free(r);
  sc_mesh_free(streamed);
  sc_recon_free(NULL);
  sc_mesh_free(NULL);

  /* A grid on the faces of a cube is full of cospherical points, where the
   * order of the cells in memory (which differs between one insertion and
   * chunks) could break ties, and every point is on the hull, where the
   * normal sums the hull facets' in that order: the meshes must still be
   * the same arrays, normals too, in every mode. */
  {
    enum { G = 24 };
    double *grid = malloc(3 * 6 * G * G * sizeof *grid);
    size_t ng = 0;
    for (int face = 0; face < 6; ++face)
      for (int i = 0; i < G; ++i)
        for (int j = 0; j < G; ++j) {
          double u = (i + 0.5) / G, v = (j + 0.5) / G, w = face & 1;
          int ax = face / 2;
          grid[3 * ng + ax] = w;
          grid[3 * ng + (ax + 1) % 3] = u;
          grid[3 * ng + (ax + 2) % 3] = v;
          ++ng;
        }
    const sc_mode_t gm[] = {SC_MODE_COCONE, SC_MODE_BOUNDARY,
                            SC_MODE_WATERTIGHT};
    for (int k = 0; k < 3; ++k) {
      sc_params_t q = p;
      q.mode = gm[k];
      sc_mesh_t *one = NULL, *chunked = NULL;
      EXPECT_EQ(sc_reconstruct(grid, ng, &q, &one, msg, sizeof msg), 0);
      EXPECT_EQ(sc_recon_new(&q, &r), 0);
      for (size_t at = 0; at < ng; at += 500)
        EXPECT_EQ(sc_recon_add(r, grid + 3 * at, ng - at < 500 ? ng - at : 500,
                               msg, sizeof msg),
                  0);
      EXPECT_EQ(sc_recon_finish(r, &chunked, msg, sizeof msg), 0);
      sc_recon_free(r);
      EXPECT(one && chunked && one->triangle_count > 0 &&
             one->triangle_count == chunked->triangle_count &&
             memcmp(one->triangles, chunked->triangles,
                    3 * one->triangle_count * sizeof *one->triangles) == 0);
      EXPECT(one && chunked && one->normals && chunked->normals &&
             memcmp(one->normals, chunked->normals,
                    3 * ng * sizeof *one->normals) == 0);
      sc_mesh_free(one);
      sc_mesh_free(chunked);
    }
    free(grid);
  }

  /* A failed add leaves only free() allowed. */
  EXPECT_EQ(sc_recon_new(&p, &r), 0);
  double nan_pt[3] = {0, 0, 0};
  nan_pt[1] = 0.0 / 0.0;
  EXPECT_EQ(sc_recon_add(r, nan_pt, 1, msg, sizeof msg), SC_ENONFINITE);
  EXPECT_EQ(sc_recon_add(r, xyz, N, msg, sizeof msg), SC_EBAD_STATE);
  sc_recon_free(r);
  sc_params_t bad = p;
  bad.r = 2;
  r = (sc_recon_t *)&r;
  EXPECT_EQ(sc_recon_new(&bad, &r), SC_EINVALID_ARGUMENT);
  EXPECT_NULL(r);

  /* More threads (the smoothing's, here none) give the same surface. */
  sc_params_t par = p;
  par.threads = 2;
  sc_mesh_t *pm = NULL;
  EXPECT_EQ(sc_reconstruct(xyz, N, &par, &pm, msg, sizeof msg), 0);
  EXPECT(pm && same_surface(ref, pm));
  sc_mesh_free(pm);

  /* Progress visits the stages in order with fractions in [0, 1]. */
  progress_t pr = {-1, 0, -1, 0};
  p.progress = on_progress;
  p.progress_user = &pr;
  sc_mesh_t *m = NULL;
  EXPECT_EQ(sc_reconstruct(xyz, N, &p, &m, msg, sizeof msg), 0);
  EXPECT_GT(pr.calls, SC_STAGE_COUNT);
  EXPECT(!pr.regress);
  EXPECT_EQ(pr.last_stage, SC_STAGE_EXTRACT);
  sc_mesh_free(m);

  /* Cancelling in any stage stops the run with CANCELLED and no mesh. */
  for (int s = 0; s < SC_STAGE_COUNT; ++s) {
    pr = (progress_t){s, 0, -1, 0};
    m = (sc_mesh_t *)&m;
    int rc = sc_reconstruct(xyz, N, &p, &m, msg, sizeof msg);
    if (rc != SC_ECANCELLED)
      fprintf(stderr, "cancel in stage %s: got %d\n", sc_stage_name(s), rc);
    EXPECT_EQ(rc, SC_ECANCELLED);
    EXPECT_NULL(m);
    EXPECT_EQ(pr.last_stage, s);
  }

  /* Smoothing on 3 threads stops when cancelled in its iterations. */
  sc_params_t sm = p;
  sm.denoise = 1;
  sm.denoise_scale = 0.15;
  sm.threads = 3;
  sm.progress = cancel_late_input;
  m = (sc_mesh_t *)&m;
  EXPECT_EQ(sc_reconstruct(xyz, N, &sm, &m, msg, sizeof msg), SC_ECANCELLED);
  EXPECT_NULL(m);
  EXPECT(strstr(msg, "input") != NULL);

  /* The allocator hint is taken by glibc's own malloc (the sanitizers
   * bring theirs) and changes nothing in the result. */
  int tuned = sc_tune_allocator();
#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__) &&                    \
    !defined(__SANITIZE_THREAD__)
  EXPECT_EQ(tuned, SC_OK);
#else
  EXPECT(tuned == SC_OK || tuned == SC_EINTERNAL);
#endif
  sc_params_init(&p);
  sc_mesh_t *tuned_mesh = NULL;
  EXPECT_EQ(sc_reconstruct(xyz, N, &p, &tuned_mesh, msg, sizeof msg), 0);
  EXPECT(tuned_mesh && same_surface(ref, tuned_mesh));
  sc_mesh_free(tuned_mesh);

  sc_mesh_free(ref);
  free(xyz);
  return sct_finish("core_api");
}
