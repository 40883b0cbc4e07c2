/*
 * PLY: reading ascii and binary files of either byte order (the x, y, z
 * properties of the "vertex" element, its other scalar properties when
 * asked for, and the index list of the "face" element; everything else is
 * skipped), and writing ascii or binary little-endian files, with the
 * properties read.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "scf_internal.h"

#include <math.h>
#include <stdio.h>

typedef enum ply_type {
  PT_NONE = 0,
  PT_I8,
  PT_U8,
  PT_I16,
  PT_U16,
  PT_I32,
  PT_U32,
  PT_F32,
  PT_F64
} ply_type_t;

static ply_type_t ply_type_of(const char *name) {
  static const struct {
    const char *name;
    ply_type_t type;
  } table[] = {{"char", PT_I8},    {"int8", PT_I8},     {"uchar", PT_U8},
               {"uint8", PT_U8},   {"short", PT_I16},   {"int16", PT_I16},
               {"ushort", PT_U16}, {"uint16", PT_U16},  {"int", PT_I32},
               {"int32", PT_I32},  {"uint", PT_U32},    {"uint32", PT_U32},
               {"float", PT_F32},  {"float32", PT_F32}, {"double", PT_F64},
               {"float64", PT_F64}};
  for (size_t i = 0; i < sizeof table / sizeof table[0]; i++)
    if (strcmp(name, table[i].name) == 0)
      return table[i].type;
  return PT_NONE;
}

/* The types are numbered alike in both enums (shortcrust_files.h). */
static scf_type_t ply_scf_type(ply_type_t t) { return (scf_type_t)t; }

static size_t ply_type_size(ply_type_t t) {
  return scf_type_size(ply_scf_type(t));
}

static int ply_type_is_int(ply_type_t t) { return t >= PT_I8 && t <= PT_U32; }

/* Integer types only (the header parser makes sure of that). */
static int64_t ply_int(const unsigned char *b, ply_type_t t, int big_endian) {
  return scf__integer(b, ply_scf_type(t), big_endian);
}

static double ply_double(const unsigned char *b, ply_type_t t, int big_endian) {
  return scf__number(b, ply_scf_type(t), big_endian);
}

#define PLY_NAME 32
#define PLY_MAX_ELEMENTS 256
#define PLY_MAX_PROPS 1024

typedef struct ply_prop {
  char name[PLY_NAME];
  ply_type_t type;       /* of the value, or of the items of a list */
  ply_type_t count_type; /* PT_NONE for a scalar */
  size_t offset;         /* in a fixed-size binary record */
} ply_prop_t;

typedef struct ply_elem {
  char name[PLY_NAME];
  uint64_t count;
  ply_prop_t *props;
  size_t n_props, cap_props;
  int fixed;       /* no list properties */
  size_t rec_size; /* binary record size, the minimum when not fixed */
} ply_elem_t;

enum { PLY_ASCII = 1, PLY_LE, PLY_BE };
enum { ROLE_OTHER, ROLE_VERTEX, ROLE_FACE };

typedef struct ply {
  int format;
  ply_elem_t *elems;
  size_t n_elems;
  int vertex, face;    /* element indices, -1 when absent */
  int px, py, pz;      /* property indices in the vertex element */
  int pface;           /* the index list in the face element */
  uint64_t header_end; /* line number of end_header */
  int *amap; /* per vertex property: its index in the attributes, or -1 */
} ply_t;

/* Stores a value of type t, read from a file of the given byte order, in
 * an attribute record (little-endian). */
static void ply_put_attr(unsigned char *dst, const unsigned char *src,
                         ply_type_t t, int big_endian) {
  size_t sz = ply_type_size(t);
  for (size_t i = 0; i < sz; i++)
    dst[i] = big_endian ? src[sz - 1 - i] : src[i];
}

/* The same from the number an ascii file gave: 0, or -1 when an integer
 * type cannot hold it (not a whole number, or out of the type's range). */
