/*
 * Samples of the test surfaces at the three densities.
 *
 * The well-spaced modes use weighted sample elimination (C. Yuksel,
 * "Sample Elimination for Generating Poisson Disk Sample Sets", Eurographics
 * 2015): draw k times too many random candidates, give each a weight that
 * measures how crowded its neighbourhood is, and remove the most crowded
 * one until exactly n are left. Unlike dart throwing this hits the count
 * exactly, and unlike a grid it leaves no lattice pattern.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Above this many points the well-spaced modes would need tens of GB. */
#define MAX_SPACED_POINTS 500000000u

/*
 * Oversampling factor: 4 is past the point where more candidates stop
 * improving the spacing. Above 200,000 points it falls with 1/sqrt(n), but
 * not below 2, to bound the time of large samples (test_speed prints the
 * time for a million).
 */
static double oversampling(size_t n) {
  if (n <= 200000)
    return 4;
  double k = 4 * sqrt(200000.0 / (double)n);
  return k < 2 ? 2 : k;
}

static const char *density_names[SCS_DENSITY_COUNT] = {"uniform-random",
                                                       "uniform", "adaptive"};

const char *scs_density_name(int density) {
  if (density < 0 || density >= SCS_DENSITY_COUNT)
    return "?";
  return density_names[density];
}

int scs_density_from_name(const char *name) {
  if (!name)
    return -1;
  for (int d = 0; d < SCS_DENSITY_COUNT; d++)
    if (strcmp(name, density_names[d]) == 0)
      return d;
  return -1;
}

/*
 * A hash grid over the candidates: cell keys pack three 21-bit cell
 * coordinates; the candidates are stored sorted by cell, and an open-
 * addressing table maps a cell key to its range in that order.
 */
#define CELL_BITS 21
#define CELL_MAX ((1 << CELL_BITS) - 2)
#define EMPTY_KEY UINT64_MAX

typedef struct grid {
  double origin[3];
  double inv_h;
  size_t mask;       /* table size - 1 */
  uint64_t *keys;    /* table keys, EMPTY_KEY for a free slot */
  uint32_t *start;   /* first sorted position of the cell */
  uint32_t *end;     /* one past its last */
} grid_t;

static uint64_t cell_hash(uint64_t key) {
  return (key * 0x9e3779b97f4a7c15ull) >> 20;
}

static void cell_of(const grid_t *g, const double p[3], int64_t c[3]) {
  for (int i = 0; i < 3; i++) {
    int64_t v = (int64_t)((p[i] - g->origin[i]) * g->inv_h);
    c[i] = v < 0 ? 0 : v > CELL_MAX ? CELL_MAX : v;
  }
}

/* The key of cell c + 1, so that c - 1 never goes below 0. */
static uint64_t cell_key(int64_t x, int64_t y, int64_t z) {
  return (uint64_t)(x + 1) | (uint64_t)(y + 1) << CELL_BITS |
         (uint64_t)(z + 1) << (2 * CELL_BITS);
}

/* The range of sorted positions in a cell; start == end when empty. */
static void cell_range(const grid_t *g, uint64_t key, uint32_t *b,
                       uint32_t *e) {
  for (size_t slot = cell_hash(key) & g->mask;; slot = (slot + 1) & g->mask) {
    if (g->keys[slot] == key) {
      *b = g->start[slot];
      *e = g->end[slot];
      return;
    }
    if (g->keys[slot] == EMPTY_KEY) {
      *b = *e = 0;
      return;
    }
  }
}

/* The 27 cell ranges around cell c; returns how many are non-empty. */
static int neighbour_ranges(const grid_t *g, const int64_t c[3],
                            uint32_t b[27], uint32_t e[27]) {
  int k = 0;
  for (int dz = -1; dz <= 1; dz++)
    for (int dy = -1; dy <= 1; dy++)
      for (int dx = -1; dx <= 1; dx++) {
        cell_range(g, cell_key(c[0] + dx, c[1] + dy, c[2] + dz), &b[k], &e[k]);
        if (b[k] < e[k])
          k++;
      }
  return k;
}

