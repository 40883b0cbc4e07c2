/*
 * LAS (ASPRS LIDAR Data Exchange Format), versions 1.0 to 1.4, point data
 * record formats 0 to 10: the x, y, z of every point record and, when
 * asked, its attributes (intensity, returns, classification, GPS time,
 * colour, near infrared). LAZ, its compressed form, is refused with a
 * message that says how to decompress.
 *
 * A LAS file is a public header (227 bytes in 1.0 to 1.2, 235 in 1.3, 375
 * in 1.4, or more when the header size field says so), variable-length
 * records up to the offset to point data, then count fixed-size point
 * records, then perhaps extended variable-length records (1.3 and 1.4),
 * which are not read. All numbers are little-endian.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "scf_internal.h"

#include <math.h>

/*
 * The point data record formats: the smallest record of each and where its
 * fields start, 0 meaning that the format lacks the field (offset 0 is
 * always X). Every record begins with int32 X, Y and Z at 0, 4 and 8; the
 * attributes are read from the columns here (the wave packets are not). Formats
 * 6 to 10 (LAS 1.4) keep the return number and the number of returns in 4 bits
 * each and the classification in a byte of its own ("wide"); formats 0 to 5
 * pack them into 3 + 3 bits and 5 bits plus flags. A record may be longer than
 * its format's minimum: the extra bytes that follow are skipped.
 */
typedef struct las_format {
  uint8_t min_len;   /* bytes */
  uint8_t wide;      /* 1 for formats 6 to 10 */
  uint8_t intensity; /* uint16 */
  uint8_t returns;   /* the byte with the return number */
  uint8_t classes;   /* the classification byte */
  uint8_t gps_time;  /* double */
  uint8_t rgb;       /* 3 x uint16 */
  uint8_t nir;       /* uint16 */
  uint8_t wave;      /* the 29-byte wave packet descriptor */
} las_format_t;

#define LAS_FORMATS 11
static const las_format_t las_formats[LAS_FORMATS] = {
    /* len wide int ret cls gps rgb nir wave */
    {20, 0, 12, 14, 15, 0, 0, 0, 0},     /* 0 */
    {28, 0, 12, 14, 15, 20, 0, 0, 0},    /* 1 */
    {26, 0, 12, 14, 15, 0, 20, 0, 0},    /* 2 */
    {34, 0, 12, 14, 15, 20, 28, 0, 0},   /* 3 */
    {57, 0, 12, 14, 15, 20, 0, 0, 28},   /* 4 */
    {63, 0, 12, 14, 15, 20, 28, 0, 34},  /* 5 */
    {30, 1, 12, 14, 16, 22, 0, 0, 0},    /* 6 */
    {36, 1, 12, 14, 16, 22, 30, 0, 0},   /* 7 */
    {38, 1, 12, 14, 16, 22, 30, 36, 0},  /* 8 */
    {59, 1, 12, 14, 16, 22, 0, 0, 30},   /* 9 */
    {67, 1, 12, 14, 16, 22, 30, 36, 38}, /* 10 */
};

/* Byte offsets of the public header fields that are read. */
enum {
  LAS_VERSION = 24,     /* major, minor: uint8 each */
  LAS_HEADER_SIZE = 94, /* uint16 */
  LAS_DATA_OFFSET = 96, /* uint32 */
  LAS_FORMAT_ID = 104,  /* uint8; bits 7 and 6 mark LAZ */
  LAS_RECORD_LEN = 105, /* uint16 */
  LAS_COUNT = 107,      /* uint32, the legacy count */
  LAS_SCALE = 131,      /* 3 doubles, then 3 doubles of offset */
  LAS_OFFSET = 155,
  LAS_COUNT_64 = 247,  /* uint64, LAS 1.4 */
  LAS_HEADER_MAX = 375 /* the 1.4 header, the largest */
};

#define LAS_DECOMPRESS                                                         \
  "decompress it first, e.g. with LASzip (laszip -i in.laz -o out.las) or "    \
  "PDAL (pdal translate in.laz out.las)"

int scf__refuse_laz(const char *path, char *msg, size_t msg_len) {
  return scf__fail(msg, msg_len, SCF_EUNSUPPORTED, path,
                   "LAZ (compressed LAS) is not supported: " LAS_DECOMPRESS);
}

