/*
 * The mesh checker on small meshes built by hand, whose every count is
 * known: a tetrahedron and an octahedron, and what goes wrong when faces
 * are flipped, removed, repeated or glued where a surface cannot be.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "sct_assert.h"
#include "synth.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The unit tetrahedron, every face counter-clockwise seen from outside. */
static const double tet_xyz[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
static const uint32_t tet_tri[] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};

/* The octahedron with vertices on the unit axes, outward. */
static const double oct_xyz[] = {1, 0,  0, -1, 0, 0, 0, 1, 0,
                                 0, -1, 0, 0,  0, 1, 0, 0, -1};
static const uint32_t oct_tri[] = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4,
                                   2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};

static void check(size_t n, const double *xyz, const uint32_t *tri, size_t ntri,
                  const unsigned char *ignore, scs_meshcheck_t *c) {
  int rc = scs_meshcheck(n, xyz, tri, ntri, ignore, c);
  EXPECT_EQ(rc, SCS_OK);
}

/* Copies of the vertex and triangle arrays, shifted and with room. */
typedef struct mesh {
  double xyz[3 * 64];
  uint32_t tri[3 * 64];
  size_t n, nt;
} mesh_t;

static void add(mesh_t *m, const double *xyz, size_t n, const uint32_t *tri,
                size_t nt, double dx, int flip) {
  for (size_t i = 0; i < n; i++) {
    m->xyz[3 * (m->n + i)] = xyz[3 * i] + dx;
    m->xyz[3 * (m->n + i) + 1] = xyz[3 * i + 1];
    m->xyz[3 * (m->n + i) + 2] = xyz[3 * i + 2];
  }
  for (size_t t = 0; t < nt; t++)
    for (int k = 0; k < 3; k++)
      m->tri[3 * (m->nt + t) + k] =
          (uint32_t)m->n + tri[3 * t + (flip && k ? 3 - k : k)];
  m->n += n;
  m->nt += nt;
}

static void expect_ok(const scs_meshcheck_t *c, scs_surface_t s, unsigned flags) {
  char why[256];
  int ok = scs_meshcheck_expect(c, s, flags, why, sizeof why);
  EXPECT_MSG(ok, "expected a good %s, got: %s", scs_surface_name(s), why);
}

static void expect_bad(const scs_meshcheck_t *c, scs_surface_t s, unsigned flags,
                       const char *reason) {
  char why[256];
  int ok = scs_meshcheck_expect(c, s, flags, why, sizeof why);
  EXPECT_MSG(!ok && strstr(why, reason) != NULL,
             "expected a failure with \"%s\", got %d \"%s\"", reason, ok, why);
}

static void test_tetrahedron(void) {
  scs_meshcheck_t c;
  check(4, tet_xyz, tet_tri, 4, NULL, &c);
  EXPECT_EQ(c.points, 4);
  EXPECT_EQ(c.triangles, 4);
  EXPECT_EQ(c.faces, 4);
  EXPECT_EQ(c.edges, 6);
  EXPECT_EQ(c.vertices_used, 4);
  EXPECT_EQ(c.euler, 2);
  EXPECT_EQ(c.components, 1);
  EXPECT_EQ(c.closed_components, 1);
  EXPECT_EQ(c.genus_total, 0);
  EXPECT_EQ(c.boundary_edges + c.nonmanifold_edges + c.nonmanifold_vertices +
                c.orientation_errors + c.samples_unused,
            0);
  EXPECT_MSG(c.manifold && c.closed && c.oriented, "flags %d %d %d", c.manifold,
             c.closed, c.oriented);
  EXPECT_EQ(c.component_count, 1);
  EXPECT_EQ(c.comp[0].vertices, 4);
  EXPECT_EQ(c.comp[0].genus, 0);
  EXPECT_NEAR(c.volume, 1.0 / 6, 1e-15);
  EXPECT_NEAR(c.comp[0].volume, 1.0 / 6, 1e-15);
  /* Three right triangles of area 1/2 and an equilateral one. */
  EXPECT_NEAR(c.area, 1.5 + 0.8660254037844386, 1e-15);
  expect_ok(&c, SCS_SURF_SPHERE, SCS_EXPECT_ALL_USED | SCS_EXPECT_OUTWARD);
  char line[512];
  scs_meshcheck_summary(&c, line, sizeof line);
  EXPECT_MSG(
      strstr(line, "faces=4 V=4 E=6 comps=1 closed=1/1 genus=[0] chi=2") !=
          NULL,
      "summary: %s", line);
  scs_meshcheck_free(&c);
  scs_meshcheck_free(&c);
  scs_meshcheck_free(NULL);
}

