/*
 * Tiles (docs/algorithm.md section 17): the same points split into 2 to 16
 * tiles, run on one thread or two, give exactly the triangles, normals and
 * counts of one triangulation, in the cocone and shortcrust modes, on a
 * synthetic sample, a real scan, a grid (cospherical everywhere, flat hull
 * faces), an exact sample of a sphere and a very uneven density; a cancel
 * during the tiles stops them all; the modes that run one triangulation say so
 * (tiles 0); points smoothed on two threads are smoothed as on one. A FILE that
 * is a mesh is sampled at 6000 random points over its surface. Each tile run as
 * a job of its own (tile_count, tile_index) and merged (sc_reconstruct_merge())
 * gives the same, and results that cannot be one job's tiles are refused.
 *
 *   test_core_tiles [SCAN.ply|MESH.ply ...]
 *   test_core_tiles --files SCAN.ply|MESH.ply ...   (only those)
 *   test_core_tiles --quick [CLOSED.ply ...]
 *                  (a small torus on two threads, one triangulation
 *                   scanned on two, watertight mode's labelling beside
 *                   the extraction on CLOSED, and the cancels: for the
 *                   ThreadSanitizer build)
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sct_assert.h"
#include "shortcrust.h"
#include "shortcrust_files.h"
#include "synth.h"

static sc_mesh_t *run_with(const char *what, const double *xyz, size_t n,
                           const sc_params_t *p) {
  sc_mesh_t *mesh = NULL;
  char msg[256] = "";
  int rc = sc_reconstruct(xyz, n, p, &mesh, msg, sizeof msg);
  if (rc != 0) {
    EXPECT_FAIL("%s, %s, %d tiles: %s: %s", what, sc_mode_name(p->mode),
                p->tiles, sc_err_name(rc), msg);
    return NULL;
  }
  return mesh;
}

static sc_mesh_t *run(const char *what, const double *xyz, size_t n,
                      sc_mode_t mode, int tiles, int threads) {
  sc_params_t p;
  sc_params_init(&p);
  p.mode = mode;
  p.tiles = tiles;
  p.threads = threads;
  return run_with(what, xyz, n, &p);
}

/* b's mesh must be a's, array for array, and what their triangulations
 * counted the same; 0 when the triangles differ. */
static int same_output(const char *tag, const sc_mesh_t *a,
                       const sc_mesh_t *b) {
  if (a->triangle_count != b->triangle_count) {
    EXPECT_FAIL("%s: %zu triangles, one triangulation %zu", tag,
                b->triangle_count, a->triangle_count);
    return 0;
  }
  if (memcmp(a->triangles, b->triangles,
             3 * a->triangle_count * sizeof *a->triangles) != 0)
    EXPECT_FAIL("%s: other triangles", tag);
  if (memcmp(a->normals, b->normals, 3 * a->point_count * sizeof(double)))
    EXPECT_FAIL("%s: other normals", tag);
  /* What the triangulation counted, counted once over the tiles. */
  EXPECT_EQ(a->diag.duplicates_merged, b->diag.duplicates_merged);
  EXPECT_EQ(a->diag.delaunay_vertices, b->diag.delaunay_vertices);
  EXPECT_EQ(a->diag.delaunay_cells, b->diag.delaunay_cells);
  EXPECT_EQ(a->diag.delaunay_facets, b->diag.delaunay_facets);
  EXPECT_EQ(a->diag.hull_facets, b->diag.hull_facets);
  EXPECT_EQ(a->diag.hull_vertices, b->diag.hull_vertices);
  EXPECT_EQ(a->diag.candidates, b->diag.candidates);
  EXPECT_EQ(a->diag.genus, b->diag.genus);
  /* Shortcrust mode's check saw the same, and chose the same r. */
  EXPECT_EQ(a->diag.checked, b->diag.checked);
  EXPECT_EQ(a->diag.topology_doubt, b->diag.topology_doubt);
  EXPECT_EQ(a->diag.r_used, b->diag.r_used);
  return 1;
}

/* The tiled mesh must be the single triangulation's, array for array. */
static void same(const char *what, const sc_mesh_t *a, const sc_mesh_t *b,
                 int tiles, int threads) {
  char tag[160];
  snprintf(tag, sizeof tag, "%s, %d tiles on %d threads", what, tiles, threads);
  EXPECT_EQ(b->diag.tiles > 1, 1);
  EXPECT_EQ(a->diag.tiles, 0);
  if (!same_output(tag, a, b))
    return;
  printf("ok: %s: %zu triangles, %llu tiles, %llu points triangulated twice "
         "(%.0f%%)\n",
         tag, b->triangle_count, (unsigned long long)b->diag.tiles,
         (unsigned long long)b->diag.tile_points_foreign,
         100.0 * (double)b->diag.tile_points_foreign /
             (double)b->diag.delaunay_vertices);
}

