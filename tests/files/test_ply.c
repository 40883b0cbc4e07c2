/*
 * Reading PLY: ascii and both binary byte orders, every scalar type under
 * both of its names, properties and elements the reader must step over
 * (lists included), faces as triangle fans, and files large enough that
 * records straddle the reader's buffer.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "tmpdir.h"
#include "shortcrust_files.h"
#include "plybuf.h"

#include <math.h>

/* Four values per type, chosen to reach its limits and its sign bit, so
 * that a wrong width, sign extension or byte order cannot go unnoticed. */
static const double values[TY_COUNT][4] = {
    [I8] = {-128, 127, -1, 5},
    [U8] = {255, 0, 128, 1},
    [I16] = {-32768, 32767, -2, 300},
    [U16] = {65535, 0, 256, 32768},
    [I32] = {-2147483648.0, 2147483647.0, -1, 65536},
    [U32] = {4294967295.0, 0, 2147483648.0, 16777217},
    [F32] = {1.5, -0.1, 3.4e38, 1e-45},
    [F64] = {0.1, -1e300, 5e-324, 123456789.12345679},
};

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

/*
 * Vertices of type t in format fmt, with a uchar property between y and z;
 * with_list also puts a list into the vertex element, which makes its
 * records variable in size (the reader's other path). An element with a
 * list comes before the vertices and a face element after them, and both
 * must be skipped.
 */
static void test_types(void) {
  for (int fmt = 0; fmt < FMT_COUNT; fmt++)
    for (int t = 0; t < TY_COUNT; t++)
      for (int alias = 0; alias < 2; alias++)
        for (int with_list = 0; with_list < 2; with_list++) {
          const char *tn = alias ? ty_alias[t] : ty_name[t];
          buf_t b = {0};
          buf_printf(&b, "ply\nformat %s 1.0\n", fmt_name[fmt]);
          buf_printf(&b, "comment type %s\nobj_info made by hand\n", tn);
          buf_printf(&b, "element camera 2\nproperty float focal\n"
                         "property list uchar int ids\nproperty double d\n");
          buf_printf(&b, "element vertex 4\nproperty %s x\n", tn);
          buf_printf(&b, "property uchar red\nproperty %s y\n", tn);
          if (with_list)
            buf_printf(&b, "property list ushort float uv\n");
          buf_printf(&b, "property %s z\n", tn);
          buf_printf(&b, "element face 1\n"
                         "property list uchar int vertex_indices\n"
                         "end_header\n");
          for (int c = 0; c < 2; c++) {
            buf_val(&b, fmt, F32, 35.0 + c);
            buf_val(&b, fmt, U8, 2 + c);
            for (int k = 0; k < 2 + c; k++)
              buf_val(&b, fmt, I32, -7 * k);
            buf_val(&b, fmt, F64, 1e10);
            buf_eol(&b, fmt);
          }
          for (int i = 0; i < 4; i++) {
            buf_val(&b, fmt, (ty_t)t, values[t][i]);
            buf_val(&b, fmt, U8, 200 + i);
            buf_val(&b, fmt, (ty_t)t, values[t][(i + 1) % 4]);
            if (with_list) {
              buf_val(&b, fmt, U16, i);
              for (int k = 0; k < i; k++)
                buf_val(&b, fmt, F32, 0.25 * k);
            }
            buf_val(&b, fmt, (ty_t)t, values[t][(i + 2) % 4]);
            buf_eol(&b, fmt);
          }
          buf_val(&b, fmt, U8, 3);
          for (int k = 0; k < 3; k++)
            buf_val(&b, fmt, I32, k);
          buf_eol(&b, fmt);
          const char *path = tmp_path("types.ply");
          buf_write(&b, path);
          buf_free(&b);

          scf_points_t p;
          read_ok(path, &p);
          ASSERT_EQ(p.count, 4);
          for (int i = 0; i < 4; i++)
            for (int c = 0; c < 3; c++)
              ASSERT_DBL_SAME(p.xyz[3 * i + c],
                             ty_round((ty_t)t, values[t][(i + c) % 4]));
          scf_points_free(&p);

          /* The same file as a mesh: the vertices and one triangle. */
          uint32_t *tri;
          size_t nt;
          mesh_ok(path, &p, &tri, &nt);
          ASSERT_EQ(p.count, 4);
          ASSERT_EQ(nt, 1);
          ASSERT_EQ(tri[0], 0);
          ASSERT_EQ(tri[1], 1);
          ASSERT_EQ(tri[2], 2);
          ASSERT_DBL_SAME(p.xyz[11], ty_round((ty_t)t, values[t][1]));
          free(tri);
          scf_points_free(&p);
        }
}

