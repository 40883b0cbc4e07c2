/*
 * OFF (also COFF, NOFF, CNOFF, STOFF): reading vertices and faces, writing.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "scf_internal.h"

/* The next line with something on it after comments are removed. */
static int next_content_line(scf__rd_t *r, char **cur) {
  char *line;
  int rc;
  while ((rc = scf__rd_line(r, &line)) == 1) {
    scf__strip_comment(line);
    *cur = line + strspn(line, SCF__WS);
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

int scf__read_off(scf__rd_t *r, scf__vbuf_t *v, scf__tbuf_t *t) {
  char *cur, *tok, buf[SCF__SHOW_MAX + 4];
  int rc = next_content_line(r, &cur);
  if (rc < 0)
    return rc;
  tok = rc ? scf__next_tok(&cur, SCF__WS) : NULL;
  int kw = tok ? off_keyword(tok) : 0;
  if (kw < 0)
    return scf__rd_fail_line(r, r->line, SCF_EUNSUPPORTED,
                             "'%s' files (not three coordinates) are not "
                             "supported",
                             scf__show(tok, buf));
  if (kw == 0)
    return scf__rd_fail_line(r, rc ? r->line : 1, SCF_EFORMAT,
                             "not an OFF file: expected 'OFF' first, got '%s'",
                             tok ? scf__show(tok, buf) : "");
  tok = scf__next_tok(&cur, SCF__WS);
  if (tok != NULL && strcmp(tok, "BINARY") == 0)
    return scf__rd_fail_line(r, r->line, SCF_EUNSUPPORTED,
                             "binary OFF is not supported");
  /* The counts may follow the keyword on the same line. */
  if (tok == NULL) {
    if ((rc = next_content_line(r, &cur)) < 0)
      return rc;
    if (rc == 0)
      return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                               "file ends before the vertex and face counts");
    tok = scf__next_tok(&cur, SCF__WS);
  }
  char *ftok = scf__next_tok(&cur, SCF__WS);
  uint64_t nv, nf;
  if (scf__parse_u64(tok, &nv) < 0 || ftok == NULL ||
      scf__parse_u64(ftok, &nf) < 0)
    return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                             "expected the vertex and face counts, got '%s'",
                             scf__show(tok, buf));
  uint64_t rem = scf__rd_remaining(r);
  /* A vertex line holds at least "0 0 0\n", a face line "3 0 1 2\n". */
  uint64_t need = scf__sat_mul_add(scf__sat_mul_add(0, nv, 6), t ? nf : 0, 8);
  if (rem != UINT64_MAX && need > 0 && need - 1 > rem)
    return scf__rd_fail_line(
        r, r->line, SCF_EFORMAT,
        "the header declares %llu vertices%s%s, which need "
        "at least %llu bytes, but only %llu bytes follow",
        (scf__ull)nv, t ? " and faces " : "", t ? ftok : "",
        (scf__ull)(need - 1), (scf__ull)rem);
  if (t != NULL && nv > UINT32_MAX)
    return scf__rd_fail_line(r, r->line, SCF_EUNSUPPORTED,
                             "meshes with more than 2^32 - 1 vertices are not "
                             "supported");
  if (nv > 0 && (rc = scf__vbuf_reserve(
                     r, v, rem == UINT64_MAX && nv > 65536 ? 65536 : nv)) < 0)
    return rc;
  for (uint64_t k = 0; k < nv; k++) {
    if ((rc = next_content_line(r, &cur)) < 0)
      return rc;
    if (rc == 0)
      return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                               "file ends after %llu of %llu vertices",
                               (scf__ull)k, (scf__ull)nv);
    double xyz[3];
    const char *bad;
    int ntok;
    if (scf__three_numbers(&cur, SCF__WS, xyz, &bad, &ntok) < 0)
      return scf__bad_numbers(r, " for a vertex", bad, ntok);
    if ((rc = scf__vbuf_push(r, v, xyz[0], xyz[1], xyz[2])) < 0)
      return rc;
  }
  for (uint64_t k = 0; t != NULL && k < nf; k++) {
    if ((rc = next_content_line(r, &cur)) < 0)
      return rc;
    if (rc == 0)
      return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                               "file ends after %llu of %llu faces",
                               (scf__ull)k, (scf__ull)nf);
    tok = scf__next_tok(&cur, SCF__WS);
    int64_t n;
    if (scf__parse_i64(tok, &n) < 0 || n < 3)
      return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                               "expected a vertex count of at least 3 for face "
                               "%llu, got '%s'",
                               (scf__ull)k, scf__show(tok, buf));
    scf__fan_t fan = {0, 0, 0};
    for (int64_t i = 0; i < n; i++) {
      int64_t idx;
      tok = scf__next_tok(&cur, SCF__WS);
      if (tok == NULL)
        return scf__rd_fail_line(
            r, r->line, SCF_EFORMAT,
            "face %llu has %lld of its %lld vertex indices", (scf__ull)k,
            (long long)i, (long long)n);
      if (scf__parse_i64(tok, &idx) < 0 || idx < 0 || (uint64_t)idx >= nv)
        return scf__rd_fail_line(r, r->line, SCF_EFORMAT,
                                 "expected a vertex index below %llu in face "
                                 "%llu, got '%s'",
                                 (scf__ull)nv, (scf__ull)k,
                                 scf__show(tok, buf));
      if ((rc = scf__fan_add(r, t, &fan, (uint32_t)idx)) < 0)
        return rc;
    }
  }
  return 0;
}

int scf__write_off(scf__aout_t *o, const scf__mesh_in_t *m) {
  int rc = scf__out_printf(o, "OFF\n%zu %zu 0\n", m->n, m->nt);
  for (size_t i = 0; rc == 0 && i < m->n; i++) {
    const double *p = m->xyz + 3 * i;
    rc = scf__out_printf(o, "%.17g %.17g %.17g\n", p[0], p[1], p[2]);
  }
  for (size_t i = 0; rc == 0 && i < m->nt; i++) {
    const uint32_t *t = m->tri + 3 * i;
    rc = scf__out_printf(o, "3 %u %u %u\n", (unsigned)t[0], (unsigned)t[1],
                         (unsigned)t[2]);
  }
  return rc;
}
