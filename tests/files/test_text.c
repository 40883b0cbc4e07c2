/*
 * Reading the text formats: XYZ-like files (.xyz .txt .pts .csv) with
 * every separator, extra columns, comments, blank lines and CRLF; the
 * .pts count line and the .csv header; OFF and OBJ vertices and faces;
 * ascii and binary STL meshes.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "tmpdir.h"
#include "shortcrust_files.h"

#include <math.h>

static void read_ok(const char *path, scf_points_t *p) {
  char msg[512];
  int rc = scf_points_read(path, p, msg, sizeof msg);
  if (rc != 0)
    ASSERT_FAIL("reading %s: %s (%s)", path, scf_err_name(rc), msg);
}

static void mesh_ok(const char *path, scf_points_t *p, uint32_t **tri,
                    size_t *nt) {
  char msg[512];
  int rc = scf_mesh_read(path, p, tri, nt, msg, sizeof msg);
  if (rc != 0)
    ASSERT_FAIL("reading %s: %s (%s)", path, scf_err_name(rc), msg);
}

/* Writes text to name in the private directory and reads its points. */
static void points_of(const char *name, const char *text, scf_points_t *p) {
  const char *path = tmp_path(name);
  write_text(path, text);
  read_ok(path, p);
}

static void check_points(const scf_points_t *p, const double *want, size_t n) {
  ASSERT_EQ(p->count, n);
  for (size_t i = 0; i < 3 * n; i++)
    ASSERT_DBL_SAME(p->xyz[i], want[i]);
}

static const double three[9] = {1, 2, 3, -4.5, 5e-3, 6e10, 0.1, -0.0, 9};

/* The same three points written in many ways, under every extension. */
static void test_xyz_layouts(void) {
  static const char *const texts[] = {
      /* spaces */
      "1 2 3\n-4.5 5e-3 6e10\n0.1 -0 9\n",
      /* tabs and runs of blanks, leading and trailing */
      "\t1\t2\t3\n  -4.5   5e-3\t 6e10  \n0.1\t\t-0 9\t\n",
      /* commas, with and without blanks */
      "1,2,3\n-4.5, 5e-3, 6e10\n0.1 ,-0,9\n",
      /* extra columns: normals, colours, intensity */
      "1 2 3 0 0 1 255 0 0\n-4.5 5e-3 6e10 7\n0.1 -0 9 a b c\n",
      /* comments, whole-line and trailing, and blank lines */
      "# a scan\n\n1 2 3 # first\n   \n# more\n-4.5 5e-3 6e10\n\n0.1 -0 9#\n",
      /* CRLF everywhere, and a last line without a line end */
      "1 2 3\r\n\r\n-4.5 5e-3 6e10\r\n0.1 -0 9",
      /* semicolons, as some spreadsheets write */
      "1;2;3\n-4.5;5e-3;6e10\n0.1;-0;9\n",
  };
  static const char *const exts[] = {"xyz", "txt", "pts", "csv", "XYZ", "Txt"};
  for (size_t t = 0; t < sizeof texts / sizeof texts[0]; t++)
    for (size_t e = 0; e < sizeof exts / sizeof exts[0]; e++) {
      char name[32];
      snprintf(name, sizeof name, "layout%zu.%s", t, exts[e]);
      scf_points_t p;
      points_of(name, texts[t], &p);
      check_points(&p, three, 3);
      scf_points_free(&p);
    }
}