/* A square pyramid: a quad base and four triangles. */
static const double pyramid[5][3] = {
    {0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5, 0.5, 1}};
static const int pyramid_faces[5][5] = {
    {4, 0, 3, 2, 1}, {3, 0, 1, 4}, {3, 1, 2, 4}, {3, 2, 3, 4}, {3, 3, 0, 4}};
/* The fan of the quad around its first vertex, then the triangles. */
static const uint32_t pyramid_tris[6][3] = {{0, 3, 2}, {0, 2, 1}, {0, 1, 4},
                                            {1, 2, 4}, {2, 3, 4}, {3, 0, 4}};

/*
 * The pyramid as a mesh: the face list under either name and with several
 * count and index types, next to other properties of the face element (a
 * scalar and another list) and other elements before, between and after.
 */
static void test_faces(void) {
  static const struct {
    ty_t count, index;
    const char *name;
  } lists[] = {{U8, I32, "vertex_indices"},
               {U16, U32, "vertex_index"},
               {I8, I16, "vertex_indices"},
               {U32, U8, "vertex_indices"},
               {I32, U16, "vertex_index"}};
  for (int fmt = 0; fmt < FMT_COUNT; fmt++)
    for (size_t l = 0; l < sizeof lists / sizeof lists[0]; l++)
      for (int face_first = 0; face_first < 2; face_first++) {
        buf_t b = {0}, verts = {0}, faces = {0};
        buf_printf(&b, "ply\r\nformat %s 1.0\r\ncomment CRLF header\r\n",
                   fmt_name[fmt]);
        buf_printf(&verts, "element vertex 5\nproperty double x\n"
                           "property double y\nproperty double z\n"
                           "property float nx\n");
        buf_printf(&faces,
                   "element face 5\nproperty uchar flags\n"
                   "property list uchar float texcoord\n"
                   "property list %s %s %s\nproperty short material\n",
                   ty_name[lists[l].count], ty_name[lists[l].index],
                   lists[l].name);
        buf_put(&b, face_first ? faces.p : verts.p,
                face_first ? faces.n : verts.n);
        buf_printf(&b, "element edge 2\nproperty int v1\nproperty int v2\n");
        buf_put(&b, face_first ? verts.p : faces.p,
                face_first ? verts.n : faces.n);
        buf_printf(&b, "element trailer 1\nproperty list uint double junk\n"
                       "end_header\r\n");
        buf_free(&verts);
        buf_free(&faces);
        buf_t vdata = {0}, fdata = {0};
        for (int i = 0; i < 5; i++) {
          for (int c = 0; c < 3; c++)
            buf_val(&vdata, fmt, F64, pyramid[i][c]);
          buf_val(&vdata, fmt, F32, -1);
          buf_eol(&vdata, fmt);
        }
        for (int f = 0; f < 5; f++) {
          buf_val(&fdata, fmt, U8, 7);
          buf_val(&fdata, fmt, U8, 2 * (f % 2));
          for (int k = 0; k < 2 * (f % 2); k++)
            buf_val(&fdata, fmt, F32, 0.5);
          int n = pyramid_faces[f][0];
          buf_val(&fdata, fmt, lists[l].count, n);
          for (int k = 0; k < n; k++)
            buf_val(&fdata, fmt, lists[l].index, pyramid_faces[f][1 + k]);
          buf_val(&fdata, fmt, I16, -f);
          buf_eol(&fdata, fmt);
        }
        buf_put(&b, face_first ? fdata.p : vdata.p,
                face_first ? fdata.n : vdata.n);
        for (int e = 0; e < 2; e++) {
          buf_val(&b, fmt, I32, e);
          buf_val(&b, fmt, I32, e + 1);
          buf_eol(&b, fmt);
        }
        buf_put(&b, face_first ? vdata.p : fdata.p,
                face_first ? vdata.n : fdata.n);
        buf_val(&b, fmt, U32, 2);
        buf_val(&b, fmt, F64, 1);
        buf_val(&b, fmt, F64, 2);
        buf_eol(&b, fmt);
        buf_free(&vdata);
        buf_free(&fdata);
        const char *path = tmp_path("pyramid.PLY");
        buf_write(&b, path);
        buf_free(&b);

        scf_points_t p;
        uint32_t *tri;
        size_t nt;
        mesh_ok(path, &p, &tri, &nt);
        ASSERT_EQ(p.count, 5);
        for (int i = 0; i < 5; i++)
          for (int c = 0; c < 3; c++)
            ASSERT_DBL_SAME(p.xyz[3 * i + c], pyramid[i][c]);
        ASSERT_EQ(nt, 6);
        for (int t = 0; t < 6; t++)
          for (int c = 0; c < 3; c++)
            ASSERT_EQ(tri[3 * t + c], pyramid_tris[t][c]);
        free(tri);
        scf_points_free(&p);

        /* As points, the faces are not even looked at. */
        read_ok(path, &p);
        ASSERT_EQ(p.count, 5);
        ASSERT_DBL_SAME(p.xyz[14], 1.0);
        scf_points_free(&p);
      }
}