static int ply_put_attr_number(unsigned char *dst, double d, ply_type_t t) {
  static const double lo[] = {0, -128, 0, -32768, 0, -2147483648.0, 0};
  static const double hi[] = {0,     127,          255,         32767,
                              65535, 2147483647.0, 4294967295.0};
  unsigned char b[8];
  if (t == PT_F32) {
    scf__put_f32le(b, (float)d);
  } else if (t == PT_F64) {
    scf__put_f64le(b, d);
  } else {
    if (!(d >= lo[t] && d <= hi[t]) || d != floor(d))
      return -1;
    /* Two's complement, low bytes first. */
    uint64_t u = (uint64_t)(int64_t)d;
    for (int i = 0; i < 8; i++)
      b[i] = (unsigned char)(u >> (8 * i));
  }
  memcpy(dst, b, ply_type_size(t));
  return 0;
}

static void ply_free(ply_t *p) {
  free(p->amap);
  for (size_t i = 0; i < p->n_elems; i++)
    free(p->elems[i].props);
  free(p->elems);
}

static void copy_name(char dst[PLY_NAME], const char *src) {
  size_t n = strlen(src);
  if (n >= PLY_NAME)
    n = PLY_NAME - 1;
  memcpy(dst, src, n);
  dst[n] = '\0';
}

static int ply_header_line(scf__rd_t *r, ply_t *p, char *line, int *done) {
  char *cur = line, buf[SCF__SHOW_MAX + 4];
  char *kw = scf__next_tok(&cur, SCF__WS);
  if (kw == NULL || strcmp(kw, "comment") == 0 || strcmp(kw, "obj_info") == 0)
    return 0;
  if (strcmp(kw, "end_header") == 0) {
    *done = 1;
    return 0;
  }
  if (strcmp(kw, "format") == 0) {
    char *fmt = scf__next_tok(&cur, SCF__WS),
         *ver = scf__next_tok(&cur, SCF__WS);
    if (p->format != 0)
      return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                               "second format line in the header");
    if (fmt == NULL || ver == NULL)
      return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                               "expected 'format <type> 1.0'");
    if (strcmp(fmt, "ascii") == 0)
      p->format = PLY_ASCII;
    else if (strcmp(fmt, "binary_little_endian") == 0)
      p->format = PLY_LE;
    else if (strcmp(fmt, "binary_big_endian") == 0)
      p->format = PLY_BE;
    else
      return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                               "unknown PLY format '%s' (expected ascii, "
                               "binary_little_endian or binary_big_endian)",
                               scf__show(fmt, buf));
    if (strcmp(ver, "1.0") != 0)
      return scf__rd_fail_line(r, r->line, SCF_EUNSUPPORTED,
                               "PLY version '%s' (only 1.0 is supported)",
                               scf__show(ver, buf));
    return 0;
  }
  if (strcmp(kw, "element") == 0) {
    char *name = scf__next_tok(&cur, SCF__WS),
         *count = scf__next_tok(&cur, SCF__WS);
    if (name == NULL || count == NULL)
      return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                               "expected 'element <name> <count>'");
    uint64_t n;
    if (scf__parse_u64(count, &n) < 0)
      return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                               "expected a count for element '%s', got '%s'",
                               name, scf__show(count, buf));
    if (p->n_elems == PLY_MAX_ELEMENTS)
      return scf__rd_fail_line(r, r->line, SCF_EUNSUPPORTED,
                               "more than %d elements", PLY_MAX_ELEMENTS);
    if (p->n_elems % 8 == 0) {
      ply_elem_t *e = realloc(p->elems, (p->n_elems + 8) * sizeof *e);
      if (e == NULL)
        return scf__rd_fail_line(r, r->line, SCF_ENOMEM, "out of memory");
      p->elems = e;
    }
    ply_elem_t *e = &p->elems[p->n_elems++];
    memset(e, 0, sizeof *e);
    copy_name(e->name, name);
    e->count = n;
    e->fixed = 1;
    return 0;
  }
  if (strcmp(kw, "property") == 0) {
    if (p->n_elems == 0)
      return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                               "property before any element");
    ply_elem_t *e = &p->elems[p->n_elems - 1];
    ply_prop_t prop;
    memset(&prop, 0, sizeof prop);
    char *type = scf__next_tok(&cur, SCF__WS);
    if (type != NULL && strcmp(type, "list") == 0) {
      char *ct = scf__next_tok(&cur, SCF__WS);
      if (ct == NULL)
        return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                                 "expected 'property list <count type> <item "
                                 "type> <name>'");
      prop.count_type = ply_type_of(ct);
      if (!ply_type_is_int(prop.count_type))
        return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                                 "list count type '%s' is not an integer type",
                                 scf__show(ct, buf));
      type = scf__next_tok(&cur, SCF__WS);
    }
    char *name = scf__next_tok(&cur, SCF__WS);
    if (type == NULL || name == NULL)
      return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                               "expected 'property <type> <name>'");
    prop.type = ply_type_of(type);
    if (prop.type == PT_NONE)
      return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                               "unknown property type '%s'",
                               scf__show(type, buf));
    copy_name(prop.name, name);
    if (e->n_props == PLY_MAX_PROPS)
      return scf__rd_fail_line(r, r->line, SCF_EUNSUPPORTED,
                               "more than %d properties in element '%s'",
                               PLY_MAX_PROPS, e->name);
    if (e->n_props == e->cap_props) {
      size_t cap = e->cap_props ? e->cap_props * 2 : 8;
      ply_prop_t *np = realloc(e->props, cap * sizeof *np);
      if (np == NULL)
        return scf__rd_fail_line(r, r->line, SCF_ENOMEM, "out of memory");
      e->props = np;
      e->cap_props = cap;
    }
    prop.offset = e->rec_size;
    if (prop.count_type != PT_NONE) {
      e->fixed = 0;
      e->rec_size += ply_type_size(prop.count_type);
    } else {
      e->rec_size += ply_type_size(prop.type);
    }
    e->props[e->n_props++] = prop;
    return 0;
  }
  return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                           "unknown header keyword '%s'", scf__show(kw, buf));
}

