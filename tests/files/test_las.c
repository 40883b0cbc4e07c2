/*
 * Reading LAS: files written here byte by byte, in every version (1.0 to
 * 1.4) and every point data record format (0 to 10), with records longer
 * than their format's minimum, variable-length records and a longer header
 * to step over, georeferenced offsets, and enough points that records
 * straddle the reader's buffer. Every coordinate must come back as
 * X * scale + offset computed in double. Then every inconsistency the
 * header can hold, a file cut at every byte, the same file through a pipe
 * (size unknown), and LAZ, which is refused.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "lasbuf.h"
#include "shortcrust_files.h"
#include "tmpdir.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <sys/types.h>
#include <sys/wait.h>

static void read_ok(const char *path, scf_points_t *p) {
  char msg[512];
  int rc = scf_points_read(path, p, msg, sizeof msg);
  if (rc != 0)
    ASSERT_FAIL("reading %s: %s (%s)", path, scf_err_name(rc), msg);
}

static void check_points(const char *path, const las_spec_t *s) {
  scf_points_t p;
  read_ok(path, &p);
  ASSERT_EQ(p.count, s->n);
  for (size_t k = 0; k < s->n; k++)
    for (int a = 0; a < 3; a++) {
      double want = las_value(s->xyz[3 * k + a], s->scale[a], s->offset[a]);
      /* The same bits: exactly the value LAS defines. */
      if (memcmp(&p.xyz[3 * k + a], &want, sizeof want) != 0)
        ASSERT_FAIL("%s: point %zu, axis %d: %.17g, expected %.17g", path, k, a,
                    p.xyz[3 * k + a], want);
    }
  EXPECT_DBL_SAME(p.xyz[3 * s->n - 1],
                  las_value(s->xyz[3 * s->n - 1], s->scale[2], s->offset[2]));
  scf_points_free(&p);
}

/* Reads path as points and expects code rc and no points, with a message
 * that starts with the path and contains both fragments. */
static void expect_fail(const char *path, int rc, const char *frag1,
                        const char *frag2) {
  expect_read_fail(path, 0, rc, frag1, frag2);
}

/* n points of coordinates that reach the limits of int32 and its sign,
 * then pseudo-random ones. */
static int32_t *make_xyz(size_t n) {
  static const int32_t edges[] = {INT32_MIN, INT32_MAX, 0,      -1,
                                  1,         123456,    -98765, 1 << 30};
  int32_t *xyz = malloc(3 * n * sizeof *xyz + 1);
  ASSERT(xyz != NULL);
  uint64_t state = 0x9e3779b97f4a7c15u;
  for (size_t i = 0; i < 3 * n; i++) {
    state = state * 6364136223846793005u + 1442695040888963407u;
    xyz[i] = i < sizeof edges / sizeof edges[0]
                 ? edges[(i * 5) % (sizeof edges / sizeof edges[0])]
                 : (int32_t)(uint32_t)(state >> 32);
  }
  return xyz;
}

/* A survey's usual frame: millimetres from a UTM-sized offset. */
static const double geo_scale[3] = {0.001, 0.001, 0.001};
static const double geo_offset[3] = {500000, 4000000, 100};

/* Every version and format, with the minimum record length and with extra
 * bytes, a longer header and a variable-length record before the points,
 * and scales that differ per axis. */
