/*
 * Internals of the point and mesh file module, shared by its source files:
 * messages (errors.c), the buffered reader and growing arrays (reader.c),
 * the atomic writer (atomic.c), and the reader and writer of each format
 * (ply.c, text.c, off.c, obj.c, stl.c; las.c reads only) that the
 * dispatcher (dispatch.c) picks by the file's extension.
 *
 * The helpers that run once per line, token, value or record are static
 * inline here, so that each format's hot loop has them inlined as it did
 * when the module was one file; their rare paths (refilling the buffer,
 * growing an array, writing a message) are out of line.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SCF_INTERNAL_H
#define SCF_INTERNAL_H

#include "shortcrust_files.h"

#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SCF__PRINTF_LIKE(f, a) __attribute__((format(printf, f, a)))

typedef unsigned long long scf__ull;

/* Messages (errors.c). */

/*
 * Writes "<path>: [<kind> <where>: ]<message>" to msg and returns code.
 * kind is "line", "byte" or NULL.
 */
int scf__vfail(char *msg, size_t msg_len, int code, const char *path,
               const char *kind, uint64_t where, const char *fmt, va_list ap);

/* As scf__vfail() without a place; a NULL path is shown as "(null)". */
SCF__PRINTF_LIKE(5, 6)
int scf__fail(char *msg, size_t msg_len, int code, const char *path,
              const char *fmt, ...);

/*
 * Tokens from a file go into messages; non-printing bytes are replaced so
 * that a binary file read as text still gives a one-line, readable message.
 * Returns buf.
 */
#define SCF__SHOW_MAX 40
const char *scf__show(const char *tok, char buf[SCF__SHOW_MAX + 4]);

/* The formats, as told by a path's extension (dispatch.c). */
enum scf__kind {
  SCF__K_NONE,
  SCF__K_PLY,
  SCF__K_XYZ,
  SCF__K_CSV,
  SCF__K_PTS,
  SCF__K_OFF,
  SCF__K_OBJ,
  SCF__K_STL,
  SCF__K_LAS,
  SCF__K_LAZ, /* known only to be refused */
  SCF__K_STDIO /* "-": standard input (PLY or XYZ, by PLY's magic) or output */
};

/* "-" names standard input or standard output. */
static inline int scf__is_stdio(const char *path) {
  return path != NULL && path[0] == '-' && path[1] == '\0';
}

/*
 * The buffered reader (reader.c). The buffer holds one byte more than
 * SCF__RD_CAP so that a last line without a line end can still be
 * NUL-terminated in place. SCF__RD_CAP bounds a text line and a binary
 * record (records are at most PLY_MAX_PROPS * 8 bytes, see ply.c).
 */
#define SCF__RD_CAP ((size_t)1 << 16)

typedef struct scf__rd {
  int fd;
  const char *path;
  char *msg;
  size_t msg_len;
  unsigned char *buf;
  size_t pos, end; /* unread bytes are buf[pos, end) */
  uint64_t base;   /* file offset of buf[0] */
  uint64_t line;   /* number of lines handed out so far */
  uint64_t size;   /* file size, UINT64_MAX when not a regular file */
  int eof;
} scf__rd_t;

SCF__PRINTF_LIKE(4, 5)
int scf__rd_fail_line(scf__rd_t *r, uint64_t line, int code, const char *fmt,
                      ...);
SCF__PRINTF_LIKE(4, 5)
int scf__rd_fail_byte(scf__rd_t *r, uint64_t offset, int code, const char *fmt,
                      ...);

int scf__rd_open(scf__rd_t *r, const char *path, char *msg, size_t msg_len);
void scf__rd_close(scf__rd_t *r);

/* Moves the unread bytes to the front and reads once more (sets eof). */
int scf__rd_fill(scf__rd_t *r);

/* Consumes n bytes, or fewer at the end of the file (*skipped says). */
int scf__rd_skip(scf__rd_t *r, uint64_t n, uint64_t *skipped);

static inline uint64_t scf__rd_offset(const scf__rd_t *r) {
  return r->base + r->pos;
}

