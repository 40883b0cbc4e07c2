/*
 * Point and mesh files: the one place that reads and writes PLY, XYZ-like
 * text, OFF, OBJ and STL, and reads LAS, shared by the local command and
 * the client. The module's public names start with scf_ (SCF_ for
 * constants), to keep them apart from the core's sc_ names; the internals
 * shared between its source files (scf_internal.h) start with scf__.
 *
 * Readers stream the file through a fixed buffer, so a file is never held in
 * memory whole, and they check every count a header declares against the
 * file's size before allocating for it. Every failure returns a negative
 * code and writes one line to the caller's message buffer naming the file,
 * the line (text) or byte offset (binary) and what was expected there.
 *
 * Writers never leave a half-written file behind: they write a temporary
 * file next to the target, flush it to disk and rename it over the target,
 * so an existing target is either replaced whole or left as it was.
 *
 * Numbers in text files are parsed with strtod(), so the process must keep
 * the "C" locale for LC_NUMERIC (the default unless setlocale() changes it).
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SHORTCRUST_FILES_H
#define SHORTCRUST_FILES_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

/*
 * Error codes, in a range of their own (-101 to -106) so that a program can
 * report them next to the core's codes without confusing the two.
 */
#define SCF_ERRNO_MAP(X)                                                       \
  X(INVAL, -101, "invalid argument")                                           \
  X(NOENT, -102, "no such file")                                               \
  X(IO, -103, "input/output error")                                            \
  X(FORMAT, -104, "malformed file")                                            \
  X(UNSUPPORTED, -105, "unsupported file format")                              \
  X(NOMEM, -106, "out of memory")

typedef enum scf_err {
  SCF_OK = 0,
#define SCF_ERR_ENUM_(name, value, text) SCF_E##name = (value),
  SCF_ERRNO_MAP(SCF_ERR_ENUM_)
#undef SCF_ERR_ENUM_
} scf_err_t;

/* A fixed English description of a code; "unknown error" for other values. */
const char *scf_strerror(int code);
/* The code's name without the prefix, e.g. "FORMAT", as the other modules
 * name theirs; "UNKNOWN" for other values. */
const char *scf_err_name(int code);

/* Points as 3 * count doubles (x, y, z of each point in turn). */
typedef struct scf_points {
  double *xyz;
  size_t count;
} scf_points_t;

/*
 * Reads the points of a file into *out, choosing the format by the file's
 * extension (case-insensitive):
 *   .ply                      PLY, ascii or binary of either byte order: the
 *                             x, y, z properties of the "vertex" element, of
 *                             any scalar type; everything else is skipped,
 *                             so a mesh file yields its vertices.
 *   .xyz .txt .pts .csv       one point per line, the first three numbers
 *                             separated by spaces, tabs or commas; further
 *                             columns are ignored, as are blank lines and
 *                             text after '#'. A .pts file may start with a
 *                             line holding only the point count, and a .csv
 *                             file with a line of column names; both are
 *                             skipped.
 *   .off                      OFF (also COFF, NOFF, CNOFF, STOFF): vertices.
 *   .obj                      Wavefront OBJ: the 'v' lines.
 *   .las                      LAS 1.0 to 1.4, point data record formats 0
 *                             to 10: X * scale + offset of every point
 *                             record (likewise Y, Z); with
 *                             scf_points_read_attrs(), also intensity,
 *                             return_number, number_of_returns,
 *                             classification and, where the format has
 *                             them, gps_time, red, green, blue, nir. Wave
 *                             packets, the variable-length records and
 *                             bytes after the points are skipped. LAZ (.laz, or
 * a .las file whose format byte marks compression) is refused with
 * SCF_EUNSUPPORTED: decompress it first (laszip, pdal translate).
 *   -                         standard input: PLY when it starts with the
 *                             line "ply", else .xyz text.
 * PLY and OFF files must start with their magic word, LAS files with
 * "LASF". A non-finite number ("nan", "inf") is returned as it is; a token
 * that is not a number is an error. A file without points is not an
 * error: count is 0 and xyz NULL.
 *
 * On success returns 0 and fills *out, which the caller releases with
 * scf_points_free(). On failure returns a negative SCF_E* code, leaves
 * *out zeroed, and writes a one-line message to msg (when msg_len > 0).
 */
