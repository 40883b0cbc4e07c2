/*
 * Malformed input, one kind at a time: each must give its code and a
 * message naming the file, the line or byte offset and what was expected
 * there, and leave the outputs zeroed. A binary PLY file is cut at every
 * byte, and every cut must be reported at the exact offset.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "tmpdir.h"
#include "shortcrust_files.h"
#include "plybuf.h"

typedef struct bad_case {
  const char *name; /* the extension chooses the reader */
  const char *text;
  int mesh;
  int rc;
  const char *frag1, *frag2;
} bad_case_t;

#define VX "property float x\nproperty float y\nproperty float z\n"
/* Three OFF vertices, long enough for the size check of one face. */
#define V3 "0.0 0.0 0.0\n1.0 0.0 0.0\n0.0 1.0 0.0\n"

static const bad_case_t bad_headers[] = {
    {"empty.ply", "", 0, SCF_EFORMAT, "line 1: ", "not a PLY file"},
    {"upper.ply", "PLY\nformat ascii 1.0\n", 0, SCF_EFORMAT,
     "line 1: ", "first line is not 'ply'"},
    {"noformat.ply", "ply\nelement vertex 0\n" VX "end_header\n", 0,
     SCF_EFORMAT, "line 6: ", "no format line"},
    {"badformat.ply", "ply\nformat binary 1.0\n", 0, SCF_EFORMAT,
     "line 2: ", "unknown PLY format 'binary'"},
    {"version.ply", "ply\nformat ascii 2.0\n", 0, SCF_EUNSUPPORTED,
     "line 2: ", "version '2.0'"},
    {"shortformat.ply", "ply\nformat ascii\n", 0, SCF_EFORMAT,
     "line 2: ", "expected 'format <type> 1.0'"},
    {"twoformats.ply", "ply\nformat ascii 1.0\nformat ascii 1.0\n", 0,
     SCF_EFORMAT, "line 3: ", "second format line"},
    {"nocount.ply", "ply\nformat ascii 1.0\nelement vertex\n", 0,
     SCF_EFORMAT, "line 3: ", "expected 'element <name> <count>'"},
    {"negcount.ply", "ply\nformat ascii 1.0\nelement vertex -1\n", 0,
     SCF_EFORMAT, "line 3: ", "expected a count for element 'vertex'"},
    {"hugecount.ply",
     "ply\nformat ascii 1.0\nelement vertex 99999999999999999999\n", 0,
     SCF_EFORMAT, "line 3: ", "got '99999999999999999999'"},
    {"early.ply", "ply\nformat ascii 1.0\nproperty float x\n", 0,
     SCF_EFORMAT, "line 3: ", "property before any element"},
    {"type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty real x\n",
     0, SCF_EFORMAT, "line 4: ", "unknown property type 'real'"},
    {"listcount.ply",
     "ply\nformat ascii 1.0\nelement face 1\n"
     "property list float int vertex_indices\n",
     0, SCF_EFORMAT, "line 4: ", "count type 'float' is not an integer"},
    {"listname.ply",
     "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int\n", 0,
     SCF_EFORMAT, "line 4: ", "expected 'property <type> <name>'"},
    {"keyword.ply", "ply\nformat ascii 1.0\ncomment fine\nelements vertex 1\n",
     0, SCF_EFORMAT, "line 4: ", "unknown header keyword 'elements'"},
    {"noend.ply", "ply\nformat ascii 1.0\nelement vertex 1\n" VX, 0,
     SCF_EFORMAT, "line 6: ", "file ends inside the header"},
    {"novertex.ply",
     "ply\nformat ascii 1.0\nelement point 1\n" VX "end_header\n1 2 3\n", 0,
     SCF_EFORMAT, "line 7: ", "no vertex element"},
    {"noz.ply",
     "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
     "property float y\nproperty float w\nend_header\n1 2 3\n",
     0, SCF_EFORMAT, "line 7: ", "no property 'z'"},
    {"listx.ply",
     "ply\nformat ascii 1.0\nelement vertex 1\nproperty list uchar float x\n"
     "property float y\nproperty float z\nend_header\n1 2 3\n",
     0, SCF_EFORMAT, "line 7: ", "vertex property 'x' is a list"},
    {"twovertex.ply",
     "ply\nformat ascii 1.0\nelement vertex 1\n" VX "element vertex 1\n" VX
     "end_header\n",
     0, SCF_EFORMAT, "line 11: ", "two vertex elements"},
    {"noindices.ply",
     "ply\nformat ascii 1.0\nelement vertex 3\n" VX
     "element face 1\nproperty list uchar int corners\nend_header\n"
     "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
     1, SCF_EFORMAT, "line 9: ", "no vertex_indices list"},
    {"floatindices.ply",
     "ply\nformat ascii 1.0\nelement vertex 3\n" VX
     "element face 1\nproperty list uchar float vertex_indices\nend_header\n"
     "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
     1, SCF_EFORMAT, "line 9: ", "not of an integer type"},
};