/* Every face turned over: still consistent, but inside out. */
static void test_inverted(void) {
  mesh_t m = {.n = 0};
  add(&m, tet_xyz, 4, tet_tri, 4, 0, 1);
  scs_meshcheck_t c;
  check(m.n, m.xyz, m.tri, m.nt, NULL, &c);
  EXPECT_MSG(c.closed && c.oriented, "closed %d oriented %d", c.closed,
             c.oriented);
  EXPECT_NEAR(c.comp[0].volume, -1.0 / 6, 1e-15);
  expect_ok(&c, SCS_SURF_SPHERE, 0);
  expect_bad(&c, SCS_SURF_SPHERE, SCS_EXPECT_OUTWARD, "signed volume");
  scs_meshcheck_free(&c);
}

/* One face turned over: each of its three edges is then used twice in
 * the same direction. */
static void test_inconsistent(void) {
  uint32_t tri[12];
  memcpy(tri, tet_tri, sizeof tri);
  tri[10] = 3;
  tri[11] = 2;
  scs_meshcheck_t c;
  check(4, tet_xyz, tri, 4, NULL, &c);
  EXPECT_EQ(c.orientation_errors, 3);
  EXPECT_MSG(c.manifold && c.closed && !c.oriented, "%d %d %d", c.manifold,
             c.closed, c.oriented);
  expect_bad(&c, SCS_SURF_SPHERE, 0, "inconsistent orientation");
  scs_meshcheck_free(&c);
}

/* A face missing: three boundary edges in one loop; still a disc, so
 * genus 0. */
static void test_boundary(void) {
  scs_meshcheck_t c;
  check(4, tet_xyz, tet_tri, 3, NULL, &c);
  EXPECT_EQ(c.boundary_edges, 3);
  EXPECT_EQ(c.boundary_loops, 1);
  EXPECT_EQ(c.comp[0].boundary_loops, 1);
  EXPECT_EQ(c.comp[0].euler, 1);
  EXPECT_EQ(c.comp[0].genus, 0);
  EXPECT_EQ(c.closed_components, 0);
  EXPECT_MSG(c.manifold && !c.closed && c.oriented, "%d %d %d", c.manifold,
             c.closed, c.oriented);
  /* Open components add nothing to the totals. */
  EXPECT_EQ(c.genus_total, 0);
  EXPECT_NEAR(c.volume, 0, 0);
  expect_bad(&c, SCS_SURF_SPHERE, 0, "boundary edges");
  scs_meshcheck_free(&c);

  /* An open band of four quads (an annulus): two loops, genus 0. */
  double xyz[8 * 3];
  uint32_t tri[8 * 3];
  for (int i = 0; i < 4; i++)
    for (int z = 0; z < 2; z++) {
      double *p = xyz + 3 * (2 * i + z);
      p[0] = i == 0 ? 1 : i == 2 ? -1 : 0;
      p[1] = i == 1 ? 1 : i == 3 ? -1 : 0;
      p[2] = z;
    }
  for (uint32_t i = 0; i < 4; i++) {
    uint32_t a = 2 * i, b = 2 * ((i + 1) % 4);
    uint32_t q[6] = {a, b, b + 1, a, b + 1, a + 1};
    memcpy(tri + 6 * i, q, sizeof q);
  }
  check(8, xyz, tri, 8, NULL, &c);
  EXPECT_EQ(c.boundary_edges, 8);
  EXPECT_EQ(c.boundary_loops, 2);
  EXPECT_EQ(c.euler, 0);
  EXPECT_EQ(c.comp[0].genus, 0);
  EXPECT_MSG(c.oriented && c.manifold, "%d %d", c.oriented, c.manifold);
  scs_meshcheck_free(&c);
}

/* Three triangles on one edge. */
static void test_nonmanifold_edge(void) {
  static const double xyz[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1};
  static const uint32_t tri[] = {0, 1, 2, 1, 0, 3, 0, 1, 4};
  scs_meshcheck_t c;
  check(5, xyz, tri, 3, NULL, &c);
  EXPECT_EQ(c.nonmanifold_edges, 1);
  EXPECT_EQ(c.edges, 7);
  EXPECT_EQ(c.components, 1);
  /* 0 -> 1 is used by the first and the third. */
  EXPECT_EQ(c.orientation_errors, 1);
  EXPECT_MSG(!c.manifold && !c.closed, "%d %d", c.manifold, c.closed);
  expect_bad(&c, SCS_SURF_SPHERE, 0, "non-manifold edges");
  scs_meshcheck_free(&c);
}