/*
 * A coordinate as LAS defines it, value * scale + offset, in two
 * statements so that no compiler fuses them into one fma and the result
 * is the same everywhere. The int32 is sign-extended by arithmetic, which,
 * unlike a cast of a large uint32_t, is defined by the standard; compilers
 * make it one instruction.
 */
static inline double las_coord(const unsigned char *b, double scale,
                               double offset) {
  uint32_t u = (uint32_t)scf__load_uint(b, 4, 0);
  int64_t v = (int64_t)u - ((int64_t)(u & 0x80000000u) << 1);
  double scaled = (double)v * scale;
  return scaled + offset;
}

/* The public header's fields that reading the points needs. */
typedef struct las_header {
  unsigned minor, header_size, format, record_len;
  uint64_t data_offset, count;
  int count_at; /* the offset of the count field used, for messages */
  double scale[3], offset[3];
} las_header_t;

static int las_header(scf__rd_t *r, las_header_t *h) {
  const unsigned char *b;
  size_t got;
  int rc = scf__rd_peek(r, LAS_HEADER_MAX, &b, &got);
  if (rc < 0)
    return rc;
  if (got < 4 || memcmp(b, "LASF", 4) != 0)
    return scf__rd_fail_byte(r, 0, SCF_EFORMAT,
                             "not a LAS file: it does not start with 'LASF'");
  if (got < LAS_VERSION + 2)
    return scf__rd_fail_byte(r, got, SCF_EFORMAT,
                             "file ends inside the public header (got %zu "
                             "bytes)",
                             got);
  unsigned major = b[LAS_VERSION];
  h->minor = b[LAS_VERSION + 1];
  if (major != 1 || h->minor > 4)
    return scf__rd_fail_byte(r, LAS_VERSION, SCF_EUNSUPPORTED,
                             "LAS version %u.%u (1.0 to 1.4 are supported)",
                             major, h->minor);
  /* 1.3 added the start of the waveform data, 1.4 the extended counts. */
  size_t least = h->minor >= 4 ? 375 : h->minor == 3 ? 235 : 227;
  if (got < least)
    return scf__rd_fail_byte(r, got, SCF_EFORMAT,
                             "file ends inside the %zu-byte public header of "
                             "LAS 1.%u (got %zu bytes)",
                             least, h->minor, got);
  h->header_size = (unsigned)scf__load_uint(b + LAS_HEADER_SIZE, 2, 0);
  if (h->header_size < least)
    return scf__rd_fail_byte(r, LAS_HEADER_SIZE, SCF_EFORMAT,
                             "header size %u is smaller than the %zu bytes of "
                             "a LAS 1.%u header",
                             h->header_size, least, h->minor);
  h->data_offset = scf__load_uint(b + LAS_DATA_OFFSET, 4, 0);
  if (h->data_offset < h->header_size)
    return scf__rd_fail_byte(r, LAS_DATA_OFFSET, SCF_EFORMAT,
                             "offset to point data %llu lies inside the "
                             "%u-byte header",
                             (scf__ull)h->data_offset, h->header_size);
  unsigned id = b[LAS_FORMAT_ID];
  if (id & 0xc0)
    return scf__rd_fail_byte(r, LAS_FORMAT_ID, SCF_EUNSUPPORTED,
                             "point data format byte %u marks LAZ compression, "
                             "which is not supported: " LAS_DECOMPRESS,
                             id);
  if (id >= LAS_FORMATS)
    return scf__rd_fail_byte(r, LAS_FORMAT_ID, SCF_EUNSUPPORTED,
                             "point data format %u (0 to 10 are supported)",
                             id);
  h->format = id;
  /* A format newer than the version (e.g. 6 in a 1.2 file) is accepted:
   * the header's layout follows from the version and the records' from
   * the format, so nothing is ambiguous. */
  h->record_len = (unsigned)scf__load_uint(b + LAS_RECORD_LEN, 2, 0);
  if (h->record_len < las_formats[id].min_len)
    return scf__rd_fail_byte(r, LAS_RECORD_LEN, SCF_EFORMAT,
                             "point record length %u is smaller than the %u "
                             "bytes of point data format %u",
                             h->record_len, (unsigned)las_formats[id].min_len,
                             id);
  /*
   * LAS 1.4 counts in 64 bits; the 32-bit legacy count is then 0 for
   * formats 6 to 10 and for more than 2^32 - 1 points, and equal to the
   * 64-bit count otherwise. Writers that fill in only the legacy count
   * are read too, but two counts that disagree are an error.
   */
  uint64_t legacy = scf__load_uint(b + LAS_COUNT, 4, 0);
  h->count = legacy;
  h->count_at = LAS_COUNT;
  if (h->minor >= 4) {
    uint64_t wide = scf__load_uint(b + LAS_COUNT_64, 8, 0);
    if (legacy != 0 && wide != 0 && legacy != wide)
      return scf__rd_fail_byte(r, LAS_COUNT, SCF_EFORMAT,
                               "the legacy point count %llu differs from the "
                               "64-bit point count %llu at byte %d",
                               (scf__ull)legacy, (scf__ull)wide, LAS_COUNT_64);
    if (wide != 0) {
      h->count = wide;
      h->count_at = LAS_COUNT_64;
    }
  }
  static const char axes[3] = {'x', 'y', 'z'};
  for (int a = 0; a < 3; a++) {
    h->scale[a] = scf__number(b + LAS_SCALE + 8 * a, SCF_TYPE_FLOAT64, 0);
    h->offset[a] = scf__number(b + LAS_OFFSET + 8 * a, SCF_TYPE_FLOAT64, 0);
    if (!isfinite(h->scale[a]) || h->scale[a] == 0)
      return scf__rd_fail_byte(r, (uint64_t)(LAS_SCALE + 8 * a), SCF_EFORMAT,
                               "%c scale factor %g is not a finite, non-zero "
                               "number",
                               axes[a], h->scale[a]);
    if (!isfinite(h->offset[a]))
      return scf__rd_fail_byte(r, (uint64_t)(LAS_OFFSET + 8 * a), SCF_EFORMAT,
                               "%c offset %g is not a finite number", axes[a],
                               h->offset[a]);
  }
  return 0;
}

