/*
 * The mesh checker: topology and geometry of a triangle soup, measured
 * from scratch with sort-based tables.
 *
 * Plan: drop out-of-range and degenerate triangles; sort the vertex sets
 * to drop duplicates; sort all edges of the rest by their vertex pair,
 * which groups the triangles around each edge. From the groups: boundary,
 * non-manifold and mis-oriented edges, components (union-find over
 * triangles), and the fans around vertices (union-find over corners, a
 * corner being a triangle at one of its vertices). Boundary loops are then
 * components of boundary edges whose endpoints are fans, not vertices.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "internal.h"

#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static uint32_t uf_find(uint32_t *parent, uint32_t x) {
  uint32_t root = x;
  while (parent[root] != root)
    root = parent[root];
  while (parent[x] != root) {
    uint32_t next = parent[x];
    parent[x] = root;
    x = next;
  }
  return root;
}

/* Joins the classes of a and b; the smaller root wins, which keeps the
 * result independent of the order of unions. */
static void uf_union(uint32_t *parent, uint32_t a, uint32_t b) {
  a = uf_find(parent, a);
  b = uf_find(parent, b);
  if (a < b)
    parent[b] = a;
  else if (b < a)
    parent[a] = b;
}

void scs_meshcheck_free(scs_meshcheck_t *c) {
  if (!c)
    return;
  free(c->comp);
  c->comp = NULL;
  c->component_count = 0;
}

/* Scratch of one check; every pointer is freed at the end. */
typedef struct work {
  uint32_t *live;     /* indices of the measured triangles */
  uint64_t *keys, *tmpk;
  uint32_t *vals, *tmpv;
  uint32_t *tri_parent;    /* union-find over measured triangles */
  uint32_t *corner_parent; /* union-find over corners 3 t + k */
  uint32_t *loop_parent;   /* union-find over corner roots, for loops */
  uint32_t *comp_of;       /* measured triangle -> component */
  uint32_t *vfirst;        /* vertex -> first corner with it, or none */
  uint32_t *sorted;         /* sorted vertex triple per measured triangle */
  unsigned char *drop;      /* duplicate copies to leave out */
  unsigned char *used;
  unsigned char *flag;
} work_t;

static void work_free(work_t *w) {
  free(w->live);
  free(w->keys);
  free(w->tmpk);
  free(w->vals);
  free(w->tmpv);
  free(w->tri_parent);
  free(w->corner_parent);
  free(w->loop_parent);
  free(w->comp_of);
  free(w->vfirst);
  free(w->sorted);
  free(w->drop);
  free(w->used);
  free(w->flag);
}

/* Corner k of measured triangle t, as a vertex index. */
#define CORNER(tri, live, t, k) ((tri)[3 * (size_t)(live)[t] + (k)])