typedef struct elim {
  size_t m;          /* candidates */
  double *xyz;       /* sorted by cell */
  double *r;         /* local Poisson-disk radius, sorted by cell */
  uint32_t *order;   /* sorted position -> candidate index */
  double *w;         /* weight per sorted position */
  uint32_t *heap;    /* max-heap of sorted positions */
  uint32_t *where;   /* sorted position -> heap slot, UINT32_MAX if gone */
  size_t heap_n;
  double dmin_frac;  /* weight limiting, as a fraction of r_i + r_j */
  grid_t grid;
} elim_t;

/*
 * Yuksel's weight with his defaults (alpha = 8, beta = 0.65, gamma = 1.5):
 * (1 - d / (r_i + r_j))^8 for d below r_i + r_j, the sum of the two local
 * Poisson-disk radii, with d first raised to a floor that stops very close
 * pairs from dominating. Symmetric in i and j, so a weight removed later is
 * bit-identical to the one added.
 */
static double pair_weight(const elim_t *el, double d, double ri, double rj) {
  double s = ri + rj;
  if (d >= s)
    return 0;
  double floor_d = el->dmin_frac * s;
  if (d < floor_d)
    d = floor_d;
  double t = 1 - d / s;
  double t2 = t * t, t4 = t2 * t2;
  return t4 * t4;
}

/* Heap order: heavier first; equal weights by larger position. */
static int heavier(const elim_t *el, uint32_t a, uint32_t b) {
  return el->w[a] > el->w[b] || (el->w[a] == el->w[b] && a > b);
}

static void heap_place(elim_t *el, size_t slot, uint32_t v) {
  el->heap[slot] = v;
  el->where[v] = (uint32_t)slot;
}

static void sift_down(elim_t *el, size_t slot) {
  uint32_t v = el->heap[slot];
  for (;;) {
    size_t c = 2 * slot + 1;
    if (c >= el->heap_n)
      break;
    if (c + 1 < el->heap_n && heavier(el, el->heap[c + 1], el->heap[c]))
      c++;
    if (!heavier(el, el->heap[c], v))
      break;
    heap_place(el, slot, el->heap[c]);
    slot = c;
  }
  heap_place(el, slot, v);
}

static uint32_t heap_pop(elim_t *el) {
  uint32_t top = el->heap[0];
  el->where[top] = UINT32_MAX;
  el->heap_n--;
  if (el->heap_n > 0) {
    heap_place(el, 0, el->heap[el->heap_n]);
    sift_down(el, 0);
  }
  return top;
}

static double dist(const double *a, const double *b) {
  double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
  return sqrt(dx * dx + dy * dy + dz * dz);
}

static void elim_free(elim_t *el) {
  free(el->xyz);
  free(el->r);
  free(el->order);
  free(el->w);
  free(el->heap);
  free(el->where);
  free(el->grid.keys);
  free(el->grid.start);
  free(el->grid.end);
}

/*
 * Sorts the candidates into the hash grid. cand and radius are in candidate
 * order; el gets its own copies in cell order.
 */