static void run_cases(const bad_case_t *cases, size_t n) {
  for (size_t i = 0; i < n; i++) {
    const char *path = tmp_path(cases[i].name);
    write_text(path, cases[i].text);
    expect_read_fail(path, cases[i].mesh, cases[i].rc, cases[i].frag1,
                     cases[i].frag2);
  }
}

/* The face element is only a problem for a mesh: as points the same files
 * read fine. */
static void test_bad_headers(void) {
  run_cases(bad_headers, sizeof bad_headers / sizeof bad_headers[0]);
  scf_points_t p;
  char msg[256];
  ASSERT_EQ(scf_points_read(tmp_path("noindices.ply"), &p, msg, sizeof msg),
               0);
  ASSERT_EQ(p.count, 3);
  scf_points_free(&p);
}

/*
 * Counts a header declares that the rest of the file cannot hold. The
 * counts are far beyond memory, so only a check made before allocating
 * gives EFORMAT here rather than ENOMEM.
 */
static void test_counts_beyond_file(void) {
  /* 2^60 vertices of 12 bytes, three present; the header is 110 bytes. */
  buf_t b = {0};
  buf_printf(&b, "ply\nformat binary_little_endian 1.0\n"
                 "element vertex 1152921504606846976\n" VX "end_header\n");
  size_t header = b.n;
  for (int i = 0; i < 9; i++)
    buf_val(&b, FMT_LE, F32, i);
  const char *path = tmp_path("huge.ply");
  buf_write(&b, path);
  char want[128];
  snprintf(want, sizeof want, "byte %zu: ", header + 36);
  expect_read_fail(path, 0, SCF_EFORMAT, want,
                   "file ends before vertex 3 of 1152921504606846976");
  buf_free(&b);

  /* A count whose size overflows 64 bits. */
  b = (buf_t){0};
  buf_printf(&b, "ply\nformat binary_big_endian 1.0\n"
                 "element vertex 9223372036854775807\n"
                 "property double x\nproperty double y\nproperty double z\n"
                 "end_header\n");
  header = b.n;
  buf_val(&b, FMT_BE, F64, 1);
  path = tmp_path("overflow.ply");
  buf_write(&b, path);
  snprintf(want, sizeof want, "byte %zu: ", header);
  expect_read_fail(
      path, 0, SCF_EFORMAT, want,
      "file ends inside vertex 0 of 9223372036854775807 (expected 24 "
      "bytes, got 8)");
  buf_free(&b);

  /* An element before the vertices, with lists so that its size is only a
   * lower bound: the message points at the end of the header. */
  b = (buf_t){0};
  buf_printf(&b, "ply\nformat binary_little_endian 1.0\n"
                 "element junk 1000000000000\nproperty list uchar int l\n"
                 "element vertex 1\n" VX "end_header\n");
  header = b.n;
  buf_put(&b, "\0\0\0", 3);
  path = tmp_path("junk.ply");
  buf_write(&b, path);
  snprintf(want, sizeof want, "byte %zu: ", header);
  expect_read_fail(path, 0, SCF_EFORMAT, want,
                   "declares 1000000000000 junk records");
  buf_free(&b);

  /* Faces: only a mesh read needs them. */
  b = (buf_t){0};
  buf_printf(&b, "ply\nformat binary_little_endian 1.0\nelement vertex 3\n" VX
                 "element face 4000000000\n"
                 "property list uchar int vertex_indices\nend_header\n");
  header = b.n;
  for (int i = 0; i < 9; i++)
    buf_val(&b, FMT_LE, F32, i);
  buf_val(&b, FMT_LE, U8, 3);
  for (int i = 0; i < 3; i++)
    buf_val(&b, FMT_LE, I32, i);
  path = tmp_path("faces.ply");
  buf_write(&b, path);
  snprintf(want, sizeof want, "byte %zu: ", header);
  expect_read_fail(path, 1, SCF_EFORMAT, want, "4000000000 face records");
  buf_free(&b);
  scf_points_t p;
  char msg[256];
  ASSERT_EQ(scf_points_read(path, &p, msg, sizeof msg), 0);
  ASSERT_EQ(p.count, 3);
  scf_points_free(&p);

  static const bad_case_t text[] = {
      {"huge_ascii.ply",
       "ply\nformat ascii 1.0\nelement vertex 1000000000000\n" VX
       "end_header\n1 2 3\n4 5 6\n",
       0, SCF_EFORMAT, "line 7: ", "declares 1000000000000 vertex"},
      /* Enough bytes for the size check, too few values. */
      {"short_ascii.ply",
       "ply\nformat ascii 1.0\nelement vertex 3\n" VX "end_header\n"
       "1.0 2.0 3.0\n4.0 5.0 6.0\n7.0 8.0\n",
       0, SCF_EFORMAT,
       "line 10: ", "file ends inside vertex 2 of 3 (expected property 'z')"},
      {"short_list.ply",
       "ply\nformat ascii 1.0\nelement vertex 3\n" VX
       "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
       "1.0 2.0 3.0\n4.0 5.0 6.0\n7.0 8.0 9.0\n3 0 1\n",
       1, SCF_EFORMAT, "line 13: ",
       "file ends inside face 0 of 1 (expected an item of list "
       "'vertex_indices')"},
      {"huge.off", "OFF\n# counts\n1000000000 0 0\n0 0 0\n", 0, SCF_EFORMAT,
       "line 3: ", "declares 1000000000 vertices"},
      {"hugefaces.off", "OFF\n3 1000000000 0\n0 0 0\n1 0 0\n0 1 0\n", 1,
       SCF_EFORMAT, "line 2: ", "and faces 1000000000"},
      /* Long enough to pass the size check, but short of the counts. */
      {"short.off", "OFF\n3 0 0\n0.5 0.5 0.5\n1.5 0 0\n", 0, SCF_EFORMAT,
       "line 4: ", "file ends after 2 of 3 vertices"},
      {"shortfaces.off", "OFF\n3 2 0\n" V3 "3 0 1 2\n", 1, SCF_EFORMAT,
       "line 6: ", "file ends after 1 of 2 faces"},
  };
  run_cases(text, sizeof text / sizeof text[0]);

  /* Binary STL: a million triangles declared, one present. */
  unsigned char stl[134];
  memset(stl, 0, sizeof stl);
  memcpy(stl, "binary", 6);
  stl[80] = 0x40;
  stl[81] = 0x42;
  stl[82] = 0x0f;
  path = tmp_path("huge.stl");
  write_bytes(path, stl, sizeof stl);
  expect_read_fail(path, 1, SCF_EFORMAT,
                   "byte 80: ", "declares 1000000 triangles");
  path = tmp_path("tiny.stl");
  write_bytes(path, stl, 40);
  expect_read_fail(path, 1, SCF_EFORMAT,
                   "byte 40: ", "inside the 84-byte binary STL header");
}