/* The job split into k tile jobs, each run alone as on another machine,
 * and merged (sc_reconstruct_merge()); tile jobs in reverse order. */
/* Tile jobs 0 .. k-1 of p's job (p->tile_count set to k) into parts, from
 * the last: 1 when every one ran. */
static int tile_jobs(const char *what, const double *xyz, size_t n,
                     sc_params_t *p, int k, sc_mesh_t **parts) {
  char msg[256] = "";
  int ok = 1;
  p->tile_count = k;
  for (int i = k - 1; i >= 0; --i) {
    p->tile_index = i;
    int rc = sc_reconstruct(xyz, n, p, &parts[i], msg, sizeof msg);
    if (rc != 0) {
      EXPECT_FAIL("%s, %s, tile %d of %d: %s: %s", what, sc_mode_name(p->mode),
                  i, k, sc_err_name(rc), msg);
      ok = 0;
    }
  }
  return ok;
}

static sc_mesh_t *run_apart(const char *what, const double *xyz, size_t n,
                            sc_mode_t mode, int k) {
  sc_mesh_t *parts[16] = {NULL};
  sc_params_t p;
  sc_params_init(&p);
  p.mode = mode;
  char msg[256] = "";
  const int ok = tile_jobs(what, xyz, n, &p, k, parts);
  sc_mesh_t *mesh = NULL;
  if (ok) {
    int rc = sc_reconstruct_merge(xyz, n, &p, (const sc_mesh_t *const *)parts,
                                  (size_t)k, &mesh, msg, sizeof msg);
    if (rc != 0)
      EXPECT_FAIL("%s, %s, %d tiles merged: %s: %s", what, sc_mode_name(mode),
                  k, sc_err_name(rc), msg);
  }
  for (int i = 0; i < k; ++i)
    sc_mesh_free(parts[i]);
  return mesh;
}

/* Tile results merged: the mesh of one triangulation in p's mode. */
static void merged_same(const char *tag, const double *xyz, size_t n,
                        const sc_params_t *p, const sc_mesh_t *const *parts,
                        int k) {
  sc_mesh_t *m = NULL;
  char msg[256] = "";
  EXPECT_EQ(
      sc_reconstruct_merge(xyz, n, p, parts, (size_t)k, &m, msg, sizeof msg),
      SC_OK);
  sc_mesh_t *ref = run(tag, xyz, n, p->mode, 1, 1);
  if (m && ref)
    same(tag, ref, m, k, 1);
  sc_mesh_free(ref);
  sc_mesh_free(m);
}

/* Every mode, in tiles: the boundary modes' detection runs over the tiles
 * too (docs/algorithm.md section 17.1), and tile jobs are for the cocone
 * and shortcrust modes only. */
static void check(const char *what, const double *xyz, size_t n,
                  int all_modes) {
  const sc_mode_t modes[] = {SC_MODE_COCONE, SC_MODE_SHORTCRUST,
                             SC_MODE_BOUNDARY, SC_MODE_WATERTIGHT,
                             SC_MODE_AUTO};
  const int tiles[][2] = {{3, 2}, {16, 2}, {2, 1}, {5, 1}};
  for (size_t m = 0; m < (all_modes ? 5u : 2u); ++m) {
    const int boundary = m >= 2;
    sc_mesh_t *one = run(what, xyz, n, modes[m], 1, 1);
    if (!one)
      continue;
    EXPECT_GT(one->triangle_count, 0);
    for (size_t k = 0; k < (boundary ? 2 : 4); ++k) {
      sc_mesh_t *t = run(what, xyz, n, modes[m], tiles[k][0], tiles[k][1]);
      if (t) {
        char tag[160];
        snprintf(tag, sizeof tag, "%s, %s", what, sc_mode_name(modes[m]));
        same(tag, one, t, tiles[k][0], tiles[k][1]);
        EXPECT_EQ(one->diag.boundary_samples, t->diag.boundary_samples);
        EXPECT_EQ(one->diag.boundary_loops, t->diag.boundary_loops);
      }
      sc_mesh_free(t);
    }
    if (boundary) {
      sc_mesh_free(one);
      continue;
    }
    const int apart[] = {2, 5};
    for (size_t k = 0; k < 2; ++k) {
      char tag[160];
      snprintf(tag, sizeof tag, "%s, tile jobs merged", what);
      sc_mesh_t *t = run_apart(what, xyz, n, modes[m], apart[k]);
      if (t)
        same(tag, one, t, apart[k], 1);
      sc_mesh_free(t);
    }
    sc_mesh_free(one);
  }
}

/* A cancel once the progress has come `after` times in `stage`. */
typedef struct {
  sc_stage_t stage;
  int after, calls;
} cancel_at_t;