static int elim_build(elim_t *el, const double *cand, const double *radius,
                      size_t m) {
  double lo[3], hi[3], rmax = 0;
  for (int i = 0; i < 3; i++)
    lo[i] = hi[i] = cand[i];
  for (size_t j = 0; j < m; j++) {
    for (int i = 0; i < 3; i++) {
      double v = cand[3 * j + i];
      lo[i] = v < lo[i] ? v : lo[i];
      hi[i] = v > hi[i] ? v : hi[i];
    }
    rmax = radius[j] > rmax ? radius[j] : rmax;
  }
  /* Any two candidates that interact are at most 2 rmax apart, so with
   * cells that wide all of them are in the 27 cells around. */
  double h = 2 * rmax;
  for (int i = 0; i < 3; i++)
    if ((hi[i] - lo[i]) / CELL_MAX * 1.01 > h)
      h = (hi[i] - lo[i]) / CELL_MAX * 1.01;
  el->grid.inv_h = 1 / h;
  memcpy(el->grid.origin, lo, sizeof lo);

  int rc = SCS_ENOMEM;
  uint64_t *keys = malloc(m * sizeof *keys);
  uint64_t *tmpk = malloc(m * sizeof *tmpk);
  uint32_t *tmpv = malloc(m * sizeof *tmpv);
  el->order = malloc(m * sizeof *el->order);
  el->xyz = malloc(3 * m * sizeof *el->xyz);
  el->r = malloc(m * sizeof *el->r);
  if (!keys || !tmpk || !tmpv || !el->order || !el->xyz || !el->r)
    goto out;
  for (size_t j = 0; j < m; j++) {
    int64_t c[3];
    cell_of(&el->grid, cand + 3 * j, c);
    keys[j] = cell_key(c[0], c[1], c[2]);
    el->order[j] = (uint32_t)j;
  }
  if ((rc = scs_radix_sort(keys, el->order, m, 3 * CELL_BITS, tmpk, tmpv)))
    goto out;
  size_t cells = 0;
  for (size_t j = 0; j < m; j++) {
    uint32_t o = el->order[j];
    memcpy(el->xyz + 3 * j, cand + 3 * (size_t)o, 3 * sizeof *el->xyz);
    el->r[j] = radius[o];
    if (j == 0 || keys[j] != keys[j - 1])
      cells++;
  }
  size_t size = 16;
  while (size < 2 * cells)
    size *= 2;
  rc = SCS_ENOMEM;
  el->grid.mask = size - 1;
  el->grid.keys = malloc(size * sizeof *el->grid.keys);
  el->grid.start = malloc(size * sizeof *el->grid.start);
  el->grid.end = malloc(size * sizeof *el->grid.end);
  if (!el->grid.keys || !el->grid.start || !el->grid.end)
    goto out;
  for (size_t i = 0; i < size; i++)
    el->grid.keys[i] = EMPTY_KEY;
  for (size_t j = 0; j < m;) {
    size_t e = j + 1;
    while (e < m && keys[e] == keys[j])
      e++;
    size_t slot = cell_hash(keys[j]) & el->grid.mask;
    while (el->grid.keys[slot] != EMPTY_KEY)
      slot = (slot + 1) & el->grid.mask;
    el->grid.keys[slot] = keys[j];
    el->grid.start[slot] = (uint32_t)j;
    el->grid.end[slot] = (uint32_t)e;
    j = e;
  }
  rc = SCS_OK;
out:
  free(keys);
  free(tmpk);
  free(tmpv);
  return rc;
}

/*
 * Keeps exactly n of the m candidates; keep[j] is set to 1 for the kept
 * candidate j (in candidate order) and 0 for the others.
 */
static int eliminate(const double *cand, const double *radius, size_t m,
                     size_t n, unsigned char *keep) {
  elim_t el;
  memset(&el, 0, sizeof el);
  el.m = m;
  /* Yuksel's r_min = r_max * beta * (1 - (n/m)^gamma), relative to 2 r_max. */
  double ratio = (double)n / (double)m;
  el.dmin_frac = 0.65 * (1 - ratio * sqrt(ratio)) / 2;
  int rc = elim_build(&el, cand, radius, m);
  if (rc)
    goto out;
  rc = SCS_ENOMEM;
  el.w = calloc(m, sizeof *el.w);
  el.heap = malloc(m * sizeof *el.heap);
  el.where = malloc(m * sizeof *el.where);
  if (!el.w || !el.heap || !el.where)
    goto out;

  /* Initial weights, cell by cell so the 27 ranges are looked up once. */
  for (size_t j = 0; j < m;) {
    int64_t c[3];
    cell_of(&el.grid, el.xyz + 3 * j, c);
    uint32_t b[27], e[27], cb, ce;
    cell_range(&el.grid, cell_key(c[0], c[1], c[2]), &cb, &ce);
    int k = neighbour_ranges(&el.grid, c, b, e);
    for (size_t i = cb; i < ce; i++) {
      double sum = 0;
      for (int q = 0; q < k; q++)
        for (uint32_t o = b[q]; o < e[q]; o++)
          if (o != i)
            sum += pair_weight(&el, dist(el.xyz + 3 * i, el.xyz + 3 * o),
                               el.r[i], el.r[o]);
      el.w[i] = sum;
    }
    j = ce;
  }

  /* Bottom-up heap construction. */
  el.heap_n = m;
  for (size_t i = 0; i < m; i++)
    heap_place(&el, i, (uint32_t)i);
  for (size_t i = m / 2; i-- > 0;)
    sift_down(&el, i);

  while (el.heap_n > n) {
    uint32_t i = heap_pop(&el);
    int64_t c[3];
    cell_of(&el.grid, el.xyz + 3 * (size_t)i, c);
    uint32_t b[27], e[27];
    int k = neighbour_ranges(&el.grid, c, b, e);
    for (int q = 0; q < k; q++)
      for (uint32_t o = b[q]; o < e[q]; o++) {
        if (el.where[o] == UINT32_MAX)
          continue;
        double wt = pair_weight(&el, dist(el.xyz + 3 * (size_t)i,
                                          el.xyz + 3 * (size_t)o),
                                el.r[i], el.r[o]);
        if (wt > 0) {
          el.w[o] -= wt;
          sift_down(&el, el.where[o]);
        }
      }
  }
  memset(keep, 0, m);
  for (size_t i = 0; i < el.heap_n; i++)
    keep[el.order[el.heap[i]]] = 1;
  rc = SCS_OK;
out:
  elim_free(&el);
  return rc;
}