/*
 * A binary file at every length short of complete. The layout is recorded
 * piece by piece while the file is built (a piece being what the reader
 * takes in one go: a fixed-size record, a scalar, a list count, a face
 * index or a skipped list), which gives the offset and wording each cut
 * must be reported with.
 */
typedef struct piece {
  size_t start, size, rec_start;
  int rec;
  const char *elem;
} piece_t;

typedef struct layout {
  piece_t pieces[256];
  size_t n;
} layout_t;

static void piece(layout_t *l, const buf_t *b, size_t start, size_t rec_start,
                  int rec, const char *elem) {
  ASSERT(l->n < sizeof l->pieces / sizeof l->pieces[0]);
  l->pieces[l->n++] = (piece_t){start, b->n - start, rec_start, rec, elem};
}

/*
 * Checks the message for a file cut at byte cut. generic, when not NULL,
 * says the reader's size check must catch it (an element whose records
 * vary in size needs more than is left even at its smallest), naming the
 * element with this text and the end of the header; otherwise the piece
 * the cut falls in is named exactly.
 */
static void check_cut(const char *path, int mesh, const layout_t *l,
                      size_t header, size_t cut, const char *generic) {
  char want1[96], want2[160];
  if (cut + 1 == header) {
    /* Only the line end after end_header is missing: the header is whole
     * and the data, all of it missing, begins where the file ends. */
    snprintf(want1, sizeof want1, "byte %zu: ", cut);
    expect_read_fail(path, mesh, SCF_EFORMAT, want1,
                     generic ? generic : "file ends before vertex 0 of 5");
    return;
  }
  if (cut < header) {
    /* Inside the header the reader works in lines. A cut can also leave
     * a valid-looking but unsupported line ("format ascii 1"). */
    char msg[256];
    scf_points_t p;
    uint32_t *tri;
    size_t nt;
    int rc = mesh ? scf_mesh_read(path, &p, &tri, &nt, msg, sizeof msg)
                  : scf_points_read(path, &p, msg, sizeof msg);
    if (rc != SCF_EFORMAT && rc != SCF_EUNSUPPORTED)
      ASSERT_FAIL("cut at %zu: %s (%s)", cut, scf_err_name(rc), msg);
    ASSERT_STR_CONTAINS(msg, ": line ");
    return;
  }
  if (generic != NULL) {
    snprintf(want1, sizeof want1, "byte %zu: ", header);
    expect_read_fail(path, mesh, SCF_EFORMAT, want1, generic);
    return;
  }
  const piece_t *pc = NULL;
  for (size_t i = 0; i < l->n && pc == NULL; i++)
    if (l->pieces[i].size > 0 && l->pieces[i].start + l->pieces[i].size > cut)
      pc = &l->pieces[i];
  ASSERT(pc != NULL);
  size_t got = cut - pc->start;
  snprintf(want1, sizeof want1, "byte %zu: ", pc->start);
  if (got == 0 && pc->start == pc->rec_start)
    snprintf(want2, sizeof want2, "file ends before %s %d of ", pc->elem,
             pc->rec);
  else
    snprintf(want2, sizeof want2,
             "file ends inside %s %d of %s (expected %zu bytes, got %zu)",
             pc->elem, pc->rec, strcmp(pc->elem, "vertex") ? "4" : "5",
             pc->size, got);
  expect_read_fail(path, mesh, SCF_EFORMAT, want1, want2);
}