static int cancel_at(void *user, sc_stage_t stage, double fraction) {
  (void)fraction;
  cancel_at_t *c = user;
  return stage == c->stage && ++c->calls > c->after;
}

/* Watches the progress of a job: the stages must come in order and,
 * within one, the fraction must never go back. */
typedef struct {
  int stage, calls, back, in_delaunay;
  double last;
} watch_t;

static int watch(void *user, sc_stage_t stage, double fraction) {
  watch_t *w = user;
  ++w->calls;
  w->in_delaunay += stage == SC_STAGE_DELAUNAY;
  if ((int)stage < w->stage || !(fraction >= 0 && fraction <= 1) ||
      ((int)stage == w->stage && fraction < w->last))
    ++w->back;
  w->stage = (int)stage;
  w->last = fraction;
  return 0;
}

/* Tiles on two threads, in each mode that tiles, and one triangulation:
 * the bar never goes back within a stage (a tile's phases, and the steps
 * of pruning and extraction that count from 0 again, each have their
 * share of the stage), and the mesh is that of one triangulation. */
static void progress_forward(const double *xyz, size_t n) {
  const sc_mode_t modes[] = {SC_MODE_COCONE, SC_MODE_BOUNDARY,
                             SC_MODE_WATERTIGHT, SC_MODE_COCONE};
  for (size_t m = 0; m < sizeof modes / sizeof *modes; ++m) {
    const int tiled = m < 3;
    sc_params_t p;
    sc_params_init(&p);
    p.mode = modes[m];
    p.tiles = tiled ? 3 : 1;
    p.threads = tiled ? 2 : 1;
    watch_t w = {-1, 0, 0, 0, 0};
    p.progress = watch;
    p.progress_user = &w;
    sc_mesh_t *t = run_with("torus, watched", xyz, n, &p);
    sc_mesh_t *one = run("torus", xyz, n, modes[m], 1, 1);
    char tag[160];
    snprintf(tag, sizeof tag, "torus, %s, %s watched", sc_mode_name(modes[m]),
             tiled ? "3 tiles" : "one triangulation");
    if (t && one && same_output(tag, one, t)) {
      if (w.back)
        fprintf(stderr, "%s: the progress went back %d times in %d calls\n",
                tag, w.back, w.calls);
      EXPECT_EQ(w.back, 0);
      EXPECT_GT(w.in_delaunay, 2);
      EXPECT_EQ(w.stage, SC_STAGE_EXTRACT);
      printf("ok: %s: %d calls, none back\n", tag, w.calls);
    }
    sc_mesh_free(t);
    sc_mesh_free(one);
  }
  /* In chunks, each chunk counts its insertion from 0 (how many will come
   * is not known), and the stage goes on from the last one's. */
  sc_params_t p;
  sc_params_init(&p);
  watch_t w = {-1, 0, 0, 0, 0};
  p.progress = watch;
  p.progress_user = &w;
  sc_recon_t *r = NULL;
  char msg[256] = "";
  EXPECT_EQ(sc_recon_new(&p, &r), 0);
  const size_t chunks = 3;
  for (size_t c = 0; r && c < chunks; ++c)
    EXPECT_EQ(sc_recon_add(r, xyz + 3 * (n * c / chunks),
                           n * (c + 1) / chunks - n * c / chunks, msg,
                           sizeof msg),
              0);
  sc_mesh_t *m = NULL;
  if (r)
    EXPECT_EQ(sc_recon_finish(r, &m, msg, sizeof msg), 0);
  sc_recon_free(r);
  EXPECT_EQ(w.back, (int)chunks - 1);
  EXPECT_EQ(w.stage, SC_STAGE_EXTRACT);
  printf("ok: torus in %zu chunks watched: %d calls, back %d times\n", chunks,
         w.calls, w.back);
  sc_mesh_free(m);
}

/* Watertight mode on two threads labels the cells beside the extraction
 * (docs/algorithm.md section 11.5), where boundary samples were found or
 * the triangulation is small, and stops where the patches settle the
 * closure: the mesh and diagnostics of one thread, by default and with the
 * labelling alone; and a cancel while it runs stops it. */
