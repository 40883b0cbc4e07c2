/*
 * A job's parameters in the client library: the defaults, the checks and
 * the job options, all made from the core's parameter table (SC_PARAM_MAP
 * in shortcrust.h; only the header: the library does not link the core).
 * The fixed fields of JOB_BEGIN (mode, r, theta) have fields of their own
 * in sc_client_params_t; every row the table marks OPTION is a field of the
 * same name, sent as a job option when it is not left unset.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "client_internal.h"

#include <stddef.h>
#include <stdio.h>
#include <string.h>

/* A row of the table as the client holds it: where the value lives in
 * sc_client_params_t, and whether a value stands for the daemon's default
 * (has_unset: that value, unset, is not checked and not sent). */
typedef struct scc_param_row {
  const char *name; /* the field's, and for an option the option's */
  int option;       /* 1: a job option; 0: a fixed field of JOB_BEGIN */
  int kind;
  size_t offset;
  double dflt, lo, hi;
  int range;
  const char *text;
  int has_unset;
  double unset;
} scc_param_row_t;

/* The fixed fields: JOB_BEGIN always carries mode and r; theta 0 asks for
 * the daemon's default (PROTOCOL.md 6.3). */
#define SCC_FIXED_FIELD_mode mode
#define SCC_FIXED_UNSET_mode 0, 0
#define SCC_FIXED_FIELD_r r
#define SCC_FIXED_UNSET_r 0, 0
#define SCC_FIXED_FIELD_cocone_theta theta
#define SCC_FIXED_UNSET_cocone_theta 1, 0

#define SCC_STR_(x) #x
#define SCC_STR(x) SCC_STR_(x)
#define SCC_ROW_(field_, option_, kind_, dflt_, lo_, hi_, range_, text_,       \
                 unset_)                                                       \
  {SCC_STR(field_), option_, SC_PARAM_##kind_,                                 \
   offsetof(sc_client_params_t, field_),                                       \
   (double)(dflt_), (double)(lo_), (double)(hi_), (range_), text_, unset_},
/* Options are unset at -1 when an integer, at 0 otherwise. */
#define SCC_UNSET_MODE 1, 0
#define SCC_UNSET_REAL 1, 0
#define SCC_UNSET_ANGLE 1, 0
#define SCC_UNSET_FLAG 1, 0
#define SCC_UNSET_INT 1, -1
#define SCC_ROW_OPTION(field, kind, dflt, lo, hi, range, text)                 \
  SCC_ROW_(field, 1, kind, dflt, lo, hi, range, text, SCC_UNSET_##kind)
#define SCC_ROW_FIXED(field, kind, dflt, lo, hi, range, text)                  \
  SCC_ROW_(SCC_FIXED_FIELD_##field, 0, kind, dflt, lo, hi, range, text,       \
           SCC_FIXED_UNSET_##field)
#define SCC_ROW_LOCAL(field, kind, dflt, lo, hi, range, text)
#define SCC_ROW_ANY_(field, type, kind, dflt, lo, hi, range, text, wire, ...)  \
  SCC_ROW_##wire(field, kind, dflt, lo, hi, range, text)

static const scc_param_row_t rows[] = {SC_PARAM_MAP(SCC_ROW_ANY_)};
enum { NROWS = sizeof rows / sizeof rows[0] };

static int is_int(const scc_param_row_t *r) {
  return r->kind == SC_PARAM_INT || r->kind == SC_PARAM_FLAG ||
         r->kind == SC_PARAM_MODE;
}

static double get(const sc_client_params_t *p, const scc_param_row_t *r) {
  const char *f = (const char *)p + r->offset;
  return is_int(r) ? (double)*(const int *)f : *(const double *)f;
}

void sc_client_params_init(sc_client_params_t *p) {
  memset(p, 0, sizeof *p);
  for (size_t i = 0; i < NROWS; ++i) {
    char *f = (char *)p + rows[i].offset;
    double v = rows[i].has_unset ? rows[i].unset : rows[i].dflt;
    if (is_int(&rows[i]))
      *(int *)f = (int)v;
    else
      *(double *)f = v;
  }
  p->retries = 0;
  p->retry_backoff_ms = 100;
}

int scc_check_params(sc_client_t *c, const sc_client_params_t *p) {
  if (p->retries < 0 || p->retries > 1000)
    return scc_fail(c, SC_CLIENT_EINVAL, "retries must be 0 to 1000, got %d",
                    p->retries);
  if (p->retry_backoff_ms < 0 || p->retry_backoff_ms > 60000)
    return scc_fail(c, SC_CLIENT_EINVAL,
                    "retry_backoff_ms must be 0 to 60000, got %d",
                    p->retry_backoff_ms);
  for (size_t i = 0; i < NROWS; ++i) {
    const scc_param_row_t *r = &rows[i];
    double v = get(p, r);
    if (r->has_unset && v == r->unset)
      continue;
    /* 0 stands for the default through unset here, not through the
     * core's range. */
    if (SC_IN_RANGE(v, r->lo, r->hi, r->range & ~SC_RANGE_ZERO_DEFAULT))
      continue;
    const char *unit = r->kind == SC_PARAM_ANGLE ? " radians" : "";
    const char *name = r->name;
    if (r->kind == SC_PARAM_MODE)
      return scc_fail(c, SC_CLIENT_EINVAL, "unknown mode %d", (int)v);
    if (!r->has_unset || r->kind == SC_PARAM_FLAG)
      return is_int(r) ? scc_fail(c, SC_CLIENT_EINVAL, "%s must be %s, got %d",
                                  name, r->text, (int)v)
                       : scc_fail(c, SC_CLIENT_EINVAL,
                                  "%s must be %s%s, got %g", name, r->text,
                                  unit, v);
    return is_int(r)
               ? scc_fail(c, SC_CLIENT_EINVAL,
                          "%s must be %s, or %d for the default; got %d", name,
                          r->text, (int)r->unset, (int)v)
               : scc_fail(c, SC_CLIENT_EINVAL,
                          "%s must be %s%s, or %g for the default; got %g",
                          name, r->text, unit, r->unset, v);
  }
  return 0;
}

uint32_t scc_job_options(const sc_client_params_t *p, scp_value_t *opts,
                         uint32_t cap) {
  uint32_t n = 0;
  for (size_t i = 0; i < NROWS && n < cap; ++i) {
    const scc_param_row_t *r = &rows[i];
    if (!r->option)
      continue;
    double v = get(p, r);
    if (v == r->unset)
      continue;
    opts[n].name = r->name;
    if (is_int(r)) {
      opts[n].kind = SCP_KIND_U64;
      opts[n].v.u = (uint64_t)*(const int *)((const char *)p + r->offset);
    } else {
      opts[n].kind = SCP_KIND_F64;
      opts[n].v.f = v;
    }
    n++;
  }
  return n;
}
