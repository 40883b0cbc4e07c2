/*
 * Point and mesh files (see shortcrust_files.h for the contract).
 *
 * Reading goes through rd_t, a fixed buffer over a file descriptor that
 * knows the byte offset and line number of what it hands out, so that every
 * error can say where it happened. Text formats are read line by line,
 * binary ones record by record; nothing depends on the whole file fitting
 * in memory. Counts from headers are checked against the bytes left in the
 * file before anything is allocated for them, and allocation then grows
 * with the data actually read, which also covers inputs of unknown size.
 *
 * Writing goes through aout_t: a temporary file beside the target, renamed
 * over it only after everything was written and synced.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "shortcrust_files.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#define PRINTF_LIKE(f, a) __attribute__((format(printf, f, a)))

typedef unsigned long long ull;

const char *scf_strerror(int code) {
  switch (code) {
  case SCF_OK:
    return "success";
#define SCF_ERR_TEXT_(name, value, text)                                   \
  case SCF_E##name:                                                        \
    return text;
    SCF_ERRNO_MAP(SCF_ERR_TEXT_)
#undef SCF_ERR_TEXT_
  default:
    return "unknown error";
  }
}

const char *scf_err_name(int code) {
  switch (code) {
  case SCF_OK:
    return "OK";
#define SCF_ERR_NAME_(name, value, text)                                   \
  case SCF_E##name:                                                        \
    return "E" #name;
    SCF_ERRNO_MAP(SCF_ERR_NAME_)
#undef SCF_ERR_NAME_
  default:
    return "UNKNOWN";
  }
}

/*
 * Writes "<path>: [<kind> <where>: ]<message>" to msg and returns code.
 * kind is "line", "byte" or NULL.
 */
static int vfail(char *msg, size_t msg_len, int code, const char *path,
                 const char *kind, uint64_t where, const char *fmt,
                 va_list ap) {
  if (msg == NULL || msg_len == 0)
    return code;
  int n = kind ? snprintf(msg, msg_len, "%s: %s %llu: ", path, kind,
                          (ull)where)
               : snprintf(msg, msg_len, "%s: ", path);
  if (n >= 0 && (size_t)n < msg_len)
    vsnprintf(msg + n, msg_len - (size_t)n, fmt, ap);
  return code;
}

PRINTF_LIKE(5, 6)
static int fail(char *msg, size_t msg_len, int code, const char *path,
                const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vfail(msg, msg_len, code, path ? path : "(null)", NULL, 0, fmt, ap);
  va_end(ap);
  return code;
}

/*
 * Tokens from a file go into messages; non-printing bytes are replaced so
 * that a binary file read as text still gives a one-line, readable message.
 */
#define SHOW_MAX 40
static const char *show(const char *tok, char buf[SHOW_MAX + 4]) {
  size_t i = 0;
  for (; tok[i] && i < SHOW_MAX; i++) {
    unsigned char c = (unsigned char)tok[i];
    buf[i] = (c < 0x20 || c == 0x7f) ? '?' : (char)c;
  }
  if (tok[i]) {
    memcpy(buf + i, "...", 3);
    i += 3;
  }
  buf[i] = '\0';
  return buf;
}

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

enum kind { K_NONE, K_PLY, K_XYZ, K_CSV, K_PTS, K_OFF, K_OBJ, K_STL };

static enum kind kind_of(const char *path) {
  char ext[8];
  path_ext(path, ext);
  static const struct {
    const char *ext;
    enum kind kind;
  } table[] = {{"ply", K_PLY}, {"xyz", K_XYZ}, {"txt", K_XYZ},
               {"pts", K_PTS}, {"csv", K_CSV}, {"off", K_OFF},
               {"obj", K_OBJ}, {"stl", K_STL}};
  for (size_t i = 0; i < sizeof table / sizeof table[0]; i++)
    if (strcmp(ext, table[i].ext) == 0)
      return table[i].kind;
  return K_NONE;
}

/*
 * The buffered reader. The buffer holds one byte more than RD_CAP so that
 * a last line without a line end can still be NUL-terminated in place.
 * RD_CAP bounds a text line and a binary record (records are at most
 * PLY_MAX_PROPS * 8 bytes).
 */
#define RD_CAP ((size_t)1 << 16)

typedef struct rd {
  int fd;
  const char *path;
  char *msg;
  size_t msg_len;
  unsigned char *buf;
  size_t pos, end;  /* unread bytes are buf[pos, end) */
  uint64_t base;    /* file offset of buf[0] */
  uint64_t line;    /* number of lines handed out so far */
  uint64_t size;    /* file size, UINT64_MAX when not a regular file */
  int eof;
} rd_t;

PRINTF_LIKE(4, 5)
static int rd_fail_line(rd_t *r, uint64_t line, int code, const char *fmt,
                        ...) {
  va_list ap;
  va_start(ap, fmt);
  vfail(r->msg, r->msg_len, code, r->path, "line", line, fmt, ap);
  va_end(ap);
  return code;
}

PRINTF_LIKE(4, 5)
static int rd_fail_byte(rd_t *r, uint64_t offset, int code, const char *fmt,
                        ...) {
  va_list ap;
  va_start(ap, fmt);
  vfail(r->msg, r->msg_len, code, r->path, "byte", offset, fmt, ap);
  va_end(ap);
  return code;
}

static int rd_open(rd_t *r, const char *path, char *msg, size_t msg_len) {
  memset(r, 0, sizeof *r);
  r->fd = -1;
  r->path = path;
  r->msg = msg;
  r->msg_len = msg_len;
  r->size = UINT64_MAX;
  r->fd = open(path, O_RDONLY | O_CLOEXEC);
  if (r->fd < 0) {
    int e = errno;
    return fail(msg, msg_len, e == ENOENT ? SCF_ENOENT : SCF_EIO,
                path, "cannot open: %s", strerror(e));
  }
  struct stat st;
  if (fstat(r->fd, &st) != 0)
    return fail(msg, msg_len, SCF_EIO, path, "cannot stat: %s",
                strerror(errno));
  if (S_ISDIR(st.st_mode))
    return fail(msg, msg_len, SCF_EIO, path,
                "is a directory, not a file");
  if (S_ISREG(st.st_mode))
    r->size = (uint64_t)st.st_size;
  r->buf = malloc(RD_CAP + 1);
  if (r->buf == NULL)
    return fail(msg, msg_len, SCF_ENOMEM, path,
                "out of memory for the read buffer");
  return 0;
}

static void rd_close(rd_t *r) {
  if (r->fd >= 0)
    close(r->fd);
  free(r->buf);
  r->fd = -1;
  r->buf = NULL;
}

static uint64_t rd_offset(const rd_t *r) { return r->base + r->pos; }

/* Bytes after the current position, or UINT64_MAX when unknown. */
static uint64_t rd_remaining(const rd_t *r) {
  if (r->size == UINT64_MAX)
    return UINT64_MAX;
  uint64_t off = rd_offset(r);
  return off < r->size ? r->size - off : 0;
}

/* Moves the unread bytes to the front and reads once more (sets eof). */
static int rd_fill(rd_t *r) {
  if (r->pos > 0) {
    memmove(r->buf, r->buf + r->pos, r->end - r->pos);
    r->base += r->pos;
    r->end -= r->pos;
    r->pos = 0;
  }
  while (!r->eof && r->end < RD_CAP) {
    ssize_t n = read(r->fd, r->buf + r->end, RD_CAP - r->end);
    if (n < 0) {
      if (errno == EINTR)
        continue;
      return rd_fail_byte(r, r->base + r->end, SCF_EIO,
                          "read failed: %s", strerror(errno));
    }
    if (n == 0)
      r->eof = 1;
    else
      r->end += (size_t)n;
    break;
  }
  return 0;
}

/*
 * Hands out the next line, NUL-terminated and without its "\n" or "\r\n",
 * valid until the next call. Returns 1, 0 at the end of the file, or a
 * negative code.
 */
static int rd_line(rd_t *r, char **line) {
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
    if (avail >= RD_CAP)
      return rd_fail_line(r, r->line + 1, SCF_EFORMAT,
                          "line longer than %zu bytes", RD_CAP);
    scanned = avail;
    int rc = rd_fill(r);
    if (rc < 0)
      return rc;
  }
  r->line++;
  if (len > 0 && start[len - 1] == '\r')
    start[--len] = '\0';
  /* A NUL would silently cut the line short; it means a binary file. */
  if (memchr(start, '\0', len) != NULL)
    return rd_fail_line(r, r->line, SCF_EFORMAT,
                        "NUL byte in a text line (a binary file?)");
  *line = (char *)start;
  return 1;
}

/* Makes up to n bytes (n <= RD_CAP) available at *p without consuming
 * them; *got is less than n only at the end of the file. */
