/*
 * shortcrust-noise-table: at what noise does the output stop being a closed
 * manifold of the right genus, with and without denoising? Well-spaced
 * samples of the analytic test surfaces, each point moved by an isotropic
 * Gaussian of standard deviation sigma (a multiple of the spacing),
 * reconstructed by each run below and by CGAL's scale-space reconstruction
 * in the same process; prints one Markdown table and, per surface and run,
 * the largest sigma at which every seed came out right.
 *
 *   shortcrust-noise-table [--points N] [--seeds K] [--surface NAME]...
 *                          [--no-peer]
 *
 * "Right" means: a 2-manifold, closed, consistently oriented, with the
 * surface's components and genus, and at least 99% of the samples used.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "peer_scale_space.h"
#include "shortcrust.h"
#include "synth.h"

static const double levels[] = {0, 0.1, 0.25, 0.33, 0.5, 0.75, 1.0};
#define LEVEL_COUNT (sizeof levels / sizeof levels[0])

/* What is run on each sample: a mode with or without --denoise, or the
 * peer (mode -1). */
typedef struct run {
  const char *name;
  int mode, denoise;
} run_t;
static const run_t runs[] = {
    {"watertight", SC_MODE_WATERTIGHT, 0},
    {"watertight --denoise", SC_MODE_WATERTIGHT, 1},
    {"cocone --denoise", SC_MODE_COCONE, 1},
    {"auto", SC_MODE_AUTO, 0},
    {"cgal scale-space", -1, 0},
};
#define RUN_COUNT (sizeof runs / sizeof runs[0])

/* Wall-clock seconds, for the time column. */
static double seconds_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void usage(FILE *f, const char *argv0) {
  fprintf(f,
          "usage: %s [--points N] [--seeds K] [--surface NAME]... "
          "[--no-peer]\n"
          "  --points N      samples per surface (default 20000)\n"
          "  --seeds K       samples of each kind, each with its own noise\n"
          "                  (default 3)\n"
          "  --surface NAME  sphere, ellipsoid, torus, genus2, two-spheres or\n"
          "                  nested-spheres; repeatable (default sphere,\n"
          "                  torus, genus2)\n"
          "  --no-peer       leave out CGAL's scale-space reconstruction\n",
          argv0);
}

/* The tallies of one row: a run at one noise level over every seed. */
typedef struct tally {
  int right, closed, failed;
  int64_t genus_lo, genus_hi;
  uint64_t comps_lo, comps_hi, unused;
  double seconds, noise;
} tally_t;

static void tally_mesh(tally_t *t, const scs_surface_info_t *info, size_t n,
                       const double *xyz, const uint32_t *tri, size_t nt) {
  scs_meshcheck_t c;
  if (scs_meshcheck(n, xyz, tri, nt, NULL, &c) != 0) {
    t->failed++;
    return;
  }
  t->closed += c.closed;
  t->genus_lo = c.genus_total < t->genus_lo ? c.genus_total : t->genus_lo;
  t->genus_hi = c.genus_total > t->genus_hi ? c.genus_total : t->genus_hi;
  t->comps_lo = c.components < t->comps_lo ? c.components : t->comps_lo;
  t->comps_hi = c.components > t->comps_hi ? c.components : t->comps_hi;
  t->unused = c.samples_unused > t->unused ? c.samples_unused : t->unused;
  t->right += c.manifold && c.closed && c.oriented &&
              c.components == (uint64_t)info->components &&
              c.genus_total == info->genus_total && 100 * c.samples_unused <= n;
  scs_meshcheck_free(&c);
}

/* One run on one sample, into the row's tallies. */
static void run_one(const run_t *r, const scs_surface_info_t *info, size_t n,
                    const double *xyz, tally_t *t) {
  double t0 = seconds_now();
  if (r->mode < 0) {
    uint32_t *tri = NULL;
    size_t nt = 0;
    int rc = peer_scale_space(xyz, n, &tri, &nt);
    t->seconds += seconds_now() - t0;
    if (rc != 0)
      t->failed++;
    else
      tally_mesh(t, info, n, xyz, tri, nt);
    free(tri);
    return;
  }
  sc_params_t p;
  sc_params_init(&p);
  p.mode = (sc_mode_t)r->mode;
  p.denoise = r->denoise;
  sc_mesh_t *mesh = NULL;
  char msg[256];
  int rc = sc_reconstruct(xyz, n, &p, &mesh, msg, sizeof msg);
  t->seconds += seconds_now() - t0;
  if (rc != 0) {
    fprintf(stderr, "%s, %s: %s\n", info->name, r->name, msg);
    t->failed++;
    return;
  }
  t->noise += mesh->diag.noise;
  tally_mesh(t, info, n, xyz, mesh->triangles, mesh->triangle_count);
  sc_mesh_free(mesh);
}

static void range_text(char *buf, size_t len, long long lo, long long hi) {
  if (lo > hi)
    snprintf(buf, len, "-");
  else if (lo == hi)
    snprintf(buf, len, "%lld", lo);
  else
    snprintf(buf, len, "%lld-%lld", lo, hi);
}