static int ply_find_prop(const ply_elem_t *e, const char *name) {
  for (size_t i = 0; i < e->n_props; i++)
    if (strcmp(e->props[i].name, name) == 0)
      return (int)i;
  return -1;
}

static int ply_header(scf__rd_t *r, ply_t *p, int want_faces) {
  char *line;
  int rc = scf__rd_line(r, &line);
  if (rc < 0)
    return rc;
  if (rc == 0 || strcmp(line, "ply") != 0)
    return scf__rd_fail_line(r, 1, SCF_EFORMAT,
                             "not a PLY file: the first line is not 'ply'");
  for (int done = 0; !done;) {
    rc = scf__rd_line(r, &line);
    if (rc < 0)
      return rc;
    if (rc == 0)
      return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                               "file ends inside the header (no end_header)");
    rc = ply_header_line(r, p, line, &done);
    if (rc < 0)
      return rc;
  }
  p->header_end = r->line;
  if (p->format == 0)
    return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                             "no format line in the header");
  p->vertex = p->face = -1;
  for (size_t i = 0; i < p->n_elems; i++) {
    if (strcmp(p->elems[i].name, "vertex") == 0) {
      if (p->vertex >= 0)
        return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                                 "two vertex elements in the header");
      p->vertex = (int)i;
    } else if (want_faces && p->face < 0 &&
               strcmp(p->elems[i].name, "face") == 0) {
      p->face = (int)i;
    }
  }
  if (p->vertex < 0)
    return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                             "no vertex element in the header");
  const ply_elem_t *v = &p->elems[p->vertex];
  int *slots[3] = {&p->px, &p->py, &p->pz};
  static const char *const axes[3] = {"x", "y", "z"};
  for (int a = 0; a < 3; a++) {
    *slots[a] = ply_find_prop(v, axes[a]);
    if (*slots[a] < 0)
      return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                               "the vertex element has no property '%s'",
                               axes[a]);
    if (v->props[*slots[a]].count_type != PT_NONE)
      return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                               "vertex property '%s' is a list", axes[a]);
  }
  p->pface = -1;
  if (p->face >= 0) {
    const ply_elem_t *f = &p->elems[p->face];
    p->pface = ply_find_prop(f, "vertex_indices");
    if (p->pface < 0)
      p->pface = ply_find_prop(f, "vertex_index");
    if (p->pface < 0 || f->props[p->pface].count_type == PT_NONE)
      return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                               "the face element has no vertex_indices list");
    if (!ply_type_is_int(f->props[p->pface].type))
      return scf__rd_fail_line(
          r, r->line, SCF_EFORMAT,
          "face vertex indices are not of an integer type");
    if (v->count > UINT32_MAX)
      return scf__rd_fail_line(r, r->line, SCF_EUNSUPPORTED,
                               "%llu vertices: meshes with more than 2^32 - 1 "
                               "vertices are not supported",
                               (scf__ull)v->count);
  }
  return 0;
}

