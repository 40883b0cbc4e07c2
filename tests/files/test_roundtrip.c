/*
 * Every output format, written and read back: the same points bit for bit
 * (floats for binary STL) and the same triangles, with and without normals.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "tmpdir.h"
#include "shortcrust_files.h"

#include <math.h>

enum { N = 50, NT = 60 };

static double xyz[3 * N], normals[3 * N];
static uint32_t tri[3 * NT];

static uint64_t rng = 88172645463325252ull;
static uint64_t next_u64(void) {
  rng ^= rng << 13;
  rng ^= rng >> 7;
  rng ^= rng << 17;
  return rng;
}

/* Coordinates with all 53 bits in use, so that any rounding would show. */
static double next_double(void) {
  return ((double)(next_u64() >> 11) / 9007199254740992.0 - 0.5) * 3.0;
}

static void make_mesh(void) {
  for (int i = 0; i < 3 * N; i++)
    xyz[i] = next_double();
  xyz[3] = -0.0;
  xyz[4] = 1e-300;
  xyz[5] = -12345678.901234567;
  for (int i = 0; i < N; i++) {
    double *q = normals + 3 * i, len = 0;
    for (int c = 0; c < 3; c++) {
      q[c] = next_double();
      len += q[c] * q[c];
    }
    for (int c = 0; c < 3; c++)
      q[c] /= sqrt(len);
  }
  /* The last point stays unused, so it must survive as a plain vertex. */
  for (int t = 0; t < NT; t++) {
    uint32_t a = (uint32_t)(next_u64() % (N - 1)), b, c;
    do
      b = (uint32_t)(next_u64() % (N - 1));
    while (b == a);
    do
      c = (uint32_t)(next_u64() % (N - 1));
    while (c == a || c == b);
    tri[3 * t] = a;
    tri[3 * t + 1] = b;
    tri[3 * t + 2] = c;
  }
}

static const struct {
  scf_mesh_format_t fmt;
  const char *ext;
} formats[] = {
    {SCF_MESH_FMT_PLY_BINARY, "ply"}, {SCF_MESH_FMT_PLY_ASCII, "ply"},
    {SCF_MESH_FMT_OFF, "off"},        {SCF_MESH_FMT_OBJ, "obj"},
    {SCF_MESH_FMT_STL_BINARY, "stl"}, {SCF_MESH_FMT_STL_ASCII, "stl"},
};

static void check_same_mesh(const char *path, int stl, int stl_float) {
  scf_points_t p;
  uint32_t *t;
  size_t nt;
  char msg[512];
  int rc = scf_mesh_read(path, &p, &t, &nt, msg, sizeof msg);
  if (rc != 0)
    fprintf(stderr, "%s\n", msg);
  ASSERT_EQ(rc, 0);
  ASSERT_EQ(nt, NT);
  if (!stl) {
    ASSERT_EQ(p.count, N);
    for (int i = 0; i < 3 * N; i++)
      ASSERT_DBL_SAME(p.xyz[i], xyz[i]);
    for (int i = 0; i < 3 * NT; i++)
      ASSERT_EQ(t[i], tri[i]);
  } else {
    /* STL repeats the vertices of every triangle. */
    ASSERT_EQ(p.count, 3 * NT);
    for (int i = 0; i < 3 * NT; i++) {
      ASSERT_EQ(t[i], i);
      for (int c = 0; c < 3; c++) {
        double want = xyz[3 * tri[i] + c];
        if (stl_float)
          want = (double)(float)want;
        ASSERT_DBL_SAME(p.xyz[3 * i + c], want);
      }
    }
  }
  free(t);
  scf_points_free(&p);
  if (stl)
    return;
  rc = scf_points_read(path, &p, msg, sizeof msg);
  ASSERT_EQ(rc, 0);
  ASSERT_EQ(p.count, N);
  for (int i = 0; i < 3 * N; i++)
    ASSERT_DBL_SAME(p.xyz[i], xyz[i]);
  scf_points_free(&p);
}

