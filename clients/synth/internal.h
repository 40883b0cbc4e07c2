/*
 * Internals shared by the files of the synth module.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SCS_INTERNAL_H
#define SCS_INTERNAL_H

#include "synth.h"

#include <stddef.h>
#include <stdint.h>

/*
 * Sorts n (key, value) pairs by key, stably, with an LSD radix sort over the
 * low key_bits bits of the keys (higher bits must be zero). tmp_keys and
 * tmp_vals are scratch arrays of n entries. Returns 0 or SCS_ENOMEM.
 */
int scs_radix_sort(uint64_t *keys, uint32_t *vals, size_t n, int key_bits,
                   uint64_t *tmp_keys, uint32_t *tmp_vals);

/* Number of bits needed to hold x (0 for 0). */
int scs_bits(uint64_t x);

/*
 * A random pick by weight: cum holds the k running sums of the weights
 * (ascending, cum[k - 1] their total); draws one uniform number from rng
 * and returns the first index whose running sum exceeds it times the
 * total.
 */
size_t scs_rng_pick(scs_rng_t *rng, const double *cum, size_t k);

/* One area-uniform random point of surface s (any component). */
void scs_surface_point(scs_surface_t s, scs_rng_t *rng, double p[3]);

/* The largest |principal curvature| of s at the surface point p. */
double scs_surface_kmax(scs_surface_t s, const double p[3]);

#endif /* SCS_INTERNAL_H */