static void test_versions_and_formats(void) {
  enum { N = 41 };
  int32_t *xyz = make_xyz(N);
  for (unsigned minor = 0; minor <= 4; minor++)
    for (unsigned format = 0; format <= 10; format++)
      for (int variant = 0; variant < 3; variant++) {
        las_spec_t s = {.minor = minor, .format = format, .n = N, .xyz = xyz};
        memcpy(s.scale, geo_scale, sizeof s.scale);
        memcpy(s.offset, geo_offset, sizeof s.offset);
        if (variant >= 1) {
          s.record_len = min_len[format] + 3 + 11 * (unsigned)variant;
          s.vlr_payload = 17;
        }
        if (variant == 2) {
          s.extra_header = 9;
          s.scale[0] = 0.01;
          s.scale[1] = 0.25;
          s.scale[2] = 1e-7;
          s.offset[0] = -1234.5;
          s.offset[1] = 0;
          s.offset[2] = 0.1;
        }
        char name[64];
        snprintf(name, sizeof name, "v1%u_f%u_%d.las", minor, format, variant);
        const char *path = tmp_path(name);
        buf_t b;
        las_build(&b, &s);
        buf_write(&b, path);
        buf_free(&b);
        check_points(path, &s);
      }
  free(xyz);
}

/* Enough points that records straddle the 64 KiB buffer at every phase;
 * the extension in capitals; a file without points. */
static void test_large_and_edges(void) {
  enum { N = 100003 };
  int32_t *xyz = make_xyz(N);
  unsigned formats[2] = {3, 10};
  for (int i = 0; i < 2; i++) {
    las_spec_t s = {.minor = 4, .format = formats[i], .n = N, .xyz = xyz};
    s.record_len = min_len[formats[i]] + 1;
    memcpy(s.scale, geo_scale, sizeof s.scale);
    memcpy(s.offset, geo_offset, sizeof s.offset);
    buf_t b;
    las_build(&b, &s);
    const char *path = tmp_path(i ? "LARGE.LAS" : "large.Las");
    buf_write(&b, path);
    ASSERT(b.n > 40 * 65536);
    buf_free(&b);
    check_points(path, &s);
  }
  free(xyz);

  las_spec_t s = {.minor = 2, .format = 1, .scale = {1, 1, 1}};
  buf_t b;
  las_build(&b, &s);
  const char *path = tmp_path("empty.las");
  buf_write(&b, path);
  buf_free(&b);
  scf_points_t p;
  read_ok(path, &p);
  ASSERT(p.xyz == NULL);
  ASSERT_EQ(p.count, 0);

  /* 1.4 with formats 0 to 5 may fill in both counts, or (some writers)
   * only the legacy one. */
  int32_t one[3] = {1, 2, 3};
  s = (las_spec_t){.minor = 4, .format = 1, .n = 1, .xyz = one};
  memcpy(s.scale, geo_scale, sizeof s.scale);
  las_build(&b, &s);
  poke(&b, AT_COUNT_64, 0, 8);
  path = tmp_path("legacy_only.las");
  buf_write(&b, path);
  buf_free(&b);
  check_points(path, &s);
}

/* A valid 1.4 file of three format 3 points with a variable-length record,
 * for the malformed variants below. */
static void small_file(buf_t *b, unsigned minor) {
  static const int32_t xyz[9] = {1, 2, 3, -4, -5, -6, 7000, 8000, 9000};
  las_spec_t s = {.minor = minor, .format = 3, .n = 3, .xyz = xyz};
  s.vlr_payload = 20;
  memcpy(s.scale, geo_scale, sizeof s.scale);
  memcpy(s.offset, geo_offset, sizeof s.offset);
  las_build(b, &s);
}

static void write_and_fail(buf_t *b, const char *name, int rc,
                           const char *frag1, const char *frag2) {
  const char *path = tmp_path(name);
  buf_write(b, path);
  buf_free(b);
  expect_fail(path, rc, frag1, frag2);
}

