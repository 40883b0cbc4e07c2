/*
 * Per-point properties: every scalar property of a PLY file's vertices
 * (each type, in ascii and both binary byte orders, with a list property
 * among them) is read with its name and type and written back on the same
 * vertex of the mesh unchanged, in binary and ascii PLY; the input's
 * normals win over computed ones; OBJ gets the colours; a property can be
 * removed.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <math.h>

#include "plybuf.h"
#include "sct_assert.h"
#include "shortcrust_files.h"

enum { N = 5 };

/* The value of property t of point i, in range for every type. */
static double value(ty_t t, size_t i) {
  const double v = (double)(i * 37 % 101) - 40 + (t >= F32 ? 0.125 : 0);
  return t == U8 || t == U16 || t == U32 ? v + 50 : v;
}

/* A PLY of N points with one property of each type between x and y, a list
 * of bytes after z (which makes the records variable in size), and a
 * face. */
static void write_input(const char *path, int fmt) {
  buf_t b = {0};
  buf_printf(&b, "ply\nformat %s 1.0\nelement vertex %d\nproperty double x\n",
             fmt_name[fmt], N);
  for (int t = 0; t < TY_COUNT; t++)
    buf_printf(&b, "property %s p_%s\n", ty_name[t], ty_name[t]);
  buf_printf(&b, "property float y\nproperty float z\n"
                 "property list uchar uchar tags\nelement face 1\n"
                 "property list uchar int vertex_indices\nend_header\n");
  for (size_t i = 0; i < N; i++) {
    buf_val(&b, fmt, F64, (double)i);
    for (int t = 0; t < TY_COUNT; t++)
      buf_val(&b, fmt, (ty_t)t, value((ty_t)t, i));
    buf_val(&b, fmt, F32, (double)(i * i));
    buf_val(&b, fmt, F32, (double)(i % 2));
    buf_val(&b, fmt, U8, 2);
    buf_val(&b, fmt, U8, 7);
    buf_val(&b, fmt, U8, 9);
    buf_eol(&b, fmt);
  }
  buf_val(&b, fmt, U8, 3);
  for (int k = 0; k < 3; k++)
    buf_val(&b, fmt, I32, k);
  buf_eol(&b, fmt);
  buf_write(&b, path);
  buf_free(&b);
}

/* The properties are those of write_input(), by name, type and value. */
static void check_attrs(const scf_attrs_t *a, const char *what) {
  EXPECT_MSG(a->count == TY_COUNT && a->points == N,
             "%s: %zu properties, %zu "
             "points",
             what, a->count, a->points);
  for (size_t k = 0; k < a->count && k < TY_COUNT; k++) {
    char name[32];
    snprintf(name, sizeof name, "p_%s", ty_name[k]);
    EXPECT_STR_EQ(a->props[k].name, name);
    EXPECT_EQ((int)a->props[k].type, (int)k + 1);
    for (size_t i = 0; i < a->points; i++)
      EXPECT_MSG(
          scf_attrs_value(a, i, k) == ty_round((ty_t)k, value((ty_t)k, i)),
          "%s: point %zu, %s: %g", what, i, name, scf_attrs_value(a, i, k));
  }
}

static void round_trips(void) {
  const uint32_t tri[3] = {0, 1, 2};
  const double normals[3 * N] = {0};
  for (int fmt = 0; fmt < FMT_COUNT; fmt++) {
    const char *in = tmp_path("in.ply");
    write_input(in, fmt);
    char msg[256];
    scf_points_t pts;
    scf_attrs_t a;
    ASSERT_MSG(scf_points_read_attrs(in, &pts, &a, msg, sizeof msg) == 0, "%s",
               msg);
    EXPECT_EQ(pts.count, (size_t)N);
    EXPECT(pts.count == N && pts.xyz[3 * 3 + 1] == 9.0);
    check_attrs(&a, fmt_name[fmt]);
    for (int ascii = 0; ascii < 2; ascii++) {
      const char *out = tmp_path("out.ply");
      EXPECT_MSG(
          scf_mesh_write_attrs(
              out, ascii ? SCF_MESH_FMT_PLY_ASCII : SCF_MESH_FMT_PLY_BINARY,
              pts.xyz, pts.count, tri, 1, normals, &a, msg, sizeof msg) == 0,
          "%s", msg);
      scf_points_t back;
      scf_attrs_t b;
      ASSERT_MSG(scf_points_read_attrs(out, &back, &b, msg, sizeof msg) == 0,
                 "%s", msg);
      /* The computed normals come before the properties. */
      EXPECT_EQ(scf_attrs_find(&b, "nx"), 0);
      EXPECT(scf_attrs_remove(&b, "nx") && scf_attrs_remove(&b, "ny") &&
             scf_attrs_remove(&b, "nz"));
      EXPECT(!scf_attrs_remove(&b, "nx"));
      check_attrs(&b, ascii ? "written ascii" : "written binary");
      scf_points_free(&back);
      scf_attrs_free(&b);
    }
    scf_points_free(&pts);
    scf_attrs_free(&a);
  }
  /* A text file of three columns has none. */
  scf_attrs_t none;
  scf_points_t pts;
  char msg[256];
  write_bytes(tmp_path("p.xyz"), "0 0 0\n1 0 0\n", 12);
  EXPECT_EQ(
      scf_points_read_attrs(tmp_path("p.xyz"), &pts, &none, msg, sizeof msg),
      0);
  EXPECT(none.count == 0 && none.data == NULL);
  scf_points_free(&pts);
}