/* The last element a read needs: the vertices, and the faces for a mesh. */
static size_t ply_last_needed(const ply_t *p) {
  return (size_t)(p->face > p->vertex ? p->face : p->vertex);
}

/*
 * The message for a binary file that ends at offset at, within record k of
 * e (which starts at rec): the piece being read needed expected bytes and
 * got fewer. It is "before" the record only when nothing of it was there.
 */
static int ply_truncated(scf__rd_t *r, uint64_t rec, uint64_t at,
                         const ply_elem_t *e, uint64_t k, uint64_t expected,
                         uint64_t got) {
  if (got == 0 && at == rec)
    return scf__rd_fail_byte(r, at, SCF_EFORMAT,
                             "file ends before %s %llu of %llu", e->name,
                             (scf__ull)k, (scf__ull)e->count);
  return scf__rd_fail_byte(r, at, SCF_EFORMAT,
                           "file ends inside %s %llu of %llu (expected %llu "
                           "bytes, got %llu)",
                           e->name, (scf__ull)k, (scf__ull)e->count,
                           (scf__ull)expected, (scf__ull)got);
}

/*
 * Checks that the elements up to the last one needed fit in what is left of
 * the file, at their smallest (empty lists; one digit and a separator per
 * value in ascii), before anything is allocated for them.
 */
static int ply_check_size(scf__rd_t *r, const ply_t *p) {
  uint64_t rem = scf__rd_remaining(r), need = 0;
  int exact = 1; /* whether need is the exact size so far */
  if (rem == UINT64_MAX)
    return 0;
  for (size_t i = 0; i <= ply_last_needed(p); i++) {
    const ply_elem_t *e = &p->elems[i];
    uint64_t per =
        p->format == PLY_ASCII ? 2 * (uint64_t)e->n_props : e->rec_size;
    uint64_t before = need;
    need = scf__sat_mul_add(need, e->count, per);
    /* An ascii file may lack the line end after its last value. */
    uint64_t least = (p->format == PLY_ASCII && need > 0) ? need - 1 : need;
    if (least <= rem) {
      exact = exact && e->fixed;
      continue;
    }
    if (p->format == PLY_ASCII)
      return scf__rd_fail_line(
          r, p->header_end, SCF_EFORMAT,
          "the header declares %llu %s records; with the elements before "
          "them they need at least %llu bytes, but only %llu bytes follow "
          "the header",
          (scf__ull)e->count, e->name, (scf__ull)least, (scf__ull)rem);
    /* With fixed-size records so far, the point where the file ends is
     * known exactly, and saying so is the most useful message. */
    if (exact && e->fixed) {
      uint64_t left = rem - before, k = left / e->rec_size;
      uint64_t at = scf__rd_offset(r) + before + k * e->rec_size;
      return ply_truncated(r, at, at, e, k, e->rec_size, left % e->rec_size);
    }
    return scf__rd_fail_byte(
        r, scf__rd_offset(r), SCF_EFORMAT,
        "the header declares %llu %s records; with the elements before them "
        "they need at least %llu bytes, but only %llu bytes follow the "
        "header",
        (scf__ull)e->count, e->name, (scf__ull)least, (scf__ull)rem);
  }
  return 0;
}

static int ply_reserve(scf__rd_t *r, const ply_t *p, scf__vbuf_t *v) {
  uint64_t n = p->elems[p->vertex].count;
  /* Without a known file size the count is unchecked: grow as data comes. */
  if (scf__rd_remaining(r) == UINT64_MAX && n > 65536)
    n = 65536;
  return n > 0 ? scf__vbuf_reserve(r, v, n) : 0;
}