/* One inconsistency at a time, each named at its field. */
static void test_bad_headers(void) {
  buf_t b;
  small_file(&b, 4);
  memcpy(b.p, "LASG", 4);
  write_and_fail(&b, "magic.las", SCF_EFORMAT,
                 "byte 0: ", "not a LAS file: it does not start with 'LASF'");
  write_text(tmp_path("text.las"), "1 2 3\n");
  expect_fail(tmp_path("text.las"), SCF_EFORMAT, "byte 0: ", "not a LAS");

  small_file(&b, 4);
  b.p[AT_VERSION] = 2;
  b.p[AT_VERSION + 1] = 0;
  write_and_fail(&b, "v20.las", SCF_EUNSUPPORTED,
                 "byte 24: ", "LAS version 2.0 (1.0 to 1.4 are supported)");
  small_file(&b, 4);
  b.p[AT_VERSION + 1] = 5;
  write_and_fail(&b, "v15.las", SCF_EUNSUPPORTED,
                 "byte 24: ", "LAS version 1.5");

  small_file(&b, 4);
  poke(&b, AT_HEADER_SIZE, 235, 2);
  write_and_fail(&b, "hsize.las", SCF_EFORMAT, "byte 94: ",
                 "header size 235 is smaller than the 375 bytes of a LAS 1.4 "
                 "header");
  small_file(&b, 2);
  poke(&b, AT_HEADER_SIZE, 226, 2);
  write_and_fail(&b, "hsize12.las", SCF_EFORMAT,
                 "byte 94: ", "smaller than the 227 bytes of a LAS 1.2 header");

  /* A header size beyond the file: a header shorter than it says. */
  small_file(&b, 2);
  poke(&b, AT_HEADER_SIZE, 60000, 2);
  poke(&b, AT_DATA_OFFSET, 60000, 4);
  size_t n = b.n;
  char want[64];
  snprintf(want, sizeof want, "byte %zu: ", n);
  write_and_fail(&b, "hshort.las", SCF_EFORMAT, want,
                 "file ends inside the public header, whose size is 60000 "
                 "bytes");

  small_file(&b, 3);
  poke(&b, AT_DATA_OFFSET, 234, 4);
  write_and_fail(&b, "offset_low.las", SCF_EFORMAT, "byte 96: ",
                 "offset to point data 234 lies inside the 235-byte header");
  small_file(&b, 4);
  poke(&b, AT_DATA_OFFSET, 4000000000u, 4);
  write_and_fail(&b, "offset_high.las", SCF_EFORMAT, "byte 96: ",
                 "the point data start at byte 4000000000, beyond the end of "
                 "the file");

  small_file(&b, 4);
  b.p[AT_FORMAT] = 11;
  write_and_fail(&b, "format11.las", SCF_EUNSUPPORTED,
                 "byte 104: ", "point data format 11 (0 to 10 are supported)");
  small_file(&b, 4);
  b.p[AT_FORMAT] = 63;
  write_and_fail(&b, "format63.las", SCF_EUNSUPPORTED,
                 "byte 104: ", "point data format 63");

  for (unsigned f = 0; f <= 10; f++) {
    small_file(&b, 4);
    b.p[AT_FORMAT] = (unsigned char)f;
    poke(&b, AT_RECORD_LEN, min_len[f] - 1, 2);
    char name[32], frag[96];
    snprintf(name, sizeof name, "short_rec%u.las", f);
    snprintf(frag, sizeof frag,
             "point record length %u is smaller than the %u bytes of point "
             "data format %u",
             min_len[f] - 1, min_len[f], f);
    write_and_fail(&b, name, SCF_EFORMAT, "byte 105: ", frag);
  }

  /* Counts beyond the file, legacy (1.2) and 64-bit (1.4); the largest
   * overflows 64 bits. No memory is asked for them. */
  small_file(&b, 2);
  poke(&b, AT_COUNT, 4, 4);
  write_and_fail(&b, "count12.las", SCF_EFORMAT, "byte 107: ",
                 "the header declares 4 points of 34 bytes, which need 136 "
                 "bytes");
  small_file(&b, 4);
  poke(&b, AT_COUNT, 0, 4);
  poke(&b, AT_COUNT_64, 1000000000000u, 8);
  write_and_fail(&b, "count14.las", SCF_EFORMAT,
                 "byte 247: ", "declares 1000000000000 points of 34 bytes");
  small_file(&b, 4);
  poke(&b, AT_COUNT, 0, 4);
  poke(&b, AT_COUNT_64, UINT64_MAX, 8);
  write_and_fail(&b, "count_max.las", SCF_EFORMAT,
                 "byte 247: ", "declares 18446744073709551615 points");
  small_file(&b, 4);
  poke(&b, AT_COUNT, 2, 4);
  write_and_fail(&b, "counts_differ.las", SCF_EFORMAT, "byte 107: ",
                 "the legacy point count 2 differs from the 64-bit point "
                 "count 3 at byte 247");

  static const struct {
    size_t at;
    double v;
    const char *frag;
  } numbers[] = {
      {AT_SCALE, 0.0, "x scale factor 0 is not a finite, non-zero number"},
      {AT_SCALE + 8, NAN, "y scale factor nan"},
      {AT_SCALE + 16, INFINITY, "z scale factor inf"},
      {AT_SCALE, -0.0, "x scale factor -0"},
      {AT_OFFSET, NAN, "x offset nan is not a finite number"},
      {AT_OFFSET + 16, -INFINITY, "z offset -inf"},
  };
  for (size_t i = 0; i < sizeof numbers / sizeof numbers[0]; i++) {
    small_file(&b, 4);
    poke_f64(&b, numbers[i].at, numbers[i].v);
    char name[32], at[32];
    snprintf(name, sizeof name, "number%zu.las", i);
    snprintf(at, sizeof at, "byte %zu: ", numbers[i].at);
    write_and_fail(&b, name, SCF_EFORMAT, at, numbers[i].frag);
  }
  /* A negative scale is unusual but well defined. */
  int32_t one[3] = {10, -20, 30};
  las_spec_t s = {.minor = 2,
                  .format = 0,
                  .n = 1,
                  .xyz = one,
                  .scale = {-0.5, 2, -1e-3},
                  .offset = {1, 2, 3}};
  las_build(&b, &s);
  buf_write(&b, tmp_path("negative_scale.las"));
  buf_free(&b);
  check_points(tmp_path("negative_scale.las"), &s);
}