/* Bytes after the current position, or UINT64_MAX when unknown. */
static inline uint64_t scf__rd_remaining(const scf__rd_t *r) {
  if (r->size == UINT64_MAX)
    return UINT64_MAX;
  uint64_t off = scf__rd_offset(r);
  return off < r->size ? r->size - off : 0;
}

/*
 * Hands out the next line, NUL-terminated and without its "\n" or "\r\n",
 * valid until the next call. Returns 1, 0 at the end of the file, or a
 * negative code.
 */
static inline int scf__rd_line(scf__rd_t *r, char **line) {
  size_t scanned = 0, len;
  unsigned char *start;
  for (;;) {
    start = r->buf + r->pos;
    size_t avail = r->end - r->pos;
    unsigned char *nl = memchr(start + scanned, '\n', avail - scanned);
    if (nl != NULL) {
      *nl = '\0';
      len = (size_t)(nl - start);
      r->pos += len + 1;
      break;
    }
    if (r->eof) {
      if (avail == 0)
        return 0;
      start[avail] = '\0';
      len = avail;
      r->pos = r->end;
      break;
    }
    if (avail >= SCF__RD_CAP) {
      /* The constant, not the call's result, tells the compiler that
       * *line is set whenever 1 is returned. */
      scf__rd_fail_line(r, r->line + 1, SCF_EFORMAT,
                        "line longer than %zu bytes", SCF__RD_CAP);
      return SCF_EFORMAT;
    }
    scanned = avail;
    int rc = scf__rd_fill(r);
    if (rc < 0)
      return rc;
  }
  r->line++;
  if (len > 0 && start[len - 1] == '\r')
    start[--len] = '\0';
  /* A NUL would silently cut the line short; it means a binary file. */
  if (memchr(start, '\0', len) != NULL) {
    scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                      "NUL byte in a text line (a binary file?)");
    return SCF_EFORMAT;
  }
  *line = (char *)start;
  return 1;
}

/* Makes up to n bytes (n <= SCF__RD_CAP) available at *p without consuming
 * them; *got is less than n only at the end of the file. */
static inline int scf__rd_peek(scf__rd_t *r, size_t n, const unsigned char **p,
                               size_t *got) {
  while (r->end - r->pos < n && !r->eof) {
    int rc = scf__rd_fill(r);
    if (rc < 0)
      return rc;
  }
  size_t avail = r->end - r->pos;
  *p = r->buf + r->pos;
  *got = avail < n ? avail : n;
  return 0;
}

/* As scf__rd_peek(), and consumes what it hands out. */
static inline int scf__rd_bytes(scf__rd_t *r, size_t n, const unsigned char **p,
                                size_t *got) {
  int rc = scf__rd_peek(r, n, p, got);
  if (rc == 0)
    r->pos += *got;
  return rc;
}

/* Growing arrays of points and of triangles. */
typedef struct scf__vbuf {
  double *xyz;
  size_t count, cap;
  scf_attrs_t *attrs; /* NULL when the caller wants x, y, z only */
  size_t acap;        /* points attrs->data has room for */
} scf__vbuf_t;

/* Appends one point's record of attrs->stride bytes (attrs.c). */
int scf__attrs_push(scf__rd_t *r, scf__vbuf_t *v, const unsigned char *rec);
/* Adds a property at the end of every record (no points yet): 0 or < 0. */
int scf__attrs_add(scf__rd_t *r, scf_attrs_t *a, const char *name,
                   scf_type_t type);

typedef struct scf__tbuf {
  uint32_t *idx;
  size_t count, cap;
} scf__tbuf_t;

int scf__vbuf_reserve(scf__rd_t *r, scf__vbuf_t *v, uint64_t cap);
int scf__tbuf_grow(scf__rd_t *r, scf__tbuf_t *t);

static inline int scf__vbuf_push(scf__rd_t *r, scf__vbuf_t *v, double x,
                                 double y, double z) {
  if (v->count == v->cap) {
    int rc = scf__vbuf_reserve(r, v, v->cap ? (uint64_t)v->cap * 2 : 4096);
    if (rc < 0)
      return rc;
  }
  double *p = v->xyz + 3 * v->count++;
  p[0] = x;
  p[1] = y;
  p[2] = z;
  return 0;
}

