/*
 * Test support for shortcrust: what only the tests need. The assertions are
 * in sct_assert.h; the surface samples and the mesh checker the tests share
 * with the benchmarks and the load generator are the synth module
 * (clients/synth/synth.h). Every name here starts with sct_.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SCT_TESTSUPPORT_H
#define SCT_TESTSUPPORT_H

#ifdef __cplusplus
extern "C" {
#endif

/* Wall-clock seconds from a monotonic clock, for timing in tests. */
double sct_seconds(void);

#ifdef __cplusplus
}
#endif

#endif /* SCT_TESTSUPPORT_H */