/* The file cut at every byte, in 1.2 and 1.4: each cut is named where the
 * file first falls short of what the header promises. */
static void test_every_cut(void) {
  for (unsigned minor = 2; minor <= 4; minor += 2) {
    buf_t b;
    small_file(&b, minor);
    size_t least = header_len(minor), data = least + 54 + 20;
    ASSERT_EQ(b.n, data + 3 * 34);
    const char *path = tmp_path("cut.las");
    char want1[64], want2[160];
    for (size_t cut = 0; cut < b.n; cut++) {
      write_bytes(path, b.p, cut);
      if (cut < 4) {
        expect_fail(path, SCF_EFORMAT, "byte 0: ", "not a LAS file");
        continue;
      }
      snprintf(want1, sizeof want1, "byte %zu: ", cut);
      if (cut < 26) {
        expect_fail(path, SCF_EFORMAT, want1,
                    "file ends inside the public header");
      } else if (cut < least) {
        snprintf(want2, sizeof want2,
                 "file ends inside the %zu-byte public header of LAS 1.%u "
                 "(got %zu bytes)",
                 least, minor, cut);
        expect_fail(path, SCF_EFORMAT, want1, want2);
      } else if (cut < data) {
        snprintf(want2, sizeof want2,
                 "the point data start at byte %zu, beyond the end of the "
                 "file (%zu bytes)",
                 data, cut);
        expect_fail(path, SCF_EFORMAT, "byte 96: ", want2);
      } else {
        snprintf(want1, sizeof want1,
                 "byte %d: ", minor == 4 ? AT_COUNT_64 : AT_COUNT);
        snprintf(want2, sizeof want2,
                 "the header declares 3 points of 34 bytes, which need 102 "
                 "bytes from byte %zu, but the file has %zu",
                 data, cut);
        expect_fail(path, SCF_EFORMAT, want1, want2);
      }
    }
    buf_free(&b);
  }
}