static void test_every_cut(void) {
  for (int fmt = FMT_LE; fmt <= FMT_BE; fmt++)
    for (int variant = 0; variant < 2; variant++) {
      /* variant 0: fixed-size vertex records (read whole);
       * variant 1: a list in the vertices (read value by value). */
      buf_t b = {0};
      layout_t l = {.n = 0};
      buf_printf(&b,
                 "ply\nformat %s 1.0\nelement vertex 5\n"
                 "property float x\nproperty uchar q\nproperty double y\n"
                 "%sproperty short z\n"
                 "element face 4\nproperty list uchar int vertex_indices\n"
                 "property uchar flags\nend_header\n",
                 fmt_name[fmt],
                 variant ? "property list uchar float extra\n" : "");
      size_t header = b.n;
      for (int i = 0; i < 5; i++) {
        size_t rec = b.n;
        if (variant == 0) {
          buf_val(&b, fmt, F32, i);
          buf_val(&b, fmt, U8, i);
          buf_val(&b, fmt, F64, -i);
          buf_val(&b, fmt, I16, i);
          piece(&l, &b, rec, rec, i, "vertex");
          continue;
        }
        size_t at = b.n;
        buf_val(&b, fmt, F32, i);
        piece(&l, &b, at, rec, i, "vertex");
        at = b.n;
        buf_val(&b, fmt, U8, i);
        piece(&l, &b, at, rec, i, "vertex");
        at = b.n;
        buf_val(&b, fmt, F64, -i);
        piece(&l, &b, at, rec, i, "vertex");
        at = b.n;
        buf_val(&b, fmt, U8, i % 3);
        piece(&l, &b, at, rec, i, "vertex");
        at = b.n;
        for (int k = 0; k < i % 3; k++)
          buf_val(&b, fmt, F32, k);
        piece(&l, &b, at, rec, i, "vertex");
        at = b.n;
        buf_val(&b, fmt, I16, i);
        piece(&l, &b, at, rec, i, "vertex");
      }
      size_t vertices_end = b.n;
      for (int f = 0; f < 4; f++) {
        size_t rec = b.n, at = b.n;
        buf_val(&b, fmt, U8, 3);
        piece(&l, &b, at, rec, f, "face");
        for (int k = 0; k < 3; k++) {
          at = b.n;
          buf_val(&b, fmt, I32, (f + k) % 5);
          piece(&l, &b, at, rec, f, "face");
        }
        at = b.n;
        buf_val(&b, fmt, U8, 1);
        piece(&l, &b, at, rec, f, "face");
      }
      /* The smallest size the header allows: lists empty. */
      size_t vmin = 5 * (variant ? 4 + 1 + 8 + 1 + 2 : 4 + 1 + 8 + 2);
      size_t fmin = vmin + 4 * 2;
      const char *path = tmp_path("cut.ply");
      for (size_t cut = 0; cut < b.n; cut++) {
        write_bytes(path, b.p, cut);
        size_t rem = cut > header ? cut - header : 0;
        /* Fixed-size vertices are located exactly even by the size
         * check; variable ones only once they are being read. */
        const char *vgeneric =
            variant == 1 && rem < vmin ? "declares 5 vertex records" : NULL;
        if (cut < vertices_end)
          check_cut(path, 0, &l, header, cut, vgeneric);
        check_cut(path, 1, &l, header, cut,
                  rem < vmin   ? vgeneric
                  : rem < fmin ? "declares 4 face records"
                               : NULL);
      }
      buf_write(&b, path);
      scf_points_t p;
      uint32_t *tri;
      size_t nt;
      char msg[256];
      ASSERT_EQ(scf_mesh_read(path, &p, &tri, &nt, msg, sizeof msg), 0);
      ASSERT_EQ(p.count, 5);
      ASSERT_EQ(nt, 4);
      ASSERT_DBL_SAME(p.xyz[13], -4.0);
      free(tri);
      scf_points_free(&p);
      buf_free(&b);
    }
}