/* Normals among the input's properties are written instead of computed
 * ones; removing them lets the computed ones through. */
static void input_normals(void) {
  buf_t b = {0};
  buf_printf(&b, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                 "property float y\nproperty float z\nproperty float nx\n"
                 "property float ny\nproperty float nz\nproperty uchar red\n"
                 "property uchar green\nproperty uchar blue\nend_header\n"
                 "0 0 0 0 0 1 255 0 0\n1 0 0 0 0 1 0 255 0\n"
                 "0 1 0 0 0 1 0 0 51\n");
  buf_write(&b, tmp_path("n.ply"));
  buf_free(&b);
  char msg[256];
  scf_points_t pts;
  scf_attrs_t a;
  ASSERT_MSG(
      scf_points_read_attrs(tmp_path("n.ply"), &pts, &a, msg, sizeof msg) == 0,
      "%s", msg);
  const uint32_t tri[3] = {0, 1, 2};
  const double computed[9] = {0, 0, -1, 0, 0, -1, 0, 0, -1};
  EXPECT(scf_mesh_write_attrs(tmp_path("o.ply"), SCF_MESH_FMT_PLY_ASCII,
                              pts.xyz, 3, tri, 1, computed, &a, msg,
                              sizeof msg) == 0);
  scf_points_t back;
  scf_attrs_t c;
  ASSERT(scf_points_read_attrs(tmp_path("o.ply"), &back, &c, msg, sizeof msg) ==
         0);
  int nz = scf_attrs_find(&c, "nz");
  EXPECT(c.count == 6 && nz == 2 && scf_attrs_value(&c, 0, (size_t)nz) == 1.0);
  scf_points_free(&back);
  scf_attrs_free(&c);
  /* OBJ: the colours, scaled to [0, 1]. */
  EXPECT(scf_mesh_write_attrs(tmp_path("o.obj"), SCF_MESH_FMT_OBJ, pts.xyz, 3,
                              tri, 1, NULL, &a, msg, sizeof msg) == 0);
  FILE *f = fopen(tmp_path("o.obj"), "r");
  char line[256] = "", v3[256] = "";
  while (f && fgets(line, sizeof line, f))
    if (strncmp(line, "v ", 2) == 0)
      snprintf(v3, sizeof v3, "%s", line);
  if (f)
    fclose(f);
  EXPECT_STR_EQ(v3, "v 0 1 0 0 0 0.2\n");
  /* ... and the input's normals as vn, not the computed ones. */
  f = fopen(tmp_path("o.obj"), "r");
  int vn_up = 0;
  while (f && fgets(line, sizeof line, f))
    vn_up += strcmp(line, "vn 0 0 1\n") == 0;
  if (f)
    fclose(f);
  EXPECT_EQ(vn_up, 3);
  /* Without them, the computed normals. */
  scf_attrs_remove(&a, "nx");
  scf_attrs_remove(&a, "ny");
  scf_attrs_remove(&a, "nz");
  EXPECT_EQ(a.count, (size_t)3);
  EXPECT(scf_mesh_write_attrs(tmp_path("o.ply"), SCF_MESH_FMT_PLY_BINARY,
                              pts.xyz, 3, tri, 1, computed, &a, msg,
                              sizeof msg) == 0);
  ASSERT(scf_points_read_attrs(tmp_path("o.ply"), &back, &c, msg, sizeof msg) ==
         0);
  nz = scf_attrs_find(&c, "nz");
  EXPECT(c.count == 6 && nz == 2 && scf_attrs_value(&c, 2, (size_t)nz) == -1.0);
  EXPECT_EQ(scf_attrs_value(&c, 2, (size_t)scf_attrs_find(&c, "blue")), 51.0);
  /* Properties for another number of points are refused. */
  EXPECT_EQ(scf_mesh_write_attrs(tmp_path("x.ply"), SCF_MESH_FMT_PLY_BINARY,
                                 pts.xyz, 2, tri, 0, NULL, &a, msg, sizeof msg),
            SCF_EINVAL);
  scf_points_free(&back);
  scf_attrs_free(&c);
  scf_points_free(&pts);
  scf_attrs_free(&a);
}

/* Text columns after x, y, z: doubles named by a .csv header or f0, f1,
 * ...; a line with another number of them fails; a label column is not a
 * property. */