static void labelling_beside(const char *path) {
  scf_points_t pts;
  char msg[256] = "";
  if (scf_points_read(path, &pts, msg, sizeof msg) != 0) {
    EXPECT_FAIL("%s: %s", path, msg);
    return;
  }
  /* Watertight mode, with and without --labels, and auto mode, which
   * closes this sample by labelling too. */
  for (int variant = 0; variant < 3; ++variant) {
    sc_params_t p;
    sc_params_init(&p);
    p.mode = variant < 2 ? SC_MODE_WATERTIGHT : SC_MODE_AUTO;
    p.watertight_labels = variant == 1;
    p.threads = 1;
    sc_mesh_t *one = run_with(path, pts.xyz, pts.count, &p);
    p.threads = 2;
    sc_mesh_t *two = run_with(path, pts.xyz, pts.count, &p);
    char tag[300];
    snprintf(tag, sizeof tag, "%s, %s on 2 threads", path,
             variant == 0   ? "watertight"
             : variant == 1 ? "watertight (labels)"
                            : "auto");
    if (one && two && same_output(tag, one, two)) {
      /* (Labelled with --labels always; otherwise where the patches
       * leave doubt, the same on both.) */
      EXPECT(two->diag.labelled || variant != 1);
      EXPECT_EQ(one->diag.labelled, two->diag.labelled);
      EXPECT_EQ(one->diag.boundary_samples, two->diag.boundary_samples);
      EXPECT_EQ(one->diag.path, two->diag.path);
      EXPECT_EQ(one->diag.cells_relabelled, two->diag.cells_relabelled);
      EXPECT_EQ(one->diag.samples_attached, two->diag.samples_attached);
      printf("ok: %s: %zu triangles, genus %lld, %s, %llu cells relabelled\n",
             tag, two->triangle_count, (long long)two->diag.genus,
             two->diag.labelled ? "labelled" : "the patches' closure",
             (unsigned long long)two->diag.cells_relabelled);
    }
    sc_mesh_free(one);
    sc_mesh_free(two);
  }
  sc_params_t p;
  sc_params_init(&p);
  p.mode = SC_MODE_WATERTIGHT;
  p.threads = 2;
  cancel_at_t at = {SC_STAGE_EXTRACT, 1, 0};
  p.progress = cancel_at;
  p.progress_user = &at;
  sc_mesh_t *mesh = NULL;
  EXPECT_EQ(sc_reconstruct(pts.xyz, pts.count, &p, &mesh, msg, sizeof msg),
            SC_ECANCELLED);
  EXPECT_NULL(mesh);
  printf("ok: cancel beside the labelling: %s\n", msg);
  scf_points_free(&pts);
}

/* A real scan, as given; or a mesh's surface at 6000 random points (a flat
 * face of the hull, sampled, where the hull facets' normals turned inward
 * at random; thin parts, which the labelling closes on a triangulation
 * built again for it): check() in every mode. */
static void check_file(const char *path) {
  scf_points_t pts = {0};
  uint32_t *tri = NULL;
  size_t ntri = 0;
  char msg[256];
  if (scf_mesh_read(path, &pts, &tri, &ntri, msg, sizeof msg) != 0) {
    EXPECT_FAIL("%s: %s", path, msg);
    return;
  }
  if (ntri > 0) {
    const size_t k = 6000;
    double *some = malloc(3 * k * sizeof *some);
    EXPECT_NOT_NULL(some);
    if (some &&
        scs_sample_mesh(pts.xyz, pts.count, tri, ntri, k, 1, some) == 0) {
      char what[300];
      snprintf(what, sizeof what, "%s, %zu random points", path, k);
      check(what, some, k, 1);
    } else {
      EXPECT_FAIL("%s: cannot sample", path);
    }
    free(some);
  } else {
    check(path, pts.xyz, pts.count, 1);
  }
  free(tri);
  scf_points_free(&pts);
}

/* n points of the uniform torus sample of seed `seed`, in an array with
 * room for `room` (>= n) points; NULL (a failed check) if it cannot be
 * made. */
static double *torus(size_t n, size_t room, unsigned seed) {
  double *xyz = malloc(3 * room * sizeof *xyz);
  EXPECT_NOT_NULL(xyz);
  if (xyz && scs_sample_surface(SCS_SURF_TORUS, SCS_DENSITY_UNIFORM, n, seed,
                                xyz) != 0) {
    EXPECT_FAIL("cannot sample %zu points of a torus", n);
    free(xyz);
    xyz = NULL;
  }
  return xyz;
}

/* One tile a thread on an exact sample of a genus-2 surface, 100 000
 * points: the first pass over each tile's cells stays below the bound of
 * section 17.4, and the tiles give up once a sample of the points that
 * pass found has gone in (or, before that, once all of them had). The
 * mesh is still one triangulation's: a closed surface of genus 2. */