/*
 * Through a pipe the file's size is unknown: the header's counts cannot
 * be checked first, and a short file is found while reading, at the exact
 * record. A child process writes len bytes of b into the pipe.
 */
static int read_through_fifo(const buf_t *b, size_t len, scf_points_t *p,
                             char *msg, size_t msg_len) {
  const char *path = tmp_path("pipe.las");
  unlink(path);
  ASSERT(mkfifo(path, 0600) == 0);
  pid_t pid = fork();
  ASSERT(pid >= 0);
  if (pid == 0) {
    signal(SIGPIPE, SIG_IGN);
    int fd = open(path, O_WRONLY);
    size_t done = 0;
    while (fd >= 0 && done < len) {
      ssize_t w = write(fd, b->p + done, len - done);
      if (w <= 0)
        break;
      done += (size_t)w;
    }
    _exit(0);
  }
  int rc = scf_points_read(path, p, msg, msg_len);
  int status;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR)
    ;
  return rc;
}

static void test_pipe(void) {
  buf_t b;
  small_file(&b, 4);
  scf_points_t p;
  char msg[512];
  ASSERT_EQ(read_through_fifo(&b, b.n, &p, msg, sizeof msg), 0);
  ASSERT_EQ(p.count, 3);
  ASSERT_DBL_SAME(p.xyz[3], las_value(-4, 0.001, 500000));
  ASSERT_DBL_SAME(p.xyz[8], las_value(9000, 0.001, 100));
  scf_points_free(&p);

  static const struct {
    size_t cut;
    const char *where, *what;
  } cuts[] = {
      {300, "byte 300: ", "file ends inside the 375-byte public header"},
      {400, "byte 400: ", "file ends before the point data at byte 449"},
      {449 + 34, "byte 483: ", "file ends before point 1 of 3"},
      {449 + 34 + 12, "byte 483: ",
       "file ends inside point 1 of 3 (expected 34 bytes, got 12)"},
      {449 + 101, "byte 517: ",
       "file ends inside point 2 of 3 (expected 34 bytes, got 33)"},
  };
  for (size_t i = 0; i < sizeof cuts / sizeof cuts[0]; i++) {
    ASSERT(cuts[i].cut < b.n);
    int rc = read_through_fifo(&b, cuts[i].cut, &p, msg, sizeof msg);
    EXPECT_EQ(rc, SCF_EFORMAT);
    ASSERT(p.xyz == NULL && p.count == 0);
    EXPECT_STR_CONTAINS(msg, cuts[i].where);
    EXPECT_STR_CONTAINS(msg, cuts[i].what);
  }
  buf_free(&b);
}

/* LAZ: by the extension, before the file is looked at, and by the
 * compression bits of the format byte in a .las file. Neither is a mesh. */
static void test_laz(void) {
  const char *path = tmp_path("missing.laz");
  expect_fail(path, SCF_EUNSUPPORTED, "LAZ (compressed LAS) is not supported",
              "laszip -i in.laz -o out.las");
  expect_fail(tmp_path("POINTS.LAZ"), SCF_EUNSUPPORTED,
              "pdal translate in.laz out.las", NULL);
  unsigned char bits[3] = {0x80, 0x40, 0xc0};
  for (int i = 0; i < 3; i++) {
    buf_t b;
    small_file(&b, 2);
    b.p[AT_FORMAT] |= bits[i];
    char name[32], frag[96];
    snprintf(name, sizeof name, "compressed%d.las", i);
    snprintf(frag, sizeof frag,
             "point data format byte %u marks LAZ compression",
             (unsigned)(3 | bits[i]));
    write_and_fail(&b, name, SCF_EUNSUPPORTED, "byte 104: ", frag);
    expect_fail(tmp_path(name), SCF_EUNSUPPORTED, "laszip -i", "pdal");
  }

  buf_t b;
  small_file(&b, 2);
  buf_write(&b, tmp_path("mesh.las"));
  buf_free(&b);
  const char *names[2] = {"mesh.las", "mesh.laz"};
  for (int i = 0; i < 2; i++) {
    scf_points_t p;
    uint32_t *tri;
    size_t nt;
    char msg[256];
    ASSERT_EQ(scf_mesh_read(tmp_path(names[i]), &p, &tri, &nt, msg, sizeof msg),
              SCF_EUNSUPPORTED);
    ASSERT_STR_CONTAINS(msg, "unknown extension");
    ASSERT_STR_CONTAINS(msg, "expected .ply, .off, .obj or .stl");
  }
}