static void text_columns(void) {
  char msg[256];
  scf_points_t pts;
  scf_attrs_t a;
  const char xyz[] = "0 0 0 5 -1.5\n1 0 0 6 2.25 # comment\n";
  write_bytes(tmp_path("c.xyz"), xyz, sizeof xyz - 1);
  ASSERT_MSG(
      scf_points_read_attrs(tmp_path("c.xyz"), &pts, &a, msg, sizeof msg) == 0,
      "%s", msg);
  EXPECT(a.count == 2 && a.points == 2);
  EXPECT(a.count == 2 && strcmp(a.props[0].name, "f0") == 0 &&
         strcmp(a.props[1].name, "f1") == 0 &&
         a.props[1].type == SCF_TYPE_FLOAT64);
  EXPECT(a.count == 2 && scf_attrs_value(&a, 0, 0) == 5 &&
         scf_attrs_value(&a, 1, 1) == 2.25);
  scf_points_free(&pts);
  scf_attrs_free(&a);

  const char csv[] = "x,y,z,intensity,quality\n0,0,0,7,0.5\n1,0,0,8,0.25\n";
  write_bytes(tmp_path("c.csv"), csv, sizeof csv - 1);
  ASSERT_MSG(
      scf_points_read_attrs(tmp_path("c.csv"), &pts, &a, msg, sizeof msg) == 0,
      "%s", msg);
  EXPECT(a.count == 2 && strcmp(a.props[0].name, "intensity") == 0 &&
         strcmp(a.props[1].name, "quality") == 0 &&
         scf_attrs_value(&a, 1, 1) == 0.25);
  /* Into a PLY and back: the same names and values. */
  const uint32_t tri[3] = {0, 1, 1};
  EXPECT(scf_mesh_write_attrs(tmp_path("c.ply"), SCF_MESH_FMT_PLY_BINARY,
                              pts.xyz, 2, tri, 0, NULL, &a, msg,
                              sizeof msg) == 0);
  scf_points_free(&pts);
  scf_attrs_free(&a);
  ASSERT(scf_points_read_attrs(tmp_path("c.ply"), &pts, &a, msg, sizeof msg) ==
         0);
  EXPECT(a.count == 2 && strcmp(a.props[0].name, "intensity") == 0 &&
         scf_attrs_value(&a, 0, 0) == 7 && scf_attrs_value(&a, 1, 1) == 0.25);
  scf_points_free(&pts);
  scf_attrs_free(&a);

  const char ragged[] = "0 0 0 1 2\n1 0 0 3\n";
  write_bytes(tmp_path("r.xyz"), ragged, sizeof ragged - 1);
  EXPECT_EQ(scf_points_read_attrs(tmp_path("r.xyz"), &pts, &a, msg, sizeof msg),
            SCF_EFORMAT);
  EXPECT_STR_CONTAINS(msg, "line 2: 1 columns after x, y, z, but the first "
                           "point had 2");
  EXPECT(pts.count == 0 && a.count == 0 && a.data == NULL);
  /* Without asking, the same file reads as before. */
  EXPECT_EQ(scf_points_read(tmp_path("r.xyz"), &pts, msg, sizeof msg), 0);
  EXPECT_EQ(pts.count, (size_t)2);
  scf_points_free(&pts);

  const char label[] = "0 0 0 wall\n1 0 0 roof 3\n";
  write_bytes(tmp_path("l.xyz"), label, sizeof label - 1);
  EXPECT_EQ(scf_points_read_attrs(tmp_path("l.xyz"), &pts, &a, msg, sizeof msg),
            0);
  EXPECT(pts.count == 2 && a.count == 0);
  scf_points_free(&pts);
}

/* An ascii value that an integer property's type cannot hold is an error
 * naming it (found by the readers' fuzzer: the conversion was undefined);
 * a float property takes any number. */
static void ascii_range(void) {
  static const struct {
    const char *type, *value;
    int ok;
  } cases[] = {{"uchar", "255", 1},       {"uchar", "256", 0},
               {"uchar", "-1", 0},        {"uchar", "2.5", 0},
               {"char", "-128", 1},       {"short", "40000", 0},
               {"uint", "4294967295", 1}, {"int", "7777777777777777777777", 0},
               {"uchar", "nan", 0},       {"float", "1e300", 1}};
  for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
    buf_t b = {0};
    buf_printf(&b,
               "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
               "property float y\nproperty float z\nproperty %s v\n"
               "end_header\n0 0 0 %s\n",
               cases[c].type, cases[c].value);
    buf_write(&b, tmp_path("range.ply"));
    buf_free(&b);
    char msg[256];
    scf_points_t pts;
    scf_attrs_t a;
    int rc =
        scf_points_read_attrs(tmp_path("range.ply"), &pts, &a, msg, sizeof msg);
    EXPECT_MSG(rc == (cases[c].ok ? 0 : SCF_EFORMAT), "%s %s: %d %s",
               cases[c].type, cases[c].value, rc, msg);
    if (!cases[c].ok)
      EXPECT_STR_CONTAINS(msg, "does not fit property 'v'");
    else
      EXPECT(a.count == 1 &&
             (scf_attrs_value(&a, 0, 0) == strtod(cases[c].value, NULL) ||
              isinf(scf_attrs_value(&a, 0, 0))));
    scf_points_free(&pts);
    scf_attrs_free(&a);
  }
}

int main(void) {
  tmp_init();
  round_trips();
  input_normals();
  text_columns();
  ascii_range();
  return sct_finish("files_attrs");
}
