/*
 * xoshiro256** (Blackman and Vigna), seeded by splitmix64 so that nearby
 * seeds such as 1 and 2 still give unrelated streams.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <math.h>

#include "internal.h"
#include "shortcrust.h"

static uint64_t splitmix64(uint64_t *x) {
  uint64_t z = (*x += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

void scs_rng_seed(scs_rng_t *rng, uint64_t seed) {
  uint64_t x = seed;
  for (int i = 0; i < 4; i++)
    rng->s[i] = splitmix64(&x);
}

uint64_t scs_rng_next(scs_rng_t *rng) {
  uint64_t *s = rng->s;
  uint64_t result = rotl(s[1] * 5, 7) * 9;
  uint64_t t = s[1] << 17;
  s[2] ^= s[0];
  s[3] ^= s[1];
  s[1] ^= s[2];
  s[0] ^= s[3];
  s[2] ^= t;
  s[3] = rotl(s[3], 45);
  return result;
}

double scs_rng_uniform(scs_rng_t *rng) {
  return (double)(scs_rng_next(rng) >> 11) * 0x1.0p-53;
}

double scs_rng_gauss(scs_rng_t *rng) {
  double u = scs_rng_uniform(rng), v = scs_rng_uniform(rng);
  if (u < 1e-300)
    u = 1e-300;
  return sqrt(-2 * log(u)) * cos(2 * SC_PI * v);
}

void scs_add_noise(double *xyz, size_t n, double sigma, uint64_t seed) {
  scs_rng_t rng;
  scs_rng_seed(&rng, seed);
  for (size_t i = 0; i < 3 * n; ++i)
    xyz[i] += sigma * scs_rng_gauss(&rng);
}

size_t scs_rng_pick(scs_rng_t *rng, const double *cum, size_t k) {
  const double t = scs_rng_uniform(rng) * cum[k - 1];
  size_t lo = 0, hi = k - 1;
  while (lo < hi) {
    const size_t mid = (lo + hi) / 2;
    if (cum[mid] > t)
      hi = mid;
    else
      lo = mid + 1;
  }
  return lo;
}