/* Two tetrahedra sharing only a vertex: two closed components, pinched
 * at one non-manifold vertex. */
static void test_pinched(void) {
  mesh_t m = {.n = 0};
  add(&m, tet_xyz, 4, tet_tri, 4, 0, 0);
  add(&m, tet_xyz, 4, tet_tri, 4, -1, 0);
  /* Glue vertex 1 of the second (at the origin) onto vertex 0. */
  for (size_t i = 12; i < 24; i++)
    if (m.tri[i] == 5)
      m.tri[i] = 0;
  scs_meshcheck_t c;
  check(m.n, m.xyz, m.tri, m.nt, NULL, &c);
  EXPECT_EQ(c.nonmanifold_vertices, 1);
  EXPECT_EQ(c.nonmanifold_edges, 0);
  EXPECT_EQ(c.components, 2);
  EXPECT_EQ(c.closed_components, 2);
  EXPECT_EQ(c.vertices_used, 7);
  EXPECT_EQ(c.samples_unused, 1);
  EXPECT_EQ(c.euler, 7 - 12 + 8);
  EXPECT_EQ(c.comp[0].vertices, 4);
  EXPECT_EQ(c.comp[1].vertices, 4);
  EXPECT_EQ(c.comp[0].genus, 0);
  EXPECT_EQ(c.comp[1].genus, 0);
  EXPECT_MSG(!c.manifold && !c.closed && c.oriented, "%d %d %d", c.manifold,
             c.closed, c.oriented);
  expect_bad(&c, SCS_SURF_TWO_SPHERES, 0, "non-manifold vertices");
  scs_meshcheck_free(&c);

  /* Two triangles touching at a vertex: two boundary loops, kept apart at
   * the shared vertex. */
  static const double xyz[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, -1, 0, 0, 0, -1, 0};
  static const uint32_t tri[] = {0, 1, 2, 0, 3, 4};
  check(5, xyz, tri, 2, NULL, &c);
  EXPECT_EQ(c.nonmanifold_vertices, 1);
  EXPECT_EQ(c.boundary_loops, 2);
  EXPECT_EQ(c.components, 2);
  scs_meshcheck_free(&c);
}

/* A torus as a 6 x 4 grid of quads: genus 1. */
static void torus(mesh_t *m) {
  enum { U = 6, V = 4 };
  /* Coordinates need not be exact for topology; a coarse polygon ring. */
  static const double cu[U] = {1, 0.5, -0.5, -1, -0.5, 0.5};
  static const double su[U] = {0, 0.866, 0.866, 0, -0.866, -0.866};
  static const double cv[V] = {1, 0, -1, 0}, sv[V] = {0, 1, 0, -1};
  m->n = m->nt = 0;
  for (int i = 0; i < U; i++)
    for (int j = 0; j < V; j++) {
      double rho = 1 + 0.35 * cv[j];
      double *p = m->xyz + 3 * (V * i + j);
      p[0] = rho * cu[i];
      p[1] = rho * su[i];
      p[2] = 0.35 * sv[j];
    }
  m->n = U * V;
  for (uint32_t i = 0; i < U; i++)
    for (uint32_t j = 0; j < V; j++) {
      uint32_t a = V * i + j, b = V * ((i + 1) % U) + j;
      uint32_t c = V * ((i + 1) % U) + (j + 1) % V, d = V * i + (j + 1) % V;
      uint32_t q[6] = {a, b, c, a, c, d};
      memcpy(m->tri + 3 * m->nt, q, sizeof q);
      m->nt += 2;
    }
}

static void test_genus(void) {
  mesh_t m;
  torus(&m);
  scs_meshcheck_t c;
  check(m.n, m.xyz, m.tri, m.nt, NULL, &c);
  EXPECT_EQ(c.faces, 48);
  EXPECT_EQ(c.edges, 72);
  EXPECT_EQ(c.euler, 0);
  EXPECT_EQ(c.genus_total, 1);
  EXPECT_MSG(c.closed && c.oriented, "%d %d", c.closed, c.oriented);
  EXPECT_LT(0, c.volume);
  expect_ok(&c, SCS_SURF_TORUS, SCS_EXPECT_ALL_USED | SCS_EXPECT_OUTWARD);
  expect_bad(&c, SCS_SURF_SPHERE, 0, "genus 1 where 0 was expected");
  scs_meshcheck_free(&c);

  check(4, tet_xyz, tet_tri, 4, NULL, &c);
  expect_bad(&c, SCS_SURF_TORUS, 0, "genus 0 where 1 was expected");
  expect_bad(&c, SCS_SURF_GENUS2, 0, "genus 0 where 2 was expected");
  scs_meshcheck_free(&c);
}