static int rd_peek(rd_t *r, size_t n, const unsigned char **p, size_t *got) {
  while (r->end - r->pos < n && !r->eof) {
    int rc = rd_fill(r);
    if (rc < 0)
      return rc;
  }
  size_t avail = r->end - r->pos;
  *p = r->buf + r->pos;
  *got = avail < n ? avail : n;
  return 0;
}

/* As rd_peek(), and consumes what it hands out. */
static int rd_bytes(rd_t *r, size_t n, const unsigned char **p, size_t *got) {
  int rc = rd_peek(r, n, p, got);
  if (rc == 0)
    r->pos += *got;
  return rc;
}

/* Consumes n bytes, or fewer at the end of the file (*skipped says). */
static int rd_skip(rd_t *r, uint64_t n, uint64_t *skipped) {
  uint64_t done = 0;
  while (done < n) {
    if (r->pos == r->end) {
      if (r->eof)
        break;
      int rc = rd_fill(r);
      if (rc < 0)
        return rc;
      continue;
    }
    size_t avail = r->end - r->pos;
    size_t take = (n - done) < avail ? (size_t)(n - done) : avail;
    r->pos += take;
    done += take;
  }
  *skipped = done;
  return 0;
}

/* Growing arrays of points and of triangles. */
typedef struct vbuf {
  double *xyz;
  size_t count, cap;
} vbuf_t;

typedef struct tbuf {
  uint32_t *idx;
  size_t count, cap;
} tbuf_t;

static int vbuf_reserve(rd_t *r, vbuf_t *v, uint64_t cap) {
  if (cap <= v->cap)
    return 0;
  if (cap > SIZE_MAX / (3 * sizeof(double)))
    return fail(r->msg, r->msg_len, SCF_ENOMEM, r->path,
                "too many points for memory (%llu)", (ull)cap);
  double *p = realloc(v->xyz, (size_t)cap * 3 * sizeof(double));
  if (p == NULL)
    return fail(r->msg, r->msg_len, SCF_ENOMEM, r->path,
                "out of memory for %llu points", (ull)cap);
  v->xyz = p;
  v->cap = (size_t)cap;
  return 0;
}

static int vbuf_push(rd_t *r, vbuf_t *v, double x, double y, double z) {
  if (v->count == v->cap) {
    int rc = vbuf_reserve(r, v, v->cap ? (uint64_t)v->cap * 2 : 4096);
    if (rc < 0)
      return rc;
  }
  double *p = v->xyz + 3 * v->count++;
  p[0] = x;
  p[1] = y;
  p[2] = z;
  return 0;
}

static int tbuf_push(rd_t *r, tbuf_t *t, uint32_t a, uint32_t b, uint32_t c) {
  if (t->count == t->cap) {
    size_t cap = t->cap ? t->cap * 2 : 4096;
    if (cap < t->cap || cap > SIZE_MAX / (3 * sizeof(uint32_t)))
      return fail(r->msg, r->msg_len, SCF_ENOMEM, r->path,
                  "too many triangles for memory");
    uint32_t *p = realloc(t->idx, cap * 3 * sizeof(uint32_t));
    if (p == NULL)
      return fail(r->msg, r->msg_len, SCF_ENOMEM, r->path,
                  "out of memory after %zu triangles", t->count);
    t->idx = p;
    t->cap = cap;
  }
  uint32_t *p = t->idx + 3 * t->count++;
  p[0] = a;
  p[1] = b;
  p[2] = c;
  return 0;
}

/* Polygons become fans around their first vertex; fan_t feeds one. */
typedef struct fan {
  uint32_t first, prev;
  size_t n;
} fan_t;

static int fan_add(rd_t *r, tbuf_t *t, fan_t *f, uint32_t v) {
  int rc = 0;
  if (f->n == 0)
    f->first = v;
  else if (f->n >= 2)
    rc = tbuf_push(r, t, f->first, f->prev, v);
  f->prev = v;
  f->n++;
  return rc;
}

/* Text helpers. */
#define WS " \t\r\v\f"
#define XYZ_SEPS " \t\r\v\f,;"

/* Splits the next token off *cur, NUL-terminating it in place; NULL at the
 * end of the line. */