/* The normals as the file holds them, checked format by format. */
static void check_normals(const char *path, scf_mesh_format_t fmt,
                          int with) {
  size_t len;
  char *s = read_all(path, &len);
  switch (fmt) {
  case SCF_MESH_FMT_PLY_BINARY: {
    ASSERT_EQ(strstr(s, "property float nx\nproperty float ny\n"
                           "property float nz\n") != NULL,
                 with);
    const char *body = strstr(s, "end_header\n") + strlen("end_header\n");
    size_t rec = with ? 36 : 24;
    ASSERT_EQ(len, (size_t)(body - s) + N * rec + NT * 13);
    for (int i = 0; with && i < N; i++)
      for (int c = 0; c < 3; c++) {
        float f;
        memcpy(&f, body + i * rec + 24 + 4 * c, 4);
        ASSERT_DBL_SAME((double)f, (double)(float)normals[3 * i + c]);
      }
    break;
  }
  case SCF_MESH_FMT_PLY_ASCII: {
    const char *body = strstr(s, "end_header\n") + strlen("end_header\n");
    char line[512];
    size_t ll = strcspn(body, "\n");
    ASSERT(ll < sizeof line);
    memcpy(line, body, ll);
    line[ll] = '\0';
    double v[6];
    int n = sscanf(line, "%lf %lf %lf %lf %lf %lf", &v[0], &v[1], &v[2],
                   &v[3], &v[4], &v[5]);
    ASSERT_EQ(n, with ? 6 : 3);
    for (int c = 0; with && c < 3; c++)
      ASSERT_DBL_SAME((double)(float)v[3 + c], (double)(float)normals[c]);
    break;
  }
  case SCF_MESH_FMT_OBJ: {
    int vn = 0;
    for (const char *q = s; (q = strstr(q, "\nvn ")) != NULL; q++)
      vn++;
    ASSERT_EQ(vn, with ? N : 0);
    char face[128];
    unsigned a = tri[0] + 1, b = tri[1] + 1, c = tri[2] + 1;
    if (with)
      snprintf(face, sizeof face, "\nf %u//%u %u//%u %u//%u\n", a, a, b, b,
               c, c);
    else
      snprintf(face, sizeof face, "\nf %u %u %u\n", a, b, c);
    ASSERT_STR_CONTAINS(s, face);
    if (with) {
      double q[3];
      const char *first = strstr(s, "\nvn ");
      ASSERT_EQ(sscanf(first, "\nvn %lf %lf %lf", &q[0], &q[1], &q[2]), 3);
      for (int k = 0; k < 3; k++)
        ASSERT_NEAR(q[k], normals[k], 1e-8);
    }
    break;
  }
  case SCF_MESH_FMT_STL_BINARY: {
    ASSERT_EQ(len, 84 + 50 * (size_t)NT);
    ASSERT(memcmp(s, "solid", 5) != 0);
    for (int i = 0; i < NT; i++) {
      const double *a = xyz + 3 * tri[3 * i], *b = xyz + 3 * tri[3 * i + 1],
                   *c = xyz + 3 * tri[3 * i + 2];
      double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
      double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
      double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2],
                     u[0] * w[1] - u[1] * w[0]};
      double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      for (int k = 0; k < 3; k++) {
        float f;
        memcpy(&f, s + 84 + 50 * i + 4 * k, 4);
        ASSERT_NEAR((double)f, n[k] / l, 1e-6);
      }
    }
    break;
  }
  default:
    break;
  }
  free(s);
}

static void test_formats(void) {
  for (size_t f = 0; f < sizeof formats / sizeof formats[0]; f++)
    for (int with = 0; with < 2; with++) {
      char name[64], msg[512];
      snprintf(name, sizeof name, "mesh_%zu_%d.%s", f, with, formats[f].ext);
      const char *path = tmp_path(name);
      int rc = scf_mesh_write(path, formats[f].fmt, xyz, N, tri, NT,
                             with ? normals : NULL, msg, sizeof msg);
      if (rc != 0)
        fprintf(stderr, "%s\n", msg);
      ASSERT_EQ(rc, 0);
      int stl = formats[f].fmt == SCF_MESH_FMT_STL_BINARY ||
                formats[f].fmt == SCF_MESH_FMT_STL_ASCII;
      check_same_mesh(path, stl, formats[f].fmt == SCF_MESH_FMT_STL_BINARY);
      check_normals(path, formats[f].fmt, with);
    }
}

static void test_format_from_path(void) {
  scf_mesh_format_t fmt;
  char msg[256];
  ASSERT_EQ(scf_mesh_format_from_path("a/b.ply", 0, &fmt, msg, sizeof msg),
               0);
  ASSERT_EQ(fmt, SCF_MESH_FMT_PLY_BINARY);
  ASSERT_EQ(scf_mesh_format_from_path("b.PLY", 1, &fmt, msg, sizeof msg), 0);
  ASSERT_EQ(fmt, SCF_MESH_FMT_PLY_ASCII);
  ASSERT_EQ(scf_mesh_format_from_path("b.Off", 1, &fmt, msg, sizeof msg), 0);
  ASSERT_EQ(fmt, SCF_MESH_FMT_OFF);
  ASSERT_EQ(scf_mesh_format_from_path("b.obj", 0, &fmt, msg, sizeof msg), 0);
  ASSERT_EQ(fmt, SCF_MESH_FMT_OBJ);
  ASSERT_EQ(scf_mesh_format_from_path("b.stl", 0, &fmt, msg, sizeof msg), 0);
  ASSERT_EQ(fmt, SCF_MESH_FMT_STL_BINARY);
  ASSERT_EQ(scf_mesh_format_from_path("b.STL", 1, &fmt, msg, sizeof msg), 0);
  ASSERT_EQ(fmt, SCF_MESH_FMT_STL_ASCII);
  ASSERT_EQ(scf_mesh_format_from_path("out.xyz", 0, &fmt, msg, sizeof msg),
               SCF_EUNSUPPORTED);
  ASSERT_STR_CONTAINS(msg, "out.xyz: unknown extension '.xyz'");
  ASSERT_EQ(scf_mesh_format_from_path("dir.ply/out", 0, &fmt, msg,
                                        sizeof msg),
               SCF_EUNSUPPORTED);
  ASSERT_STR_CONTAINS(msg, "dir.ply/out: no file extension");
}

