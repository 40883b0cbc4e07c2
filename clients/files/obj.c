/*
 * Wavefront OBJ: reading 'v' and 'f' lines, writing vertices, normals and
 * faces.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "scf_internal.h"

/*
 * OBJ: 'v' lines, and 'f' lines for a mesh. Positive face indices may refer
 * to vertices defined later, so they are checked once all are known.
 */
int scf__read_obj(scf__rd_t *r, scf__vbuf_t *v, scf__tbuf_t *t) {
  char *line, buf[SCF__SHOW_MAX + 4];
  int rc;
  int64_t max_idx = -1;
  uint64_t max_line = 0;
  while ((rc = scf__rd_line(r, &line)) == 1) {
    scf__strip_comment(line);
    char *cur = line;
    char *kw = scf__next_tok(&cur, SCF__WS);
    if (kw == NULL)
      continue;
    if (strcmp(kw, "v") == 0) {
      double xyz[3];
      const char *bad;
      int ntok;
      if (scf__three_numbers(&cur, SCF__WS, xyz, &bad, &ntok) < 0)
        return scf__bad_numbers(r, " after 'v'", bad, ntok);
      if ((rc = scf__vbuf_push(r, v, xyz[0], xyz[1], xyz[2])) < 0)
        return rc;
      continue;
    }
    if (t == NULL || strcmp(kw, "f") != 0)
      continue;
    scf__fan_t fan = {0, 0, 0};
    char *tok;
    while ((tok = scf__next_tok(&cur, SCF__WS)) != NULL) {
      char *slash = strchr(tok, '/');
      if (slash != NULL)
        *slash = '\0';
      int64_t i;
      if (scf__parse_i64(tok, &i) < 0 || i == 0)
        return scf__rd_fail_line(
            r, r->line, SCF_EFORMAT,
            "expected a vertex index (1-based, or negative "
            "from the last vertex), got '%s'",
            scf__show(tok, buf));
      int64_t idx = i > 0 ? i - 1 : (int64_t)v->count + i;
      if (idx < 0)
        return scf__rd_fail_line(
            r, r->line, SCF_EFORMAT,
            "relative vertex index %lld reaches before the "
            "first vertex (%zu so far)",
            (long long)i, v->count);
      if (idx > UINT32_MAX - 1)
        return scf__rd_fail_line(r, r->line, SCF_EUNSUPPORTED,
                                 "vertex index %lld is beyond 2^32 - 1",
                                 (long long)i);
      if (idx > max_idx) {
        max_idx = idx;
        max_line = r->line;
      }
      if ((rc = scf__fan_add(r, t, &fan, (uint32_t)idx)) < 0)
        return rc;
    }
    if (fan.n < 3)
      return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                               "face with %zu vertices (expected at least 3)",
                               fan.n);
  }
  if (rc < 0)
    return rc;
  if (max_idx >= 0 && (uint64_t)max_idx >= v->count)
    return scf__rd_fail_line(r, max_line, SCF_EFORMAT,
                             "face refers to vertex %lld, but the file has %zu "
                             "vertices",
                             (long long)max_idx + 1, v->count);
  return 0;
}

/* A colour channel scaled to [0, 1]: integers by their type's largest
 * value, floats as they are. */
static double obj_channel(const scf_attrs_t *a, size_t i, int k) {
  static const double top[] = {1,     127,        255,       32767,
                               65535, 2147483647, 4294967295.0};
  const scf_type_t t = a->props[k].type;
  const double v = scf_attrs_value(a, i, (size_t)k);
  return t <= SCF_TYPE_UINT32 ? v / top[t] : v;
}

int scf__write_obj(scf__aout_t *o, const scf__mesh_in_t *m) {
  int rc = scf__out_printf(o, "# written by shortcrust\n");
  /* Vertex colours, the common `v x y z r g b` extension, when the points
   * have red, green and blue. */
  const scf_attrs_t *at = m->attrs;
  const int cr = scf_attrs_find(at, "red"), cg = scf_attrs_find(at, "green"),
            cb = scf_attrs_find(at, "blue");
  const int colours = cr >= 0 && cg >= 0 && cb >= 0;
  for (size_t i = 0; rc == 0 && i < m->n; i++) {
    const double *p = m->xyz + 3 * i;
    rc = scf__out_printf(o, "v %.17g %.17g %.17g", p[0], p[1], p[2]);
    if (rc == 0 && colours) {
      rc = scf__out_printf(o, " %.9g %.9g %.9g", obj_channel(at, i, cr),
                           obj_channel(at, i, cg), obj_channel(at, i, cb));
    }
    if (rc == 0)
      rc = scf__out_write(o, "\n", 1);
  }
  /* The input's own normals win over the computed ones, as in PLY. */
  const int nx = scf_attrs_find(at, "nx"), ny = scf_attrs_find(at, "ny"),
            nz = scf_attrs_find(at, "nz");
  const int own = nx >= 0 && ny >= 0 && nz >= 0;
  const int vn = own || m->normals != NULL;
  for (size_t i = 0; rc == 0 && vn && i < m->n; i++) {
    double q[3];
    if (own) {
      q[0] = scf_attrs_value(at, i, (size_t)nx);
      q[1] = scf_attrs_value(at, i, (size_t)ny);
      q[2] = scf_attrs_value(at, i, (size_t)nz);
    } else {
      memcpy(q, m->normals + 3 * i, sizeof q);
    }
    rc = scf__out_printf(o, "vn %.9g %.9g %.9g\n", q[0], q[1], q[2]);
  }
  for (size_t i = 0; rc == 0 && i < m->nt; i++) {
    scf__ull a = (scf__ull)m->tri[3 * i] + 1,
             b = (scf__ull)m->tri[3 * i + 1] + 1,
             c = (scf__ull)m->tri[3 * i + 2] + 1;
    if (vn)
      rc = scf__out_printf(o, "f %llu//%llu %llu//%llu %llu//%llu\n", a, a, b,
                           b, c, c);
    else
      rc = scf__out_printf(o, "f %llu %llu %llu\n", a, b, c);
  }
  return rc;
}