/* A .pts file may open with its point count, alone on the line. */
static void test_pts(void) {
  scf_points_t p;
  points_of("count.pts", "3\n1 2 3\n-4.5 5e-3 6e10\n0.1 -0 9\n", &p);
  check_points(&p, three, 3);
  scf_points_free(&p);
  /* After comments and blank lines, with CRLF, and a wrong count (it is
   * skipped, not trusted). */
  points_of("late.pts", "# header\r\n\r\n  1000000 \r\n1 2 3\r\n", &p);
  check_points(&p, three, 1);
  scf_points_free(&p);
  /* Without a count line the first line is a point. */
  points_of("nocount.pts", "1 2 3 4\n", &p);
  check_points(&p, three, 1);
  scf_points_free(&p);
  /* Only the first line may be a count. */
  const char *path = tmp_path("twocounts.pts");
  write_text(path, "2\n1 2 3\n5\n");
  char msg[256];
  ASSERT_EQ(scf_points_read(path, &p, msg, sizeof msg), SCF_EFORMAT);
  ASSERT_STR_CONTAINS(msg, "line 3");
  /* Elsewhere a lone number is a bad line, not a count. */
  path = tmp_path("count.xyz");
  write_text(path, "1\n1 2 3\n");
  ASSERT_EQ(scf_points_read(path, &p, msg, sizeof msg), SCF_EFORMAT);
  ASSERT_STR_CONTAINS(msg, "line 1");
}

/* A .csv file may open with a line of column names. */
static void test_csv(void) {
  scf_points_t p;
  points_of("head.csv", "x,y,z\n1,2,3\n-4.5,5e-3,6e10\n0.1,-0,9\n", &p);
  check_points(&p, three, 3);
  scf_points_free(&p);
  points_of("quoted.csv", "\"X\",\"Y\",\"Z\",\"intensity\"\r\n1,2,3,0.5\r\n",
            &p);
  check_points(&p, three, 1);
  scf_points_free(&p);
  points_of("nohead.csv", "1,2,3\n", &p);
  check_points(&p, three, 1);
  scf_points_free(&p);
  /* Only the first line may name columns. */
  const char *path = tmp_path("late.csv");
  write_text(path, "x,y,z\n1,2,3\nx,y,z\n");
  char msg[256];
  ASSERT_EQ(scf_points_read(path, &p, msg, sizeof msg), SCF_EFORMAT);
  ASSERT_STR_CONTAINS(msg, "line 3");
  ASSERT_STR_CONTAINS(msg, "'x'");
  /* Elsewhere a header is an error. */
  path = tmp_path("head.xyz");
  write_text(path, "x y z\n1 2 3\n");
  ASSERT_EQ(scf_points_read(path, &p, msg, sizeof msg), SCF_EFORMAT);
  ASSERT_STR_CONTAINS(msg, "line 1");
}

/* Files without points are not errors. */
static void test_no_points(void) {
  static const char *const names[] = {"e.xyz", "e.pts", "e.csv", "e.obj"};
  static const char *const texts[] = {"", "# nothing\n\n", "x,y,z\n",
                                      "# no vertices\nvt 0 0\n"};
  for (int i = 0; i < 4; i++) {
    scf_points_t p;
    points_of(names[i], texts[i], &p);
    ASSERT_EQ(p.count, 0);
    ASSERT(p.xyz == NULL);
  }
}

/*
 * Many lines, so that lines straddle the reader's buffer at every
 * position; each point is recognisable by its line number.
 */
static void test_many_lines(void) {
  enum { N = 30000 };
  const char *path = tmp_path("many.xyz");
  FILE *f = fopen(path, "wb");
  ASSERT(f != NULL);
  for (int i = 0; i < N; i++)
    fprintf(f, "%d%s%.17g %d%s", i, i % 3 ? " " : ",\t", i * 0.001, -i,
            i % 7 ? "\n" : " 1 2 3 # extra\r\n");
  ASSERT(fclose(f) == 0);
  scf_points_t p;
  read_ok(path, &p);
  ASSERT_EQ(p.count, N);
  for (int i = 0; i < N; i++) {
    ASSERT_DBL_SAME(p.xyz[3 * i], (double)i);
    ASSERT_DBL_SAME(p.xyz[3 * i + 1], i * 0.001);
    ASSERT_DBL_SAME(p.xyz[3 * i + 2], (double)-i);
  }
  scf_points_free(&p);
}