int scs_meshcheck(size_t n, const double *xyz, const uint32_t *tri,
                  size_t ntri, const unsigned char *ignore,
                  scs_meshcheck_t *out) {
  if (!out)
    return SCS_EINVAL;
  memset(out, 0, sizeof *out);
  if ((ntri && !tri) || n > UINT32_MAX || ntri > UINT32_MAX / 3)
    return SCS_EINVAL;
  out->points = n;
  out->triangles = ntri;

  work_t w;
  memset(&w, 0, sizeof w);
  int rc = SCS_ENOMEM;
  int vbits = scs_bits(n ? n - 1 : 0);
  if (vbits == 0)
    vbits = 1;

  /* Out-of-range and degenerate triangles. */
  w.live = malloc((ntri ? ntri : 1) * sizeof *w.live);
  if (!w.live)
    goto fail;
  size_t nlive = 0;
  for (size_t t = 0; t < ntri; t++) {
    const uint32_t *v = tri + 3 * t;
    if (v[0] >= n || v[1] >= n || v[2] >= n)
      out->out_of_range++;
    else if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2])
      out->degenerate++;
    else
      w.live[nlive++] = (uint32_t)t;
  }

  /* Duplicates: sort the vertex triples, each put in ascending order, in
   * two stable passes: by (b, c) first, then by a. */
  size_t cap = nlive ? 3 * nlive : 1;
  w.keys = malloc(cap * sizeof *w.keys);
  w.tmpk = malloc(cap * sizeof *w.tmpk);
  w.vals = malloc(cap * sizeof *w.vals);
  w.tmpv = malloc(cap * sizeof *w.tmpv);
  if (!w.keys || !w.tmpk || !w.vals || !w.tmpv)
    goto fail;
  if (nlive > 1) {
    uint32_t *sorted = w.sorted = malloc(3 * nlive * sizeof *sorted);
    unsigned char *drop = w.drop = calloc(nlive, 1);
    if (!sorted || !drop)
      goto fail;
    for (size_t t = 0; t < nlive; t++) {
      uint32_t a = CORNER(tri, w.live, t, 0), b = CORNER(tri, w.live, t, 1),
               c = CORNER(tri, w.live, t, 2), x;
      if (a > b) x = a, a = b, b = x;
      if (b > c) x = b, b = c, c = x;
      if (a > b) x = a, a = b, b = x;
      sorted[3 * t] = a;
      sorted[3 * t + 1] = b;
      sorted[3 * t + 2] = c;
      w.vals[t] = (uint32_t)t;
    }
    for (size_t t = 0; t < nlive; t++)
      w.keys[t] = (uint64_t)sorted[3 * t + 1] << vbits | sorted[3 * t + 2];
    if ((rc = scs_radix_sort(w.keys, w.vals, nlive, 2 * vbits, w.tmpk,
                             w.tmpv)))
      goto fail;
    for (size_t t = 0; t < nlive; t++)
      w.keys[t] = sorted[3 * (size_t)w.vals[t]];
    if ((rc = scs_radix_sort(w.keys, w.vals, nlive, vbits, w.tmpk, w.tmpv)))
      goto fail;
    /* Within a run of equal triples keep the earliest (smallest index). */
    for (size_t i = 0; i < nlive;) {
      size_t j = i + 1;
      const uint32_t *a = sorted + 3 * (size_t)w.vals[i];
      while (j < nlive &&
             memcmp(sorted + 3 * (size_t)w.vals[j], a, 3 * sizeof *a) == 0)
        j++;
      uint32_t first = w.vals[i];
      for (size_t k = i + 1; k < j; k++)
        if (w.vals[k] < first)
          first = w.vals[k];
      for (size_t k = i; k < j; k++)
        if (w.vals[k] != first)
          drop[w.vals[k]] = 1;
      out->duplicates += j - i - 1;
      i = j;
    }
    size_t kept = 0;
    for (size_t t = 0; t < nlive; t++)
      if (!drop[t])
        w.live[kept++] = w.live[t];
    nlive = kept;
    free(w.sorted);
    free(w.drop);
    w.sorted = NULL;
    w.drop = NULL;
    rc = SCS_ENOMEM;
  }
  out->faces = nlive;

  /* Vertices used and unused samples. */
  w.used = calloc(n ? n : 1, 1);
  if (!w.used)
    goto fail;
  for (size_t t = 0; t < nlive; t++)
    for (int k = 0; k < 3; k++)
      w.used[CORNER(tri, w.live, t, k)] = 1;
  for (size_t v = 0; v < n; v++) {
    if (w.used[v])
      out->vertices_used++;
    else if (!ignore || !ignore[v])
      out->samples_unused++;
  }

  /* The edge table: key (min, max), value the corner 3 t + k of the edge
   * from corner k to corner k + 1. */
  size_t ne = 3 * nlive;
  for (size_t t = 0; t < nlive; t++)
    for (int k = 0; k < 3; k++) {
      uint32_t a = CORNER(tri, w.live, t, k);
      uint32_t b = CORNER(tri, w.live, t, (k + 1) % 3);
      uint64_t lo = a < b ? a : b, hi = a < b ? b : a;
      w.keys[3 * t + k] = lo << vbits | hi;
      w.vals[3 * t + k] = (uint32_t)(3 * t + k);
    }
  if ((rc = scs_radix_sort(w.keys, w.vals, ne, 2 * vbits, w.tmpk, w.tmpv)))
    goto fail;
  rc = SCS_ENOMEM;

  w.tri_parent = malloc((nlive ? nlive : 1) * sizeof *w.tri_parent);
  w.corner_parent = malloc((ne ? ne : 1) * sizeof *w.corner_parent);
  if (!w.tri_parent || !w.corner_parent)
    goto fail;
  for (size_t t = 0; t < nlive; t++)
    w.tri_parent[t] = (uint32_t)t;
  for (size_t c = 0; c < ne; c++)
    w.corner_parent[c] = (uint32_t)c;

  for (size_t i = 0; i < ne;) {
    size_t j = i + 1;
    while (j < ne && w.keys[j] == w.keys[i])
      j++;
    size_t m = j - i;
    out->edges++;
    if (m == 1)
      out->boundary_edges++;
    else if (m > 2)
      out->nonmanifold_edges++;
    /* A directed edge used twice shows as two entries with the same start
     * vertex; groups have two entries on a good mesh, so compare pairs. */
    int bad = 0;
    for (size_t x = i; x < j && !bad; x++)
      for (size_t y = x + 1; y < j && !bad; y++) {
        uint32_t cx = w.vals[x], cy = w.vals[y];
        uint32_t ax = CORNER(tri, w.live, cx / 3, cx % 3);
        uint32_t ay = CORNER(tri, w.live, cy / 3, cy % 3);
        if (ax == ay)
          bad = 1;
      }
    out->orientation_errors += bad;
    /* Join the triangles, and at each endpoint the corners of the
     * triangles around this edge. */
    uint32_t c0 = w.vals[i], t0 = c0 / 3;
    uint32_t a0 = CORNER(tri, w.live, t0, c0 % 3);
    for (size_t x = i + 1; x < j; x++) {
      uint32_t cx = w.vals[x], tx = cx / 3;
      uint32_t ax = CORNER(tri, w.live, tx, cx % 3);
      uf_union(w.tri_parent, t0, tx);
      /* Corner k of an edge entry is its start vertex, k + 1 its end. */
      uint32_t s0 = c0, e0 = 3 * t0 + (c0 % 3 + 1) % 3;
      uint32_t sx = cx, ex = 3 * tx + (cx % 3 + 1) % 3;
      if (ax == a0) {
        uf_union(w.corner_parent, s0, sx);
        uf_union(w.corner_parent, e0, ex);
      } else {
        uf_union(w.corner_parent, s0, ex);
        uf_union(w.corner_parent, e0, sx);
      }
    }
    i = j;
  }
  out->euler = (int64_t)out->vertices_used - (int64_t)out->edges +
               (int64_t)out->faces;

  /* Components, numbered in the order of their smallest triangle. */
  w.comp_of = malloc((nlive ? nlive : 1) * sizeof *w.comp_of);
  if (!w.comp_of)
    goto fail;
  size_t ncomp = 0;
  for (size_t t = 0; t < nlive; t++) {
    uint32_t r = uf_find(w.tri_parent, (uint32_t)t);
    w.comp_of[t] = r == t ? (uint32_t)ncomp++ : w.comp_of[r];
  }
  out->components = ncomp;
  if (ncomp) {
    out->comp = calloc(ncomp, sizeof *out->comp);
    if (!out->comp)
      goto fail;
    out->component_count = ncomp;
  }

  /* Faces, edges, boundary edges per component. */
  for (size_t t = 0; t < nlive; t++)
    out->comp[w.comp_of[t]].triangles++;
  for (size_t i = 0; i < ne;) {
    size_t j = i + 1;
    while (j < ne && w.keys[j] == w.keys[i])
      j++;
    scs_meshcheck_component_t *cp = &out->comp[w.comp_of[w.vals[i] / 3]];
    cp->edges++;
    if (j - i == 1)
      cp->boundary_edges++;
    i = j;
  }

  /* Fans: every corner-class root is one fan of one vertex. A vertex with
   * more than one fan is non-manifold. Vertices per component count the
   * distinct (vertex, component) pairs; the fans of one vertex are few, so
   * the list of its components is searched linearly. */
  w.vfirst = malloc((n ? n : 1) * sizeof *w.vfirst);
  w.flag = calloc(ne ? ne : 1, 1);
  if (!w.vfirst || !w.flag)
    goto fail;
  for (size_t v = 0; v < n; v++)
    w.vfirst[v] = UINT32_MAX;
  /* Chain the fan roots of each vertex through the tmpv array. */
  for (size_t c = 0; c < ne; c++) {
    if (uf_find(w.corner_parent, (uint32_t)c) != c)
      continue;
    uint32_t v = CORNER(tri, w.live, c / 3, c % 3);
    w.tmpv[c] = w.vfirst[v];
    w.vfirst[v] = (uint32_t)c;
  }
  for (size_t v = 0; v < n; v++) {
    uint32_t head = w.vfirst[v];
    if (head == UINT32_MAX)
      continue;
    if (w.tmpv[head] != UINT32_MAX)
      out->nonmanifold_vertices++;
    for (uint32_t c = head; c != UINT32_MAX; c = w.tmpv[c]) {
      uint32_t comp = w.comp_of[c / 3];
      int seen = 0;
      for (uint32_t d = head; d != c; d = w.tmpv[d])
        if (w.comp_of[d / 3] == comp)
          seen = 1;
      if (!seen)
        out->comp[comp].vertices++;
    }
  }

  /* Boundary loops: join, per boundary edge, the fans of its endpoints;
   * each class of fans touched by a boundary edge is a loop. */
  if (out->boundary_edges) {
    w.loop_parent = malloc(ne * sizeof *w.loop_parent);
    if (!w.loop_parent)
      goto fail;
    for (size_t c = 0; c < ne; c++)
      w.loop_parent[c] = (uint32_t)c;
    for (size_t i = 0; i < ne;) {
      size_t j = i + 1;
      while (j < ne && w.keys[j] == w.keys[i])
        j++;
      if (j - i == 1) {
        uint32_t c = w.vals[i], t = c / 3;
        uint32_t s = uf_find(w.corner_parent, c);
        uint32_t e = uf_find(w.corner_parent, 3 * t + (c % 3 + 1) % 3);
        uf_union(w.loop_parent, s, e);
        w.flag[s] = w.flag[e] = 1;
      }
      i = j;
    }
    for (size_t c = 0; c < ne; c++)
      if (w.flag[c] && uf_find(w.loop_parent, (uint32_t)c) == c) {
        out->boundary_loops++;
        out->comp[w.comp_of[c / 3]].boundary_loops++;
      }
  }

  /* Area and signed volume, each component about its first vertex so that
   * far-away meshes do not lose digits. */
  if (xyz) {
    double (*origin)[3] = malloc((ncomp ? ncomp : 1) * sizeof *origin);
    unsigned char *have = calloc(ncomp ? ncomp : 1, 1);
    if (!origin || !have) {
      free(origin);
      free(have);
      goto fail;
    }
    for (size_t t = 0; t < nlive; t++) {
      uint32_t comp = w.comp_of[t];
      const double *p[3];
      for (int k = 0; k < 3; k++)
        p[k] = xyz + 3 * (size_t)CORNER(tri, w.live, t, k);
      if (!have[comp]) {
        memcpy(origin[comp], p[0], sizeof origin[comp]);
        have[comp] = 1;
      }
      double a[3], b[3], c[3];
      for (int i = 0; i < 3; i++) {
        a[i] = p[0][i] - origin[comp][i];
        b[i] = p[1][i] - origin[comp][i];
        c[i] = p[2][i] - origin[comp][i];
      }
      double bxc[3] = {b[1] * c[2] - b[2] * c[1], b[2] * c[0] - b[0] * c[2],
                       b[0] * c[1] - b[1] * c[0]};
      out->comp[comp].volume +=
          (a[0] * bxc[0] + a[1] * bxc[1] + a[2] * bxc[2]) / 6;
      double u[3], v[3];
      for (int i = 0; i < 3; i++) {
        u[i] = b[i] - a[i];
        v[i] = c[i] - a[i];
      }
      double nx = u[1] * v[2] - u[2] * v[1], ny = u[2] * v[0] - u[0] * v[2],
             nz = u[0] * v[1] - u[1] * v[0];
      out->comp[comp].area += sqrt(nx * nx + ny * ny + nz * nz) / 2;
    }
    free(origin);
    free(have);
  }

  for (size_t i = 0; i < ncomp; i++) {
    scs_meshcheck_component_t *cp = &out->comp[i];
    cp->closed = cp->boundary_edges == 0;
    cp->euler = (int64_t)cp->vertices - (int64_t)cp->edges +
                (int64_t)cp->triangles;
    int64_t twice = 2 - cp->euler - (int64_t)cp->boundary_loops;
    cp->genus = twice >= 0 && twice % 2 == 0 ? twice / 2 : -1;
    out->area += cp->area;
    if (cp->closed) {
      out->closed_components++;
      out->genus_total += cp->genus;
      out->volume += cp->volume;
    }
  }
  out->manifold = out->out_of_range == 0 && out->degenerate == 0 &&
                  out->duplicates == 0 && out->nonmanifold_edges == 0 &&
                  out->nonmanifold_vertices == 0;
  out->closed = out->manifold && out->boundary_edges == 0;
  out->oriented = out->orientation_errors == 0;
  work_free(&w);
  return SCS_OK;