static void genus2_given_up(void) {
  const size_t n = 100000;
  double *xyz = malloc(3 * n * sizeof *xyz);
  EXPECT_NOT_NULL(xyz);
  if (!xyz)
    return;
  if (scs_sample_surface(SCS_SURF_GENUS2, SCS_DENSITY_UNIFORM, n, 1, xyz) !=
      0) {
    EXPECT_FAIL("cannot sample %zu points of a genus-2 surface", n);
    free(xyz);
    return;
  }
  sc_mesh_t *one = run("genus 2", xyz, n, SC_MODE_COCONE, 1, 1);
  sc_mesh_t *t = run("genus 2", xyz, n, SC_MODE_COCONE, 0, 2);
  if (one && t) {
    EXPECT_EQ(t->diag.tiles, 0);
    EXPECT_GT(t->diag.tile_points_foreign, 0);
    EXPECT_EQ(t->diag.closed, 1);
    EXPECT_EQ(t->diag.components, 1);
    EXPECT_EQ(t->diag.genus, 2);
    if (same_output("genus 2, tiles given up", one, t))
      printf("ok: one tile a thread gave up on the exact genus-2 sample "
             "(%llu points taken in), one triangulation instead: "
             "%zu triangles, genus %lld\n",
             (unsigned long long)t->diag.tile_points_foreign, t->triangle_count,
             (long long)t->diag.genus);
  }
  sc_mesh_free(one);
  sc_mesh_free(t);
  free(xyz);
}