/* A token that is not a number is reported with its line. */
static const bad_case_t bad_tokens[] = {
    {"word.xyz", "1 2 3\n4 5 6\n\n7 eight 9\n", 0, SCF_EFORMAT,
     "line 4: ", "expected 3 numbers, got 'eight'"},
    {"suffix.txt", "# c\n1 2 3abc\n", 0, SCF_EFORMAT,
     "line 2: ", "got '3abc'"},
    {"two.xyz", "1 2 3\r\n1 2\r\n", 0, SCF_EFORMAT,
     "line 2: ", "expected 3 numbers, got 2"},
    {"ctrl.xyz", "1 2 \x01\x02x\n", 0, SCF_EFORMAT,
     "line 1: ", "got '??x'"},
    {"long.xyz",
     "1 2 zzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzz\n", 0,
     SCF_EFORMAT,
     "line 1: ", "got 'zzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzz...'"},
    {"vertex.off", "OFF\n2 0 0\n0 0 0\n# x\n1 y 0\n", 0, SCF_EFORMAT,
     "line 5: ", "expected 3 numbers for a vertex, got 'y'"},
    {"counts.off", "OFF\nthree 0 0\n", 0, SCF_EFORMAT,
     "line 2: ", "expected the vertex and face counts, got 'three'"},
    {"index.off", "OFF\n3 1 0\n" V3 "3 0 1 two\n", 1, SCF_EFORMAT,
     "line 6: ", "got 'two'"},
    {"v.obj", "v 0 0 0\nvn 1 2 3\nv 1 2 three\n", 0, SCF_EFORMAT,
     "line 3: ", "expected 3 numbers after 'v', got 'three'"},
    {"f.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", 1, SCF_EFORMAT,
     "line 4: ", "expected a vertex index"},
    {"value.ply",
     "ply\nformat ascii 1.0\nelement vertex 2\n" VX "end_header\n"
     "1 2 3\n4 5 oops\n",
     0, SCF_EFORMAT, "line 9: ", "property 'z' of vertex 1, got 'oops'"},
    {"list.ply",
     "ply\nformat ascii 1.0\nelement vertex 1\n" VX
     "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
     "1 2 3\nthree 0 0 0\n",
     1, SCF_EFORMAT, "line 11: ", "list length for 'vertex_indices'"},
    {"vertex.stl",
     "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n"
     "vertex 1 0 q\n",
     1, SCF_EFORMAT, "line 5: ", "after 'vertex', got 'q'"},
};

