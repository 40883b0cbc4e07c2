/*
 * A radix sort for the edge and cell tables: they hold millions of 64-bit
 * keys, where a comparison sort would cost several times more.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "internal.h"

#include <stdlib.h>
#include <string.h>

/* Eleven-bit digits keep the counting array (16 KiB) in the L1 cache. */
#define DIGIT_BITS 11
#define DIGIT_COUNT (1u << DIGIT_BITS)

int scs_bits(uint64_t x) {
  int b = 0;
  while (x) {
    b++;
    x >>= 1;
  }
  return b;
}

int scs_radix_sort(uint64_t *keys, uint32_t *vals, size_t n, int key_bits,
                   uint64_t *tmp_keys, uint32_t *tmp_vals) {
  if (n < 2)
    return SCS_OK;
  size_t *count = malloc(DIGIT_COUNT * sizeof *count);
  if (!count)
    return SCS_ENOMEM;
  uint64_t *src_k = keys, *dst_k = tmp_keys;
  uint32_t *src_v = vals, *dst_v = tmp_vals;
  for (int shift = 0; shift < key_bits; shift += DIGIT_BITS) {
    memset(count, 0, DIGIT_COUNT * sizeof *count);
    for (size_t i = 0; i < n; i++)
      count[(src_k[i] >> shift) & (DIGIT_COUNT - 1)]++;
    /* A digit on which every key agrees moves nothing; skip the pass. */
    if (count[(src_k[0] >> shift) & (DIGIT_COUNT - 1)] == n)
      continue;
    size_t sum = 0;
    for (size_t d = 0; d < DIGIT_COUNT; d++) {
      size_t c = count[d];
      count[d] = sum;
      sum += c;
    }
    for (size_t i = 0; i < n; i++) {
      size_t at = count[(src_k[i] >> shift) & (DIGIT_COUNT - 1)]++;
      dst_k[at] = src_k[i];
      dst_v[at] = src_v[i];
    }
    uint64_t *sk = src_k;
    src_k = dst_k;
    dst_k = sk;
    uint32_t *sv = src_v;
    src_v = dst_v;
    dst_v = sv;
  }
  if (src_k != keys) {
    memcpy(keys, src_k, n * sizeof *keys);
    memcpy(vals, src_v, n * sizeof *vals);
  }
  free(count);
  return SCS_OK;
}
