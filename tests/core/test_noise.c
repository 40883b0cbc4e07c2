/*
 * Denoising (docs/algorithm.md section 16) on noisy samples of the analytic
 * surfaces: with the mode's denoising the output is a closed, oriented
 * 2-manifold with the surface's components and genus and at least 99% of
 * the samples used; the triangles index the original points, and the
 * smoothed positions, when asked for, lie near the true surface. Without
 * noise nothing is smoothed and the mesh is the one without denoising.
 *
 *   test_core_noise SURFACE N SIGMA MODE [SEED]
 *
 * SIGMA is the noise in sample spacings; MODE a mode name, "auto" meaning
 * auto mode without the option (it must denoise by itself above the
 * floor), any other with params.denoise set.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "diag.h"
#include "sct_assert.h"
#include "shortcrust.h"
#include "synth.h"

/* The checks of a closed surface of the right topology. */
static void check_surface(const char *what, const scs_surface_info_t *info,
                          size_t n, const double *xyz, const sc_mesh_t *m) {
  scs_meshcheck_t c;
  ASSERT_EQ(scs_meshcheck(n, xyz, m->triangles, m->triangle_count, NULL, &c),
            0);
  char line[512];
  printf("%s: %s noise=%.3f curvature=%.3f denoised=%d scale=%.4g "
         "shift=%.3f\n",
         what, scs_meshcheck_summary(&c, line, sizeof line), m->diag.noise,
         m->diag.curvature, m->diag.denoised, m->diag.denoise_scale,
         m->diag.denoise_shift);
  EXPECT(c.manifold);
  EXPECT(c.closed);
  EXPECT(c.oriented);
  EXPECT_EQ(c.components, (uint64_t)info->components);
  EXPECT_EQ(c.genus_total, info->genus_total);
  EXPECT_LE(100 * c.samples_unused, n);
  /* The report agrees with the independent checker. */
  EXPECT_EQ(m->diag.components, c.components);
  EXPECT_EQ(m->diag.genus, c.genus_total);
  scs_meshcheck_free(&c);
}