static int ply_check_index(scf__rd_t *r, const ply_t *p, int64_t idx,
                           uint64_t k, int binary, uint64_t at) {
  uint64_t nv = p->elems[p->vertex].count;
  if (idx >= 0 && (uint64_t)idx < nv)
    return 0;
  const char *fmt = "face %llu refers to vertex %lld, but there are %llu "
                    "vertices";
  if (binary)
    return scf__rd_fail_byte(r, at, SCF_EFORMAT, fmt, (scf__ull)k,
                             (long long)idx, (scf__ull)nv);
  return scf__rd_fail_line(r, at, SCF_EFORMAT, fmt, (scf__ull)k, (long long)idx,
                           (scf__ull)nv);
}

static int ply_binary_elem(scf__rd_t *r, const ply_t *p, size_t ei,
                           scf__vbuf_t *v, scf__tbuf_t *t) {
  const ply_elem_t *e = &p->elems[ei];
  int be = p->format == PLY_BE;
  int role = (int)ei == p->vertex ? ROLE_VERTEX
             : (int)ei == p->face ? ROLE_FACE
                                  : ROLE_OTHER;
  const unsigned char *b;
  size_t got;
  uint64_t skipped;
  int rc;
  /* A point's attribute record: at most one 8-byte value per property. */
  unsigned char arec[PLY_MAX_PROPS * 8];

  if (e->fixed && role == ROLE_OTHER) {
    uint64_t start = scf__rd_offset(r);
    uint64_t total = scf__sat_mul_add(0, e->count, e->rec_size);
    if ((rc = scf__rd_skip(r, total, &skipped)) < 0)
      return rc;
    if (skipped < total) {
      uint64_t k = skipped / e->rec_size;
      uint64_t at = start + k * e->rec_size;
      return ply_truncated(r, at, at, e, k, e->rec_size,
                           skipped - k * e->rec_size);
    }
    return 0;
  }
  if (role == ROLE_VERTEX && (rc = ply_reserve(r, p, v)) < 0)
    return rc;
  for (uint64_t k = 0; k < e->count; k++) {
    uint64_t rec = scf__rd_offset(r), at = rec;
    if (e->fixed) {
      if ((rc = scf__rd_bytes(r, e->rec_size, &b, &got)) < 0)
        return rc;
      if (got < e->rec_size)
        return ply_truncated(r, at, at, e, k, e->rec_size, got);
      const ply_prop_t *pp = e->props;
      rc = scf__vbuf_push(r, v,
                          ply_double(b + pp[p->px].offset, pp[p->px].type, be),
                          ply_double(b + pp[p->py].offset, pp[p->py].type, be),
                          ply_double(b + pp[p->pz].offset, pp[p->pz].type, be));
      if (rc == 0 && role == ROLE_VERTEX && p->amap != NULL) {
        for (size_t j = 0; j < e->n_props; j++)
          if (p->amap[j] >= 0)
            ply_put_attr(arec + v->attrs->props[p->amap[j]].offset,
                         b + pp[j].offset, pp[j].type, be);
        rc = scf__attrs_push(r, v, arec);
      }
      if (rc < 0)
        return rc;
      continue;
    }
    double xyz[3] = {0, 0, 0};
    for (size_t j = 0; j < e->n_props; j++) {
      const ply_prop_t *pp = &e->props[j];
      at = scf__rd_offset(r);
      if (pp->count_type == PT_NONE) {
        size_t sz = ply_type_size(pp->type);
        if ((rc = scf__rd_bytes(r, sz, &b, &got)) < 0)
          return rc;
        if (got < sz)
          return ply_truncated(r, rec, at, e, k, sz, got);
        if (role == ROLE_VERTEX) {
          if ((int)j == p->px)
            xyz[0] = ply_double(b, pp->type, be);
          else if ((int)j == p->py)
            xyz[1] = ply_double(b, pp->type, be);
          else if ((int)j == p->pz)
            xyz[2] = ply_double(b, pp->type, be);
          else if (p->amap != NULL && p->amap[j] >= 0)
            ply_put_attr(arec + v->attrs->props[p->amap[j]].offset, b, pp->type,
                         be);
        }
        continue;
      }
      size_t csz = ply_type_size(pp->count_type);
      if ((rc = scf__rd_bytes(r, csz, &b, &got)) < 0)
        return rc;
      if (got < csz)
        return ply_truncated(r, rec, at, e, k, csz, got);
      int64_t n = ply_int(b, pp->count_type, be);
      if (n < 0)
        return scf__rd_fail_byte(r, at, SCF_EFORMAT,
                                 "negative list length %lld in %s %llu",
                                 (long long)n, e->name, (scf__ull)k);
      size_t isz = ply_type_size(pp->type);
      if (role == ROLE_FACE && (int)j == p->pface) {
        if (n < 3)
          return scf__rd_fail_byte(r, at, SCF_EFORMAT,
                                   "face %llu has %lld vertices (expected at "
                                   "least 3)",
                                   (scf__ull)k, (long long)n);
        scf__fan_t fan = {0, 0, 0};
        for (int64_t i = 0; i < n; i++) {
          at = scf__rd_offset(r);
          if ((rc = scf__rd_bytes(r, isz, &b, &got)) < 0)
            return rc;
          if (got < isz)
            return ply_truncated(r, rec, at, e, k, isz, got);
          int64_t idx = ply_int(b, pp->type, be);
          if ((rc = ply_check_index(r, p, idx, k, 1, at)) < 0 ||
              (rc = scf__fan_add(r, t, &fan, (uint32_t)idx)) < 0)
            return rc;
        }
        continue;
      }
      uint64_t bytes = (uint64_t)n * isz;
      at = scf__rd_offset(r);
      if ((rc = scf__rd_skip(r, bytes, &skipped)) < 0)
        return rc;
      if (skipped < bytes)
        return ply_truncated(r, rec, at, e, k, bytes, skipped);
    }
    if (role == ROLE_VERTEX &&
        ((rc = scf__vbuf_push(r, v, xyz[0], xyz[1], xyz[2])) < 0 ||
         (p->amap != NULL && (rc = scf__attrs_push(r, v, arec)) < 0)))
      return rc;
  }
  return 0;
}