static const double cube[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                  {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};

static void check_cube_points(const scf_points_t *p) {
  ASSERT_EQ(p->count, 8);
  for (int i = 0; i < 8; i++)
    for (int c = 0; c < 3; c++)
      ASSERT_DBL_SAME(p->xyz[3 * i + c], cube[i][c]);
}

/* The six quads of the cube, each split at its first vertex. */
static const uint32_t cube_tris[12][3] = {
    {0, 3, 2}, {0, 2, 1}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
    {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};

static void check_cube_tris(const uint32_t *tri, size_t nt) {
  ASSERT_EQ(nt, 12);
  for (int t = 0; t < 12; t++)
    for (int c = 0; c < 3; c++)
      ASSERT_EQ(tri[3 * t + c], cube_tris[t][c]);
}

static void test_off(void) {
  static const char *const texts[] = {
      "OFF\n8 6 12\n"
      "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n"
      "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 1 2 6 5\n4 2 3 7 6\n4 3 0 4 7\n",
      /* counts on the keyword line, comments, blank lines, CRLF, tabs */
      "OFF 8 6 0 # the cube\r\n\r\n# vertices\r\n"
      "0 0 0\r\n1\t0 0\r\n1 1 0\r\n0 1 0 # four\r\n"
      "0 0 1\r\n1 0 1\r\n1 1 1\r\n0 1 1\r\n"
      "# faces\r\n4 0 3 2 1\r\n4 4 5 6 7\r\n4 0 1 5 4\r\n"
      "4 1 2 6 5\r\n4 2 3 7 6\r\n  4 3 0 4 7",
      /* colours after the coordinates and after the indices */
      "COFF\n8 6 12\n"
      "0 0 0 255 0 0 255\n1 0 0 1 1 1 1\n1 1 0 0 0 0 0\n0 1 0 0 0 0 0\n"
      "0 0 1 0 0 0 0\n1 0 1 0 0 0 0\n1 1 1 0 0 0 0\n0 1 1 0 0 0 0\n"
      "4 0 3 2 1 0.5 0.5 0.5\n4 4 5 6 7\n4 0 1 5 4\n4 1 2 6 5\n"
      "4 2 3 7 6\n4 3 0 4 7 1 0 0\n",
      /* normals after the coordinates */
      "NOFF\n8 6 12\n"
      "0 0 0 0 0 -1\n1 0 0 0 0 -1\n1 1 0 0 0 -1\n0 1 0 0 0 -1\n"
      "0 0 1 0 0 1\n1 0 1 0 0 1\n1 1 1 0 0 1\n0 1 1 0 0 1\n"
      "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 1 2 6 5\n4 2 3 7 6\n4 3 0 4 7\n",
  };
  for (size_t t = 0; t < sizeof texts / sizeof texts[0]; t++) {
    char name[32];
    snprintf(name, sizeof name, "cube%zu.%s", t, t % 2 ? "OFF" : "off");
    const char *path = tmp_path(name);
    write_text(path, texts[t]);
    scf_points_t p;
    read_ok(path, &p);
    check_cube_points(&p);
    scf_points_free(&p);
    uint32_t *tri;
    size_t nt;
    mesh_ok(path, &p, &tri, &nt);
    check_cube_points(&p);
    check_cube_tris(tri, nt);
    free(tri);
    scf_points_free(&p);
  }
  /* As points, the faces of an OFF file are never read: broken ones are
   * no obstacle. */
  const char *path = tmp_path("badfaces.off");
  write_text(path, "OFF\n3 1 0\n1 2 3\n1 2 3\n1 2 3\n3 0 1 99\n");
  scf_points_t p;
  read_ok(path, &p);
  ASSERT_EQ(p.count, 3);
  scf_points_free(&p);
}

static void test_obj(void) {
  const char *path = tmp_path("cube.obj");
  write_text(path, "# cube\r\nmtllib cube.mtl\r\no cube\r\n"
                   "v 0 0 0\r\nv 1 0 0\r\nv 1 1 0\r\nv 0 1 0 1.0\r\n"
                   "vt 0.5 0.5\r\nvn 0 0 1\r\n\r\n"
                   "f 1 4 3 2\r\n"
                   "v 0 0 1\r\nv\t1 0 1 # w follows\r\nv 1 1 1\r\nv 0 1 1\r\n"
                   "usemtl red\r\ng side\r\ns off\r\n"
                   "f 5/1 6/1 7/1 8/1\r\n"
                   "f 1//1 2//1 6//1 5//1\r\n"
                   "f -7/1/1 -6/1/1 -2/1/1 -3/1/1\r\n"
                   "f 3 4 8 7 # relative and absolute mixed below\r\n"
                   "f 4 -8 -4 -1");
  scf_points_t p;
  read_ok(path, &p);
  check_cube_points(&p);
  scf_points_free(&p);
  uint32_t *tri;
  size_t nt;
  mesh_ok(path, &p, &tri, &nt);
  check_cube_points(&p);
  check_cube_tris(tri, nt);
  free(tri);
  scf_points_free(&p);

  /* A face may name vertices that come later in the file. */
  path = tmp_path("forward.obj");
  write_text(path, "f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n");
  mesh_ok(path, &p, &tri, &nt);
  ASSERT_EQ(p.count, 3);
  ASSERT_EQ(nt, 1);
  ASSERT_EQ(tri[2], 2);
  free(tri);
  scf_points_free(&p);
}

/* Binary STL data for two triangles with the given 80-byte header. */
static size_t stl_binary(unsigned char *out, const char *header) {
  memset(out, 0, 84);
  memcpy(out, header, strlen(header));
  out[80] = 2;
  static const float v[2][12] = {
      {0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0},
      {0, 0, -1, 0.5f, 0.25f, 0, -1, 0, 0, 0, -2.5f, 0}};
  for (int t = 0; t < 2; t++) {
    unsigned char *r = out + 84 + 50 * t;
    for (int k = 0; k < 12; k++) {
      uint32_t w;
      memcpy(&w, &v[t][k], 4);
      for (int b = 0; b < 4; b++)
        r[4 * k + b] = (unsigned char)(w >> (8 * b));
    }
    r[48] = r[49] = 0;
  }
  return 84 + 100;
}

static void check_stl(const char *path) {
  static const double want[6][3] = {{0, 0, 0},      {1, 0, 0},  {0, 1, 0},
                                    {0.5, 0.25, 0}, {-1, 0, 0}, {0, -2.5, 0}};
  scf_points_t p;
  uint32_t *tri;
  size_t nt;
  mesh_ok(path, &p, &tri, &nt);
  ASSERT_EQ(p.count, 6);
  for (int i = 0; i < 6; i++)
    for (int c = 0; c < 3; c++)
      ASSERT_DBL_SAME(p.xyz[3 * i + c], want[i][c]);
  ASSERT_EQ(nt, 2);
  for (int i = 0; i < 6; i++)
    ASSERT_EQ(tri[i], i);
  free(tri);
  scf_points_free(&p);
}

static void test_stl(void) {
  const char *path = tmp_path("two.stl");
  write_text(path, "solid two\r\n"
                   "  facet normal 0 0 1\r\n    outer loop\r\n"
                   "      vertex 0 0 0\r\n      vertex 1 0 0\r\n"
                   "      vertex 0 1 0\r\n    endloop\r\n  endfacet\r\n"
                   "  facet normal 0 0 -1\n    outer loop\n"
                   "      vertex 0.5 0.25 0\n      vertex -1 0 0\n"
                   "      vertex\t0 -2.5 0\n    endloop\n  endfacet\n"
                   "endsolid two\n");
  check_stl(path);
  unsigned char bin[184];
  path = tmp_path("bin.STL");
  write_bytes(path, bin, stl_binary(bin, "made by hand"));
  check_stl(path);
  /* A binary file whose header starts with "solid", as some exporters
   * write: its size tells it apart. */
  path = tmp_path("solid.stl");
  write_bytes(path, bin, stl_binary(bin, "solid but binary"));
  check_stl(path);
}

int main(void) {
  tmp_init();
  test_xyz_layouts();
  test_pts();
  test_csv();
  test_no_points();
  test_many_lines();
  test_off();
  test_obj();
  test_stl();
  return sct_finish("files_text");
}