/* The attributes, from the specification's record layouts (a table of
 * this test's own): every format's fields come back as properties with
 * the record's values, the packed return and class bits unpacked. */
static void test_attributes(void) {
  static const struct {
    unsigned gps, rgb, nir; /* offsets, 0 when absent */
  } lay[11] = {{0, 0, 0},    {20, 0, 0},  {0, 20, 0},  {20, 28, 0},
               {20, 0, 0},   {20, 28, 0}, {22, 0, 0},  {22, 30, 0},
               {22, 30, 36}, {22, 0, 0},  {22, 30, 36}};
  enum { NP = 40 };
  int32_t *xyz = make_xyz(NP);
  for (unsigned format = 0; format <= 10; format++) {
    las_spec_t spec = {4,         format, 0,  0, 0, {0.01, 0.01, 0.01},
                       {0, 0, 0}, NP,     xyz};
    buf_t b;
    las_build(&b, &spec);
    const char *path = tmp_path("attrs.las");
    buf_write(&b, path);
    scf_points_t pts;
    scf_attrs_t a;
    char msg[256];
    ASSERT_MSG(scf_points_read_attrs(path, &pts, &a, msg, sizeof msg) == 0,
               "format %u: %s", format, msg);
    const size_t want = 4 + (lay[format].gps ? 1 : 0) +
                        (lay[format].rgb ? 3 : 0) + (lay[format].nir ? 1 : 0);
    EXPECT_MSG(a.count == want && a.points == NP,
               "format %u: %zu properties for %zu points", format, a.count,
               a.points);
    const int wide = format >= 6;
    for (size_t k = 0; k < NP && a.count == want; k++) {
      const unsigned char *rec = b.p + b.n - (NP - k) * min_len[format];
      const unsigned char *ar = a.data + k * a.stride;
#define PROP(name) (ar + a.props[scf_attrs_find(&a, name)].offset)
      EXPECT(memcmp(PROP("intensity"), rec + 12, 2) == 0);
      EXPECT_EQ(*PROP("return_number"), wide ? rec[14] & 15 : rec[14] & 7);
      EXPECT_EQ(*PROP("number_of_returns"),
                wide ? rec[14] >> 4 : (rec[14] >> 3) & 7);
      EXPECT_EQ(*PROP("classification"), wide ? rec[16] : rec[15] & 31);
      if (lay[format].gps)
        EXPECT(memcmp(PROP("gps_time"), rec + lay[format].gps, 8) == 0);
      if (lay[format].rgb)
        EXPECT(memcmp(PROP("red"), rec + lay[format].rgb, 2) == 0 &&
               memcmp(PROP("green"), rec + lay[format].rgb + 2, 2) == 0 &&
               memcmp(PROP("blue"), rec + lay[format].rgb + 4, 2) == 0);
      if (lay[format].nir)
        EXPECT(memcmp(PROP("nir"), rec + lay[format].nir, 2) == 0);
#undef PROP
    }
    scf_points_free(&pts);
    scf_attrs_free(&a);
    buf_free(&b);
  }
  free(xyz);
}

int main(void) {
  tmp_init();
  test_versions_and_formats();
  test_large_and_edges();
  test_bad_headers();
  test_every_cut();
  test_pipe();
  test_laz();
  test_attributes();
  return sct_finish("files_las");
}