/* Ascii PLY values form one stream of tokens; line breaks are not
 * significant, but line numbers go into messages. */
typedef struct tokens {
  scf__rd_t *r;
  char *cur;
} tokens_t;

static int tokens_next(tokens_t *ts, char **tok) {
  for (;;) {
    if (ts->cur != NULL && (*tok = scf__next_tok(&ts->cur, SCF__WS)) != NULL)
      return 1;
    int rc = scf__rd_line(ts->r, &ts->cur);
    if (rc <= 0)
      return rc;
  }
}

static int ply_ascii_value(tokens_t *ts, const ply_elem_t *e, uint64_t k,
                           const char *what, char **tok) {
  int rc = tokens_next(ts, tok);
  if (rc < 0)
    return rc;
  if (rc == 0)
    return scf__rd_fail_line(ts->r, ts->r->line, SCF_EFORMAT,
                             "file ends inside %s %llu of %llu (expected %s)",
                             e->name, (scf__ull)k, (scf__ull)e->count, what);
  return 0;
}

static int ply_ascii_elem(tokens_t *ts, const ply_t *p, size_t ei,
                          scf__vbuf_t *v, scf__tbuf_t *t) {
  const ply_elem_t *e = &p->elems[ei];
  scf__rd_t *r = ts->r;
  int role = (int)ei == p->vertex ? ROLE_VERTEX
             : (int)ei == p->face ? ROLE_FACE
                                  : ROLE_OTHER;
  char *tok = NULL, buf[SCF__SHOW_MAX + 4], what[PLY_NAME + 32];
  int rc;
  unsigned char arec[PLY_MAX_PROPS * 8]; /* as in ply_binary_elem() */
  if (role == ROLE_VERTEX && (rc = ply_reserve(r, p, v)) < 0)
    return rc;
  for (uint64_t k = 0; k < e->count; k++) {
    double xyz[3] = {0, 0, 0};
    for (size_t j = 0; j < e->n_props; j++) {
      const ply_prop_t *pp = &e->props[j];
      snprintf(what, sizeof what, "%s '%s'",
               pp->count_type == PT_NONE ? "property" : "the length of list",
               pp->name);
      if ((rc = ply_ascii_value(ts, e, k, what, &tok)) < 0)
        return rc;
      if (pp->count_type == PT_NONE) {
        double d;
        if (scf__parse_double(tok, &d) < 0)
          return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                                   "expected a number for property '%s' of %s "
                                   "%llu, got '%s'",
                                   pp->name, e->name, (scf__ull)k,
                                   scf__show(tok, buf));
        if (role == ROLE_VERTEX) {
          if ((int)j == p->px)
            xyz[0] = d;
          else if ((int)j == p->py)
            xyz[1] = d;
          else if ((int)j == p->pz)
            xyz[2] = d;
          else if (p->amap != NULL && p->amap[j] >= 0 &&
                   ply_put_attr_number(
                       arec + v->attrs->props[p->amap[j]].offset, d, pp->type) <
                       0)
            return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                                     "'%s' does not fit property '%s' (%s) "
                                     "of %s %llu",
                                     scf__show(tok, buf), pp->name,
                                     scf_type_name(ply_scf_type(pp->type)),
                                     e->name, (scf__ull)k);
        }
        continue;
      }
      int64_t n;
      if (scf__parse_i64(tok, &n) < 0 || n < 0)
        return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                                 "expected a list length for '%s' of %s %llu, "
                                 "got '%s'",
                                 pp->name, e->name, (scf__ull)k,
                                 scf__show(tok, buf));
      int is_face = role == ROLE_FACE && (int)j == p->pface;
      if (is_face && n < 3)
        return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                                 "face %llu has %lld vertices (expected at "
                                 "least 3)",
                                 (scf__ull)k, (long long)n);
      scf__fan_t fan = {0, 0, 0};
      snprintf(what, sizeof what, "an item of list '%s'", pp->name);
      for (int64_t i = 0; i < n; i++) {
        if ((rc = ply_ascii_value(ts, e, k, what, &tok)) < 0)
          return rc;
        if (is_face) {
          int64_t idx;
          if (scf__parse_i64(tok, &idx) < 0)
            return scf__rd_fail_line(
                r, r->line, SCF_EFORMAT,
                "expected a vertex index in face %llu, got "
                "'%s'",
                (scf__ull)k, scf__show(tok, buf));
          if ((rc = ply_check_index(r, p, idx, k, 0, r->line)) < 0 ||
              (rc = scf__fan_add(r, t, &fan, (uint32_t)idx)) < 0)
            return rc;
        } else {
          double d;
          if (scf__parse_double(tok, &d) < 0)
            return scf__rd_fail_line(
                r, r->line, SCF_EFORMAT,
                "expected a number in list '%s' of %s %llu, "
                "got '%s'",
                pp->name, e->name, (scf__ull)k, scf__show(tok, buf));
        }
      }
    }
    if (role == ROLE_VERTEX &&
        ((rc = scf__vbuf_push(r, v, xyz[0], xyz[1], xyz[2])) < 0 ||
         (p->amap != NULL && (rc = scf__attrs_push(r, v, arec)) < 0)))
      return rc;
  }
  return 0;
}