static char *next_tok(char **cur, const char *seps) {
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

static void strip_comment(char *line) {
  char *h = strchr(line, '#');
  if (h != NULL)
    *h = '\0';
}

/* The whole token must be a number; "nan" and "inf" are numbers. */
static int parse_double(const char *tok, double *out) {
  char *end;
  double v = strtod(tok, &end);
  if (end == tok || *end != '\0')
    return -1;
  *out = v;
  return 0;
}

/* A decimal integer with an optional sign, the whole token. */
static int parse_i64(const char *tok, int64_t *out) {
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

static int parse_u64(const char *tok, uint64_t *out) {
  int64_t v;
  if (tok[0] == '-' || tok[0] == '+' || parse_i64(tok, &v) < 0)
    return -1;
  *out = (uint64_t)v;
  return 0;
}

/* Multiplies and adds without wrapping: UINT64_MAX stands for "too big". */
static uint64_t sat_mul_add(uint64_t acc, uint64_t a, uint64_t b) {
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
static int three_numbers(char **cur, const char *seps, double c[3],
                         const char **bad, int *ntok) {
  for (int i = 0; i < 3; i++) {
    char *t = next_tok(cur, seps);
    if (t == NULL) {
      *bad = NULL;
      *ntok = i;
      return -1;
    }
    if (parse_double(t, &c[i]) < 0) {
      *bad = t;
      *ntok = i;
      return -1;
    }
  }
  return 0;
}

static int bad_numbers(rd_t *r, const char *what, const char *bad, int ntok) {
  char buf[SHOW_MAX + 4];
  if (bad != NULL)
    return rd_fail_line(r, r->line, SCF_EFORMAT,
                        "expected 3 numbers%s, got '%s'", what,
                        show(bad, buf));
  return rd_fail_line(r, r->line, SCF_EFORMAT,
                      "expected 3 numbers%s, got %d", what, ntok);
}

/* PLY. */
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
  } table[] = {{"char", PT_I8},     {"int8", PT_I8},     {"uchar", PT_U8},
               {"uint8", PT_U8},    {"short", PT_I16},   {"int16", PT_I16},
               {"ushort", PT_U16},  {"uint16", PT_U16},  {"int", PT_I32},
               {"int32", PT_I32},   {"uint", PT_U32},    {"uint32", PT_U32},
               {"float", PT_F32},   {"float32", PT_F32}, {"double", PT_F64},
               {"float64", PT_F64}};
  for (size_t i = 0; i < sizeof table / sizeof table[0]; i++)
    if (strcmp(name, table[i].name) == 0)
      return table[i].type;
  return PT_NONE;
}

static size_t ply_type_size(ply_type_t t) {
  switch (t) {
  case PT_I8:
  case PT_U8:
    return 1;
  case PT_I16:
  case PT_U16:
    return 2;
  case PT_I32:
  case PT_U32:
  case PT_F32:
    return 4;
  case PT_F64:
    return 8;
  default:
    return 0;
  }
}

static int ply_type_is_int(ply_type_t t) { return t >= PT_I8 && t <= PT_U32; }

static uint64_t load_uint(const unsigned char *b, size_t n, int big_endian) {
  uint64_t v = 0;
  for (size_t i = 0; i < n; i++)
    v |= (uint64_t)b[big_endian ? n - 1 - i : i] << (8 * i);
  return v;
}

static int64_t sign_extend(uint64_t u, unsigned bits) {
  uint64_t top = (uint64_t)1 << (bits - 1);
  return (u & top) ? (int64_t)u - (int64_t)(top << 1) : (int64_t)u;
}

/* Integer types only (the header parser makes sure of that). */
static int64_t ply_int(const unsigned char *b, ply_type_t t, int big_endian) {
  uint64_t u = load_uint(b, ply_type_size(t), big_endian);
  switch (t) {
  case PT_I8:
    return sign_extend(u, 8);
  case PT_I16:
    return sign_extend(u, 16);
  case PT_I32:
    return sign_extend(u, 32);
  default:
    return (int64_t)u;
  }
}

static double ply_double(const unsigned char *b, ply_type_t t,
                         int big_endian) {
  if (t == PT_F32) {
    uint32_t w = (uint32_t)load_uint(b, 4, big_endian);
    float f;
    memcpy(&f, &w, sizeof f);
    return f;
  }
  if (t == PT_F64) {
    uint64_t w = load_uint(b, 8, big_endian);
    double d;
    memcpy(&d, &w, sizeof d);
    return d;
  }
  return (double)ply_int(b, t, big_endian);
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
} ply_t;

static void ply_free(ply_t *p) {
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

static int ply_header_line(rd_t *r, ply_t *p, char *line, int *done) {
  char *cur = line, buf[SHOW_MAX + 4];
  char *kw = next_tok(&cur, WS);
  if (kw == NULL || strcmp(kw, "comment") == 0 ||
      strcmp(kw, "obj_info") == 0)
    return 0;
  if (strcmp(kw, "end_header") == 0) {
    *done = 1;
    return 0;
  }
  if (strcmp(kw, "format") == 0) {
    char *fmt = next_tok(&cur, WS), *ver = next_tok(&cur, WS);
    if (p->format != 0)
      return rd_fail_line(r, r->line, SCF_EFORMAT,
                          "second format line in the header");
    if (fmt == NULL || ver == NULL)
      return rd_fail_line(r, r->line, SCF_EFORMAT,
                          "expected 'format <type> 1.0'");
    if (strcmp(fmt, "ascii") == 0)
      p->format = PLY_ASCII;
    else if (strcmp(fmt, "binary_little_endian") == 0)
      p->format = PLY_LE;
    else if (strcmp(fmt, "binary_big_endian") == 0)
      p->format = PLY_BE;
    else
      return rd_fail_line(r, r->line, SCF_EFORMAT,
                          "unknown PLY format '%s' (expected ascii, "
                          "binary_little_endian or binary_big_endian)",
                          show(fmt, buf));
    if (strcmp(ver, "1.0") != 0)
      return rd_fail_line(r, r->line, SCF_EUNSUPPORTED,
                          "PLY version '%s' (only 1.0 is supported)",
                          show(ver, buf));
    return 0;
  }
  if (strcmp(kw, "element") == 0) {
    char *name = next_tok(&cur, WS), *count = next_tok(&cur, WS);
    if (name == NULL || count == NULL)
      return rd_fail_line(r, r->line, SCF_EFORMAT,
                          "expected 'element <name> <count>'");
    uint64_t n;
    if (parse_u64(count, &n) < 0)
      return rd_fail_line(r, r->line, SCF_EFORMAT,
                          "expected a count for element '%s', got '%s'",
                          name, show(count, buf));
    if (p->n_elems == PLY_MAX_ELEMENTS)
      return rd_fail_line(r, r->line, SCF_EUNSUPPORTED,
                          "more than %d elements", PLY_MAX_ELEMENTS);
    if (p->n_elems % 8 == 0) {
      ply_elem_t *e = realloc(p->elems, (p->n_elems + 8) * sizeof *e);
      if (e == NULL)
        return rd_fail_line(r, r->line, SCF_ENOMEM, "out of memory");
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
      return rd_fail_line(r, r->line, SCF_EFORMAT,
                          "property before any element");
    ply_elem_t *e = &p->elems[p->n_elems - 1];
    ply_prop_t prop;
    memset(&prop, 0, sizeof prop);
    char *type = next_tok(&cur, WS);
    if (type != NULL && strcmp(type, "list") == 0) {
      char *ct = next_tok(&cur, WS);
      if (ct == NULL)
        return rd_fail_line(r, r->line, SCF_EFORMAT,
                            "expected 'property list <count type> <item "
                            "type> <name>'");
      prop.count_type = ply_type_of(ct);
      if (!ply_type_is_int(prop.count_type))
        return rd_fail_line(r, r->line, SCF_EFORMAT,
                            "list count type '%s' is not an integer type",
                            show(ct, buf));
      type = next_tok(&cur, WS);
    }
    char *name = next_tok(&cur, WS);
    if (type == NULL || name == NULL)
      return rd_fail_line(r, r->line, SCF_EFORMAT,
                          "expected 'property <type> <name>'");
    prop.type = ply_type_of(type);
    if (prop.type == PT_NONE)
      return rd_fail_line(r, r->line, SCF_EFORMAT,
                          "unknown property type '%s'", show(type, buf));
    copy_name(prop.name, name);
    if (e->n_props == PLY_MAX_PROPS)
      return rd_fail_line(r, r->line, SCF_EUNSUPPORTED,
                          "more than %d properties in element '%s'",
                          PLY_MAX_PROPS, e->name);
    if (e->n_props == e->cap_props) {
      size_t cap = e->cap_props ? e->cap_props * 2 : 8;
      ply_prop_t *np = realloc(e->props, cap * sizeof *np);
      if (np == NULL)
        return rd_fail_line(r, r->line, SCF_ENOMEM, "out of memory");
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
  return rd_fail_line(r, r->line, SCF_EFORMAT,
                      "unknown header keyword '%s'", show(kw, buf));
}

static int ply_find_prop(const ply_elem_t *e, const char *name) {
  for (size_t i = 0; i < e->n_props; i++)
    if (strcmp(e->props[i].name, name) == 0)
      return (int)i;
  return -1;
}

static int ply_header(rd_t *r, ply_t *p, int want_faces) {
  char *line;
  int rc = rd_line(r, &line);
  if (rc < 0)
    return rc;
  if (rc == 0 || strcmp(line, "ply") != 0)
    return rd_fail_line(r, 1, SCF_EFORMAT,
                        "not a PLY file: the first line is not 'ply'");
  for (int done = 0; !done;) {
    rc = rd_line(r, &line);
    if (rc < 0)
      return rc;
    if (rc == 0)
      return rd_fail_line(r, r->line, SCF_EFORMAT,
                          "file ends inside the header (no end_header)");
    rc = ply_header_line(r, p, line, &done);
    if (rc < 0)
      return rc;
  }
  p->header_end = r->line;
  if (p->format == 0)
    return rd_fail_line(r, r->line, SCF_EFORMAT,
                        "no format line in the header");
  p->vertex = p->face = -1;
  for (size_t i = 0; i < p->n_elems; i++) {
    if (strcmp(p->elems[i].name, "vertex") == 0) {
      if (p->vertex >= 0)
        return rd_fail_line(r, r->line, SCF_EFORMAT,
                            "two vertex elements in the header");
      p->vertex = (int)i;
    } else if (want_faces && p->face < 0 &&
               strcmp(p->elems[i].name, "face") == 0) {
      p->face = (int)i;
    }
  }
  if (p->vertex < 0)
    return rd_fail_line(r, r->line, SCF_EFORMAT,
                        "no vertex element in the header");
  const ply_elem_t *v = &p->elems[p->vertex];
  int *slots[3] = {&p->px, &p->py, &p->pz};
  static const char *const axes[3] = {"x", "y", "z"};
  for (int a = 0; a < 3; a++) {
    *slots[a] = ply_find_prop(v, axes[a]);
    if (*slots[a] < 0)
      return rd_fail_line(r, r->line, SCF_EFORMAT,
                          "the vertex element has no property '%s'",
                          axes[a]);
    if (v->props[*slots[a]].count_type != PT_NONE)
      return rd_fail_line(r, r->line, SCF_EFORMAT,
                          "vertex property '%s' is a list", axes[a]);
  }
  p->pface = -1;
  if (p->face >= 0) {
    const ply_elem_t *f = &p->elems[p->face];
    p->pface = ply_find_prop(f, "vertex_indices");
    if (p->pface < 0)
      p->pface = ply_find_prop(f, "vertex_index");
    if (p->pface < 0 || f->props[p->pface].count_type == PT_NONE)
      return rd_fail_line(r, r->line, SCF_EFORMAT,
                          "the face element has no vertex_indices list");
    if (!ply_type_is_int(f->props[p->pface].type))
      return rd_fail_line(r, r->line, SCF_EFORMAT,
                          "face vertex indices are not of an integer type");
    if (v->count > UINT32_MAX)
      return rd_fail_line(r, r->line, SCF_EUNSUPPORTED,
                          "%llu vertices: meshes with more than 2^32 - 1 "
                          "vertices are not supported",
                          (ull)v->count);
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
static int ply_truncated(rd_t *r, uint64_t rec, uint64_t at,
                         const ply_elem_t *e, uint64_t k, uint64_t expected,
                         uint64_t got) {
  if (got == 0 && at == rec)
    return rd_fail_byte(r, at, SCF_EFORMAT,
                        "file ends before %s %llu of %llu", e->name, (ull)k,
                        (ull)e->count);
  return rd_fail_byte(r, at, SCF_EFORMAT,
                      "file ends inside %s %llu of %llu (expected %llu "
                      "bytes, got %llu)",
                      e->name, (ull)k, (ull)e->count, (ull)expected,
                      (ull)got);
}

/*
 * Checks that the elements up to the last one needed fit in what is left of
 * the file, at their smallest (empty lists; one digit and a separator per
 * value in ascii), before anything is allocated for them.
 */
static int ply_check_size(rd_t *r, const ply_t *p) {
  uint64_t rem = rd_remaining(r), need = 0;
  int exact = 1; /* whether need is the exact size so far */
  if (rem == UINT64_MAX)
    return 0;
  for (size_t i = 0; i <= ply_last_needed(p); i++) {
    const ply_elem_t *e = &p->elems[i];
    uint64_t per =
        p->format == PLY_ASCII ? 2 * (uint64_t)e->n_props : e->rec_size;
    uint64_t before = need;
    need = sat_mul_add(need, e->count, per);
    /* An ascii file may lack the line end after its last value. */
    uint64_t least = (p->format == PLY_ASCII && need > 0) ? need - 1 : need;
    if (least <= rem) {
      exact = exact && e->fixed;
      continue;
    }
    if (p->format == PLY_ASCII)
      return rd_fail_line(
          r, p->header_end, SCF_EFORMAT,
          "the header declares %llu %s records; with the elements before "
          "them they need at least %llu bytes, but only %llu bytes follow "
          "the header",
          (ull)e->count, e->name, (ull)least, (ull)rem);
    /* With fixed-size records so far, the point where the file ends is
     * known exactly, and saying so is the most useful message. */
    if (exact && e->fixed) {
      uint64_t left = rem - before, k = left / e->rec_size;
      uint64_t at = rd_offset(r) + before + k * e->rec_size;
      return ply_truncated(r, at, at, e, k, e->rec_size,
                           left % e->rec_size);
    }
    return rd_fail_byte(
        r, rd_offset(r), SCF_EFORMAT,
        "the header declares %llu %s records; with the elements before them "
        "they need at least %llu bytes, but only %llu bytes follow the "
        "header",
        (ull)e->count, e->name, (ull)least, (ull)rem);
  }
  return 0;
}

static int ply_reserve(rd_t *r, const ply_t *p, vbuf_t *v) {
  uint64_t n = p->elems[p->vertex].count;
  /* Without a known file size the count is unchecked: grow as data comes. */
  if (rd_remaining(r) == UINT64_MAX && n > 65536)
    n = 65536;
  return n > 0 ? vbuf_reserve(r, v, n) : 0;
}

static int ply_check_index(rd_t *r, const ply_t *p, int64_t idx,
                           uint64_t k, int binary, uint64_t at) {
  uint64_t nv = p->elems[p->vertex].count;
  if (idx >= 0 && (uint64_t)idx < nv)
    return 0;
  const char *fmt = "face %llu refers to vertex %lld, but there are %llu "
                    "vertices";
  if (binary)
    return rd_fail_byte(r, at, SCF_EFORMAT, fmt, (ull)k, (long long)idx,
                        (ull)nv);
  return rd_fail_line(r, at, SCF_EFORMAT, fmt, (ull)k, (long long)idx,
                      (ull)nv);
}

static int ply_binary_elem(rd_t *r, const ply_t *p, size_t ei, vbuf_t *v,
                           tbuf_t *t) {
  const ply_elem_t *e = &p->elems[ei];
  int be = p->format == PLY_BE;
  int role = (int)ei == p->vertex ? ROLE_VERTEX
             : (int)ei == p->face ? ROLE_FACE
                                  : ROLE_OTHER;
  const unsigned char *b;
  size_t got;
  uint64_t skipped;
  int rc;

  if (e->fixed && role == ROLE_OTHER) {
    uint64_t start = rd_offset(r);
    uint64_t total = sat_mul_add(0, e->count, e->rec_size);
    if ((rc = rd_skip(r, total, &skipped)) < 0)
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
    uint64_t rec = rd_offset(r), at = rec;
    if (e->fixed) {
      if ((rc = rd_bytes(r, e->rec_size, &b, &got)) < 0)
        return rc;
      if (got < e->rec_size)
        return ply_truncated(r, at, at, e, k, e->rec_size, got);
      const ply_prop_t *pp = e->props;
      rc = vbuf_push(r, v, ply_double(b + pp[p->px].offset, pp[p->px].type, be),
                     ply_double(b + pp[p->py].offset, pp[p->py].type, be),
                     ply_double(b + pp[p->pz].offset, pp[p->pz].type, be));
      if (rc < 0)
        return rc;
      continue;
    }
    double xyz[3] = {0, 0, 0};
    for (size_t j = 0; j < e->n_props; j++) {
      const ply_prop_t *pp = &e->props[j];
      at = rd_offset(r);
      if (pp->count_type == PT_NONE) {
        size_t sz = ply_type_size(pp->type);
        if ((rc = rd_bytes(r, sz, &b, &got)) < 0)
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
        }
        continue;
      }
      size_t csz = ply_type_size(pp->count_type);
      if ((rc = rd_bytes(r, csz, &b, &got)) < 0)
        return rc;
      if (got < csz)
        return ply_truncated(r, rec, at, e, k, csz, got);
      int64_t n = ply_int(b, pp->count_type, be);
      if (n < 0)
        return rd_fail_byte(r, at, SCF_EFORMAT,
                            "negative list length %lld in %s %llu",
                            (long long)n, e->name, (ull)k);
      size_t isz = ply_type_size(pp->type);
      if (role == ROLE_FACE && (int)j == p->pface) {
        if (n < 3)
          return rd_fail_byte(r, at, SCF_EFORMAT,
                              "face %llu has %lld vertices (expected at "
                              "least 3)",
                              (ull)k, (long long)n);
        fan_t fan = {0, 0, 0};
        for (int64_t i = 0; i < n; i++) {
          at = rd_offset(r);
          if ((rc = rd_bytes(r, isz, &b, &got)) < 0)
            return rc;
          if (got < isz)
            return ply_truncated(r, rec, at, e, k, isz, got);
          int64_t idx = ply_int(b, pp->type, be);
          if ((rc = ply_check_index(r, p, idx, k, 1, at)) < 0 ||
              (rc = fan_add(r, t, &fan, (uint32_t)idx)) < 0)
            return rc;
        }
        continue;
      }
      uint64_t bytes = (uint64_t)n * isz;
      at = rd_offset(r);
      if ((rc = rd_skip(r, bytes, &skipped)) < 0)
        return rc;
      if (skipped < bytes)
        return ply_truncated(r, rec, at, e, k, bytes, skipped);
    }
    if (role == ROLE_VERTEX &&
        (rc = vbuf_push(r, v, xyz[0], xyz[1], xyz[2])) < 0)
      return rc;
  }
  return 0;
}

/* Ascii PLY values form one stream of tokens; line breaks are not
 * significant, but line numbers go into messages. */
typedef struct tokens {
  rd_t *r;
  char *cur;
} tokens_t;

static int tokens_next(tokens_t *ts, char **tok) {
  for (;;) {
    if (ts->cur != NULL && (*tok = next_tok(&ts->cur, WS)) != NULL)
      return 1;
    int rc = rd_line(ts->r, &ts->cur);
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
    return rd_fail_line(ts->r, ts->r->line, SCF_EFORMAT,
                        "file ends inside %s %llu of %llu (expected %s)",
                        e->name, (ull)k, (ull)e->count, what);
  return 0;
}

static int ply_ascii_elem(tokens_t *ts, const ply_t *p, size_t ei, vbuf_t *v,
                          tbuf_t *t) {
  const ply_elem_t *e = &p->elems[ei];
  rd_t *r = ts->r;
  int role = (int)ei == p->vertex ? ROLE_VERTEX
             : (int)ei == p->face ? ROLE_FACE
                                  : ROLE_OTHER;
  char *tok = NULL, buf[SHOW_MAX + 4], what[PLY_NAME + 32];
  int rc;
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
        if (parse_double(tok, &d) < 0)
          return rd_fail_line(r, r->line, SCF_EFORMAT,
                              "expected a number for property '%s' of %s "
                              "%llu, got '%s'",
                              pp->name, e->name, (ull)k, show(tok, buf));
        if (role == ROLE_VERTEX) {
          if ((int)j == p->px)
            xyz[0] = d;
          else if ((int)j == p->py)
            xyz[1] = d;
          else if ((int)j == p->pz)
            xyz[2] = d;
        }
        continue;
      }
      int64_t n;
      if (parse_i64(tok, &n) < 0 || n < 0)
        return rd_fail_line(r, r->line, SCF_EFORMAT,
                            "expected a list length for '%s' of %s %llu, "
                            "got '%s'",
                            pp->name, e->name, (ull)k, show(tok, buf));
      int is_face = role == ROLE_FACE && (int)j == p->pface;
      if (is_face && n < 3)
        return rd_fail_line(r, r->line, SCF_EFORMAT,
                            "face %llu has %lld vertices (expected at "
                            "least 3)",
                            (ull)k, (long long)n);
      fan_t fan = {0, 0, 0};
      snprintf(what, sizeof what, "an item of list '%s'", pp->name);
      for (int64_t i = 0; i < n; i++) {
        if ((rc = ply_ascii_value(ts, e, k, what, &tok)) < 0)
          return rc;
        if (is_face) {
          int64_t idx;
          if (parse_i64(tok, &idx) < 0)
            return rd_fail_line(r, r->line, SCF_EFORMAT,
                                "expected a vertex index in face %llu, got "
                                "'%s'",
                                (ull)k, show(tok, buf));
          if ((rc = ply_check_index(r, p, idx, k, 0, r->line)) < 0 ||
              (rc = fan_add(r, t, &fan, (uint32_t)idx)) < 0)
            return rc;
        } else {
          double d;
          if (parse_double(tok, &d) < 0)
            return rd_fail_line(r, r->line, SCF_EFORMAT,
                                "expected a number in list '%s' of %s %llu, "
                                "got '%s'",
                                pp->name, e->name, (ull)k, show(tok, buf));
        }
      }
    }
    if (role == ROLE_VERTEX &&
        (rc = vbuf_push(r, v, xyz[0], xyz[1], xyz[2])) < 0)
      return rc;
  }
  return 0;
}

static int read_ply(rd_t *r, vbuf_t *v, tbuf_t *t) {
  ply_t p;
  memset(&p, 0, sizeof p);
  int rc = ply_header(r, &p, t != NULL);
  if (rc == 0)
    rc = ply_check_size(r, &p);
  tokens_t ts = {r, NULL};
  for (size_t i = 0; rc == 0 && i <= ply_last_needed(&p); i++)
    rc = p.format == PLY_ASCII ? ply_ascii_elem(&ts, &p, i, v, t)
                               : ply_binary_elem(r, &p, i, v, t);
  ply_free(&p);
  return rc;
}

/*
 * XYZ-like text. The first line of a .pts file may be the point count and
 * the first line of a .csv file may name the columns; both are skipped.
 */
static int read_xyz(rd_t *r, enum kind kind, vbuf_t *v) {
  char *line;
  int rc, first = 1;
  while ((rc = rd_line(r, &line)) == 1) {
    strip_comment(line);
    char *cur = line + strspn(line, XYZ_SEPS);
    if (*cur == '\0')
      continue;
    if (first) {
      first = 0;
      char copy[64], *c = copy, *tok;
      snprintf(copy, sizeof copy, "%s", cur);
      uint64_t n;
      double d;
      if (kind == K_PTS && (tok = next_tok(&c, XYZ_SEPS)) != NULL &&
          parse_u64(tok, &n) == 0 && next_tok(&c, XYZ_SEPS) == NULL &&
          strlen(cur) < sizeof copy)
        continue;
      if (kind == K_CSV) {
        int numeric = 0;
        for (int i = 0; i < 3 && (tok = next_tok(&c, XYZ_SEPS)) != NULL; i++)
          numeric |= parse_double(tok, &d) == 0;
        if (!numeric)
          continue;
      }
    }
    double xyz[3];
    const char *bad;
    int ntok;
    if (three_numbers(&cur, XYZ_SEPS, xyz, &bad, &ntok) < 0)
      return bad_numbers(r, "", bad, ntok);
    if ((rc = vbuf_push(r, v, xyz[0], xyz[1], xyz[2])) < 0)
      return rc;
  }
  return rc;
}

/* The next line with something on it after comments are removed. */
static int next_content_line(rd_t *r, char **cur) {
  char *line;
  int rc;
  while ((rc = rd_line(r, &line)) == 1) {
    strip_comment(line);
    *cur = line + strspn(line, WS);
    if (**cur != '\0')
      return 1;
  }
  return rc;
}

/* OFF keywords: [ST][C][N]OFF; 4OFF and nOFF have other coordinates. */
static int off_keyword(const char *kw) {
  const char *s = kw;
  if (strncmp(s, "ST", 2) == 0)
    s += 2;
  if (*s == 'C')
    s++;
  if (*s == 'N')
    s++;
  if (strcmp(s, "OFF") == 0)
    return 1;
  if (*s == '4' || *s == 'n')
    return strstr(s, "OFF") != NULL ? -1 : 0;
  return 0;
}

static int read_off(rd_t *r, vbuf_t *v, tbuf_t *t) {
  char *cur, *tok, buf[SHOW_MAX + 4];
  int rc = next_content_line(r, &cur);
  if (rc < 0)
    return rc;
  tok = rc ? next_tok(&cur, WS) : NULL;
  int kw = tok ? off_keyword(tok) : 0;
  if (kw < 0)
    return rd_fail_line(r, r->line, SCF_EUNSUPPORTED,
                        "'%s' files (not three coordinates) are not "
                        "supported",
                        show(tok, buf));
  if (kw == 0)
    return rd_fail_line(r, rc ? r->line : 1, SCF_EFORMAT,
                        "not an OFF file: expected 'OFF' first, got '%s'",
                        tok ? show(tok, buf) : "");
  tok = next_tok(&cur, WS);
  if (tok != NULL && strcmp(tok, "BINARY") == 0)
    return rd_fail_line(r, r->line, SCF_EUNSUPPORTED,
                        "binary OFF is not supported");
  /* The counts may follow the keyword on the same line. */
  if (tok == NULL) {
    if ((rc = next_content_line(r, &cur)) < 0)
      return rc;
    if (rc == 0)
      return rd_fail_line(r, r->line, SCF_EFORMAT,
                          "file ends before the vertex and face counts");
    tok = next_tok(&cur, WS);
  }
  char *ftok = next_tok(&cur, WS);
  uint64_t nv, nf;
  if (parse_u64(tok, &nv) < 0 || ftok == NULL || parse_u64(ftok, &nf) < 0)
    return rd_fail_line(r, r->line, SCF_EFORMAT,
                        "expected the vertex and face counts, got '%s'",
                        show(tok, buf));
  uint64_t rem = rd_remaining(r);
  /* A vertex line holds at least "0 0 0\n", a face line "3 0 1 2\n". */
  uint64_t need = sat_mul_add(sat_mul_add(0, nv, 6), t ? nf : 0, 8);
  if (rem != UINT64_MAX && need > 0 && need - 1 > rem)
    return rd_fail_line(r, r->line,
                        SCF_EFORMAT,
                        "the header declares %llu vertices%s%s, which need "
                        "at least %llu bytes, but only %llu bytes follow",
                        (ull)nv, t ? " and faces " : "", t ? ftok : "",
                        (ull)(need - 1), (ull)rem);
  if (t != NULL && nv > UINT32_MAX)
    return rd_fail_line(r, r->line, SCF_EUNSUPPORTED,
                        "meshes with more than 2^32 - 1 vertices are not "
                        "supported");
  if (nv > 0 && (rc = vbuf_reserve(r, v, rem == UINT64_MAX && nv > 65536
                                             ? 65536
                                             : nv)) < 0)
    return rc;
  for (uint64_t k = 0; k < nv; k++) {
    if ((rc = next_content_line(r, &cur)) < 0)
      return rc;
    if (rc == 0)
      return rd_fail_line(r, r->line, SCF_EFORMAT,
                          "file ends after %llu of %llu vertices", (ull)k,
                          (ull)nv);
    double xyz[3];
    const char *bad;
    int ntok;
    if (three_numbers(&cur, WS, xyz, &bad, &ntok) < 0)
      return bad_numbers(r, " for a vertex", bad, ntok);
    if ((rc = vbuf_push(r, v, xyz[0], xyz[1], xyz[2])) < 0)
      return rc;
  }
  for (uint64_t k = 0; t != NULL && k < nf; k++) {
    if ((rc = next_content_line(r, &cur)) < 0)
      return rc;
    if (rc == 0)
      return rd_fail_line(r, r->line, SCF_EFORMAT,
                          "file ends after %llu of %llu faces", (ull)k,
                          (ull)nf);
    tok = next_tok(&cur, WS);
    int64_t n;
    if (parse_i64(tok, &n) < 0 || n < 3)
      return rd_fail_line(r, r->line, SCF_EFORMAT,
                          "expected a vertex count of at least 3 for face "
                          "%llu, got '%s'",
                          (ull)k, show(tok, buf));
    fan_t fan = {0, 0, 0};
    for (int64_t i = 0; i < n; i++) {
      int64_t idx;
      tok = next_tok(&cur, WS);
      if (tok == NULL)
        return rd_fail_line(r, r->line, SCF_EFORMAT,
                            "face %llu has %lld of its %lld vertex indices",
                            (ull)k, (long long)i, (long long)n);
      if (parse_i64(tok, &idx) < 0 || idx < 0 || (uint64_t)idx >= nv)
        return rd_fail_line(r, r->line, SCF_EFORMAT,
                            "expected a vertex index below %llu in face "
                            "%llu, got '%s'",
                            (ull)nv, (ull)k, show(tok, buf));
      if ((rc = fan_add(r, t, &fan, (uint32_t)idx)) < 0)
        return rc;
    }
  }
  return 0;
}

/*
 * OBJ: 'v' lines, and 'f' lines for a mesh. Positive face indices may refer
 * to vertices defined later, so they are checked once all are known.
 */
static int read_obj(rd_t *r, vbuf_t *v, tbuf_t *t) {
  char *line, buf[SHOW_MAX + 4];
  int rc;
  int64_t max_idx = -1;
  uint64_t max_line = 0;
  while ((rc = rd_line(r, &line)) == 1) {
    strip_comment(line);
    char *cur = line;
    char *kw = next_tok(&cur, WS);
    if (kw == NULL)
      continue;
    if (strcmp(kw, "v") == 0) {
      double xyz[3];
      const char *bad;
      int ntok;
      if (three_numbers(&cur, WS, xyz, &bad, &ntok) < 0)
        return bad_numbers(r, " after 'v'", bad, ntok);
      if ((rc = vbuf_push(r, v, xyz[0], xyz[1], xyz[2])) < 0)
        return rc;
      continue;
    }
    if (t == NULL || strcmp(kw, "f") != 0)
      continue;
    fan_t fan = {0, 0, 0};
    char *tok;
    while ((tok = next_tok(&cur, WS)) != NULL) {
      char *slash = strchr(tok, '/');
      if (slash != NULL)
        *slash = '\0';
      int64_t i;
      if (parse_i64(tok, &i) < 0 || i == 0)
        return rd_fail_line(r, r->line, SCF_EFORMAT,
                            "expected a vertex index (1-based, or negative "
                            "from the last vertex), got '%s'",
                            show(tok, buf));
      int64_t idx = i > 0 ? i - 1 : (int64_t)v->count + i;
      if (idx < 0)
        return rd_fail_line(r, r->line, SCF_EFORMAT,
                            "relative vertex index %lld reaches before the "
                            "first vertex (%zu so far)",
                            (long long)i, v->count);
      if (idx > UINT32_MAX - 1)
        return rd_fail_line(r, r->line, SCF_EUNSUPPORTED,
                            "vertex index %lld is beyond 2^32 - 1",
                            (long long)i);
      if (idx > max_idx) {
        max_idx = idx;
        max_line = r->line;
      }
      if ((rc = fan_add(r, t, &fan, (uint32_t)idx)) < 0)
        return rc;
    }
    if (fan.n < 3)
      return rd_fail_line(r, r->line, SCF_EFORMAT,
                          "face with %zu vertices (expected at least 3)",
                          fan.n);
  }
  if (rc < 0)
    return rc;
  if (max_idx >= 0 && (uint64_t)max_idx >= v->count)
    return rd_fail_line(r, max_line, SCF_EFORMAT,
                        "face refers to vertex %lld, but the file has %zu "
                        "vertices",
                        (long long)max_idx + 1, v->count);
  return 0;
}

static float load_f32le(const unsigned char *b) {
  uint32_t w = (uint32_t)load_uint(b, 4, 0);
  float f;
  memcpy(&f, &w, sizeof f);
  return f;
}

static int read_stl_ascii(rd_t *r, vbuf_t *v, tbuf_t *t) {
  char *line, *cur, *kw, buf[SHOW_MAX + 4];
  int rc, in_loop = 0, nloop = 0;
  while ((rc = rd_line(r, &line)) == 1) {
    cur = line;
    kw = next_tok(&cur, WS);
    if (kw == NULL || strcmp(kw, "solid") == 0 ||
        strcmp(kw, "endsolid") == 0 || strcmp(kw, "facet") == 0 ||
        strcmp(kw, "endfacet") == 0)
      continue;
    if (strcmp(kw, "outer") == 0) {
      in_loop = 1;
      nloop = 0;
    } else if (strcmp(kw, "vertex") == 0) {
      double xyz[3];
      const char *bad;
      int ntok;
      if (!in_loop || nloop == 3)
        return rd_fail_line(r, r->line, SCF_EFORMAT,
                            "vertex outside an 'outer loop' of three");
      if (three_numbers(&cur, WS, xyz, &bad, &ntok) < 0)
        return bad_numbers(r, " after 'vertex'", bad, ntok);
      if (v->count >= UINT32_MAX)
        return rd_fail_line(r, r->line, SCF_EUNSUPPORTED,
                            "more than 2^32 - 1 vertices");
      if ((rc = vbuf_push(r, v, xyz[0], xyz[1], xyz[2])) < 0)
        return rc;
      nloop++;
    } else if (strcmp(kw, "endloop") == 0) {
      if (!in_loop || nloop != 3)
        return rd_fail_line(r, r->line, SCF_EFORMAT,
                            "loop with %d vertices (expected 3)", nloop);
      uint32_t a = (uint32_t)(v->count - 3);
      if ((rc = tbuf_push(r, t, a, a + 1, a + 2)) < 0)
        return rc;
      in_loop = 0;
    } else {
      return rd_fail_line(r, r->line, SCF_EFORMAT,
                          "expected an STL keyword, got '%s'",
                          show(kw, buf));
    }
  }
  if (rc == 0 && in_loop)
    return rd_fail_line(r, r->line, SCF_EFORMAT,
                        "file ends inside a facet");
  return rc;
}

/*
 * Binary STL files may also begin with "solid", so a file is taken as
 * ascii only when it begins so and its size does not match the binary
 * layout.
 */
static int read_stl(rd_t *r, vbuf_t *v, tbuf_t *t) {
  const unsigned char *b;
  size_t got;
  int rc = rd_peek(r, 84, &b, &got);
  if (rc < 0)
    return rc;
  uint64_t n = got >= 84 ? load_uint(b + 80, 4, 0) : 0;
  int sized = r->size != UINT64_MAX && got >= 84 && r->size == 84 + 50 * n;
  if (got >= 5 && memcmp(b, "solid", 5) == 0 && !sized)
    return read_stl_ascii(r, v, t);
  if (got < 84)
    return rd_fail_byte(r, got, SCF_EFORMAT,
                        "file ends inside the 84-byte binary STL header "
                        "(got %zu bytes)",
                        got);
  if (r->size != UINT64_MAX && r->size < 84 + 50 * n)
    return rd_fail_byte(r, 80, SCF_EFORMAT,
                        "the header declares %llu triangles, which need "
                        "%llu bytes, but the file has %llu",
                        (ull)n, (ull)(84 + 50 * n), (ull)r->size);
  if (n > (UINT32_MAX - 1) / 3)
    return rd_fail_byte(r, 80, SCF_EUNSUPPORTED,
                        "%llu triangles need more than 2^32 - 1 vertices",
                        (ull)n);
  r->pos += 84;
  if ((rc = vbuf_reserve(r, v, 3 * (r->size != UINT64_MAX || n < 65536
                                        ? n
                                        : 65536))) < 0)
    return rc;
  for (uint64_t k = 0; k < n; k++) {
    uint64_t at = rd_offset(r);
    if ((rc = rd_bytes(r, 50, &b, &got)) < 0)
      return rc;
    if (got < 50)
      return rd_fail_byte(r, at, SCF_EFORMAT,
                          "file ends inside triangle %llu of %llu (expected "
                          "50 bytes, got %zu)",
                          (ull)k, (ull)n, got);
    for (int c = 0; c < 3; c++) {
      const unsigned char *q = b + 12 + 12 * c;
      if ((rc = vbuf_push(r, v, load_f32le(q), load_f32le(q + 4),
                          load_f32le(q + 8))) < 0)
        return rc;
    }
    uint32_t a = (uint32_t)(3 * k);
    if ((rc = tbuf_push(r, t, a, a + 1, a + 2)) < 0)
      return rc;
  }
  return 0;
}

static int unknown_extension(const char *path, char *msg, size_t msg_len,
                             const char *expected) {
  char ext[8];
  path_ext(path, ext);
  if (ext[0] == '\0')
    return fail(msg, msg_len, SCF_EUNSUPPORTED, path,
                "no file extension to tell the format (expected %s)",
                expected);
  return fail(msg, msg_len, SCF_EUNSUPPORTED, path,
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
                    size_t *n_tri, char *msg, size_t msg_len) {
  if (msg != NULL && msg_len > 0)
    msg[0] = '\0';
  if (pts != NULL)
    memset(pts, 0, sizeof *pts);
  if (tri != NULL)
    *tri = NULL;
  if (n_tri != NULL)
    *n_tri = 0;
  if (path == NULL || pts == NULL || (n_tri != NULL && tri == NULL))
    return fail(msg, msg_len, SCF_EINVAL, path,
                "NULL path or output argument");
  enum kind kind = kind_of(path);
  int mesh = n_tri != NULL;
  if (kind == K_NONE || (mesh && (kind == K_XYZ || kind == K_CSV ||
                                  kind == K_PTS)) ||
      (!mesh && kind == K_STL))
    return unknown_extension(path, msg, msg_len,
                             mesh ? ".ply, .off, .obj or .stl"
                                  : ".ply, .xyz, .txt, .pts, .csv, .off or "
                                    ".obj");
  rd_t r;
  vbuf_t v = {NULL, 0, 0};
  tbuf_t t = {NULL, 0, 0};
  tbuf_t *tp = mesh ? &t : NULL;
  int rc = rd_open(&r, path, msg, msg_len);
  if (rc == 0) {
    switch (kind) {
    case K_PLY:
      rc = read_ply(&r, &v, tp);
      break;
    case K_OFF:
      rc = read_off(&r, &v, tp);
      break;
    case K_OBJ:
      rc = read_obj(&r, &v, tp);
      break;
    case K_STL:
      rc = read_stl(&r, &v, tp);
      break;
    default:
      rc = read_xyz(&r, kind, &v);
      break;
    }
  }
  rd_close(&r);
  if (rc < 0) {
    free(v.xyz);
    free(t.idx);
    return rc;
  }
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
  return read_any(path, out, NULL, NULL, msg, msg_len);
}

int scf_mesh_read(const char *path, scf_points_t *pts, uint32_t **tri,
                 size_t *n_tri, char *msg, size_t msg_len) {
  if (n_tri == NULL) {
    /* The outputs that were given are zeroed, as on any failure. */
    if (pts != NULL)
      memset(pts, 0, sizeof *pts);
    if (tri != NULL)
      *tri = NULL;
    return fail(msg, msg_len, SCF_EINVAL, path, "NULL n_tri argument");
  }
  return read_any(path, pts, tri, n_tri, msg, msg_len);
}

void scf_points_free(scf_points_t *p) {
  if (p == NULL)
    return;
  free(p->xyz);
  p->xyz = NULL;
  p->count = 0;
}

/*
 * Atomic output. The temporary file is ".<name>.tmp.XXXXXX" in the target's
 * directory, so that rename() stays within one file system.
 */
#define TMP_BASE_MAX 200
typedef struct aout {
  const char *path;
  char *tmp;
  int fd;
  FILE *fp;
  char *msg;
  size_t msg_len;
} aout_t;

/* The umask, read without changing it (umask() would, for all threads). */
static mode_t current_umask(void) {
  mode_t m = 022;
  FILE *f = fopen("/proc/self/status", "r");
  if (f == NULL)
    return m;
  char line[256];
  while (fgets(line, sizeof line, f) != NULL) {
    if (strncmp(line, "Umask:", 6) == 0) {
      m = (mode_t)strtoul(line + 6, NULL, 8);
      break;
    }
  }
  fclose(f);
  return m;
}

static int aout_errno(aout_t *o, const char *what) {
  return fail(o->msg, o->msg_len, SCF_EIO, o->path, "%s: %s", what,
              strerror(errno));
}

static void aout_abort(aout_t *o) {
  if (o->fp != NULL)
    fclose(o->fp);
  else if (o->fd >= 0)
    close(o->fd);
  if (o->tmp != NULL) {
    unlink(o->tmp);
    free(o->tmp);
  }
  o->fp = NULL;
  o->fd = -1;
  o->tmp = NULL;
}

static int aout_open(aout_t *o, const char *path, char *msg, size_t msg_len) {
  memset(o, 0, sizeof *o);
  o->fd = -1;
  o->path = path;
  o->msg = msg;
  o->msg_len = msg_len;
  const char *slash = strrchr(path, '/');
  const char *base = slash ? slash + 1 : path;
  size_t dirlen = (size_t)(base - path);
  if (*base == '\0')
    return fail(msg, msg_len, SCF_EINVAL, path, "not a file name");
  /* The temporary name adds 12 bytes to the target's; a name near the
   * file system's limit (255 bytes) is cut so the temporary one fits. */
  size_t baselen = strlen(base);
  if (baselen > TMP_BASE_MAX)
    baselen = TMP_BASE_MAX;
  size_t len = dirlen + baselen + sizeof "..tmp.XXXXXX";
  o->tmp = malloc(len);
  if (o->tmp == NULL)
    return fail(msg, msg_len, SCF_ENOMEM, path, "out of memory");
  snprintf(o->tmp, len, "%.*s.%.*s.tmp.XXXXXX", (int)dirlen, path,
           (int)baselen, base);
  o->fd = mkstemp(o->tmp);
  if (o->fd < 0) {
    int rc = aout_errno(o, "cannot create a temporary file beside it");
    free(o->tmp);
    o->tmp = NULL;
    return rc;
  }
  struct stat st;
  mode_t mode = stat(path, &st) == 0 && S_ISREG(st.st_mode)
                    ? (st.st_mode & 07777)
                    : (0666 & ~current_umask());
  if (fchmod(o->fd, mode) != 0) {
    int rc = aout_errno(o, "cannot set the mode of the temporary file");
    aout_abort(o);
    return rc;
  }
  o->fp = fdopen(o->fd, "wb");
  if (o->fp == NULL) {
    int rc = aout_errno(o, "fdopen failed");
    aout_abort(o);
    return rc;
  }
  setvbuf(o->fp, NULL, _IOFBF, (size_t)1 << 20);
  return 0;
}

static int aout_commit(aout_t *o) {
  if (fflush(o->fp) != 0 || ferror(o->fp))
    return aout_errno(o, "write failed");
  if (fsync(o->fd) != 0)
    return aout_errno(o, "fsync failed");
  FILE *fp = o->fp;
  o->fp = NULL;
  o->fd = -1;
  if (fclose(fp) != 0)
    return aout_errno(o, "close failed");
  if (rename(o->tmp, o->path) != 0)
    return aout_errno(o, "cannot rename the temporary file over it");
  free(o->tmp);
  o->tmp = NULL;
  /* The rename itself becomes durable when the directory is synced; a
   * failure there leaves a complete file, so it is not reported. */
  const char *slash = strrchr(o->path, '/');
  char *dir = slash ? strdup(o->path) : NULL;
  if (dir != NULL)
    dir[slash - o->path + (slash == o->path)] = '\0';
  int dfd = open(slash ? (dir ? dir : "/") : ".", O_RDONLY | O_CLOEXEC);
  if (dfd >= 0) {
    fsync(dfd);
    close(dfd);
  }
  free(dir);
  return 0;
}

static int out_write(aout_t *o, const void *p, size_t n) {
  /* fwrite() must not be given NULL, even for nothing (an empty file). */
  if (n > 0 && fwrite(p, 1, n, o->fp) != n)
    return aout_errno(o, "write failed");
  return 0;
}

PRINTF_LIKE(2, 3)
static int out_printf(aout_t *o, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  int n = vfprintf(o->fp, fmt, ap);
  va_end(ap);
  return n < 0 ? aout_errno(o, "write failed") : 0;
}

int scf_write_atomic(const char *path, const void *data, size_t len,
                         char *msg, size_t msg_len) {
  if (msg != NULL && msg_len > 0)
    msg[0] = '\0';
  if (path == NULL || (data == NULL && len > 0))
    return fail(msg, msg_len, SCF_EINVAL, path, "NULL argument");
  aout_t o;
  int rc = aout_open(&o, path, msg, msg_len);
  if (rc == 0 && (rc = out_write(&o, data, len)) == 0)
    rc = aout_commit(&o);
  if (rc < 0)
    aout_abort(&o);
  return rc;
}

int scf_mesh_format_from_path(const char *path, int ascii,
                             scf_mesh_format_t *fmt, char *msg,
                             size_t msg_len) {
  if (path == NULL || fmt == NULL)
    return fail(msg, msg_len, SCF_EINVAL, path, "NULL argument");
  switch (kind_of(path)) {
  case K_PLY:
    *fmt = ascii ? SCF_MESH_FMT_PLY_ASCII : SCF_MESH_FMT_PLY_BINARY;
    return 0;
  case K_OFF:
    *fmt = SCF_MESH_FMT_OFF;
    return 0;
  case K_OBJ:
    *fmt = SCF_MESH_FMT_OBJ;
    return 0;
  case K_STL:
    *fmt = ascii ? SCF_MESH_FMT_STL_ASCII : SCF_MESH_FMT_STL_BINARY;
    return 0;
  default:
    return unknown_extension(path, msg, msg_len, ".ply, .off, .obj or .stl");
  }
}

static void put_u32le(unsigned char *b, uint32_t v) {
  for (int i = 0; i < 4; i++)
    b[i] = (unsigned char)(v >> (8 * i));
}

static void put_f32le(unsigned char *b, float f) {
  uint32_t w;
  memcpy(&w, &f, sizeof w);
  put_u32le(b, w);
}

static void put_f64le(unsigned char *b, double d) {
  uint64_t w;
  memcpy(&w, &d, sizeof w);
  for (int i = 0; i < 8; i++)
    b[i] = (unsigned char)(w >> (8 * i));
}

typedef struct mesh_in {
  const double *xyz;
  size_t n;
  const uint32_t *tri;
  size_t nt;
  const double *normals;
} mesh_in_t;

static int write_ply(aout_t *o, const mesh_in_t *m, int ascii) {
  int rc = out_printf(o,
                      "ply\nformat %s 1.0\ncomment written by shortcrust\n"
                      "element vertex %zu\nproperty double x\n"
                      "property double y\nproperty double z\n",
                      ascii ? "ascii" : "binary_little_endian", m->n);
  if (rc == 0 && m->normals != NULL)
    rc = out_printf(o, "property float nx\nproperty float ny\n"
                       "property float nz\n");
  /* Indices go out as int, the type most readers expect, unless they do
   * not fit. */
  if (rc == 0)
    rc = out_printf(o,
                    "element face %zu\nproperty list uchar %s "
                    "vertex_indices\nend_header\n",
                    m->nt, m->n > INT32_MAX ? "uint" : "int");
  for (size_t i = 0; rc == 0 && i < m->n; i++) {
    const double *p = m->xyz + 3 * i;
    const double *q = m->normals ? m->normals + 3 * i : NULL;
    if (ascii) {
      rc = out_printf(o, "%.17g %.17g %.17g", p[0], p[1], p[2]);
      if (rc == 0 && q != NULL)
        rc = out_printf(o, " %.9g %.9g %.9g", (double)(float)q[0],
                        (double)(float)q[1], (double)(float)q[2]);
      if (rc == 0)
        rc = out_write(o, "\n", 1);
    } else {
      unsigned char rec[36];
      for (int c = 0; c < 3; c++) {
        put_f64le(rec + 8 * c, p[c]);
        if (q != NULL)
          put_f32le(rec + 24 + 4 * c, (float)q[c]);
      }
      rc = out_write(o, rec, q != NULL ? 36 : 24);
    }
  }
  for (size_t i = 0; rc == 0 && i < m->nt; i++) {
    const uint32_t *t = m->tri + 3 * i;
    if (ascii) {
      rc = out_printf(o, "3 %u %u %u\n", (unsigned)t[0], (unsigned)t[1],
                      (unsigned)t[2]);
    } else {
      unsigned char rec[13];
      rec[0] = 3;
      for (int c = 0; c < 3; c++)
        put_u32le(rec + 1 + 4 * c, t[c]);
      rc = out_write(o, rec, sizeof rec);
    }
  }
  return rc;
}

static int write_off(aout_t *o, const mesh_in_t *m) {
  int rc = out_printf(o, "OFF\n%zu %zu 0\n", m->n, m->nt);
  for (size_t i = 0; rc == 0 && i < m->n; i++) {
    const double *p = m->xyz + 3 * i;
    rc = out_printf(o, "%.17g %.17g %.17g\n", p[0], p[1], p[2]);
  }
  for (size_t i = 0; rc == 0 && i < m->nt; i++) {
    const uint32_t *t = m->tri + 3 * i;
    rc = out_printf(o, "3 %u %u %u\n", (unsigned)t[0], (unsigned)t[1],
                    (unsigned)t[2]);
  }
  return rc;
}

static int write_obj(aout_t *o, const mesh_in_t *m) {
  int rc = out_printf(o, "# written by shortcrust\n");
  for (size_t i = 0; rc == 0 && i < m->n; i++) {
    const double *p = m->xyz + 3 * i;
    rc = out_printf(o, "v %.17g %.17g %.17g\n", p[0], p[1], p[2]);
  }
  for (size_t i = 0; rc == 0 && m->normals != NULL && i < m->n; i++) {
    const double *q = m->normals + 3 * i;
    rc = out_printf(o, "vn %.9g %.9g %.9g\n", q[0], q[1], q[2]);
  }
  for (size_t i = 0; rc == 0 && i < m->nt; i++) {
    ull a = (ull)m->tri[3 * i] + 1, b = (ull)m->tri[3 * i + 1] + 1,
        c = (ull)m->tri[3 * i + 2] + 1;
    if (m->normals != NULL)
      rc = out_printf(o, "f %llu//%llu %llu//%llu %llu//%llu\n", a, a, b, b,
                      c, c);
    else
      rc = out_printf(o, "f %llu %llu %llu\n", a, b, c);
  }
  return rc;
}

/* Unit normal of a counter-clockwise triangle; zero without area. */
static void facet_normal(const mesh_in_t *m, size_t i, double n[3]) {
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

static int write_stl(aout_t *o, const mesh_in_t *m, int ascii) {
  int rc;
  double n[3];
  if (ascii) {
    rc = out_printf(o, "solid shortcrust\n");
    for (size_t i = 0; rc == 0 && i < m->nt; i++) {
      facet_normal(m, i, n);
      rc = out_printf(o, "facet normal %.9g %.9g %.9g\nouter loop\n", n[0],
                      n[1], n[2]);
      for (int c = 0; rc == 0 && c < 3; c++) {
        const double *p = m->xyz + 3 * (size_t)m->tri[3 * i + c];
        rc = out_printf(o, "vertex %.17g %.17g %.17g\n", p[0], p[1], p[2]);
      }
      if (rc == 0)
        rc = out_printf(o, "endloop\nendfacet\n");
    }
    return rc == 0 ? out_printf(o, "endsolid shortcrust\n") : rc;
  }
  /* The header must not start with "solid", which marks ascii STL. */
  unsigned char head[84];
  memset(head, 0, sizeof head);
  memcpy(head, "binary STL written by shortcrust", 32);
  put_u32le(head + 80, (uint32_t)m->nt);
  rc = out_write(o, head, sizeof head);
  for (size_t i = 0; rc == 0 && i < m->nt; i++) {
    unsigned char rec[50];
    facet_normal(m, i, n);
    for (int k = 0; k < 3; k++)
      put_f32le(rec + 4 * k, (float)n[k]);
    for (int c = 0; c < 3; c++) {
      const double *p = m->xyz + 3 * (size_t)m->tri[3 * i + c];
      for (int k = 0; k < 3; k++)
        put_f32le(rec + 12 + 12 * c + 4 * k, (float)p[k]);
    }
    rec[48] = rec[49] = 0;
    rc = out_write(o, rec, sizeof rec);
  }
  return rc;
}

int scf_mesh_write(const char *path, scf_mesh_format_t fmt, const double *xyz,
                  size_t n_points, const uint32_t *tri, size_t n_tri,
                  const double *normals, char *msg, size_t msg_len) {
  if (msg != NULL && msg_len > 0)
    msg[0] = '\0';
  if (path == NULL || (xyz == NULL && n_points > 0) ||
      (tri == NULL && n_tri > 0))
    return fail(msg, msg_len, SCF_EINVAL, path,
                "NULL path, points or triangles");
  if (fmt == SCF_MESH_FMT_AUTO) {
    int rc = scf_mesh_format_from_path(path, 0, &fmt, msg, msg_len);
    if (rc < 0)
      return rc;
  }
  if (fmt < SCF_MESH_FMT_PLY_BINARY || fmt > SCF_MESH_FMT_STL_ASCII)
    return fail(msg, msg_len, SCF_EINVAL, path, "unknown format %d",
                (int)fmt);
  for (size_t i = 0; i < 3 * n_tri; i++)
    if (tri[i] >= n_points)
      return fail(msg, msg_len, SCF_EINVAL, path,
                  "triangle %zu refers to point %u, but there are %zu "
                  "points",
                  i / 3, (unsigned)tri[i], n_points);
  if (fmt == SCF_MESH_FMT_STL_BINARY && n_tri > UINT32_MAX)
    return fail(msg, msg_len, SCF_EUNSUPPORTED, path,
                "binary STL holds at most 2^32 - 1 triangles, not %zu",
                n_tri);
  mesh_in_t m = {xyz, n_points, tri, n_tri, normals};
  aout_t o;
  int rc = aout_open(&o, path, msg, msg_len);
  if (rc < 0)
    return rc;
  switch (fmt) {
  case SCF_MESH_FMT_PLY_BINARY:
  case SCF_MESH_FMT_PLY_ASCII:
    rc = write_ply(&o, &m, fmt == SCF_MESH_FMT_PLY_ASCII);
    break;
  case SCF_MESH_FMT_OFF:
    rc = write_off(&o, &m);
    break;
  case SCF_MESH_FMT_OBJ:
    rc = write_obj(&o, &m);
    break;
  default:
    rc = write_stl(&o, &m, fmt == SCF_MESH_FMT_STL_ASCII);
    break;
  }
  if (rc == 0)
    rc = aout_commit(&o);
  if (rc < 0)
    aout_abort(&o);
  return rc;
}
