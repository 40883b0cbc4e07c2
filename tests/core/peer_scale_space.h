/*
 * CGAL's scale-space reconstruction, for the tables that compare against it.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SC_PEER_SCALE_SPACE_H
#define SC_PEER_SCALE_SPACE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Reconstructs n points; on success returns 0 and sets *tri to 3 * *ntri
 * indices into the points (free() it); -1 on failure. */
int peer_scale_space(const double *xyz, size_t n, uint32_t **tri,
                     size_t *ntri);

#ifdef __cplusplus
}
#endif

#endif