int main(int argc, char **argv) {
  if (argc < 5) {
    fprintf(stderr, "usage: %s SURFACE N SIGMA MODE [SEED]\n", argv[0]);
    return 2;
  }
  const int surf = scs_surface_from_name(argv[1]);
  const size_t n = strtoul(argv[2], NULL, 10);
  const double sigma = atof(argv[3]);
  const int mode = sct_mode_from_name(argv[4]);
  const uint64_t seed = argc > 5 ? strtoull(argv[5], NULL, 10) : 1;
  if (surf < 0 || n < 100 || !(sigma >= 0) || mode == SC_MODE_COUNT_) {
    fprintf(stderr, "bad arguments\n");
    return 2;
  }
  const scs_surface_info_t *info = scs_surface_info((scs_surface_t)surf);
  const double spacing = scs_surface_spacing((scs_surface_t)surf, n);
  double *xyz = malloc(3 * n * sizeof *xyz);
  ASSERT_NOT_NULL(xyz);
  ASSERT_EQ(scs_sample_surface((scs_surface_t)surf, SCS_DENSITY_UNIFORM, n,
                               seed, xyz),
            0);
  scs_add_noise(xyz, n, sigma * spacing, seed + 1000);

  sc_params_t p;
  sc_params_init(&p);
  p.mode = (sc_mode_t)mode;
  p.denoise = mode != SC_MODE_AUTO;
  p.smoothed_vertices = 1;
  /* One thread here; more below, for the same smoothing. */
  p.threads = 1;
  char msg[256];
  sc_mesh_t *m = NULL;
  ASSERT_EQ(sc_reconstruct(xyz, n, &p, &m, msg, sizeof msg), 0);
  ASSERT_NOT_NULL(m);

  /* The estimate tracks the noise (it reads about 0.65 at one spacing:
   * section 16.1) and the spacing. */
  EXPECT_NEAR(m->diag.spacing, spacing, 0.1 * spacing);
  if (sigma <= 0.5)
    EXPECT_NEAR(m->diag.noise, 0.85 * sigma, 0.05 + 0.15 * sigma);
  else
    EXPECT(m->diag.noise > 0.5 && m->diag.noise < 0.8);

  const int noisy = m->diag.noise >= SC_NOISE_FLOOR;
  EXPECT_EQ(m->diag.denoised, noisy);
  if (noisy) {
    check_surface(argv[0], info, n, xyz, m);
    /* The smoothed points moved by about the noise, toward the surface. */
    ASSERT_NOT_NULL(m->smoothed);
    EXPECT_NEAR(m->diag.denoise_shift, sigma, 0.3 * sigma);
    double before = 0, after = 0;
    for (size_t i = 0; i < n; ++i) {
      before += pow(scs_surface_distance((scs_surface_t)surf, &xyz[3 * i]), 2);
      after += pow(
          scs_surface_distance((scs_surface_t)surf, &m->smoothed[3 * i]), 2);
    }
    printf("RMS distance to the surface: %.3f spacings before, %.3f after\n",
           sqrt(before / n) / spacing, sqrt(after / n) / spacing);
    EXPECT_LT(sqrt(after / n), 0.5 * sqrt(before / n));

    /* The same triangles without the smoothed positions, on 3 threads. */
    sc_params_t q = p;
    q.smoothed_vertices = 0;
    q.threads = 3;
    sc_mesh_t *m2 = NULL;
    ASSERT_EQ(sc_reconstruct(xyz, n, &q, &m2, msg, sizeof msg), 0);
    EXPECT_NULL(m2->smoothed);
    /* The estimate ran beside a triangulation of the raw points, which it
     * stopped: the same estimate to the last bit. */
    EXPECT(m2->diag.noise == m->diag.noise &&
           m2->diag.spacing == m->diag.spacing);
    EXPECT(m2->triangle_count == m->triangle_count &&
           memcmp(m2->triangles, m->triangles,
                  3 * m->triangle_count * sizeof *m->triangles) == 0);
    sc_mesh_free(m2);

    /* Streamed in chunks on 2 threads, the same mesh and the same
     * smoothed positions. */
    q = p;
    q.threads = 2;
    sc_recon_t *r = NULL;
    ASSERT_EQ(sc_recon_new(&q, &r), 0);
    for (size_t at = 0; at < n; at += 777)
      EXPECT_EQ(sc_recon_add(r, xyz + 3 * at, n - at < 777 ? n - at : 777, msg,
                             sizeof msg),
                0);
    sc_mesh_t *m3 = NULL;
    EXPECT_EQ(sc_recon_finish(r, &m3, msg, sizeof msg), 0);
    sc_recon_free(r);
    EXPECT(m3 && m3->triangle_count == m->triangle_count &&
           memcmp(m3->triangles, m->triangles,
                  3 * m->triangle_count * sizeof *m->triangles) == 0);
    EXPECT(m3 && m3->smoothed &&
           memcmp(m3->smoothed, m->smoothed, 3 * n * sizeof *m->smoothed) == 0);
    sc_mesh_free(m3);

    if (mode == SC_MODE_WATERTIGHT) {
      /* The labelling runs only where the patches leave doubt
       * (docs/modes.md, watertight mode, step 2): where the patches alone
       * give one closed piece, no handle cut and at most one sample in a
       * thousand off it before attaching, the default is their mesh. */
      q = p;
      q.smoothed_vertices = 0;
      q.watertight_patches = 1;
      sc_mesh_t *mp = NULL;
      ASSERT_EQ(sc_reconstruct(xyz, n, &q, &mp, msg, sizeof msg), 0);
      const sc_diag_t *d = &mp->diag;
      const int settled = d->closed && d->components == 1 &&
                          d->boundary_loops == 0 && d->nonmanifold_edges == 0 &&
                          d->nonmanifold_vertices == 0 && d->handles_cut == 0 &&
                          1000 * (d->samples_unused + d->samples_attached) <= n;
      printf("patches alone: %s (%llu samples attached, %llu unused); "
             "default path %s\n",
             settled ? "settled" : "in doubt",
             (unsigned long long)d->samples_attached,
             (unsigned long long)d->samples_unused, sc_path_name(m->diag.path));
      if (settled) {
        EXPECT_EQ(m->diag.labelled, 0);
        EXPECT_EQ(m->diag.path, d->path);
        EXPECT(mp->triangle_count == m->triangle_count &&
               memcmp(mp->triangles, m->triangles,
                      3 * m->triangle_count * sizeof *m->triangles) == 0);
      }
      sc_mesh_free(mp);
    }
  } else {
    /* Nothing to smooth: the mesh without denoising, no positions. */
    EXPECT_NULL(m->smoothed);
    sc_params_t q = p;
    q.denoise = 0;
    sc_mesh_t *m2 = NULL;
    ASSERT_EQ(sc_reconstruct(xyz, n, &q, &m2, msg, sizeof msg), 0);
    EXPECT(m2->triangle_count == m->triangle_count &&
           memcmp(m2->triangles, m->triangles,
                  3 * m->triangle_count * sizeof *m->triangles) == 0);
    sc_mesh_free(m2);
    /* On 2 threads the estimate runs beside the triangulation, which it
     * lets finish: the same estimate and triangles. */
    q = p;
    q.threads = 2;
    ASSERT_EQ(sc_reconstruct(xyz, n, &q, &m2, msg, sizeof msg), 0);
    EXPECT(m2->diag.noise == m->diag.noise &&
           m2->diag.spacing == m->diag.spacing && !m2->diag.denoised);
    EXPECT(m2->triangle_count == m->triangle_count &&
           memcmp(m2->triangles, m->triangles,
                  3 * m->triangle_count * sizeof *m->triangles) == 0);
    sc_mesh_free(m2);
  }
  sc_mesh_free(m);
  free(xyz);
  return sct_finish("core_noise");
}
