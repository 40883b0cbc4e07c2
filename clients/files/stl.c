/*
 * STL: reading binary and ascii files (each triangle with three vertices
 * of its own), writing either with facet normals computed from the
 * triangles.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "scf_internal.h"

#include <math.h>

static float load_f32le(const unsigned char *b) {
  uint32_t w = (uint32_t)scf__load_uint(b, 4, 0);
  float f;
  memcpy(&f, &w, sizeof f);
  return f;
}

static int read_stl_ascii(scf__rd_t *r, scf__vbuf_t *v, scf__tbuf_t *t) {
  char *line, *cur, *kw, buf[SCF__SHOW_MAX + 4];
  int rc, in_loop = 0, nloop = 0;
  while ((rc = scf__rd_line(r, &line)) == 1) {
    cur = line;
    kw = scf__next_tok(&cur, SCF__WS);
    if (kw == NULL || strcmp(kw, "solid") == 0 || strcmp(kw, "endsolid") == 0 ||
        strcmp(kw, "facet") == 0 || strcmp(kw, "endfacet") == 0)
      continue;
    if (strcmp(kw, "outer") == 0) {
      in_loop = 1;
      nloop = 0;
    } else if (strcmp(kw, "vertex") == 0) {
      double xyz[3];
      const char *bad;
      int ntok;
      if (!in_loop || nloop == 3)
        return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                                 "vertex outside an 'outer loop' of three");
      if (scf__three_numbers(&cur, SCF__WS, xyz, &bad, &ntok) < 0)
        return scf__bad_numbers(r, " after 'vertex'", bad, ntok);
      if (v->count >= UINT32_MAX)
        return scf__rd_fail_line(r, r->line, SCF_EUNSUPPORTED,
                                 "more than 2^32 - 1 vertices");
      if ((rc = scf__vbuf_push(r, v, xyz[0], xyz[1], xyz[2])) < 0)
        return rc;
      nloop++;
    } else if (strcmp(kw, "endloop") == 0) {
      if (!in_loop || nloop != 3)
        return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                                 "loop with %d vertices (expected 3)", nloop);
      uint32_t a = (uint32_t)(v->count - 3);
      if ((rc = scf__tbuf_push(r, t, a, a + 1, a + 2)) < 0)
        return rc;
      in_loop = 0;
    } else {
      return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                               "expected an STL keyword, got '%s'",
                               scf__show(kw, buf));
    }
  }
  if (rc == 0 && in_loop)
    return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                             "file ends inside a facet");
  return rc;
}

/*
 * Binary STL files may also begin with "solid", so a file is taken as
 * ascii only when it begins so and its size does not match the binary
 * layout.
 */
int scf__read_stl(scf__rd_t *r, scf__vbuf_t *v, scf__tbuf_t *t) {
  const unsigned char *b;
  size_t got;
  int rc = scf__rd_peek(r, 84, &b, &got);
  if (rc < 0)
    return rc;
  uint64_t n = got >= 84 ? scf__load_uint(b + 80, 4, 0) : 0;
  int sized = r->size != UINT64_MAX && got >= 84 && r->size == 84 + 50 * n;
  if (got >= 5 && memcmp(b, "solid", 5) == 0 && !sized)
    return read_stl_ascii(r, v, t);
  if (got < 84)
    return scf__rd_fail_byte(r, got, SCF_EFORMAT,
                             "file ends inside the 84-byte binary STL header "
                             "(got %zu bytes)",
                             got);
  if (r->size != UINT64_MAX && r->size < 84 + 50 * n)
    return scf__rd_fail_byte(r, 80, SCF_EFORMAT,
                             "the header declares %llu triangles, which need "
                             "%llu bytes, but the file has %llu",
                             (scf__ull)n, (scf__ull)(84 + 50 * n),
                             (scf__ull)r->size);
  if (n > (UINT32_MAX - 1) / 3)
    return scf__rd_fail_byte(r, 80, SCF_EUNSUPPORTED,
                             "%llu triangles need more than 2^32 - 1 vertices",
                             (scf__ull)n);
  r->pos += 84;
  if ((rc = scf__vbuf_reserve(
           r, v, 3 * (r->size != UINT64_MAX || n < 65536 ? n : 65536))) < 0)
    return rc;
  for (uint64_t k = 0; k < n; k++) {
    uint64_t at = scf__rd_offset(r);
    if ((rc = scf__rd_bytes(r, 50, &b, &got)) < 0)
      return rc;
    if (got < 50)
      return scf__rd_fail_byte(
          r, at, SCF_EFORMAT,
          "file ends inside triangle %llu of %llu (expected "
          "50 bytes, got %zu)",
          (scf__ull)k, (scf__ull)n, got);
    for (int c = 0; c < 3; c++) {
      const unsigned char *q = b + 12 + 12 * c;
      if ((rc = scf__vbuf_push(r, v, load_f32le(q), load_f32le(q + 4),
                               load_f32le(q + 8))) < 0)
        return rc;
    }
    uint32_t a = (uint32_t)(3 * k);
    if ((rc = scf__tbuf_push(r, t, a, a + 1, a + 2)) < 0)
      return rc;
  }
  return 0;
}