/*
 * Checks the header's sizes against the file's before anything is
 * allocated; a file of unknown size (a pipe) is checked as it is read.
 */
static int las_check_size(scf__rd_t *r, const las_header_t *h) {
  if (r->size == UINT64_MAX)
    return 0;
  if (r->size < h->header_size)
    return scf__rd_fail_byte(r, r->size, SCF_EFORMAT,
                             "file ends inside the public header, whose size "
                             "is %u bytes",
                             h->header_size);
  if (h->data_offset > r->size)
    return scf__rd_fail_byte(r, LAS_DATA_OFFSET, SCF_EFORMAT,
                             "the point data start at byte %llu, beyond the "
                             "end of the file (%llu bytes)",
                             (scf__ull)h->data_offset, (scf__ull)r->size);
  uint64_t need = scf__sat_mul_add(0, h->count, h->record_len);
  if (need > r->size - h->data_offset)
    return scf__rd_fail_byte(
        r, (uint64_t)h->count_at, SCF_EFORMAT,
        "the header declares %llu points of %u bytes, which need %llu bytes "
        "from byte %llu, but the file has %llu",
        (scf__ull)h->count, h->record_len, (scf__ull)need,
        (scf__ull)h->data_offset, (scf__ull)r->size);
  return 0;
}

/* The attributes of a format, as per-point properties named as PLY files
 * name them: intensity, return_number, number_of_returns,
 * classification, then gps_time, red, green, blue and nir where the format
 * has them. */
static int las_attrs_add(scf__rd_t *r, scf_attrs_t *a, const las_format_t *f) {
  int rc = scf__attrs_add(r, a, "intensity", SCF_TYPE_UINT16);
  if (rc == 0)
    rc = scf__attrs_add(r, a, "return_number", SCF_TYPE_UINT8);
  if (rc == 0)
    rc = scf__attrs_add(r, a, "number_of_returns", SCF_TYPE_UINT8);
  if (rc == 0)
    rc = scf__attrs_add(r, a, "classification", SCF_TYPE_UINT8);
  if (rc == 0 && f->gps_time)
    rc = scf__attrs_add(r, a, "gps_time", SCF_TYPE_FLOAT64);
  if (rc == 0 && f->rgb)
    rc = scf__attrs_add(r, a, "red", SCF_TYPE_UINT16);
  if (rc == 0 && f->rgb)
    rc = scf__attrs_add(r, a, "green", SCF_TYPE_UINT16);
  if (rc == 0 && f->rgb)
    rc = scf__attrs_add(r, a, "blue", SCF_TYPE_UINT16);
  if (rc == 0 && f->nir)
    rc = scf__attrs_add(r, a, "nir", SCF_TYPE_UINT16);
  return rc;
}

