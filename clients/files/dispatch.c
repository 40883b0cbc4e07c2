/*
 * The module's entry points: reading points or a mesh and writing a mesh
 * in the format a path's extension names, by handing the file to the
 * format's reader or writer.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "scf_internal.h"

/* Lower-case extension of the last path component, without the dot, or "". */
static void path_ext(const char *path, char ext[8]) {
  const char *slash = strrchr(path, '/');
  const char *base = slash ? slash + 1 : path;
  const char *dot = strrchr(base, '.');
  ext[0] = '\0';
  if (dot == NULL || dot == base || strlen(dot + 1) >= 8)
    return;
  size_t i = 0;
  for (; dot[1 + i]; i++) {
    char c = dot[1 + i];
    ext[i] = (c >= 'A' && c <= 'Z') ? (char)(c - 'A' + 'a') : c;
  }
  ext[i] = '\0';
}

static enum scf__kind kind_of(const char *path) {
  if (scf__is_stdio(path))
    return SCF__K_STDIO;
  char ext[8];
  path_ext(path, ext);
  static const struct {
    const char *ext;
    enum scf__kind kind;
  } table[] = {{"ply", SCF__K_PLY}, {"xyz", SCF__K_XYZ}, {"txt", SCF__K_XYZ},
               {"pts", SCF__K_PTS}, {"csv", SCF__K_CSV}, {"off", SCF__K_OFF},
               {"obj", SCF__K_OBJ}, {"stl", SCF__K_STL}, {"las", SCF__K_LAS},
               {"laz", SCF__K_LAZ}};
  for (size_t i = 0; i < sizeof table / sizeof table[0]; i++)
    if (strcmp(ext, table[i].ext) == 0)
      return table[i].kind;
  return SCF__K_NONE;
}

static int unknown_extension(const char *path, char *msg, size_t msg_len,
                             const char *expected) {
  char ext[8];
  path_ext(path, ext);
  if (ext[0] == '\0')
    return scf__fail(msg, msg_len, SCF_EUNSUPPORTED, path,
                     "no file extension to tell the format (expected %s)",
                     expected);
  return scf__fail(msg, msg_len, SCF_EUNSUPPORTED, path,
                   "unknown extension '.%s' (expected %s)", ext, expected);
}

/* Shrinks an array to its contents; keeps it when realloc fails. */
static void *shrink(void *p, size_t bytes) {
  if (p == NULL || bytes == 0)
    return p;
  void *q = realloc(p, bytes);
  return q ? q : p;
}