fail:
  work_free(&w);
  scs_meshcheck_free(out);
  memset(out, 0, sizeof *out);
  return rc;
}

char *scs_meshcheck_summary(const scs_meshcheck_t *c, char *buf, size_t len) {
  if (!buf || len == 0)
    return buf;
  buf[0] = '\0';
  if (!c)
    return buf;
  char genus[96];
  size_t at = 0;
  genus[0] = '\0';
  for (size_t i = 0; i < c->component_count; i++) {
    if (i == 6) {
      snprintf(genus + at, sizeof genus - at, ",...");
      break;
    }
    int k = snprintf(genus + at, sizeof genus - at, "%s%" PRId64,
                     i ? "," : "", c->comp[i].genus);
    if (k < 0 || (size_t)k >= sizeof genus - at)
      break;
    at += (size_t)k;
  }
  snprintf(buf, len,
           "faces=%" PRIu64 " V=%" PRIu64 " E=%" PRIu64 " comps=%" PRIu64
           " closed=%" PRIu64 "/%" PRIu64 " genus=[%s] chi=%" PRId64
           " bnd=%" PRIu64 "/%" PRIu64 " nm=%" PRIu64 "/%" PRIu64
           " orient=%" PRIu64 " degen=%" PRIu64 " dup=%" PRIu64
           " oor=%" PRIu64 " unused=%" PRIu64 " vol=%.6g",
           c->faces, c->vertices_used, c->edges, c->components,
           c->closed_components, c->components, genus, c->euler,
           c->boundary_edges, c->boundary_loops, c->nonmanifold_edges,
           c->nonmanifold_vertices, c->orientation_errors, c->degenerate,
           c->duplicates, c->out_of_range, c->samples_unused, c->volume);
  return buf;
}

