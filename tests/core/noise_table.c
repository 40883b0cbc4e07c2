/*
 * shortcrust-noise-table: at what noise does the output stop being a closed
 * manifold of the right genus? Well-spaced samples of the analytic test
 * surfaces, each point moved by an isotropic Gaussian of standard deviation
 * sigma (a multiple of the spacing), reconstructed in each mode; prints one
 * Markdown table and, per surface and mode, the largest sigma at which
 * every seed came out right.
 *
 *   shortcrust-noise-table [--points N] [--seeds K] [--surface NAME]...
 *
 * "Right" means: a 2-manifold, closed, consistently oriented, with the
 * surface's components and genus. Samples left out are counted but do not
 * make a result wrong (noise makes outliers).
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

#include "shortcrust.h"
#include "synth.h"


static const double levels[] = {0, 0.05, 0.1, 0.15, 0.2, 0.3, 0.5, 0.75, 1.0};
#define LEVEL_COUNT (sizeof levels / sizeof levels[0])
static const int modes[] = {SC_MODE_COCONE, SC_MODE_SHORTCRUST,
                            SC_MODE_WATERTIGHT, SC_MODE_AUTO};
static const char *const mode_names[] = {"cocone", "shortcrust", "watertight",
                                         "auto"};
#define MODE_COUNT (sizeof modes / sizeof modes[0])

/* A standard normal deviate (Box-Muller). */
/* Wall-clock seconds, for the time column. */
static double seconds_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double gauss(scs_rng_t *rng) {
  double u = scs_rng_uniform(rng), v = scs_rng_uniform(rng);
  if (u < 1e-300)
    u = 1e-300;
  return sqrt(-2 * log(u)) * cos(2 * SC_PI * v);
}

static void usage(FILE *f, const char *argv0) {
  fprintf(f,
          "usage: %s [--points N] [--seeds K] [--surface NAME]...\n"
          "  --points N      samples per surface (default 20000)\n"
          "  --seeds K       samples of each kind, each with its own noise\n"
          "                  (default 3)\n"
          "  --surface NAME  sphere, ellipsoid, torus, genus2, two-spheres or\n"
          "                  nested-spheres; repeatable (default sphere,\n"
          "                  torus, genus2)\n",
          argv0);
}