static int read_any(const char *path, scf_points_t *pts, uint32_t **tri,
                    size_t *n_tri, scf_attrs_t *attrs, char *msg,
                    size_t msg_len) {
  if (msg != NULL && msg_len > 0)
    msg[0] = '\0';
  if (pts != NULL)
    memset(pts, 0, sizeof *pts);
  if (attrs != NULL)
    memset(attrs, 0, sizeof *attrs);
  if (tri != NULL)
    *tri = NULL;
  if (n_tri != NULL)
    *n_tri = 0;
  if (path == NULL || pts == NULL || (n_tri != NULL && tri == NULL))
    return scf__fail(msg, msg_len, SCF_EINVAL, path,
                     "NULL path or output argument");
  enum scf__kind kind = kind_of(path);
  int mesh = n_tri != NULL;
  if (kind == SCF__K_NONE ||
      (mesh &&
       (kind == SCF__K_XYZ || kind == SCF__K_CSV || kind == SCF__K_PTS ||
        kind == SCF__K_LAS || kind == SCF__K_LAZ)) ||
      (!mesh && kind == SCF__K_STL))
    return unknown_extension(path, msg, msg_len,
                             mesh ? ".ply, .off, .obj or .stl"
                                  : ".ply, .xyz, .txt, .pts, .csv, .off, .obj "
                                    "or .las");
  /* No LAZ decoder is linked in: say so before opening the file. */
  if (kind == SCF__K_LAZ)
    return scf__refuse_laz(path, msg, msg_len);
  scf__rd_t r;
  scf__vbuf_t v = {NULL, 0, 0, attrs, 0};
  scf__tbuf_t t = {NULL, 0, 0};
  scf__tbuf_t *tp = mesh ? &t : NULL;
  int rc = scf__rd_open(&r, path, msg, msg_len);
  if (rc == 0 && kind == SCF__K_STDIO) {
    /* Standard input has no name to tell its format: PLY by its magic
     * word, else the points of a text file. */
    r.path = "standard input";
    while (rc == 0 && r.end - r.pos < 4 && !r.eof)
      rc = scf__rd_fill(&r);
    const unsigned char *b = r.buf + r.pos;
    const size_t have = r.end - r.pos;
    kind =
        have >= 4 && memcmp(b, "ply", 3) == 0 && (b[3] == '\n' || b[3] == '\r')
            ? SCF__K_PLY
            : SCF__K_XYZ;
    if (rc == 0 && mesh && kind != SCF__K_PLY)
      rc = scf__fail(msg, msg_len, SCF_EUNSUPPORTED, r.path,
                     "a mesh must come as PLY");
  }
  if (rc == 0) {
    switch (kind) {
    case SCF__K_PLY:
      rc = scf__read_ply(&r, &v, tp);
      break;
    case SCF__K_OFF:
      rc = scf__read_off(&r, &v, tp);
      break;
    case SCF__K_OBJ:
      rc = scf__read_obj(&r, &v, tp);
      break;
    case SCF__K_STL:
      rc = scf__read_stl(&r, &v, tp);
      break;
    case SCF__K_LAS:
      rc = scf__read_las(&r, &v);
      break;
    default:
      rc = scf__read_xyz(&r, kind, &v);
      break;
    }
  }
  scf__rd_close(&r);
  if (rc < 0) {
    free(v.xyz);
    free(t.idx);
    scf_attrs_free(attrs);
    return rc;
  }
  if (attrs != NULL && attrs->count == 0)
    scf_attrs_free(attrs);
  pts->xyz = v.count ? shrink(v.xyz, v.count * 3 * sizeof(double)) : NULL;
  if (v.count == 0)
    free(v.xyz);
  pts->count = v.count;
  if (mesh) {
    *tri = t.count ? shrink(t.idx, t.count * 3 * sizeof(uint32_t)) : NULL;
    if (t.count == 0)
      free(t.idx);
    *n_tri = t.count;
  }
  return 0;
}

int scf_points_read(const char *path, scf_points_t *out, char *msg,
                    size_t msg_len) {
  return read_any(path, out, NULL, NULL, NULL, msg, msg_len);
}

int scf_points_read_attrs(const char *path, scf_points_t *out,
                          scf_attrs_t *attrs, char *msg, size_t msg_len) {
  if (attrs == NULL)
    return scf__fail(msg, msg_len, SCF_EINVAL, path, "NULL attrs argument");
  return read_any(path, out, NULL, NULL, attrs, msg, msg_len);
}

int scf_mesh_read(const char *path, scf_points_t *pts, uint32_t **tri,
                  size_t *n_tri, char *msg, size_t msg_len) {
  if (n_tri == NULL) {
    /* The outputs that were given are zeroed, as on any failure. */
    if (pts != NULL)
      memset(pts, 0, sizeof *pts);
    if (tri != NULL)
      *tri = NULL;
    return scf__fail(msg, msg_len, SCF_EINVAL, path, "NULL n_tri argument");
  }
  return read_any(path, pts, tri, n_tri, NULL, msg, msg_len);
}

void scf_points_free(scf_points_t *p) {
  if (p == NULL)
    return;
  free(p->xyz);
  p->xyz = NULL;
  p->count = 0;
}

