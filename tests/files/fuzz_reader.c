/*
 * The point and mesh readers under libFuzzer (and, without it, over the
 * seed corpus as an ordinary test). The first byte of an input picks the
 * format, the rest is the file: written to a private directory under that
 * format's extension and read as points with their properties, and as a
 * mesh where the format holds one. Whatever the bytes, a read either
 * succeeds with consistent results or fails with a code and a message and
 * leaves its outputs zeroed; the sanitizers catch the rest.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "shortcrust_files.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static const char *const exts[] = {"ply", "las", "xyz", "csv",
                                   "pts", "off", "obj", "stl"};
enum { NEXT = sizeof exts / sizeof exts[0] };

static char dir[64];

static void cleanup(void) {
  char path[128];
  for (size_t i = 0; i < NEXT; i++) {
    snprintf(path, sizeof path, "%s/in.%s", dir, exts[i]);
    unlink(path);
  }
  rmdir(dir);
}

static void fail(const char *what) {
  fprintf(stderr, "fuzz_reader: %s\n", what);
  abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (dir[0] == '\0') {
    snprintf(dir, sizeof dir, "/tmp/sc-fuzz-files-XXXXXX");
    if (mkdtemp(dir) == NULL)
      fail("mkdtemp");
    atexit(cleanup);
  }
  if (size == 0)
    return 0;
  const char *ext = exts[data[0] % NEXT];
  char path[128];
  snprintf(path, sizeof path, "%s/in.%s", dir, ext);
  FILE *f = fopen(path, "wb");
  if (f == NULL || fwrite(data + 1, 1, size - 1, f) != size - 1 ||
      fclose(f) != 0)
    fail("cannot write the input file");

  char msg[256];
  scf_points_t pts;
  scf_attrs_t attrs;
  int rc = scf_points_read_attrs(path, &pts, &attrs, msg, sizeof msg);
  if (rc == 0) {
    if ((pts.count == 0) != (pts.xyz == NULL))
      fail("points: count and array disagree");
    if (attrs.count > 0 &&
        (attrs.points != pts.count || attrs.stride == 0 ||
         attrs.props[attrs.count - 1].offset +
                 scf_type_size(attrs.props[attrs.count - 1].type) !=
             attrs.stride))
      fail("properties: inconsistent layout");
    /* Touch every value, so that a short buffer shows. */
    volatile double sum = 0;
    for (size_t i = 0; i < 3 * pts.count; i++)
      sum += pts.xyz[i];
    volatile unsigned bytes = 0;
    for (size_t i = 0; i < attrs.stride * attrs.points; i++)
      bytes += attrs.data[i];
    (void)sum;
    (void)bytes;
  } else if (rc > 0 || msg[0] == '\0' || pts.xyz != NULL || pts.count ||
             attrs.count || attrs.data) {
    fail("a failed read without a message or with outputs left");
  }
  scf_points_free(&pts);
  scf_attrs_free(&attrs);

  uint32_t *tri = NULL;
  size_t nt = 0;
  rc = scf_mesh_read(path, &pts, &tri, &nt, msg, sizeof msg);
  if (rc == 0) {
    for (size_t i = 0; i < 3 * nt; i++)
      if (tri[i] >= pts.count)
        fail("mesh: an index out of range");
  } else if (pts.xyz != NULL || tri != NULL || nt != 0) {
    fail("a failed mesh read left outputs");
  }
  scf_points_free(&pts);
  free(tri);
  return 0;
}