static void test_components(void) {
  mesh_t m = {.n = 0};
  add(&m, oct_xyz, 6, oct_tri, 8, -1.6, 0);
  add(&m, oct_xyz, 6, oct_tri, 8, 1.6, 0);
  scs_meshcheck_t c;
  check(m.n, m.xyz, m.tri, m.nt, NULL, &c);
  EXPECT_EQ(c.components, 2);
  EXPECT_EQ(c.closed_components, 2);
  EXPECT_EQ(c.edges, 24);
  EXPECT_EQ(c.euler, 4);
  EXPECT_EQ(c.comp[0].triangles, 8);
  EXPECT_EQ(c.comp[1].edges, 12);
  /* Eight equilateral faces of side sqrt(2); volume 4/3 each. */
  EXPECT_NEAR(c.area, 2 * 4 * 1.7320508075688772, 1e-13);
  EXPECT_NEAR(c.volume, 8.0 / 3, 1e-14);
  expect_ok(&c, SCS_SURF_TWO_SPHERES, SCS_EXPECT_ALL_USED | SCS_EXPECT_OUTWARD);
  expect_bad(&c, SCS_SURF_SPHERE, 0, "2 components, expected 1");
  scs_meshcheck_free(&c);

  /* Nested: a small octahedron inside, facing away from its own centre,
   * so both volumes are positive. */
  m.n = m.nt = 0;
  add(&m, oct_xyz, 6, oct_tri, 8, 0, 0);
  add(&m, oct_xyz, 6, oct_tri, 8, 0, 0);
  for (size_t i = 18; i < 36; i++)
    m.xyz[i] *= 0.5;
  check(m.n, m.xyz, m.tri, m.nt, NULL, &c);
  EXPECT_EQ(c.components, 2);
  EXPECT_NEAR(c.comp[1].volume, 4.0 / 3 / 8, 1e-15);
  expect_ok(&c, SCS_SURF_NESTED_SPHERES, SCS_EXPECT_OUTWARD);
  scs_meshcheck_free(&c);
}

/* Points left out of the mesh count unless the caller ignores them. */
static void test_unused(void) {
  double xyz[8 * 3];
  memcpy(xyz, oct_xyz, sizeof oct_xyz);
  memcpy(xyz + 18, oct_xyz, 6 * sizeof *xyz);
  scs_meshcheck_t c;
  check(8, xyz, oct_tri, 8, NULL, &c);
  EXPECT_EQ(c.samples_unused, 2);
  EXPECT_EQ(c.vertices_used, 6);
  expect_ok(&c, SCS_SURF_SPHERE, 0);
  expect_bad(&c, SCS_SURF_SPHERE, SCS_EXPECT_ALL_USED, "2 samples unused");
  scs_meshcheck_free(&c);
  unsigned char ignore[8] = {0, 0, 0, 0, 0, 0, 1, 0};
  check(8, xyz, oct_tri, 8, ignore, &c);
  EXPECT_EQ(c.samples_unused, 1);
  scs_meshcheck_free(&c);
  ignore[7] = 1;
  /* Ignoring a vertex that is used changes nothing. */
  ignore[0] = 1;
  check(8, xyz, oct_tri, 8, ignore, &c);
  EXPECT_EQ(c.samples_unused, 0);
  EXPECT_EQ(c.vertices_used, 6);
  expect_ok(&c, SCS_SURF_SPHERE, SCS_EXPECT_ALL_USED);
  scs_meshcheck_free(&c);
}