int main(int argc, char **argv) {
  size_t n = 20000;
  int seeds = 3;
  int surfaces[SCS_SURF_COUNT], ns = 0;
  for (int i = 1; i < argc; ++i) {
    if (strcmp(argv[i], "--help") == 0) {
      usage(stdout, argv[0]);
      return 0;
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

  double *clean = malloc(3 * n * sizeof *clean);
  double *xyz = malloc(3 * n * sizeof *xyz);
  if (!clean || !xyz) {
    fprintf(stderr, "%s: out of memory\n", argv[0]);
    return 1;
  }
  /* The largest level at which every seed was right, per surface and mode;
   * -1 when even the clean sample was not. */
  double limit[SCS_SURF_COUNT][MODE_COUNT];
  printf("| surface | noise (sigma / spacing) | mode | right | closed | "
         "genus (expected) | components | samples unused, worst | time, "
         "mean |\n|---|--:|---|--:|--:|---|--:|--:|--:|\n");
  for (int si = 0; si < ns; ++si) {
    const int s = surfaces[si];
    const scs_surface_info_t *info = scs_surface_info((scs_surface_t)s);
    const double spacing = scs_surface_spacing((scs_surface_t)s, n);
    int failed[MODE_COUNT] = {0};
    for (size_t m = 0; m < MODE_COUNT; ++m)
      limit[s][m] = -1;
    for (size_t l = 0; l < LEVEL_COUNT; ++l) {
      for (size_t m = 0; m < MODE_COUNT; ++m) {
        int right = 0, closed = 0;
        int64_t genus_lo = INT64_MAX, genus_hi = INT64_MIN;
        uint64_t comps_lo = UINT64_MAX, comps_hi = 0, unused = 0;
        double seconds = 0;
        for (int k = 0; k < seeds; ++k) {
          if (scs_sample_surface((scs_surface_t)s, SCS_DENSITY_UNIFORM, n,
                                 (uint64_t)k + 1, clean) != 0) {
            fprintf(stderr, "%s: sampling failed\n", argv[0]);
            return 1;
          }
          scs_rng_t rng;
          scs_rng_seed(&rng, 1000 + (uint64_t)k);
          const double sigma = levels[l] * spacing;
          for (size_t i = 0; i < 3 * n; ++i)
            xyz[i] = clean[i] + sigma * gauss(&rng);
          sc_params_t p;
          sc_params_init(&p);
          p.mode = (sc_mode_t)modes[m];
          sc_mesh_t *mesh = NULL;
          char msg[256];
          double t0 = seconds_now();
          int rc = sc_reconstruct(xyz, n, &p, &mesh, msg, sizeof msg);
          seconds += seconds_now() - t0;
          if (rc != 0) {
            fprintf(stderr, "%s %g %s: %s\n", info->name, levels[l],
                    mode_names[m], msg);
            continue;
          }
          scs_meshcheck_t c;
          if (scs_meshcheck(n, xyz, mesh->triangles, mesh->triangle_count, NULL,
                            &c) != 0) {
            sc_mesh_free(mesh);
            continue;
          }
          closed += c.closed;
          genus_lo = c.genus_total < genus_lo ? c.genus_total : genus_lo;
          genus_hi = c.genus_total > genus_hi ? c.genus_total : genus_hi;
          comps_lo = c.components < comps_lo ? c.components : comps_lo;
          comps_hi = c.components > comps_hi ? c.components : comps_hi;
          unused = c.samples_unused > unused ? c.samples_unused : unused;
          right += c.manifold && c.closed && c.oriented &&
                   c.components == (uint64_t)info->components &&
                   c.genus_total == info->genus_total;
          scs_meshcheck_free(&c);
          sc_mesh_free(mesh);
        }
        if (right == seeds && !failed[m])
          limit[s][m] = levels[l];
        else
          failed[m] = 1;
        char genus[64], comps[64];
        if (genus_lo == genus_hi)
          snprintf(genus, sizeof genus, "%lld", (long long)genus_lo);
        else
          snprintf(genus, sizeof genus, "%lld-%lld", (long long)genus_lo,
                   (long long)genus_hi);
        if (comps_lo == comps_hi)
          snprintf(comps, sizeof comps, "%llu", (unsigned long long)comps_lo);
        else
          snprintf(comps, sizeof comps, "%llu-%llu",
                   (unsigned long long)comps_lo, (unsigned long long)comps_hi);
        printf("| %s | %.2f | %s | %d/%d | %d/%d | %s (%d) | %s | %.2f%% | "
               "%.2f s |\n",
               info->name, levels[l], mode_names[m], right, seeds, closed,
               seeds, genus, info->genus_total, comps,
               100.0 * (double)unused / (double)n, seconds / seeds);
        fflush(stdout);
      }
    }
  }
  printf("\nLargest noise (sigma / spacing) at which every seed came out "
         "right, %zu points:\n\n| surface |", n);
  for (size_t m = 0; m < MODE_COUNT; ++m)
    printf(" %s |", mode_names[m]);
  printf("\n|---|");
  for (size_t m = 0; m < MODE_COUNT; ++m)
    printf("--:|");
  printf("\n");
  for (int si = 0; si < ns; ++si) {
    const int s = surfaces[si];
    printf("| %s |", scs_surface_name((scs_surface_t)s));
    for (size_t m = 0; m < MODE_COUNT; ++m) {
      if (limit[s][m] < 0)
        printf(" none |");
      else
        printf(" %.2f |", limit[s][m]);
    }
    printf("\n");
  }
  free(clean);
  free(xyz);
  return 0;
}
