/*
 * Per-point properties (shortcrust_files.h, scf_attrs_t): their types,
 * their growth as a reader adds points, finding and removing one.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "scf_internal.h"

size_t scf_type_size(scf_type_t t) {
  switch (t) {
  case SCF_TYPE_INT8:
  case SCF_TYPE_UINT8:
    return 1;
  case SCF_TYPE_INT16:
  case SCF_TYPE_UINT16:
    return 2;
  case SCF_TYPE_INT32:
  case SCF_TYPE_UINT32:
  case SCF_TYPE_FLOAT32:
    return 4;
  case SCF_TYPE_FLOAT64:
    return 8;
  }
  return 0;
}

const char *scf_type_name(scf_type_t t) {
  static const char *const names[] = {"",    "char", "uchar", "short", "ushort",
                                      "int", "uint", "float", "double"};
  return scf_type_size(t) ? names[t] : "";
}

int64_t scf__integer(const unsigned char *b, scf_type_t t, int big_endian) {
  const size_t n = scf_type_size(t);
  uint64_t u = scf__load_uint(b, n, big_endian);
  if (t == SCF_TYPE_INT8 || t == SCF_TYPE_INT16 || t == SCF_TYPE_INT32) {
    uint64_t top = (uint64_t)1 << (8 * n - 1);
    return (u & top) ? (int64_t)u - (int64_t)(top << 1) : (int64_t)u;
  }
  return (int64_t)u;
}

double scf__number(const unsigned char *b, scf_type_t t, int big_endian) {
  if (t == SCF_TYPE_FLOAT32) {
    uint32_t w = (uint32_t)scf__load_uint(b, 4, big_endian);
    float f;
    memcpy(&f, &w, sizeof f);
    return f;
  }
  if (t == SCF_TYPE_FLOAT64) {
    uint64_t w = scf__load_uint(b, 8, big_endian);
    double d;
    memcpy(&d, &w, sizeof d);
    return d;
  }
  return (double)scf__integer(b, t, big_endian);
}

double scf_attrs_value(const scf_attrs_t *a, size_t point, size_t prop) {
  return scf__number(a->data + point * a->stride + a->props[prop].offset,
                     a->props[prop].type, 0);
}

int scf__attrs_add(scf__rd_t *r, scf_attrs_t *a, const char *name,
                   scf_type_t type) {
  scf_prop_t *p = realloc(a->props, (a->count + 1) * sizeof *p);
  if (p == NULL)
    return scf__fail(r->msg, r->msg_len, SCF_ENOMEM, r->path,
                     "out of memory for the point properties");
  a->props = p;
  scf_prop_t *q = &p[a->count++];
  memset(q, 0, sizeof *q);
  snprintf(q->name, sizeof q->name, "%s", name);
  q->type = type;
  q->offset = a->stride;
  a->stride += scf_type_size(type);
  return 0;
}

int scf__attrs_push(scf__rd_t *r, scf__vbuf_t *v, const unsigned char *rec) {
  scf_attrs_t *a = v->attrs;
  if (a->points == v->acap) {
    size_t cap = v->acap ? 2 * v->acap : 4096;
    if (cap > SIZE_MAX / a->stride)
      return scf__fail(r->msg, r->msg_len, SCF_ENOMEM, r->path,
                       "too many points for their properties");
    unsigned char *d = realloc(a->data, cap * a->stride);
    if (d == NULL)
      return scf__fail(r->msg, r->msg_len, SCF_ENOMEM, r->path,
                       "out of memory for the point properties");
    a->data = d;
    v->acap = cap;
  }
  memcpy(a->data + a->points++ * a->stride, rec, a->stride);
  return 0;
}

void scf_attrs_free(scf_attrs_t *a) {
  if (a == NULL)
    return;
  free(a->props);
  free(a->data);
  memset(a, 0, sizeof *a);
}

int scf_attrs_find(const scf_attrs_t *a, const char *name) {
  for (size_t k = 0; a != NULL && k < a->count; k++)
    if (strcmp(a->props[k].name, name) == 0)
      return (int)k;
  return -1;
}

int scf_attrs_remove(scf_attrs_t *a, const char *name) {
  int k = scf_attrs_find(a, name);
  if (k < 0)
    return 0;
  const size_t off = a->props[k].offset, sz = scf_type_size(a->props[k].type),
               stride = a->stride - sz;
  /* Records shrink in place, front to back: each one's bytes move down. */
  for (size_t i = 0; i < a->points; i++) {
    const unsigned char *src = a->data + i * a->stride;
    unsigned char *dst = a->data + i * stride;
    memmove(dst, src, off);
    memmove(dst + off, src + off + sz, a->stride - off - sz);
  }
  for (size_t j = (size_t)k + 1; j < a->count; j++) {
    a->props[j - 1] = a->props[j];
    a->props[j - 1].offset -= sz;
  }
  a->count--;
  a->stride = stride;
  if (a->count == 0) {
    free(a->data);
    a->data = NULL;
    a->points = 0;
  }
  return 1;
}