/* Area density of ADAPTIVE, relative to its maximum: in [1/6, 1]. */
static double adaptive_density(scs_surface_t s, const double p[3],
                               double ktop) {
  double k = scs_surface_kmax(s, p) / ktop;
  double rho = k * k;
  return rho > 1 ? 1 : rho < 1.0 / 6 ? 1.0 / 6 : rho;
}

int scs_sample_surface(scs_surface_t s, int density, size_t n, uint64_t seed,
                       double *xyz) {
  const scs_surface_info_t *info = scs_surface_info(s);
  if (!info || density < 0 || density >= SCS_DENSITY_COUNT || (n && !xyz))
    return SCS_EINVAL;
  if (n == 0)
    return SCS_OK;
  scs_rng_t rng;
  scs_rng_seed(&rng, seed);
  if (density == SCS_DENSITY_UNIFORM_RANDOM) {
    for (size_t i = 0; i < n; i++)
      scs_surface_point(s, &rng, xyz + 3 * i);
    return SCS_OK;
  }
  if (n > MAX_SPACED_POINTS)
    return SCS_EINVAL;

  size_t m = (size_t)ceil(oversampling(n) * (double)n);
  /* Always true (the factor is at least 2); stated so that the compiler,
   * too, knows the candidate arrays below are filled before use. */
  if (m <= n)
    return SCS_EINVAL;
  double *cand = malloc(3 * m * sizeof *cand);
  double *radius = malloc(m * sizeof *radius);
  unsigned char *keep = malloc(m);
  int rc = SCS_ENOMEM;
  if (!cand || !radius || !keep)
    goto out;

  /*
   * The ideal Poisson-disk radius of n points over area A is
   * sqrt(A / (2 sqrt(3) n)) (hexagonal packing). With a varying density
   * rho the local version uses the density n rho(p) / Z, Z the integral of
   * rho over the surface; Z is estimated from the rejection rate, since the
   * proposals are area-uniform: Z = A * (accepted / proposed).
   */
  const double two_sqrt3 = 3.4641016151377546;
  if (density == SCS_DENSITY_UNIFORM) {
    for (size_t j = 0; j < m; j++)
      scs_surface_point(s, &rng, cand + 3 * j);
    double r = sqrt(info->area / (two_sqrt3 * (double)n));
    for (size_t j = 0; j < m; j++)
      radius[j] = r;
  } else {
    uint64_t proposed = 0;
    for (size_t j = 0; j < m;) {
      double *p = cand + 3 * j;
      scs_surface_point(s, &rng, p);
      proposed++;
      double rho = adaptive_density(s, p, info->max_curvature);
      if (scs_rng_uniform(&rng) < rho) {
        radius[j] = rho;
        j++;
      }
    }
    double z = info->area * (double)m / (double)proposed;
    for (size_t j = 0; j < m; j++)
      radius[j] = sqrt(z / (two_sqrt3 * (double)n * radius[j]));
  }
  if ((rc = eliminate(cand, radius, m, n, keep)))
    goto out;
  size_t out_n = 0;
  for (size_t j = 0; j < m; j++)
    if (keep[j]) {
      memcpy(xyz + 3 * out_n, cand + 3 * j, 3 * sizeof *xyz);
      out_n++;
    }
  rc = out_n == n ? SCS_OK : SCS_EINVAL;
out:
  free(cand);
  free(radius);
  free(keep);
  return rc;
}