/* One record's attributes, in the order of las_attrs_add(); both are
 * little-endian, so values are copied byte for byte. */
static void las_attrs_record(unsigned char *out, const unsigned char *b,
                             const las_format_t *f) {
  const unsigned ret = b[f->returns];
  memcpy(out, b + f->intensity, 2);
  out[2] = (unsigned char)(f->wide ? ret & 0x0F : ret & 0x07);
  out[3] = (unsigned char)(f->wide ? ret >> 4 : (ret >> 3) & 0x07);
  out[4] = (unsigned char)(f->wide ? b[f->classes] : b[f->classes] & 0x1F);
  size_t at = 5;
  if (f->gps_time) {
    memcpy(out + at, b + f->gps_time, 8);
    at += 8;
  }
  if (f->rgb) {
    memcpy(out + at, b + f->rgb, 6);
    at += 6;
  }
  if (f->nir)
    memcpy(out + at, b + f->nir, 2);
}

int scf__read_las(scf__rd_t *r, scf__vbuf_t *v) {
  las_header_t h;
  int rc;
  uint64_t skipped;
  /* Zeroed: the compiler cannot tell that a failed las_header() leaves
   * nothing to read. */
  memset(&h, 0, sizeof h);
  if ((rc = las_header(r, &h)) < 0 || (rc = las_check_size(r, &h)) < 0)
    return rc;
  /* The header and the variable-length records before the points. */
  if ((rc = scf__rd_skip(r, h.header_size, &skipped)) < 0)
    return rc;
  if (skipped < h.header_size)
    return scf__rd_fail_byte(r, skipped, SCF_EFORMAT,
                             "file ends inside the public header, whose size "
                             "is %u bytes",
                             h.header_size);
  if ((rc = scf__rd_skip(r, h.data_offset - h.header_size, &skipped)) < 0)
    return rc;
  if (skipped < h.data_offset - h.header_size)
    return scf__rd_fail_byte(r, scf__rd_offset(r), SCF_EFORMAT,
                             "file ends before the point data at byte %llu",
                             (scf__ull)h.data_offset);
  const las_format_t *f = &las_formats[h.format];
  unsigned char arec[32]; /* the largest: 5 + 8 + 6 + 2 bytes */
  if (v->attrs != NULL && (rc = las_attrs_add(r, v->attrs, f)) < 0)
    return rc;
  uint64_t n = h.count;
  /* Without a known file size the count is unchecked: grow as data comes. */
  uint64_t reserve = r->size == UINT64_MAX && n > 65536 ? 65536 : n;
  if (reserve > 0 && (rc = scf__vbuf_reserve(r, v, reserve)) < 0)
    return rc;
  /* Whole buffers of records at a time: the loop below is the hot path. */
  size_t len = h.record_len, per_fill = SCF__RD_CAP / len;
  const double *s = h.scale, *o = h.offset;
  for (uint64_t k = 0; k < n;) {
    uint64_t at = scf__rd_offset(r);
    size_t want = (n - k < per_fill ? (size_t)(n - k) : per_fill) * len;
    const unsigned char *b;
    size_t got;
    if ((rc = scf__rd_peek(r, want, &b, &got)) < 0)
      return rc;
    size_t whole = got / len;
    if (whole == 0) {
      if (got == 0)
        return scf__rd_fail_byte(r, at, SCF_EFORMAT,
                                 "file ends before point %llu of %llu",
                                 (scf__ull)k, (scf__ull)n);
      return scf__rd_fail_byte(r, at, SCF_EFORMAT,
                               "file ends inside point %llu of %llu (expected "
                               "%zu bytes, got %zu)",
                               (scf__ull)k, (scf__ull)n, len, got);
    }
    for (size_t i = 0; i < whole; i++, b += len) {
      if ((rc = scf__vbuf_push(r, v, las_coord(b, s[0], o[0]),
                               las_coord(b + 4, s[1], o[1]),
                               las_coord(b + 8, s[2], o[2]))) < 0)
        return rc;
      if (v->attrs != NULL) {
        las_attrs_record(arec, b, f);
        if ((rc = scf__attrs_push(r, v, arec)) < 0)
          return rc;
      }
    }
    r->pos += whole * len;
    k += whole;
  }
  return 0;
}