static inline int scf__tbuf_push(scf__rd_t *r, scf__tbuf_t *t, uint32_t a,
                                 uint32_t b, uint32_t c) {
  if (t->count == t->cap) {
    int rc = scf__tbuf_grow(r, t);
    if (rc < 0)
      return rc;
  }
  uint32_t *p = t->idx + 3 * t->count++;
  p[0] = a;
  p[1] = b;
  p[2] = c;
  return 0;
}

/* Polygons become fans around their first vertex; scf__fan_t feeds one. */
typedef struct scf__fan {
  uint32_t first, prev;
  size_t n;
} scf__fan_t;

static inline int scf__fan_add(scf__rd_t *r, scf__tbuf_t *t, scf__fan_t *f,
                               uint32_t v) {
  int rc = 0;
  if (f->n == 0)
    f->first = v;
  else if (f->n >= 2)
    rc = scf__tbuf_push(r, t, f->first, f->prev, v);
  f->prev = v;
  f->n++;
  return rc;
}

/* Text helpers. */
#define SCF__WS " \t\r\v\f"
#define SCF__XYZ_SEPS " \t\r\v\f,;"

/* Splits the next token off *cur, NUL-terminating it in place; NULL at the
 * end of the line. */
static inline char *scf__next_tok(char **cur, const char *seps) {
  char *s = *cur + strspn(*cur, seps);
  if (*s == '\0') {
    *cur = s;
    return NULL;
  }
  char *e = s + strcspn(s, seps);
  if (*e != '\0')
    *e++ = '\0';
  *cur = e;
  return s;
}

static inline void scf__strip_comment(char *line) {
  char *h = strchr(line, '#');
  if (h != NULL)
    *h = '\0';
}

/* The whole token must be a number; "nan" and "inf" are numbers. */
static inline int scf__parse_double(const char *tok, double *out) {
  char *end;
  double v = strtod(tok, &end);
  if (end == tok || *end != '\0')
    return -1;
  *out = v;
  return 0;
}

/* A decimal integer with an optional sign, the whole token. */
static inline int scf__parse_i64(const char *tok, int64_t *out) {
  const char *s = tok;
  int neg = 0;
  if (*s == '+' || *s == '-')
    neg = *s++ == '-';
  if (*s < '0' || *s > '9')
    return -1;
  uint64_t v = 0;
  for (; *s >= '0' && *s <= '9'; s++) {
    if (v > ((uint64_t)INT64_MAX - (uint64_t)(*s - '0')) / 10)
      return -1;
    v = v * 10 + (uint64_t)(*s - '0');
  }
  if (*s != '\0')
    return -1;
  *out = neg ? -(int64_t)v : (int64_t)v;
  return 0;
}

int scf__parse_u64(const char *tok, uint64_t *out);

/* Multiplies and adds without wrapping: UINT64_MAX stands for "too big". */
static inline uint64_t scf__sat_mul_add(uint64_t acc, uint64_t a, uint64_t b) {
  if (a != 0 && b > UINT64_MAX / a)
    return UINT64_MAX;
  uint64_t p = a * b;
  return p > UINT64_MAX - acc ? UINT64_MAX : acc + p;
}

/*
 * Reads the first three numbers of a text line into c. Returns 0, or -1
 * with the offending token in *bad (NULL when the line had fewer than three
 * tokens, *ntok saying how many).
 */
static inline int scf__three_numbers(char **cur, const char *seps, double c[3],
                                     const char **bad, int *ntok) {
  for (int i = 0; i < 3; i++) {
    char *t = scf__next_tok(cur, seps);
    if (t == NULL) {
      *bad = NULL;
      *ntok = i;
      return -1;
    }
    if (scf__parse_double(t, &c[i]) < 0) {
      *bad = t;
      *ntok = i;
      return -1;
    }
  }
  return 0;
}

/* The message for a line whose first three numbers scf__three_numbers()
 * could not read; what says after what ("" or e.g. " after 'v'"). */
int scf__bad_numbers(scf__rd_t *r, const char *what, const char *bad, int ntok);