int main(int argc, char **argv) {
  size_t n = 20000;
  int seeds = 3, peer = 1;
  int surfaces[SCS_SURF_COUNT], ns = 0;
  for (int i = 1; i < argc; ++i) {
    if (strcmp(argv[i], "--help") == 0) {
      usage(stdout, argv[0]);
      return 0;
    }
    if (strcmp(argv[i], "--no-peer") == 0) {
      peer = 0;
      continue;
    }
    if (i + 1 >= argc) {
      fprintf(stderr, "%s: %s needs a value\n", argv[0], argv[i]);
      return 2;
    }
    const char *v = argv[++i];
    char *end;
    if (strcmp(argv[i - 1], "--points") == 0) {
      n = strtoul(v, &end, 10);
      if (*end || n < 100) {
        fprintf(stderr, "%s: --points: '%s' is not a count of at least 100\n",
                argv[0], v);
        return 2;
      }
    } else if (strcmp(argv[i - 1], "--seeds") == 0) {
      long k = strtol(v, &end, 10);
      if (*end || k < 1 || k > 100) {
        fprintf(stderr, "%s: --seeds: '%s' is not a number from 1 to 100\n",
                argv[0], v);
        return 2;
      }
      seeds = (int)k;
    } else if (strcmp(argv[i - 1], "--surface") == 0) {
      int s = scs_surface_from_name(v);
      if (s < 0) {
        fprintf(stderr, "%s: --surface: unknown surface '%s'\n", argv[0], v);
        return 2;
      }
      if (ns < SCS_SURF_COUNT)
        surfaces[ns++] = s;
    } else {
      fprintf(stderr, "%s: unknown option '%s'\n", argv[0], argv[i - 1]);
      usage(stderr, argv[0]);
      return 2;
    }
  }
  if (ns == 0) {
    surfaces[ns++] = SCS_SURF_SPHERE;
    surfaces[ns++] = SCS_SURF_TORUS;
    surfaces[ns++] = SCS_SURF_GENUS2;
  }

  double *xyz = malloc(3 * n * sizeof *xyz);
  if (!xyz) {
    fprintf(stderr, "%s: out of memory\n", argv[0]);
    return 1;
  }
  /* The largest level at which every seed was right, per surface and run;
   * -1 when even the clean sample was not. */
  double limit[SCS_SURF_COUNT][RUN_COUNT];
  printf("| surface | noise (sigma / spacing) | estimated | run | right | "
         "closed | genus (expected) | components | samples unused, worst | "
         "time, mean |\n|---|--:|--:|---|--:|--:|---|--:|--:|--:|\n");
  for (int si = 0; si < ns; ++si) {
    const int s = surfaces[si];
    const scs_surface_info_t *info = scs_surface_info((scs_surface_t)s);
    const double spacing = scs_surface_spacing((scs_surface_t)s, n);
    int failed[RUN_COUNT] = {0};
    for (size_t r = 0; r < RUN_COUNT; ++r)
      limit[s][r] = -1;
    for (size_t l = 0; l < LEVEL_COUNT; ++l) {
      for (size_t r = 0; r < RUN_COUNT; ++r) {
        if (runs[r].mode < 0 && !peer)
          continue;
        tally_t t = {.genus_lo = INT64_MAX,
                     .genus_hi = INT64_MIN,
                     .comps_lo = UINT64_MAX};
        for (int k = 0; k < seeds; ++k) {
          if (scs_sample_surface((scs_surface_t)s, SCS_DENSITY_UNIFORM, n,
                                 (uint64_t)k + 1, xyz) != 0) {
            fprintf(stderr, "%s: sampling failed\n", argv[0]);
            return 1;
          }
          scs_add_noise(xyz, n, levels[l] * spacing, 1000 + (uint64_t)k);
          run_one(&runs[r], info, n, xyz, &t);
        }
        if (t.right == seeds && !failed[r])
          limit[s][r] = levels[l];
        else
          failed[r] = 1;
        char genus[64], comps[64], noise[32] = "";
        range_text(genus, sizeof genus, t.genus_lo, t.genus_hi);
        range_text(comps, sizeof comps, (long long)t.comps_lo,
                   (long long)t.comps_hi);
        if (runs[r].mode >= 0)
          snprintf(noise, sizeof noise, "%.2f", t.noise / seeds);
        printf("| %s | %.2f | %s | %s | %d/%d | %d/%d | %s (%d) | %s | "
               "%.2f%% | %.2f s |\n",
               info->name, levels[l], noise, runs[r].name, t.right, seeds,
               t.closed, seeds, genus, info->genus_total, comps,
               100.0 * (double)t.unused / (double)n, t.seconds / seeds);
        fflush(stdout);
      }
    }
  }
  printf("\nLargest noise (sigma / spacing) at which every seed came out "
         "right, %zu points, %d seeds:\n\n| surface |",
         n, seeds);
  for (size_t r = 0; r < RUN_COUNT; ++r)
    if (runs[r].mode >= 0 || peer)
      printf(" %s |", runs[r].name);
  printf("\n|---|");
  for (size_t r = 0; r < RUN_COUNT; ++r)
    if (runs[r].mode >= 0 || peer)
      printf("--:|");
  printf("\n");
  for (int si = 0; si < ns; ++si) {
    const int s = surfaces[si];
    printf("| %s |", scs_surface_name((scs_surface_t)s));
    for (size_t r = 0; r < RUN_COUNT; ++r) {
      if (runs[r].mode < 0 && !peer)
        continue;
      if (limit[s][r] < 0)
        printf(" none |");
      else
        printf(" %.2f |", limit[s][r]);
    }
    printf("\n");
  }
  free(xyz);
  return 0;
}