int scf_points_read(const char *path, scf_points_t *out, char *msg,
                    size_t msg_len);

/* Releases the points and zeroes *p; accepts NULL and a zeroed struct. */
void scf_points_free(scf_points_t *p);

/*
 * Per-point properties carried from an input file to the mesh written from
 * it: colours, normals, intensity, confidence, anything a scanner adds.
 * Each property keeps its name and its type; the values are stored per
 * point, one record of `stride` bytes each, the property's value at
 * props[k].offset in the record, little-endian, in its own type. Values
 * are copied, never converted, so they come out exactly as they went in.
 */
typedef enum scf_type {
  SCF_TYPE_INT8 = 1,
  SCF_TYPE_UINT8,
  SCF_TYPE_INT16,
  SCF_TYPE_UINT16,
  SCF_TYPE_INT32,
  SCF_TYPE_UINT32,
  SCF_TYPE_FLOAT32,
  SCF_TYPE_FLOAT64
} scf_type_t;

typedef struct scf_prop {
  char name[32];
  scf_type_t type;
  size_t offset; /* in a point's record */
} scf_prop_t;

typedef struct scf_attrs {
  scf_prop_t *props;
  size_t count;        /* properties */
  size_t stride;       /* bytes per point */
  unsigned char *data; /* stride * points bytes */
  size_t points;
} scf_attrs_t;

/* Bytes of a value of the type (1, 2, 4 or 8); 0 for an unknown type. */
size_t scf_type_size(scf_type_t t);
/* The PLY name of the type ("uchar", "float", ...). */
const char *scf_type_name(scf_type_t t);

/*
 * scf_points_read(), also filling *attrs with the per-point properties the
 * file holds besides x, y and z: every scalar property of a PLY file's
 * vertex element, in the file's order; a LAS file's point attributes (see
 * above); a text file's numeric columns after x, y, z, as doubles named by
 * a .csv header or f0, f1, ... (when the first point's further columns
 * are all numbers; every later line must then have as many, or the read
 * fails with SCF_EFORMAT). OFF and OBJ give none (count 0).
 * *attrs is zeroed on failure; release it with scf_attrs_free().
 */
int scf_points_read_attrs(const char *path, scf_points_t *out,
                          scf_attrs_t *attrs, char *msg, size_t msg_len);
/* Releases the properties and zeroes *a; accepts NULL and a zeroed struct. */
void scf_attrs_free(scf_attrs_t *a);
/* The value of property prop of point point, as a number (every type a
 * property can have fits a double exactly). */
double scf_attrs_value(const scf_attrs_t *a, size_t point, size_t prop);
/* The index of the property of that name, or -1. */
int scf_attrs_find(const scf_attrs_t *a, const char *name);
/* Removes the named property and its values; 1 when it was there. */
int scf_attrs_remove(scf_attrs_t *a, const char *name);

/*
 * Reads a triangle mesh: vertices into *pts and 3 * *n_tri vertex indices
 * into *tri (malloc'd; release with free()). Formats by extension: .ply
 * (the "vertex" element and the "vertex_indices" or "vertex_index" list of
 * the "face" element), .off, .obj ('v' and 'f' lines, negative indices
 * counted back from the last vertex) and .stl (binary or ascii; STL has no
 * shared vertices, so each triangle gets three vertices of its own, in
 * file order). Polygons are split into a fan of triangles around their
 * first vertex. A file without faces gives *n_tri == 0 and *tri == NULL.
 * Failure as for scf_points_read(); *pts, *tri and *n_tri are then zeroed.
 */
int scf_mesh_read(const char *path, scf_points_t *pts, uint32_t **tri,
                  size_t *n_tri, char *msg, size_t msg_len);