/* Triangles that are left out of every measurement, and counted. */
static void test_left_out(void) {
  uint32_t tri[3 * 12];
  memcpy(tri, tet_tri, sizeof tet_tri);
  uint32_t extra[] = {0, 1, 4, 2, 2, 3, 1, 2, 3, 3, 2, 1, 0, 0, 0, 9, 9, 9};
  memcpy(tri + 12, extra, sizeof extra);
  scs_meshcheck_t c;
  check(4, tet_xyz, tri, 10, NULL, &c);
  EXPECT_EQ(c.triangles, 10);
  EXPECT_EQ(c.out_of_range, 2);
  EXPECT_EQ(c.degenerate, 2);
  EXPECT_EQ(c.duplicates, 2);
  EXPECT_EQ(c.faces, 4);
  EXPECT_EQ(c.edges, 6);
  EXPECT_MSG(!c.manifold && c.oriented, "%d %d", c.manifold, c.oriented);
  EXPECT_NEAR(c.volume, 1.0 / 6, 1e-15);
  expect_bad(&c, SCS_SURF_SPHERE, 0, "2 triangles with an index out of range");
  scs_meshcheck_free(&c);
  /* With only the duplicates left in, they are what fails. */
  memcpy(tri + 12, extra + 6, 6 * sizeof *tri);
  check(4, tet_xyz, tri, 6, NULL, &c);
  EXPECT_EQ(c.duplicates, 2);
  expect_bad(&c, SCS_SURF_SPHERE, 0, "2 duplicate triangles");
  scs_meshcheck_free(&c);
  /* A duplicate keeps its first copy, whichever way that one faces. */
  uint32_t first_flipped[15] = {0, 1, 2};
  memcpy(first_flipped + 3, tet_tri, sizeof tet_tri);
  check(4, tet_xyz, first_flipped, 5, NULL, &c);
  EXPECT_EQ(c.duplicates, 1);
  EXPECT_EQ(c.orientation_errors, 3);
  scs_meshcheck_free(&c);
}

static void test_arguments(void) {
  scs_meshcheck_t c;
  memset(&c, 0xff, sizeof c);
  EXPECT_EQ(scs_meshcheck(4, tet_xyz, NULL, 4, NULL, &c), SCS_EINVAL);
  EXPECT_EQ(c.faces, 0);
  EXPECT_MSG(c.comp == NULL, "comp not reset");
  EXPECT_EQ(scs_meshcheck(4, tet_xyz, tet_tri, 4, NULL, NULL), SCS_EINVAL);
  EXPECT_EQ(scs_meshcheck((size_t)1 << 32, NULL, tet_tri, 4, NULL, &c),
            SCS_EINVAL);
  /* Nothing at all is a valid, empty measurement. */
  check(0, NULL, NULL, 0, NULL, &c);
  EXPECT_EQ(c.components, 0);
  EXPECT_MSG(c.closed && c.manifold, "empty mesh flags");
  expect_bad(&c, SCS_SURF_SPHERE, 0, "0 components");
  scs_meshcheck_free(&c);
  /* Without coordinates, topology only. */
  check(4, NULL, tet_tri, 4, NULL, &c);
  EXPECT_EQ(c.genus_total, 0);
  EXPECT_NEAR(c.area, 0, 0);
  EXPECT_NEAR(c.volume, 0, 0);
  scs_meshcheck_free(&c);
  char why[8];
  EXPECT_EQ(scs_meshcheck_expect(NULL, SCS_SURF_SPHERE, 0, why, sizeof why), 0);
  EXPECT_EQ(scs_meshcheck_expect(&c, SCS_SURF_COUNT, 0, NULL, 0), 0);
}

static void test_distance(void) {
  scs_distcheck_t d;
  EXPECT_EQ(scs_mesh_distance_check(SCS_SURF_SPHERE, 6, oct_xyz, oct_tri, 8,
                                    1e-12, &d),
            SCS_OK);
  EXPECT_EQ(d.vertices, 6);
  EXPECT_EQ(d.beyond, 0);
  EXPECT_NEAR(d.max_distance, 0, 1e-15);
  double xyz[18];
  memcpy(xyz, oct_xyz, sizeof xyz);
  xyz[3 * 4 + 2] = 1.25;
  xyz[3 * 5 + 2] = -0.9;
  EXPECT_EQ(
      scs_mesh_distance_check(SCS_SURF_SPHERE, 6, xyz, oct_tri, 8, 0.15, &d),
      SCS_OK);
  EXPECT_EQ(d.beyond, 1);
  EXPECT_EQ(d.worst, 4);
  EXPECT_NEAR(d.max_distance, 0.25, 1e-15);
  EXPECT_EQ(
      scs_mesh_distance_check(SCS_SURF_COUNT, 6, xyz, oct_tri, 8, 0.1, &d),
      SCS_EINVAL);
}

int main(void) {
  test_tetrahedron();
  test_inverted();
  test_inconsistent();
  test_boundary();
  test_nonmanifold_edge();
  test_pinched();
  test_genus();
  test_components();
  test_unused();
  test_left_out();
  test_arguments();
  test_distance();
  return sct_finish("synth_meshcheck");
}