/* A point file read as a mesh has no faces; an empty one has no points. */
static void test_no_faces(void) {
  const char *path = tmp_path("nofaces.ply");
  write_text(path, "ply\nformat ascii 1.0\nelement vertex 2\n"
                   "property float x\nproperty float y\nproperty float z\n"
                   "end_header\n1 2 3\n4 5 6\n");
  static uint32_t junk[3];
  scf_points_t p;
  uint32_t *tri = junk;
  size_t nt = 7;
  mesh_ok(path, &p, &tri, &nt);
  ASSERT_EQ(p.count, 2);
  ASSERT_EQ(nt, 0);
  ASSERT(tri == NULL);
  ASSERT_DBL_SAME(p.xyz[5], 6.0);
  scf_points_free(&p);

  path = tmp_path("empty.ply");
  write_text(path, "ply\nformat binary_big_endian 1.0\nelement vertex 0\n"
                   "property float x\nproperty float y\nproperty float z\n"
                   "element face 0\nproperty list uchar int vertex_indices\n"
                   "end_header\n");
  read_ok(path, &p);
  ASSERT_EQ(p.count, 0);
  ASSERT(p.xyz == NULL);
  tri = junk;
  nt = 7;
  mesh_ok(path, &p, &tri, &nt);
  ASSERT_EQ(p.count, 0);
  ASSERT_EQ(nt, 0);
  ASSERT(tri == NULL);
  scf_points_free(&p);
}

/*
 * Ascii values are one stream of tokens: line breaks anywhere, tabs, runs
 * of blanks, CRLF, and no line end after the last value.
 */
static void test_ascii_layout(void) {
  const char *path = tmp_path("layout.ply");
  write_text(path, "ply\r\nformat ascii 1.0\r\n"
                   "element vertex 3\r\nproperty double x\r\n"
                   "property double y\r\nproperty double z\r\n"
                   "element face 1\r\n"
                   "property list uchar int vertex_indices\r\n"
                   "end_header\r\n"
                   "  1.5\t-2e-3   7\r\n"
                   "-0\r\n\r\n  1e300 \r\n 2\r\n"
                   "inf nan 0x1p-3\r\n"
                   "3\r\n0 1\r\n2");
  scf_points_t p;
  uint32_t *tri;
  size_t nt;
  mesh_ok(path, &p, &tri, &nt);
  ASSERT_EQ(p.count, 3);
  ASSERT_DBL_SAME(p.xyz[0], 1.5);
  ASSERT_DBL_SAME(p.xyz[1], -2e-3);
  ASSERT_DBL_SAME(p.xyz[2], 7.0);
  ASSERT_DBL_SAME(p.xyz[3], -0.0);
  ASSERT_DBL_SAME(p.xyz[4], 1e300);
  ASSERT_DBL_SAME(p.xyz[5], 2.0);
  ASSERT(isinf(p.xyz[6]) && p.xyz[6] > 0);
  ASSERT(isnan(p.xyz[7]));
  ASSERT_DBL_SAME(p.xyz[8], 0.125);
  ASSERT_EQ(nt, 1);
  ASSERT_EQ(tri[2], 2);
  free(tri);
  scf_points_free(&p);
}

/*
 * Many records of odd sizes, so that records, list items and single
 * values straddle every position of the reader's 64 KiB buffer. Vertex
 * i is (i, -i / 3, i * 0.5 + 0.25), exact in float and double.
 */
