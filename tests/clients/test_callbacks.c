/*
 * The client library's callbacks: progress through upload, the daemon's
 * stages and download; the mesh chunk by chunk as it arrives, in order and
 * identical to the mesh collected into a buffer, smoothed vertices too; and
 * a callback that calls back into its own handle, which the library
 * refuses.
 *
 *   test_clients_callbacks DAEMON
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <stdlib.h>
#include <string.h>

#include "common.h"

static scdt_daemon_t d;

typedef struct seen {
  sc_client_t *c;
  unsigned calls;
  unsigned upload, download, server;
  unsigned stage_mask; /* bit s for each daemon stage s */
  double last_upload, last_download;
  int out_of_order; /* a fraction outside [0, 1], or upload after
                       download */
  int reentry_rc;   /* what a call on the handle returned */
} seen_t;

static int on_progress(void *user, sc_client_job_t *job, uint32_t stage,
                       double fraction) {
  seen_t *s = user;
  s->calls++;
  if (!(fraction >= 0 && fraction <= 1))
    s->out_of_order = 1;
  if (stage == SC_CLIENT_STAGE_UPLOAD) {
    s->upload++;
    if (s->download || fraction < s->last_upload)
      s->out_of_order = 1;
    s->last_upload = fraction;
  } else if (stage == SC_CLIENT_STAGE_DOWNLOAD) {
    s->download++;
    if (fraction < s->last_download)
      s->out_of_order = 1;
    s->last_download = fraction;
  } else if (stage < 6) {
    s->server++;
    s->stage_mask |= 1u << stage;
  } else {
    s->out_of_order = 1;
  }
  if (s->calls == 1)
    s->reentry_rc = sc_client_ping(s->c, 1000, NULL);
  return 0;
}

typedef struct collected {
  uint32_t *tri;
  uint64_t ntri;
  double *normals;
  uint64_t nnormals;
  double *vertices;
  uint64_t nvertices;
  int32_t *genus;
  uint64_t ncomp;
  unsigned chunks;
  int bad;    /* a chunk out of order or of an unknown array */
  uint64_t n; /* points */
} collected_t;

static int on_chunk(void *user, sc_client_job_t *job, int array, uint64_t first,
                    uint32_t count, const void *data) {
  collected_t *k = user;
  k->chunks++;
  switch (array) {
  case SC_CLIENT_TRIANGLES:
    if (first != k->ntri)
      k->bad = 1;
    k->tri = realloc(k->tri, (size_t)(first + count) * 3 * sizeof(uint32_t));
    memcpy(k->tri + 3 * first, data, (size_t)count * 3 * sizeof(uint32_t));
    k->ntri = first + count;
    break;
  case SC_CLIENT_NORMALS:
    if (first != k->nnormals || first + count > k->n)
      k->bad = 1;
    k->normals =
        realloc(k->normals, (size_t)(first + count) * 3 * sizeof(double));
    memcpy(k->normals + 3 * first, data, (size_t)count * 3 * sizeof(double));
    k->nnormals = first + count;
    break;
  case SC_CLIENT_VERTICES:
    if (first != k->nvertices || first + count > k->n)
      k->bad = 1;
    k->vertices =
        realloc(k->vertices, (size_t)(first + count) * 3 * sizeof(double));
    memcpy(k->vertices + 3 * first, data, (size_t)count * 3 * sizeof(double));
    k->nvertices = first + count;
    break;
  case SC_CLIENT_COMPONENTS:
    if (first != k->ncomp)
      k->bad = 1;
    k->genus = realloc(k->genus, (size_t)(first + count) * sizeof(int32_t));
    memcpy(k->genus + first, data, (size_t)count * sizeof(int32_t));
    k->ncomp = first + count;
    break;
  default:
    k->bad = 1;
  }
  return 0;
}

static void progress(void) {
  /* Big enough that the daemon reports its stages (at most ten times a
   * second), small enough for a sanitizer build. */
  const uint64_t n = 40000;
  double *xyz = scdt_sample(SCS_SURF_SPHERE, n, 5);
  sc_client_t *c = scct_open(d.sock, 0);
  seen_t s;
  memset(&s, 0, sizeof s);
  s.c = c;
  sc_client_params_t p;
  sc_client_params_init(&p);
  p.progress = on_progress;
  p.progress_user = &s;
  sc_client_job_t *j;
  ASSERT_MSG(sc_client_submit(c, &p, xyz, n, &j) == 0, "submit: %s",
             sc_client_last_error(c));
  /* The upload is over when submit returns. */
  EXPECT_MSG(s.upload >= 1 && s.last_upload == 1.0,
             "upload: %u calls, last fraction %g", s.upload, s.last_upload);
  EXPECT_EQ(sc_client_wait(c, j, SCCT_WAIT_MS), 0);
  EXPECT_MSG(s.server >= 1, "no progress from the daemon's stages");
  EXPECT_MSG(s.stage_mask & (1u << 1),
             "no progress in the delaunay stage (mask "
             "0x%x)",
             s.stage_mask);
  EXPECT_MSG(s.download >= 1 && s.last_download == 1.0,
             "download: %u calls, last fraction %g", s.download,
             s.last_download);
  EXPECT_MSG(!s.out_of_order, "progress out of order");
  EXPECT_EQ(s.reentry_rc, SC_CLIENT_ESTATE);
  scct_check_mesh("sphere with progress", SCS_SURF_SPHERE, xyz, n, j);
  sc_client_job_free(j);
  sc_client_free(c);
  free(xyz);
}