int main(int argc, char **argv) {
  const int quick = argc > 1 && strcmp(argv[1], "--quick") == 0;
  if (argc > 1 && strcmp(argv[1], "--genus2") == 0) {
    genus2_given_up();
    return sct_finish("core_tiles");
  }
  /* The files alone, as a test of its own that runs beside the rest. */
  if (argc > 1 && strcmp(argv[1], "--files") == 0) {
    for (int a = 2; a < argc; ++a)
      check_file(argv[a]);
    return sct_finish("core_tiles");
  }
  /* A torus, well spaced, with a few exact duplicates. */
  const size_t n = quick ? 5000 : 12000, dups = 50;
  double *xyz = torus(n, n + dups, 7);
  if (!xyz)
    return sct_finish("core_tiles");
  for (size_t i = 0; i < dups; ++i)
    memcpy(&xyz[3 * (n + i)], &xyz[3 * (i * 97 % n)], 3 * sizeof *xyz);
  if (quick) {
    sc_mesh_t *one = run("torus", xyz, n + dups, SC_MODE_COCONE, 1, 1);
    sc_mesh_t *t = run("torus", xyz, n + dups, SC_MODE_COCONE, 2, 2);
    if (one && t)
      same("torus", one, t, 2, 2);
    sc_mesh_free(one);
    sc_mesh_free(t);
    /* Boundary detection over the tiles, on two threads. */
    one = run("torus", xyz, n + dups, SC_MODE_BOUNDARY, 1, 1);
    t = run("torus", xyz, n + dups, SC_MODE_BOUNDARY, 2, 2);
    if (one && t)
      same("torus, boundary", one, t, 2, 2);
    sc_mesh_free(one);
    sc_mesh_free(t);
    /* Smoothed on two threads (section 16), then in two tiles: the mesh
     * of one thread and one triangulation. */
    sc_params_t p;
    sc_params_init(&p);
    p.denoise = 1;
    p.denoise_scale = 0.15;
    p.tiles = 1;
    p.threads = 1;
    one = run_with("smoothed torus", xyz, n + dups, &p);
    p.tiles = 2;
    p.threads = 2;
    t = run_with("smoothed torus", xyz, n + dups, &p);
    if (one && t) {
      EXPECT(one->diag.denoised && t->diag.denoised);
      same("smoothed torus", one, t, 2, 2);
    }
    sc_mesh_free(one);
    sc_mesh_free(t);
    /* One triangulation, its facets scanned on two threads (a sample
     * large enough for that): the mesh and counts of one thread, in the
     * modes that test them differently. */
    {
      const size_t big = 12000;
      double *more = torus(big, big, 9);
      const sc_mode_t modes[] = {SC_MODE_COCONE, SC_MODE_SHORTCRUST,
                                 SC_MODE_BOUNDARY};
      for (size_t k = 0; more && k < sizeof modes / sizeof *modes; ++k) {
        one = run("torus", more, big, modes[k], 1, 1);
        t = run("torus", more, big, modes[k], 1, 2);
        char tag[160];
        snprintf(tag, sizeof tag, "torus, %s, one triangulation on 2 threads",
                 sc_mode_name(modes[k]));
        if (one && t && same_output(tag, one, t))
          printf("ok: %s: %zu triangles, %llu facets\n", tag, t->triangle_count,
                 (unsigned long long)t->diag.delaunay_facets);
        sc_mesh_free(one);
        sc_mesh_free(t);
      }
      free(more);
    }
    for (int a = 2; a < argc; ++a)
      labelling_beside(argv[a]);
    goto cancel;
  }
  check("torus", xyz, n + dups, 0);

  /* Half of a torus of twice the points: an open surface, with two
   * boundary loops. */
  double *open_torus = torus(2 * n, 2 * n, 7);
  if (open_torus) {
    double *open = open_torus;
    size_t half = 0;
    for (size_t i = 0; i < 2 * n; ++i)
      if (open[3 * i] < 0)
        memmove(&open[3 * half++], &open[3 * i], 3 * sizeof *open);
    sc_mesh_t *b = run("half torus", open, half, SC_MODE_BOUNDARY, 1, 1);
    if (b)
      EXPECT_EQ(b->diag.boundary_loops, 2);
    sc_mesh_free(b);
    check("half torus", open, half, 1);
    free(open);
  }

  /* Very uneven density: a genus-2 sample, one end 40 times as dense. */
  EXPECT_EQ(
      scs_sample_surface(SCS_SURF_GENUS2, SCS_DENSITY_UNIFORM, n, 11, xyz), 0);
  size_t kept = 0;
  for (size_t i = 0; i < n; ++i)
    if (xyz[3 * i] < 0.5 || i % 40 == 0)
      memmove(&xyz[3 * kept++], &xyz[3 * i], 3 * sizeof *xyz);
  check("uneven genus-2", xyz, kept, 0);

  /* An exact sample of a sphere: every inner ball is nearly the sphere
   * itself and every sample nearly on it, so that the filters fail and
   * each test of a sample against such a ball is exact. */
  EXPECT_EQ(scs_sample_surface(SCS_SURF_SPHERE, SCS_DENSITY_UNIFORM_RANDOM,
                               6000, 3, xyz),
            0);
  check("sphere", xyz, 6000, 0);

  /* A grid: the surface of a box of 61 x 41 x 21 points on every face. */
  kept = 0;
  for (int i = 0; i <= 60; ++i)
    for (int j = 0; j <= 40; ++j)
      for (int k = 0; k <= 20; ++k)
        if (i == 0 || i == 60 || j == 0 || j == 40 || k == 0 || k == 20) {
          xyz[3 * kept] = i * 0.125;
          xyz[3 * kept + 1] = j * 0.125;
          xyz[3 * kept + 2] = k * 0.125;
          ++kept;
        }
  check("grid box", xyz, kept, 1);

  /* Real scans, and meshes (check_file()). */
  for (int a = 1; a < argc; ++a)
    check_file(argv[a]);

  /* Cancel while the tiles triangulate, on two threads. */
cancel : {
  EXPECT_EQ(scs_sample_surface(SCS_SURF_TORUS, SCS_DENSITY_UNIFORM, n, 7, xyz),
            0);
  progress_forward(xyz, n);
  sc_params_t p;
  sc_params_init(&p);
  p.tiles = 4;
  p.threads = 2;
  cancel_at_t at = {SC_STAGE_DELAUNAY, 3, 0};
  p.progress = cancel_at;
  p.progress_user = &at;
  sc_mesh_t *mesh = NULL;
  char msg[256] = "";
  EXPECT_EQ(sc_reconstruct(xyz, n, &p, &mesh, msg, sizeof msg), SC_ECANCELLED);
  EXPECT_NULL(mesh);
  printf("ok: cancel during the tiles: %s\n", msg);
  if (quick) {
    free(xyz);
    return sct_finish("core_tiles");
  }
}

  /* Within a memory limit: tiles a few at a time, each triangulated
   * twice, the same mesh; a limit one triangulation fits runs untiled; one
   * nothing fits fails before it starts, and so does a mode that cannot
   * tile. */
  {
    sc_mesh_t *one = run("torus", xyz, n, SC_MODE_COCONE, 1, 1);
    const int threads[] = {1, 2};
    for (size_t k = 0; one && k < 2; ++k) {
      sc_params_t p;
      sc_params_init(&p);
      p.threads = threads[k];
      p.memory_limit = 24 << 20;
      sc_mesh_t *t = NULL;
      char msg[256] = "";
      EXPECT_EQ(sc_reconstruct(xyz, n, &p, &t, msg, sizeof msg), SC_OK);
      if (t)
        same("torus within 24 MB", one, t, (int)t->diag.tiles, threads[k]);
      sc_mesh_free(t);
    }
    sc_mesh_free(one);
    sc_params_t p;
    sc_params_init(&p);
    p.memory_limit = 1e9;
    sc_mesh_t *t = NULL;
    char msg[256] = "";
    EXPECT_EQ(sc_reconstruct(xyz, n, &p, &t, msg, sizeof msg), SC_OK);
    if (t)
      EXPECT_EQ(t->diag.tiles, 0);
    sc_mesh_free(t);
    t = NULL;
    p.memory_limit = 1 << 20;
    EXPECT_EQ(sc_reconstruct(xyz, n, &p, &t, msg, sizeof msg), SC_ENO_MEMORY);
    EXPECT_NULL(t);
    EXPECT_NOT_NULL(strstr(msg, "need a memory limit of at least"));
    printf("ok: 1 MB refused: %s\n", msg);
    p.mode = SC_MODE_WATERTIGHT;
    p.memory_limit = 1e9;
    EXPECT_EQ(sc_params_check(&p, msg, sizeof msg), SC_EINVALID_ARGUMENT);
    EXPECT_NOT_NULL(strstr(msg, "cocone and shortcrust modes only"));
    EXPECT_EQ(sc_reconstruct(xyz, n, &p, &t, msg, sizeof msg),
              SC_EINVALID_ARGUMENT);
    EXPECT_NULL(t);
  }

  /* The least limit that a refusal names is taken back; but the tiles of
   * a denser exact sample of a torus take in more than twice their own
   * points (the medial balls inside the tube reach across them), which
   * the model of the tiles' growth behind that least limit does not
   * foresee: a tile outgrows what the limit leaves it, and the job stops
   * with a message instead of running on far past the limit. */
  const size_t dense = 40000;
  double *dense_torus = torus(dense, dense, 7);
  if (dense_torus) {
    const double *pts = dense_torus;
    sc_params_t p;
    sc_params_init(&p);
    p.memory_limit = 1 << 20;
    sc_mesh_t *t = NULL;
    char msg[512] = "";
    EXPECT_EQ(sc_reconstruct(pts, dense, &p, &t, msg, sizeof msg),
              SC_ENO_MEMORY);
    const char *at = strstr(msg, "at least ");
    double least = 0;
    EXPECT_NOT_NULL(at);
    if (at)
      EXPECT_EQ(sscanf(at, "at least %lf MB", &least), 1);
    if (least > 0) {
      p.memory_limit = least * (1 << 20);
      EXPECT_EQ(sc_reconstruct(pts, dense, &p, &t, msg, sizeof msg),
                SC_ENO_MEMORY);
      EXPECT_NULL(t);
      EXPECT_NOT_NULL(strstr(msg, "cannot be kept"));
      printf("ok: %.1f MB, the least named, not kept: %s\n", least, msg);
    }
    sc_mesh_free(t);
    free(dense_torus);
  }

  /* One tile a thread (tiles 0) gives up where the tiles would cost more
   * than one triangulation, as on this exact sample of a torus, whose
   * inner Delaunay balls reach across the tiles, and runs one
   * triangulation, grown from the largest tile's (the duplicates of the
   * points it took in from the other tile go in again): the same mesh
   * and counts, and tile_points_foreign says how far the tiles got. The
   * tiles of a scan pay, and are kept. */
  {
    sc_mesh_t *one = run("torus", xyz, n + dups, SC_MODE_COCONE, 1, 1);
    sc_mesh_t *t = run("torus", xyz, n + dups, SC_MODE_COCONE, 0, 2);
    if (one && t) {
      EXPECT_EQ(t->diag.tiles, 0);
      EXPECT_GT(t->diag.tile_points_foreign, 0);
      EXPECT_EQ(one->diag.duplicates_merged, dups);
      (void)same_output("torus, tiles given up", one, t);
      printf("ok: one tile a thread gave up on the exact torus after %llu "
             "points, one triangulation instead\n",
             (unsigned long long)t->diag.tile_points_foreign);
    }
    sc_mesh_free(one);
    sc_mesh_free(t);
    for (int a = 1; a < argc; ++a) {
      scf_points_t pts;
      uint32_t *tri = NULL;
      size_t ntri = 0;
      char msg[256];
      if (scf_mesh_read(argv[a], &pts, &tri, &ntri, msg, sizeof msg) != 0)
        continue;
      free(tri);
      if (ntri > 0) { /* the scans only */
        scf_points_free(&pts);
        continue;
      }
      one = run(argv[a], pts.xyz, pts.count, SC_MODE_COCONE, 1, 1);
      t = run(argv[a], pts.xyz, pts.count, SC_MODE_COCONE, 0, 2);
      if (one && t)
        same(argv[a], one, t, 0, 2);
      sc_mesh_free(one);
      sc_mesh_free(t);
      scf_points_free(&pts);
    }
  }

  /* Tile jobs: what cannot be one job's tiles is refused, and so are tile
   * jobs the parameters do not allow. */
  {
    sc_params_t p;
    sc_params_init(&p);
    char msg[256] = "";
    p.tile_count = 3;
    p.tile_index = 3;
    EXPECT_EQ(sc_params_check(&p, msg, sizeof msg), SC_EINVALID_ARGUMENT);
    EXPECT_NOT_NULL(strstr(msg, "tile_index must be below tile_count"));
    p.tile_count = 0;
    p.tile_index = 1;
    EXPECT_EQ(sc_params_check(&p, msg, sizeof msg), SC_EINVALID_ARGUMENT);
    EXPECT_NOT_NULL(strstr(msg, "tile_index needs tile_count"));
    p.tile_count = 1;
    p.tile_index = 0;
    EXPECT_EQ(sc_params_check(&p, msg, sizeof msg), SC_EINVALID_ARGUMENT);
    p.tile_count = 2;
    p.mode = SC_MODE_WATERTIGHT;
    EXPECT_EQ(sc_params_check(&p, msg, sizeof msg), SC_EINVALID_ARGUMENT);
    EXPECT_NOT_NULL(strstr(msg, "cocone and shortcrust modes only"));
    p.mode = SC_MODE_COCONE;
    sc_mesh_t *parts[2] = {NULL, NULL}, *m = NULL;
    if (tile_jobs("torus", xyz, n, &p, 2, parts)) {
      EXPECT_EQ(parts[0]->diag.tiles, 2);
      EXPECT_EQ(parts[0]->component_count, 0);
      EXPECT_GT(parts[0]->triangle_count, 0);
      EXPECT_GT(parts[1]->triangle_count, 0);
      /* Another count of results, the same tile twice, another point
       * count, an index past the points. */
      const sc_mesh_t *one[1] = {parts[0]};
      EXPECT_EQ(sc_reconstruct_merge(xyz, n, &p, one, 1, &m, msg, sizeof msg),
                SC_EINVALID_ARGUMENT);
      EXPECT_NULL(m);
      const sc_mesh_t *twice[2] = {parts[0], parts[0]};
      EXPECT_EQ(sc_reconstruct_merge(xyz, n, &p, twice, 2, &m, msg, sizeof msg),
                SC_EINVALID_ARGUMENT);
      EXPECT_NOT_NULL(strstr(msg, "two tiles give the triangle"));
      const sc_mesh_t *both[2] = {parts[1], parts[0]};
      EXPECT_EQ(
          sc_reconstruct_merge(xyz, n - 1, &p, both, 2, &m, msg, sizeof msg),
          SC_EINVALID_ARGUMENT);
      EXPECT_NOT_NULL(strstr(msg, "another point count"));
      const uint32_t keep = parts[1]->triangles[4];
      parts[1]->triangles[4] = (uint32_t)n;
      EXPECT_EQ(sc_reconstruct_merge(xyz, n, &p, both, 2, &m, msg, sizeof msg),
                SC_EINVALID_ARGUMENT);
      EXPECT_NOT_NULL(strstr(msg, "past the last point"));
      printf("ok: a broken tile result refused: %s\n", msg);
      parts[1]->triangles[4] = keep;
      /* In any order, the untiled mesh. */
      merged_same("torus, two tile jobs merged in reverse", xyz, n, &p, both,
                  2);
    }
    sc_mesh_free(parts[0]);
    sc_mesh_free(parts[1]);
    /* Shortcrust mode's tile results carry its check's runs: a merge of
     * other parameters, or runs that do not add up, are refused. */
    p.mode = SC_MODE_SHORTCRUST;
    if (tile_jobs("torus", xyz, n, &p, 2, parts)) {
      EXPECT_EQ(parts[0]->diag.checked, 1);
      EXPECT_EQ(parts[0]->diag.tile_near_0 + parts[0]->diag.tile_near_1 +
                    parts[0]->diag.tile_near_2,
                parts[0]->diag.candidates);
      EXPECT_GT(parts[0]->triangle_count, parts[0]->diag.candidates);
      const sc_mesh_t *both[2] = {parts[0], parts[1]};
      p.unchecked = 1;
      EXPECT_EQ(sc_reconstruct_merge(xyz, n, &p, both, 2, &m, msg, sizeof msg),
                SC_EINVALID_ARGUMENT);
      EXPECT_NOT_NULL(strstr(msg, "carries what shortcrust mode's check"));
      p.unchecked = 0;
      parts[1]->diag.tile_near_4 += parts[1]->triangle_count;
      EXPECT_EQ(sc_reconstruct_merge(xyz, n, &p, both, 2, &m, msg, sizeof msg),
                SC_EINVALID_ARGUMENT);
      EXPECT_NOT_NULL(strstr(msg, "tile_near counts"));
      printf("ok: shortcrust tile results of another job refused: %s\n", msg);
      parts[1]->diag.tile_near_4 -= parts[1]->triangle_count;
      merged_same("torus, two shortcrust tile jobs merged", xyz, n, &p, both,
                  2);
    }
    sc_mesh_free(parts[0]);
    sc_mesh_free(parts[1]);
  }

  /* Watertight mode's labelling alone (--labels) labels the cells of one
   * triangulation, whatever the tiles. */
  {
    sc_params_t p;
    sc_params_init(&p);
    p.mode = SC_MODE_WATERTIGHT;
    p.watertight_labels = 1;
    p.tiles = 4;
    sc_mesh_t *b = run_with("torus", xyz, n, &p);
    if (b) {
      EXPECT_EQ(b->diag.tiles, 0);
      sc_mesh_free(b);
    }
  }
  free(xyz);
  return sct_finish("core_tiles");
}