static void test_large(void) {
  enum { NV = 40000, NF = 39998 };
  for (int fmt = 0; fmt < FMT_COUNT; fmt++)
    for (int with_list = 0; with_list < 2; with_list++) {
      buf_t b = {0};
      buf_printf(&b,
                 "ply\nformat %s 1.0\nelement vertex %d\n"
                 "property double x\nproperty uchar q\n"
                 "property float y\nproperty double z\n%s"
                 "element face %d\nproperty list uchar uint vertex_indices\n"
                 "property uchar pad\nend_header\n",
                 fmt_name[fmt], NV,
                 with_list ? "property list uchar short extra\n" : "", NF);
      for (int i = 0; i < NV; i++) {
        buf_val(&b, fmt, F64, i);
        buf_val(&b, fmt, U8, i % 251);
        buf_val(&b, fmt, F32, -(double)(i / 3));
        buf_val(&b, fmt, F64, i * 0.5 + 0.25);
        if (with_list) {
          buf_val(&b, fmt, U8, i % 5);
          for (int k = 0; k < i % 5; k++)
            buf_val(&b, fmt, I16, -k);
        }
        buf_eol(&b, fmt);
      }
      for (int f = 0; f < NF; f++) {
        int n = 3 + f % 2;
        buf_val(&b, fmt, U8, n);
        for (int k = 0; k < n; k++)
          buf_val(&b, fmt, U32, (f + k) % NV);
        buf_val(&b, fmt, U8, 9);
        buf_eol(&b, fmt);
      }
      const char *path = tmp_path("large.ply");
      buf_write(&b, path);
      ASSERT(b.n > 4 * 65536);
      buf_free(&b);

      scf_points_t p;
      uint32_t *tri;
      size_t nt;
      mesh_ok(path, &p, &tri, &nt);
      ASSERT_EQ(p.count, NV);
      for (int i = 0; i < NV; i++) {
        ASSERT_DBL_SAME(p.xyz[3 * i], (double)i);
        ASSERT_DBL_SAME(p.xyz[3 * i + 1], -(double)(i / 3));
        ASSERT_DBL_SAME(p.xyz[3 * i + 2], i * 0.5 + 0.25);
      }
      /* Odd faces are quads: two triangles each. */
      ASSERT_EQ(nt, NF + NF / 2);
      size_t t = 0;
      for (int f = 0; f < NF; f++) {
        uint32_t a = (uint32_t)f % NV, c1 = (uint32_t)(f + 1) % NV,
                 c2 = (uint32_t)(f + 2) % NV;
        ASSERT_EQ(tri[3 * t], a);
        ASSERT_EQ(tri[3 * t + 1], c1);
        ASSERT_EQ(tri[3 * t + 2], c2);
        t++;
        if (f % 2) {
          ASSERT_EQ(tri[3 * t], a);
          ASSERT_EQ(tri[3 * t + 1], c2);
          ASSERT_EQ(tri[3 * t + 2], (uint32_t)(f + 3) % NV);
          t++;
        }
      }
      free(tri);
      scf_points_free(&p);
    }
}

/* Bit patterns that differ in every byte, so that a reader swapping the
 * wrong bytes of a big-endian double or float would be caught. */
static void test_big_endian_bytes(void) {
  static const unsigned char be[] = {
      0x3f, 0xf0, 0x00, 0x00, 0x00, 0x00, 0x00, 0x01, /* 1 + 2^-52 */
      0xc0, 0x09, 0x21, 0xfb, 0x54, 0x44, 0x2d, 0x18, /* -pi */
      0x3e, 0xaa, 0xaa, 0xab,                         /* float 1/3 */
      0xff, 0xfe,                                     /* short -2 */
      0x80, 0x00, 0x00, 0x01,                         /* uint 2^31 + 1 */
  };
  buf_t b = {0};
  buf_printf(&b, "ply\nformat binary_big_endian 1.0\nelement vertex 1\n"
                 "property double x\nproperty double y\nproperty float z\n"
                 "property short s\nproperty uint u\nend_header\n");
  buf_put(&b, be, sizeof be);
  const char *path = tmp_path("be.ply");
  buf_write(&b, path);
  buf_free(&b);
  scf_points_t p;
  read_ok(path, &p);
  ASSERT_EQ(p.count, 1);
  ASSERT_DBL_SAME(p.xyz[0], 1.0 + 0x1p-52);
  ASSERT_DBL_SAME(p.xyz[1], -3.141592653589793);
  ASSERT_DBL_SAME(p.xyz[2], (double)(1.0f / 3.0f));
  scf_points_free(&p);

  /* The same properties reordered so that the integers carry the point. */
  b = (buf_t){0};
  buf_printf(&b, "ply\nformat binary_big_endian 1.0\nelement vertex 1\n"
                 "property double a\nproperty double b\nproperty float c\n"
                 "property short y\nproperty uint x\nproperty uchar z\n"
                 "end_header\n");
  buf_put(&b, be, sizeof be);
  buf_put(&b, "\x7f", 1);
  buf_write(&b, path);
  buf_free(&b);
  read_ok(path, &p);
  ASSERT_DBL_SAME(p.xyz[0], 2147483649.0);
  ASSERT_DBL_SAME(p.xyz[1], -2.0);
  ASSERT_DBL_SAME(p.xyz[2], 127.0);
  scf_points_free(&p);
}

int main(void) {
  tmp_init();
  test_types();
  test_faces();
  test_no_faces();
  test_ascii_layout();
  test_large();
  test_big_endian_bytes();
  return sct_finish("files_ply");
}