static void chunks(void) {
  const uint64_t n = 5000;
  double *xyz = scdt_sample(SCS_SURF_GENUS2, n, 6);
  /* The smallest frames: the mesh comes in many chunks. */
  sc_client_t *c = scct_open(d.sock, 4096);
  sc_client_params_t p;
  sc_client_params_init(&p);
  p.normals = 1;
  sc_client_job_t *whole;
  ASSERT_MSG(sc_client_submit(c, &p, xyz, n, &whole) == 0, "submit: %s",
             sc_client_last_error(c));
  collected_t k;
  memset(&k, 0, sizeof k);
  k.n = n;
  p.chunk = on_chunk;
  p.chunk_user = &k;
  sc_client_job_t *parts;
  ASSERT_MSG(sc_client_submit(c, &p, xyz, n, &parts) == 0, "submit: %s",
             sc_client_last_error(c));
  EXPECT_EQ(sc_client_wait(c, whole, SCCT_WAIT_MS), 0);
  EXPECT_EQ(sc_client_wait(c, parts, SCCT_WAIT_MS), 0);
  scct_check_mesh("genus 2, buffered", SCS_SURF_GENUS2, xyz, n, whole);

  sc_client_mesh_t a, b;
  EXPECT_EQ(sc_client_job_mesh(whole, &a), 0);
  EXPECT_EQ(sc_client_job_mesh(parts, &b), 0);
  EXPECT_MSG(!k.bad, "a chunk came out of order");
  /* 338 triangles fit in a 4096-byte frame. */
  EXPECT_MSG(k.chunks > a.triangle_count / 338, "%u chunks for %llu triangles",
             k.chunks, (unsigned long long)a.triangle_count);
  EXPECT_MSG(b.triangles == NULL && b.normals == NULL && b.genus == NULL,
             "a job with a chunk callback kept its mesh");
  EXPECT_EQ(b.triangle_count, k.ntri);
  EXPECT_EQ(b.normal_count, k.nnormals);
  EXPECT_EQ(b.component_count, k.ncomp);
  EXPECT_EQ(k.ntri, a.triangle_count);
  EXPECT_EQ(k.nnormals, n);
  EXPECT_EQ(k.ncomp, a.component_count);
  /* The same daemon, the same points: the same mesh either way, as a set
   * of triangles (their order may differ from run to run). */
  scs_meshcheck_t mc;
  ASSERT_MSG(scs_meshcheck((size_t)n, xyz, k.tri, (size_t)k.ntri, NULL, &mc) ==
                 SCS_OK,
             "mesh check");
  char why[256] = "";
  EXPECT_MSG(scs_meshcheck_expect(&mc, SCS_SURF_GENUS2, SCS_EXPECT_OUTWARD, why,
                                  sizeof why),
             "chunked mesh: %s", why);
  scs_meshcheck_free(&mc);
  EXPECT_MSG(k.genus && a.genus &&
                 memcmp(k.genus, a.genus, (size_t)k.ncomp * sizeof(int32_t)) ==
                     0,
             "genera differ");
  free(k.tri);
  free(k.normals);
  free(k.genus);
  sc_client_job_free(whole);
  sc_client_job_free(parts);
  sc_client_free(c);
  free(xyz);
}

/* Smoothed vertices (a given scale smooths even a clean sphere) come to
 * the chunk callback as they are kept in a buffer, one per point, and are
 * not the points sent. */
static void vertices(void) {
  const uint64_t n = 5000;
  double *xyz = scdt_sample(SCS_SURF_SPHERE, n, 7);
  sc_client_t *c = scct_open(d.sock, 4096);
  sc_client_params_t p;
  sc_client_params_init(&p);
  p.denoise = 1;
  p.denoise_scale = 0.1;
  p.smoothed_vertices = 1;
  sc_client_job_t *whole, *parts;
  ASSERT_MSG(sc_client_submit(c, &p, xyz, n, &whole) == 0, "submit: %s",
             sc_client_last_error(c));
  collected_t k;
  memset(&k, 0, sizeof k);
  k.n = n;
  p.chunk = on_chunk;
  p.chunk_user = &k;
  ASSERT_MSG(sc_client_submit(c, &p, xyz, n, &parts) == 0, "submit: %s",
             sc_client_last_error(c));
  EXPECT_EQ(sc_client_wait(c, whole, SCCT_WAIT_MS), 0);
  EXPECT_EQ(sc_client_wait(c, parts, SCCT_WAIT_MS), 0);
  sc_client_mesh_t a, b;
  EXPECT_EQ(sc_client_job_mesh(whole, &a), 0);
  EXPECT_EQ(sc_client_job_mesh(parts, &b), 0);
  EXPECT_EQ(sc_client_value_get(a.values, a.value_count, "denoised", 0), 1);
  EXPECT_MSG(!k.bad, "a chunk came out of order");
  EXPECT_EQ(a.vertex_count, n);
  EXPECT_EQ(k.nvertices, n);
  EXPECT_MSG(b.vertices == NULL && b.vertex_count == n,
             "a job with a chunk callback kept its vertices");
  EXPECT_MSG(a.vertices && k.vertices &&
                 memcmp(a.vertices, k.vertices, 3 * n * sizeof(double)) == 0,
             "the vertices differ between the two jobs");
  EXPECT_MSG(a.vertices && memcmp(a.vertices, xyz, 3 * n * sizeof(double)),
             "the vertices are the points sent");
  free(k.tri);
  free(k.vertices);
  free(k.genus);
  sc_client_job_free(whole);
  sc_client_job_free(parts);
  sc_client_free(c);
  free(xyz);
}

int main(int argc, char **argv) {
  scdt_init(argc, argv);
  const char *args[] = {"--workers", "2", NULL};
  ASSERT_MSG(scdt_daemon_start(&d, args) == 0, "daemon did not start");
  progress();
  chunks();
  vertices();
  EXPECT_EQ(scdt_daemon_stop(&d), 0);
  return scdt_finish();
}