static int cmp_int(const void *a, const void *b) {
  int x = *(const int *)a, y = *(const int *)b;
  return (x > y) - (x < y);
}

int scs_meshcheck_expect(const scs_meshcheck_t *c, scs_surface_t s,
                         unsigned flags, char *why, size_t why_len) {
  char scratch[8];
  if (!why || why_len == 0) {
    why = scratch;
    why_len = sizeof scratch;
  }
  why[0] = '\0';
  const scs_surface_info_t *info = scs_surface_info(s);
  if (!c || !info) {
    snprintf(why, why_len, "invalid argument");
    return 0;
  }
#define FAIL(...)                                                              \
  do {                                                                         \
    snprintf(why, why_len, __VA_ARGS__);                                       \
    return 0;                                                                  \
  } while (0)
  if (c->out_of_range)
    FAIL("%" PRIu64 " triangles with an index out of range", c->out_of_range);
  if (c->degenerate)
    FAIL("%" PRIu64 " degenerate triangles", c->degenerate);
  if (c->duplicates)
    FAIL("%" PRIu64 " duplicate triangles", c->duplicates);
  if (c->nonmanifold_edges)
    FAIL("%" PRIu64 " non-manifold edges", c->nonmanifold_edges);
  if (c->nonmanifold_vertices)
    FAIL("%" PRIu64 " non-manifold vertices", c->nonmanifold_vertices);
  if (c->boundary_edges)
    FAIL("%" PRIu64 " boundary edges in %" PRIu64 " loops", c->boundary_edges,
         c->boundary_loops);
  if (c->orientation_errors)
    FAIL("%" PRIu64 " edges with inconsistent orientation",
         c->orientation_errors);
  if (c->components != (uint64_t)info->components)
    FAIL("%" PRIu64 " components, expected %d", c->components,
         info->components);
  int want[SCS_SURF_MAX_COMPONENTS], got[SCS_SURF_MAX_COMPONENTS];
  for (int i = 0; i < info->components; i++) {
    want[i] = info->genus[i];
    got[i] = (int)c->comp[i].genus;
  }
  qsort(want, (size_t)info->components, sizeof *want, cmp_int);
  qsort(got, (size_t)info->components, sizeof *got, cmp_int);
  for (int i = 0; i < info->components; i++)
    if (want[i] != got[i])
      FAIL("genus %d where %d was expected (sorted position %d)", got[i],
           want[i], i);
  if ((flags & SCS_EXPECT_ALL_USED) && c->samples_unused)
    FAIL("%" PRIu64 " samples unused", c->samples_unused);
  if (flags & SCS_EXPECT_OUTWARD)
    for (size_t i = 0; i < c->component_count; i++)
      if (!(c->comp[i].volume > 0))
        FAIL("component %zu has signed volume %g, not positive", i,
             c->comp[i].volume);
#undef FAIL
  return 1;
}

int scs_mesh_distance_check(scs_surface_t s, size_t n, const double *xyz,
                            const uint32_t *tri, size_t ntri, double tol,
                            scs_distcheck_t *out) {
  if (!out)
    return SCS_EINVAL;
  memset(out, 0, sizeof *out);
  if (!scs_surface_info(s) || (n && !xyz) || (ntri && !tri))
    return SCS_EINVAL;
  unsigned char *seen = calloc(n ? n : 1, 1);
  if (!seen)
    return SCS_ENOMEM;
  for (size_t i = 0; i < 3 * ntri; i++) {
    uint32_t v = tri[i];
    if (v >= n || seen[v])
      continue;
    seen[v] = 1;
    out->vertices++;
    double d = scs_surface_distance(s, xyz + 3 * (size_t)v);
    /* A non-finite coordinate is as far off as it gets. */
    if (d != d)
      d = HUGE_VAL;
    if (d > tol)
      out->beyond++;
    if (d > out->max_distance) {
      out->max_distance = d;
      out->worst = v;
    }
  }
  free(seen);
  return SCS_OK;
}