/* Binary numbers, little-endian unless big_endian. */
static inline uint64_t scf__load_uint(const unsigned char *b, size_t n,
                                      int big_endian) {
  uint64_t v = 0;
  for (size_t i = 0; i < n; i++)
    v |= (uint64_t)b[big_endian ? n - 1 - i : i] << (8 * i);
  return v;
}

/* A binary value of the type as a number (attrs.c): integers of every
 * width, sign-extended where signed, and floats. */
int64_t scf__integer(const unsigned char *b, scf_type_t t, int big_endian);
double scf__number(const unsigned char *b, scf_type_t t, int big_endian);

static inline void scf__put_u32le(unsigned char *b, uint32_t v) {
  for (int i = 0; i < 4; i++)
    b[i] = (unsigned char)(v >> (8 * i));
}

static inline void scf__put_f32le(unsigned char *b, float f) {
  uint32_t w;
  memcpy(&w, &f, sizeof w);
  scf__put_u32le(b, w);
}

static inline void scf__put_f64le(unsigned char *b, double d) {
  uint64_t w;
  memcpy(&w, &d, sizeof w);
  for (int i = 0; i < 8; i++)
    b[i] = (unsigned char)(w >> (8 * i));
}

/* The readers of each format: points into v, and triangles into t when t is
 * not NULL (a mesh is wanted). kind tells .xyz/.txt, .pts and .csv apart. */
int scf__read_ply(scf__rd_t *r, scf__vbuf_t *v, scf__tbuf_t *t);
int scf__read_xyz(scf__rd_t *r, enum scf__kind kind, scf__vbuf_t *v);
int scf__read_off(scf__rd_t *r, scf__vbuf_t *v, scf__tbuf_t *t);
int scf__read_obj(scf__rd_t *r, scf__vbuf_t *v, scf__tbuf_t *t);
int scf__read_stl(scf__rd_t *r, scf__vbuf_t *v, scf__tbuf_t *t);
int scf__read_las(scf__rd_t *r, scf__vbuf_t *v);

/* The SCF_EUNSUPPORTED message for a .laz file, which says how to
 * decompress it (las.c). */
int scf__refuse_laz(const char *path, char *msg, size_t msg_len);

/*
 * Atomic output (atomic.c): a temporary file beside the target, renamed
 * over it by scf__aout_commit() only after everything was written and
 * synced; scf__aout_abort() removes it instead.
 */
typedef struct scf__aout {
  const char *path;
  char *tmp;
  int fd;
  FILE *fp;
  char *msg;
  size_t msg_len;
} scf__aout_t;

int scf__aout_open(scf__aout_t *o, const char *path, char *msg, size_t msg_len);
int scf__aout_commit(scf__aout_t *o);
void scf__aout_abort(scf__aout_t *o);
/* An SCF_EIO message "<what>: <strerror(errno)>"; returns SCF_EIO. */
int scf__aout_errno(scf__aout_t *o, const char *what);

static inline int scf__out_write(scf__aout_t *o, const void *p, size_t n) {
  /* fwrite() must not be given NULL, even for nothing (an empty file). */
  if (n > 0 && fwrite(p, 1, n, o->fp) != n)
    return scf__aout_errno(o, "write failed");
  return 0;
}

SCF__PRINTF_LIKE(2, 3)
int scf__out_printf(scf__aout_t *o, const char *fmt, ...);

/* A mesh to write, checked by scf_mesh_write(): every index is below n. */
typedef struct scf__mesh_in {
  const double *xyz;
  size_t n;
  const uint32_t *tri;
  size_t nt;
  const double *normals;
  const scf_attrs_t *attrs; /* NULL or with points == n */
} scf__mesh_in_t;

/* The writers of each format; ascii picks the text variant of PLY and STL. */
int scf__write_ply(scf__aout_t *o, const scf__mesh_in_t *m, int ascii);
int scf__write_off(scf__aout_t *o, const scf__mesh_in_t *m);
int scf__write_obj(scf__aout_t *o, const scf__mesh_in_t *m);
int scf__write_stl(scf__aout_t *o, const scf__mesh_in_t *m, int ascii);

#endif /* SCF_INTERNAL_H */