/* Faces that name vertices the file does not have, or too few. */
static const bad_case_t bad_faces[] = {
    {"range.ply",
     "ply\nformat ascii 1.0\nelement vertex 3\n" VX
     "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
     "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 3\n",
     1, SCF_EFORMAT,
     "line 14: ", "face 1 refers to vertex 3, but there are 3 vertices"},
    {"negative.ply",
     "ply\nformat ascii 1.0\nelement vertex 3\n" VX
     "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
     "0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n",
     1, SCF_EFORMAT, "line 13: ", "refers to vertex -1"},
    {"two.ply",
     "ply\nformat ascii 1.0\nelement vertex 3\n" VX
     "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
     "0 0 0\n1 0 0\n0 1 0\n2 0 1\n",
     1, SCF_EFORMAT, "line 13: ", "face 0 has 2 vertices"},
    {"range.off", "OFF\n3 1 0\n" V3 "3 0 1 3\n", 1, SCF_EFORMAT,
     "line 6: ", "vertex index below 3 in face 0, got '3'"},
    {"two.off", "OFF\n3 1 0\n" V3 "2 0 1\n", 1, SCF_EFORMAT,
     "line 6: ", "vertex count of at least 3"},
    {"few.off", "OFF\n3 1 0\n" V3 "3 0 1\n", 1, SCF_EFORMAT,
     "line 6: ", "face 0 has 2 of its 3 vertex indices"},
    {"range.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\nf 1 2 4\n", 1,
     SCF_EFORMAT,
     "line 5: ", "face refers to vertex 4, but the file has 3 vertices"},
    {"zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", 1, SCF_EFORMAT,
     "line 4: ", "got '0'"},
    {"before.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n", 1,
     SCF_EFORMAT, "line 4: ", "relative vertex index -4"},
    {"two.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n", 1, SCF_EFORMAT,
     "line 3: ", "face with 2 vertices"},
    {"loop.stl", "solid s\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\n",
     1, SCF_EFORMAT, "line 5: ", "loop with 2 vertices"},
    {"outside.stl", "solid s\nvertex 0 0 0\n", 1, SCF_EFORMAT,
     "line 2: ", "vertex outside an 'outer loop'"},
    {"open.stl", "solid s\nouter loop\nvertex 0 0 0\n", 1, SCF_EFORMAT,
     "file ends inside a facet", NULL},
    {"keyword.stl", "solid s\nfacet normal 0 0 1\nouter loop\nvertx 0 0 0\n", 1,
     SCF_EFORMAT, "line 4: ", "expected an STL keyword, got 'vertx'"},
};

/* Other kinds of text that are not what the extension says. */
static const bad_case_t bad_text[] = {
    {"notoff.off", "# OFF\nOFFICE 1 0 0\n", 0, SCF_EFORMAT,
     "line 2: ", "not an OFF file: expected 'OFF' first, got 'OFFICE'"},
    {"emptyoff.off", "", 0, SCF_EFORMAT, "line 1: ", "not an OFF file"},
    {"four.off", "4OFF\n1 0 0\n0 0 0 0\n", 0, SCF_EUNSUPPORTED,
     "line 1: ", "'4OFF'"},
    {"binary.off", "OFF BINARY\n", 0, SCF_EUNSUPPORTED,
     "line 1: ", "binary OFF"},
    {"nocounts.off", "OFF\n# nothing else\n", 0, SCF_EFORMAT,
     "file ends before the vertex and face counts", NULL},
};

static void test_bad_text(void) {
  run_cases(bad_tokens, sizeof bad_tokens / sizeof bad_tokens[0]);
  run_cases(bad_faces, sizeof bad_faces / sizeof bad_faces[0]);
  run_cases(bad_text, sizeof bad_text / sizeof bad_text[0]);
  /* A NUL inside a line, as in a binary file given a text extension. */
  const char *path = tmp_path("nul.xyz");
  write_bytes(path, "1 2 3\n4 5\0 6\n", 13);
  expect_read_fail(path, 0, SCF_EFORMAT, "line 2: ", "NUL byte");

  /* A binary face list: the offending index is named by its offset. */
  buf_t b = {0};
  buf_printf(&b, "ply\nformat binary_big_endian 1.0\nelement vertex 3\n" VX
                 "element face 2\nproperty list char uint vertex_indices\n"
                 "end_header\n");
  for (int i = 0; i < 9; i++)
    buf_val(&b, FMT_BE, F32, i);
  size_t face1 = b.n + 13;
  buf_val(&b, FMT_BE, I8, 3);
  for (int i = 0; i < 3; i++)
    buf_val(&b, FMT_BE, U32, i);
  buf_val(&b, FMT_BE, I8, 3);
  buf_val(&b, FMT_BE, U32, 2);
  buf_val(&b, FMT_BE, U32, 4000000000.0);
  buf_val(&b, FMT_BE, U32, 1);
  path = tmp_path("range_be.ply");
  buf_write(&b, path);
  char want[64];
  snprintf(want, sizeof want, "byte %zu: ", face1 + 5);
  expect_read_fail(path, 1, SCF_EFORMAT, want,
                   "face 1 refers to vertex 4000000000, but there are 3");
  /* A negative list length. */
  b.p[face1] = 0xff;
  buf_write(&b, path);
  snprintf(want, sizeof want, "byte %zu: ", face1);
  expect_read_fail(path, 1, SCF_EFORMAT, want, "negative list length -1");
  buf_free(&b);

  /* A line longer than the reader takes (64 KiB). */
  path = tmp_path("longline.xyz");
  size_t n = 70000;
  char *text = malloc(n + 16);
  ASSERT(text != NULL);
  memcpy(text, "1 2 3\n", 6);
  memset(text + 6, ' ', n);
  memcpy(text + 6 + n, "4 5 6\n", 6);
  write_bytes(path, text, n + 12);
  free(text);
  expect_read_fail(path, 0, SCF_EFORMAT, "line 2: ", "line longer than");
}