int scf_mesh_format_from_path(const char *path, int ascii,
                              scf_mesh_format_t *fmt, char *msg,
                              size_t msg_len) {
  if (path == NULL || fmt == NULL)
    return scf__fail(msg, msg_len, SCF_EINVAL, path, "NULL argument");
  switch (kind_of(path)) {
  case SCF__K_STDIO: /* standard output: PLY */
  case SCF__K_PLY:
    *fmt = ascii ? SCF_MESH_FMT_PLY_ASCII : SCF_MESH_FMT_PLY_BINARY;
    return 0;
  case SCF__K_OFF:
    *fmt = SCF_MESH_FMT_OFF;
    return 0;
  case SCF__K_OBJ:
    *fmt = SCF_MESH_FMT_OBJ;
    return 0;
  case SCF__K_STL:
    *fmt = ascii ? SCF_MESH_FMT_STL_ASCII : SCF_MESH_FMT_STL_BINARY;
    return 0;
  default:
    return unknown_extension(path, msg, msg_len, ".ply, .off, .obj or .stl");
  }
}

int scf_mesh_write(const char *path, scf_mesh_format_t fmt, const double *xyz,
                   size_t n_points, const uint32_t *tri, size_t n_tri,
                   const double *normals, char *msg, size_t msg_len) {
  return scf_mesh_write_attrs(path, fmt, xyz, n_points, tri, n_tri, normals,
                              NULL, msg, msg_len);
}

int scf_mesh_write_attrs(const char *path, scf_mesh_format_t fmt,
                         const double *xyz, size_t n_points,
                         const uint32_t *tri, size_t n_tri,
                         const double *normals, const scf_attrs_t *attrs,
                         char *msg, size_t msg_len) {
  if (msg != NULL && msg_len > 0)
    msg[0] = '\0';
  if (path == NULL || (xyz == NULL && n_points > 0) ||
      (tri == NULL && n_tri > 0))
    return scf__fail(msg, msg_len, SCF_EINVAL, path,
                     "NULL path, points or triangles");
  if (fmt == SCF_MESH_FMT_AUTO) {
    int rc = scf_mesh_format_from_path(path, 0, &fmt, msg, msg_len);
    if (rc < 0)
      return rc;
  }
  if (fmt < SCF_MESH_FMT_PLY_BINARY || fmt > SCF_MESH_FMT_STL_ASCII)
    return scf__fail(msg, msg_len, SCF_EINVAL, path, "unknown format %d",
                     (int)fmt);
  for (size_t i = 0; i < 3 * n_tri; i++)
    if (tri[i] >= n_points)
      return scf__fail(msg, msg_len, SCF_EINVAL, path,
                       "triangle %zu refers to point %u, but there are %zu "
                       "points",
                       i / 3, (unsigned)tri[i], n_points);
  if (fmt == SCF_MESH_FMT_STL_BINARY && n_tri > UINT32_MAX)
    return scf__fail(msg, msg_len, SCF_EUNSUPPORTED, path,
                     "binary STL holds at most 2^32 - 1 triangles, not %zu",
                     n_tri);
  if (attrs != NULL && attrs->count == 0)
    attrs = NULL;
  if (attrs != NULL && attrs->points != n_points)
    return scf__fail(msg, msg_len, SCF_EINVAL, path,
                     "properties for %zu points, but there are %zu points",
                     attrs->points, n_points);
  scf__mesh_in_t m = {xyz, n_points, tri, n_tri, normals, attrs};
  scf__aout_t o;
  int rc = scf__aout_open(&o, path, msg, msg_len);
  if (rc < 0)
    return rc;
  switch (fmt) {
  case SCF_MESH_FMT_PLY_BINARY:
  case SCF_MESH_FMT_PLY_ASCII:
    rc = scf__write_ply(&o, &m, fmt == SCF_MESH_FMT_PLY_ASCII);
    break;
  case SCF_MESH_FMT_OFF:
    rc = scf__write_off(&o, &m);
    break;
  case SCF_MESH_FMT_OBJ:
    rc = scf__write_obj(&o, &m);
    break;
  default:
    rc = scf__write_stl(&o, &m, fmt == SCF_MESH_FMT_STL_ASCII);
    break;
  }
  if (rc == 0)
    rc = scf__aout_commit(&o);
  if (rc < 0)
    scf__aout_abort(&o);
  return rc;
}