/* Unit normal of a counter-clockwise triangle; zero without area. */
static void facet_normal(const scf__mesh_in_t *m, size_t i, double n[3]) {
  const double *a = m->xyz + 3 * (size_t)m->tri[3 * i];
  const double *b = m->xyz + 3 * (size_t)m->tri[3 * i + 1];
  const double *c = m->xyz + 3 * (size_t)m->tri[3 * i + 2];
  double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  n[0] = u[1] * v[2] - u[2] * v[1];
  n[1] = u[2] * v[0] - u[0] * v[2];
  n[2] = u[0] * v[1] - u[1] * v[0];
  double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  for (int k = 0; k < 3; k++)
    n[k] = (len > 0 && isfinite(len)) ? n[k] / len : 0.0;
}

int scf__write_stl(scf__aout_t *o, const scf__mesh_in_t *m, int ascii) {
  int rc;
  double n[3];
  if (ascii) {
    rc = scf__out_printf(o, "solid shortcrust\n");
    for (size_t i = 0; rc == 0 && i < m->nt; i++) {
      facet_normal(m, i, n);
      rc = scf__out_printf(o, "facet normal %.9g %.9g %.9g\nouter loop\n", n[0],
                           n[1], n[2]);
      for (int c = 0; rc == 0 && c < 3; c++) {
        const double *p = m->xyz + 3 * (size_t)m->tri[3 * i + c];
        rc = scf__out_printf(o, "vertex %.17g %.17g %.17g\n", p[0], p[1], p[2]);
      }
      if (rc == 0)
        rc = scf__out_printf(o, "endloop\nendfacet\n");
    }
    return rc == 0 ? scf__out_printf(o, "endsolid shortcrust\n") : rc;
  }
  /* The header must not start with "solid", which marks ascii STL. */
  unsigned char head[84];
  memset(head, 0, sizeof head);
  memcpy(head, "binary STL written by shortcrust", 32);
  scf__put_u32le(head + 80, (uint32_t)m->nt);
  rc = scf__out_write(o, head, sizeof head);
  for (size_t i = 0; rc == 0 && i < m->nt; i++) {
    unsigned char rec[50];
    facet_normal(m, i, n);
    for (int k = 0; k < 3; k++)
      scf__put_f32le(rec + 4 * k, (float)n[k]);
    for (int c = 0; c < 3; c++) {
      const double *p = m->xyz + 3 * (size_t)m->tri[3 * i + c];
      for (int k = 0; k < 3; k++)
        scf__put_f32le(rec + 12 + 12 * c + 4 * k, (float)p[k]);
    }
    rec[48] = rec[49] = 0;
    rc = scf__out_write(o, rec, sizeof rec);
  }
  return rc;
}