/* Files that cannot be read at all, and extensions that are not known. */
static void test_unreadable(void) {
  expect_read_fail(tmp_path("missing.ply"), 0, SCF_ENOENT, "cannot open", NULL);
  expect_read_fail(tmp_path("missing.obj"), 1, SCF_ENOENT, "cannot open", NULL);
  const char *dir = tmp_path("dir.xyz");
  ASSERT(mkdir(dir, 0700) == 0);
  expect_read_fail(dir, 0, SCF_EIO, "is a directory", NULL);

  /* The extension is judged before the file is looked at. */
  expect_read_fail(tmp_path("points.e57"), 0, SCF_EUNSUPPORTED,
                   "unknown extension '.e57'", "expected .ply, .xyz");
  expect_read_fail(tmp_path("points"), 0, SCF_EUNSUPPORTED, "no file extension",
                   NULL);
  expect_read_fail(tmp_path("dir.ply/points"), 0, SCF_EUNSUPPORTED,
                   "no file extension", NULL);
  expect_read_fail(tmp_path(".ply"), 0, SCF_EUNSUPPORTED, "no file extension",
                   NULL);
  expect_read_fail(tmp_path("points.plyy"), 0, SCF_EUNSUPPORTED,
                   "unknown extension '.plyy'", NULL);
  /* Point-only formats are no meshes, and STL has no point-only use. */
  expect_read_fail(tmp_path("mesh.xyz"), 1, SCF_EUNSUPPORTED,
                   "unknown extension '.xyz'",
                   "expected .ply, .off, .obj or .stl");
  expect_read_fail(tmp_path("mesh.stl"), 0, SCF_EUNSUPPORTED,
                   "unknown extension '.stl'", NULL);
}

/* An index not below the point count: refused before anything is created,
 * in every format, and an existing file stays as it was. */