/* Output formats of scf_mesh_write(). */
typedef enum scf_mesh_format {
  SCF_MESH_FMT_AUTO = 0,   /* by the path's extension, binary PLY for .ply */
  SCF_MESH_FMT_PLY_BINARY, /* binary little-endian PLY */
  SCF_MESH_FMT_PLY_ASCII,
  SCF_MESH_FMT_OFF,
  SCF_MESH_FMT_OBJ,
  SCF_MESH_FMT_STL_BINARY,
  SCF_MESH_FMT_STL_ASCII
} scf_mesh_format_t;

/*
 * The output format for a path's extension: .ply, .off, .obj or .stl (any
 * case), or PLY for "-" (standard output). With ascii non-zero, .ply and
 * .stl give their ascii variant; OFF and OBJ are text in any case. Returns 0,
 * or SCF_EUNSUPPORTED with a message naming the extension.
 */
int scf_mesh_format_from_path(const char *path, int ascii,
                              scf_mesh_format_t *fmt, char *msg,
                              size_t msg_len);

/*
 * Writes n_points vertices (xyz, 3 * n_points doubles) and n_tri triangles
 * (tri, 3 * n_tri indices into the vertices) to path, atomically; "-" is
 * standard output, written in place (what a failure leaves there is
 * partial).
 *
 * Every point is written, used by a triangle or not, so that indices keep
 * their meaning. Coordinates are written exactly: as doubles in binary PLY
 * and with 17 significant digits in text formats; binary STL stores floats.
 * normals (3 * n_points doubles, or NULL) are written as PLY nx, ny, nz
 * properties (float) and OBJ 'vn' lines (with faces 'f a//a b//b c//c');
 * OFF has no place for them. STL facet normals are computed from each
 * triangle, counter-clockwise meaning outward, and are zero for a triangle
 * without area.
 *
 * Returns 0, or a negative code with a message: SCF_EINVAL for an index
 * not below n_points (nothing is written then), SCF_EUNSUPPORTED for a
 * mesh the format cannot hold, SCF_EIO when creating, writing, syncing
 * or renaming fails. On failure an existing file at path is left as it was
 * and the temporary file is removed.
 */
int scf_mesh_write(const char *path, scf_mesh_format_t fmt, const double *xyz,
                   size_t n_points, const uint32_t *tri, size_t n_tri,
                   const double *normals, char *msg, size_t msg_len);

/*
 * scf_mesh_write() with per-point properties (attrs may be NULL; otherwise
 * attrs->points must be n_points). PLY writes every property after x, y, z,
 * unchanged in name, type and value; when they include nx, ny or nz, the
 * given normals are not written (the input's own normals win: drop them
 * from attrs to write the computed ones). OBJ writes the colours of
 * properties red, green and blue as `v x y z r g b`, scaled to [0, 1] (by
 * 255 for uchar, 65535 for ushort; floats as they are), and its `vn`
 * lines from nx, ny, nz when the properties have them. OFF and STL have no
 * place for them.
 */
int scf_mesh_write_attrs(const char *path, scf_mesh_format_t fmt,
                         const double *xyz, size_t n_points,
                         const uint32_t *tri, size_t n_tri,
                         const double *normals, const scf_attrs_t *attrs,
                         char *msg, size_t msg_len);

/*
 * Replaces the file at path with len bytes of data, atomically in the same
 * way as scf_mesh_write() (for reports and other small outputs). A new file
 * gets mode 0666 less the umask; a replaced file keeps its mode.
 */
int scf_write_atomic(const char *path, const void *data, size_t len, char *msg,
                     size_t msg_len);

/* Writes s to f as a JSON string, for reports beside the meshes: quoted,
 * with the quote and the backslash escaped and control characters as
 * \u00XX; NULL is written as "". */
void scf_json_string(FILE *f, const char *s);

#ifdef __cplusplus
}
#endif

#endif /* SHORTCRUST_FILES_H */