int scf__read_ply(scf__rd_t *r, scf__vbuf_t *v, scf__tbuf_t *t) {
  ply_t p;
  memset(&p, 0, sizeof p);
  int rc = ply_header(r, &p, t != NULL);
  if (rc == 0)
    rc = ply_check_size(r, &p);
  if (rc == 0 && v->attrs != NULL && p.vertex >= 0) {
    /* Every scalar property of the vertices but x, y, z, in file order. */
    const ply_elem_t *e = &p.elems[p.vertex];
    p.amap = malloc((e->n_props ? e->n_props : 1) * sizeof *p.amap);
    if (p.amap == NULL)
      rc = scf__fail(r->msg, r->msg_len, SCF_ENOMEM, r->path,
                     "out of memory for the point properties");
    for (size_t j = 0; rc == 0 && j < e->n_props; j++) {
      const ply_prop_t *pp = &e->props[j];
      p.amap[j] = -1;
      if (pp->count_type != PT_NONE || (int)j == p.px || (int)j == p.py ||
          (int)j == p.pz)
        continue;
      p.amap[j] = (int)v->attrs->count;
      rc = scf__attrs_add(r, v->attrs, pp->name, ply_scf_type(pp->type));
    }
    if (rc == 0 && v->attrs->count == 0) {
      free(p.amap);
      p.amap = NULL;
    }
  }
  tokens_t ts = {r, NULL};
  for (size_t i = 0; rc == 0 && i <= ply_last_needed(&p); i++)
    rc = p.format == PLY_ASCII ? ply_ascii_elem(&ts, &p, i, v, t)
                               : ply_binary_elem(r, &p, i, v, t);
  ply_free(&p);
  return rc;
}

