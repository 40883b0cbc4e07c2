/*
 * The real scans in tests/data (the directory is argv[1]): each reads with
 * its exact point count and bounding box, measured once with an
 * independent reader and written here as exact float values, holds only
 * finite float coordinates and no repeated point, and comes back the same
 * after a round trip through binary and ascii PLY.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "tmpdir.h"
#include "shortcrust_files.h"

#include <math.h>

typedef struct expected {
  const char *name;
  size_t count;
  double lo[3], hi[3];
  double first[3], last[3];
} expected_t;

/* The files hold binary little-endian float x, y, z; the hex values are
 * those floats exactly. */
static const expected_t files[] = {
    {"kitten_points.ply",
     14472,
     {-0x1.4a209ap-2, -0x1.fa4336p-2, -0x1.2bf7aep-2},
     {0x1.4a209ap-2, 0x1.fa4336p-2, 0x1.2bf7aep-2},
     {-0.11757899820804596, -0.30997899174690247, -0.29165700078010559},
     {0.21044500172138214, -0.020556900650262833, 0.09674689918756485}},
    {"knot1_points.ply",
     3200,
     {-0x1.eb9f98p-2, -0x1p-1, -0x1.dbcba4p-3},
     {0x1.eb9f98p-2, 0x1p-1, 0x1.dbcba4p-3},
     {0.36581701040267944, 0.40974301099777222, -0.0041229100897908211},
     {0.40872400999069214, 0.15588100254535675, -0.20255899429321289}},
};

static int cmp_point(const void *a, const void *b) {
  const double *p = a, *q = b;
  for (int c = 0; c < 3; c++)
    if (p[c] != q[c])
      return p[c] < q[c] ? -1 : 1;
  return 0;
}

static void check_same(const scf_points_t *a, const scf_points_t *b) {
  ASSERT_EQ(a->count, b->count);
  for (size_t i = 0; i < 3 * a->count; i++)
    ASSERT_DBL_SAME(a->xyz[i], b->xyz[i]);
}

static void check_file(const char *dir, const expected_t *e) {
  char path[1024], msg[512];
  snprintf(path, sizeof path, "%s/%s", dir, e->name);
  scf_points_t p;
  int rc = scf_points_read(path, &p, msg, sizeof msg);
  if (rc != 0)
    ASSERT_FAIL("%s", msg);
  ASSERT_EQ(p.count, e->count);

  double lo[3], hi[3];
  for (int c = 0; c < 3; c++)
    lo[c] = hi[c] = p.xyz[c];
  for (size_t i = 0; i < p.count; i++)
    for (int c = 0; c < 3; c++) {
      double v = p.xyz[3 * i + c];
      ASSERT(isfinite(v));
      ASSERT_DBL_SAME(v, (double)(float)v);
      lo[c] = v < lo[c] ? v : lo[c];
      hi[c] = v > hi[c] ? v : hi[c];
    }
  for (int c = 0; c < 3; c++) {
    ASSERT_DBL_SAME(lo[c], e->lo[c]);
    ASSERT_DBL_SAME(hi[c], e->hi[c]);
    ASSERT_DBL_SAME(p.xyz[c], e->first[c]);
    ASSERT_DBL_SAME(p.xyz[3 * (p.count - 1) + c], e->last[c]);
  }

  /* No point twice: reconstruction input from a mesh's vertex set. */
  double *sorted = malloc(3 * p.count * sizeof *sorted);
  ASSERT(sorted != NULL);
  memcpy(sorted, p.xyz, 3 * p.count * sizeof *sorted);
  qsort(sorted, p.count, 3 * sizeof *sorted, cmp_point);
  for (size_t i = 1; i < p.count; i++)
    if (cmp_point(sorted + 3 * (i - 1), sorted + 3 * i) == 0)
      ASSERT_FAIL("%s: point %.9g %.9g %.9g appears twice", e->name,
                  sorted[3 * i], sorted[3 * i + 1], sorted[3 * i + 2]);
  free(sorted);

  /* As a mesh: the same points, no faces. */
  scf_points_t m;
  uint32_t *tri;
  size_t nt;
  ASSERT_EQ(scf_mesh_read(path, &m, &tri, &nt, msg, sizeof msg), 0);
  check_same(&p, &m);
  ASSERT_EQ(nt, 0);
  scf_points_free(&m);

  /* Written and read back, in binary and in ascii. */
  static const scf_mesh_format_t fmts[] = {SCF_MESH_FMT_PLY_BINARY,
                                          SCF_MESH_FMT_PLY_ASCII};
  for (int f = 0; f < 2; f++) {
    const char *copy = tmp_path("copy.ply");
    ASSERT_EQ(scf_mesh_write(copy, fmts[f], p.xyz, p.count, NULL, 0, NULL,
                               msg, sizeof msg),
                 0);
    ASSERT_EQ(scf_points_read(copy, &m, msg, sizeof msg), 0);
    check_same(&p, &m);
    scf_points_free(&m);
  }
  printf("%s: %zu points, box [%.9g %.9g %.9g] - [%.9g %.9g %.9g]\n", e->name,
         p.count, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
  scf_points_free(&p);
}

int main(int argc, char **argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: %s DATA_DIRECTORY\n", argv[0]);
    return 2;
  }
  tmp_init();
  for (size_t i = 0; i < sizeof files / sizeof files[0]; i++)
    check_file(argv[1], &files[i]);
  return sct_finish("files_data");
}