/* AUTO follows the extension, and binary PLY is the default for .ply. */
static void test_auto(void) {
  char msg[256];
  const char *path = tmp_path("auto.PLY");
  ASSERT_EQ(scf_mesh_write(path, SCF_MESH_FMT_AUTO, xyz, N, tri, NT, NULL,
                             msg, sizeof msg),
               0);
  char *s = read_all(path, NULL);
  ASSERT(strncmp(s, "ply\nformat binary_little_endian 1.0\n", 36) == 0);
  free(s);
  path = tmp_path("auto.obj");
  ASSERT_EQ(scf_mesh_write(path, SCF_MESH_FMT_AUTO, xyz, N, tri, NT, NULL,
                             msg, sizeof msg),
               0);
  s = read_all(path, NULL);
  ASSERT(strncmp(s, "# written by shortcrust\nv ", 26) == 0);
  free(s);
  ASSERT_EQ(scf_mesh_write(tmp_path("auto.xyz"), SCF_MESH_FMT_AUTO, xyz, N,
                             tri, NT, NULL, msg, sizeof msg),
               SCF_EUNSUPPORTED);
  ASSERT_STR_CONTAINS(msg, "auto.xyz");
  ASSERT_EQ(count_entries(tmp_path(""), "auto.xyz"), 0);
}

/* Points without triangles, and no points at all, are valid meshes. */
static void test_empty(void) {
  char msg[256];
  for (size_t f = 0; f < sizeof formats / sizeof formats[0]; f++) {
    char name[64];
    snprintf(name, sizeof name, "empty_%zu.%s", f, formats[f].ext);
    const char *path = tmp_path(name);
    size_t n = formats[f].fmt == SCF_MESH_FMT_STL_BINARY ||
                       formats[f].fmt == SCF_MESH_FMT_STL_ASCII
                   ? 0
                   : N;
    ASSERT_EQ(scf_mesh_write(path, formats[f].fmt, xyz, n, NULL, 0, NULL,
                               msg, sizeof msg),
                 0);
    scf_points_t p;
    uint32_t *t = (uint32_t *)1;
    size_t nt = 99;
    int rc = scf_mesh_read(path, &p, &t, &nt, msg, sizeof msg);
    if (rc != 0)
      fprintf(stderr, "%s\n", msg);
    ASSERT_EQ(rc, 0);
    ASSERT_EQ(nt, 0);
    ASSERT(t == NULL);
    ASSERT_EQ(p.count, n);
    scf_points_free(&p);
  }
  const char *path = tmp_path("nothing.ply");
  ASSERT_EQ(scf_mesh_write(path, SCF_MESH_FMT_AUTO, NULL, 0, NULL, 0, NULL,
                             msg, sizeof msg),
               0);
  scf_points_t p;
  ASSERT_EQ(scf_points_read(path, &p, msg, sizeof msg), 0);
  ASSERT_EQ(p.count, 0);
  ASSERT(p.xyz == NULL);
  scf_points_free(&p);
  scf_points_free(&p);
  scf_points_free(NULL);
}

/* Non-finite coordinates pass through: the core, not the reader, rejects
 * them. */
static void test_nonfinite(void) {
  double v[9] = {NAN, 1, 2, INFINITY, -INFINITY, 0, 1, 1, 1};
  uint32_t t[3] = {0, 1, 2};
  char msg[256];
  const scf_mesh_format_t fmts[] = {SCF_MESH_FMT_PLY_BINARY,
                                   SCF_MESH_FMT_PLY_ASCII, SCF_MESH_FMT_OFF,
                                   SCF_MESH_FMT_OBJ};
  const char *names[] = {"nf.ply", "nfa.ply", "nf.off", "nf.obj"};
  for (int f = 0; f < 4; f++) {
    const char *path = tmp_path(names[f]);
    ASSERT_EQ(scf_mesh_write(path, fmts[f], v, 3, t, 1, NULL, msg,
                               sizeof msg),
                 0);
    scf_points_t p;
    int rc = scf_points_read(path, &p, msg, sizeof msg);
    if (rc != 0)
      fprintf(stderr, "%s\n", msg);
    ASSERT_EQ(rc, 0);
    ASSERT_EQ(p.count, 3);
    ASSERT(isnan(p.xyz[0]));
    ASSERT(isinf(p.xyz[3]) && p.xyz[3] > 0);
    ASSERT(isinf(p.xyz[4]) && p.xyz[4] < 0);
    ASSERT_DBL_SAME(p.xyz[8], 1.0);
    scf_points_free(&p);
  }
}

int main(void) {
  tmp_init();
  make_mesh();
  test_formats();
  test_format_from_path();
  test_auto();
  test_empty();
  test_nonfinite();
  return sct_finish("files_roundtrip");
}