/* Prints one attribute value from its little-endian record bytes (every
 * integer type fits a double exactly). */
static int ply_print_attr(scf__aout_t *o, const unsigned char *b,
                          scf_type_t t) {
  const double v = scf__number(b, t, 0);
  return scf__out_printf(o, t == SCF_TYPE_FLOAT32   ? " %.9g"
                            : t == SCF_TYPE_FLOAT64 ? " %.17g"
                                                    : " %.0f",
                         v);
}

int scf__write_ply(scf__aout_t *o, const scf__mesh_in_t *m, int ascii) {
  const scf_attrs_t *a = m->attrs;
  /* The input's own normals win over the computed ones. */
  const double *normals = scf_attrs_find(a, "nx") >= 0 ||
                                  scf_attrs_find(a, "ny") >= 0 ||
                                  scf_attrs_find(a, "nz") >= 0
                              ? NULL
                              : m->normals;
  int rc = scf__out_printf(o,
                           "ply\nformat %s 1.0\ncomment written by shortcrust\n"
                           "element vertex %zu\nproperty double x\n"
                           "property double y\nproperty double z\n",
                           ascii ? "ascii" : "binary_little_endian", m->n);
  if (rc == 0 && normals != NULL)
    rc = scf__out_printf(o, "property float nx\nproperty float ny\n"
                            "property float nz\n");
  for (size_t k = 0; rc == 0 && a != NULL && k < a->count; k++)
    rc = scf__out_printf(o, "property %s %s\n", scf_type_name(a->props[k].type),
                         a->props[k].name);
  /* Indices go out as int, the type most readers expect, unless they do
   * not fit. */
  if (rc == 0)
    rc = scf__out_printf(o,
                         "element face %zu\nproperty list uchar %s "
                         "vertex_indices\nend_header\n",
                         m->nt, m->n > INT32_MAX ? "uint" : "int");
  const size_t stride = a != NULL ? a->stride : 0;
  unsigned char *vrec = malloc(36 + stride);
  if (rc == 0 && vrec == NULL)
    rc = scf__fail(o->msg, o->msg_len, SCF_ENOMEM, o->path, "out of memory");
  for (size_t i = 0; rc == 0 && i < m->n; i++) {
    const double *p = m->xyz + 3 * i;
    const double *q = normals ? normals + 3 * i : NULL;
    const unsigned char *ar = a != NULL ? a->data + i * stride : NULL;
    if (ascii) {
      rc = scf__out_printf(o, "%.17g %.17g %.17g", p[0], p[1], p[2]);
      if (rc == 0 && q != NULL)
        rc = scf__out_printf(o, " %.9g %.9g %.9g", (double)(float)q[0],
                             (double)(float)q[1], (double)(float)q[2]);
      for (size_t k = 0; rc == 0 && ar != NULL && k < a->count; k++)
        rc = ply_print_attr(o, ar + a->props[k].offset, a->props[k].type);
      if (rc == 0)
        rc = scf__out_write(o, "\n", 1);
    } else {
      for (int c = 0; c < 3; c++) {
        scf__put_f64le(vrec + 8 * c, p[c]);
        if (q != NULL)
          scf__put_f32le(vrec + 24 + 4 * c, (float)q[c]);
      }
      size_t len = q != NULL ? 36 : 24;
      if (ar != NULL)
        memcpy(vrec + len, ar, stride);
      rc = scf__out_write(o, vrec, len + stride);
    }
  }
  free(vrec);
  for (size_t i = 0; rc == 0 && i < m->nt; i++) {
    const uint32_t *t = m->tri + 3 * i;
    if (ascii) {
      rc = scf__out_printf(o, "3 %u %u %u\n", (unsigned)t[0], (unsigned)t[1],
                           (unsigned)t[2]);
    } else {
      unsigned char rec[13];
      rec[0] = 3;
      for (int c = 0; c < 3; c++)
        scf__put_u32le(rec + 1 + 4 * c, t[c]);
      rc = scf__out_write(o, rec, sizeof rec);
    }
  }
  return rc;
}