static void test_write_bad_index(void) {
  static const double xyz[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  static const uint32_t tri[6] = {0, 1, 2, 2, 1, 3};
  for (int fmt = SCF_MESH_FMT_AUTO; fmt <= SCF_MESH_FMT_STL_ASCII; fmt++) {
    char name[32], msg[256];
    snprintf(name, sizeof name, "bad%d.obj", fmt);
    const char *path = tmp_path(name);
    ASSERT_EQ(scf_mesh_write(path, (scf_mesh_format_t)fmt, xyz, 3, tri, 2,
                               NULL, msg, sizeof msg),
                 SCF_EINVAL);
    ASSERT_STR_CONTAINS(msg, path);
    ASSERT_STR_CONTAINS(msg, "triangle 1 refers to point 3, but there are 3");
    struct stat st;
    ASSERT(stat(path, &st) != 0);
    ASSERT_EQ(count_entries(tmp_path(""), ".tmp."), 0);
  }
  const char *path = tmp_path("keep.ply");
  write_text(path, "old contents\n");
  char msg[256];
  ASSERT_EQ(scf_mesh_write(path, SCF_MESH_FMT_AUTO, xyz, 3, tri, 2, NULL, msg,
                             sizeof msg),
               SCF_EINVAL);
  char *s = read_all(path, NULL);
  ASSERT_STR_EQ(s, "old contents\n");
  free(s);
  ASSERT_EQ(count_entries(tmp_path(""), ".tmp."), 0);

  /* Other refusals that come before any file is created. */
  ASSERT_EQ(scf_mesh_write(path, (scf_mesh_format_t)99, xyz, 3, tri, 1, NULL,
                             msg, sizeof msg),
               SCF_EINVAL);
  ASSERT_STR_CONTAINS(msg, "unknown format 99");
  ASSERT_EQ(scf_mesh_write(path, SCF_MESH_FMT_OFF, NULL, 3, tri, 1, NULL, msg,
                             sizeof msg),
               SCF_EINVAL);
  ASSERT_EQ(scf_mesh_write(path, SCF_MESH_FMT_OFF, xyz, 3, NULL, 1, NULL, msg,
                             sizeof msg),
               SCF_EINVAL);
  ASSERT_EQ(scf_mesh_write(NULL, SCF_MESH_FMT_OFF, xyz, 3, tri, 1, NULL, msg,
                             sizeof msg),
               SCF_EINVAL);
  ASSERT_STR_CONTAINS(msg, "(null)");
  ASSERT_EQ(scf_mesh_write(tmp_path("dir.ply/"), SCF_MESH_FMT_OFF, xyz, 3, tri,
                             1, NULL, msg, sizeof msg),
               SCF_EINVAL);
  ASSERT_STR_CONTAINS(msg, "not a file name");
  s = read_all(path, NULL);
  ASSERT_STR_EQ(s, "old contents\n");
  free(s);
}

static void test_arguments(void) {
  char msg[256];
  scf_points_t p = {(double *)msg, 9};
  ASSERT_EQ(scf_points_read(NULL, &p, msg, sizeof msg), SCF_EINVAL);
  ASSERT(p.xyz == NULL && p.count == 0);
  ASSERT_EQ(scf_points_read("a.xyz", NULL, msg, sizeof msg), SCF_EINVAL);
  ASSERT_STR_CONTAINS(msg, "a.xyz: NULL");
  uint32_t *tri = (uint32_t *)msg;
  size_t nt = 3;
  p = (scf_points_t){(double *)msg, 9};
  ASSERT_EQ(scf_mesh_read("a.ply", &p, &tri, NULL, msg, sizeof msg),
               SCF_EINVAL);
  ASSERT(p.xyz == NULL && p.count == 0 && tri == NULL);
  ASSERT_EQ(scf_mesh_read("a.ply", &p, NULL, &nt, msg, sizeof msg),
               SCF_EINVAL);
  ASSERT_EQ(nt, 0);

  /* Messages are cut to the buffer, and no buffer is fine. */
  const char *path = tmp_path("missing.xyz");
  char small[12];
  memset(small, 'x', sizeof small);
  ASSERT_EQ(scf_points_read(path, &p, small, sizeof small), SCF_ENOENT);
  ASSERT_EQ(strlen(small), sizeof small - 1);
  ASSERT(strncmp(small, path, sizeof small - 1) == 0);
  ASSERT_EQ(scf_points_read(path, &p, NULL, 0), SCF_ENOENT);
  memset(small, 'x', sizeof small);
  ASSERT_EQ(scf_points_read(path, &p, small, 0), SCF_ENOENT);
  ASSERT(small[0] == 'x');
  /* A success clears an old message. */
  write_text(tmp_path("ok.xyz"), "1 2 3\n");
  strcpy(msg, "stale");
  ASSERT_EQ(scf_points_read(tmp_path("ok.xyz"), &p, msg, sizeof msg), 0);
  ASSERT_STR_EQ(msg, "");
  scf_points_free(&p);
}

/* One table gives every code its name and text. */
static void test_codes(void) {
  static const struct {
    int code;
    const char *name, *text;
  } codes[] = {
      {SCF_OK, "OK", "success"},
      {SCF_EINVAL, "INVAL", "invalid argument"},
      {SCF_ENOENT, "NOENT", "no such file"},
      {SCF_EIO, "IO", "input/output error"},
      {SCF_EFORMAT, "FORMAT", "malformed file"},
      {SCF_EUNSUPPORTED, "UNSUPPORTED", "unsupported file format"},
      {SCF_ENOMEM, "NOMEM", "out of memory"},
  };
  for (size_t i = 0; i < sizeof codes / sizeof codes[0]; i++) {
    ASSERT_STR_EQ(scf_err_name(codes[i].code), codes[i].name);
    ASSERT_STR_EQ(scf_strerror(codes[i].code), codes[i].text);
    if (i > 0)
      ASSERT_EQ(codes[i].code, -100 - (int)i);
  }
  ASSERT_STR_EQ(scf_err_name(-100), "UNKNOWN");
  ASSERT_STR_EQ(scf_err_name(-107), "UNKNOWN");
  ASSERT_STR_EQ(scf_err_name(1), "UNKNOWN");
  ASSERT_STR_EQ(scf_strerror(-107), "unknown error");
}

int main(void) {
  tmp_init();
  test_bad_headers();
  test_counts_beyond_file();
  test_every_cut();
  test_bad_text();
  test_unreadable();
  test_write_bad_index();
  test_arguments();
  test_codes();
  return sct_finish("files_errors");
}
