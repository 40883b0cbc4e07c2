/*
 * Another sampling of a model than its vertex set: points spread uniformly
 * at random over a closed mesh (scs_sample_mesh()), reconstructed in the
 * mode named, must give one closed, oriented 2-manifold of the mesh's
 * genus (measured on the mesh itself) with every sample a vertex. The
 * fandisk's sharp edges at 10 000 random points: the patches span the
 * strips the candidates miss along them, and the samples over those
 * patches must be attached however far the patches' corners lie. The
 * dino at as many random points as it has vertices: the patches break a
 * leg off, and the labelling keeps it but with a small false handle,
 * which must be cut (docs/algorithm.md section 11.5), and is cut the same
 * on two threads. The anchor at as many random points as it has vertices:
 * the labelling keeps its four true holes, two of them small, and makes
 * tunnels beside them, which must be cut while the holes stay. The knot
 * at three times as many random points as it has vertices, and the eight
 * at as many: boundary detection takes samples of their thin tubes for
 * boundary samples, extraction opens a tube there and the patches cap it
 * (genus 0), where the cocone test at every sample keeps it, and must be
 * kept (docs/algorithm.md section 11.5). The anchor in auto mode too:
 * the sample is taken for a closed one, and must be closed as watertight
 * mode closes it, from the surface before its small holes were filled,
 * not with them filled (genus 3: section 11.6): to the same triangles.
 * And at 1 500 random points, where no boundary sample is found and the
 * cocone surface is one closed piece of genus 5 that leaves samples out:
 * auto mode must doubt it as watertight mode does, and give its mesh.
 * The knot and the dino at 2 500 random points: cells across the knot's
 * tube and in the dino's thin parts have balls that reach through the
 * surface, by which the labels cut the tube and broke a part off; they
 * must not cross there (section 11.4, step 3). The eight (634 flat
 * triangles) and the fandisk (flat faces) at 4 000 random points: the
 * points of a face are coplanar but for rounding, and its flat cells must
 * have their centres far off the face (section 4.1), not in it, where
 * every facet of a flat cell passed the cocone test (the eight: genus 3
 * to 6, in pieces) and the labels' balls tunnelled along the faces (the
 * fandisk: genus 6 to 10 with --labels).
 *
 *   test_core_mesh_sample MESH.ply N SEED MODE [patches|labels]
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "diag.h"
#include "shortcrust.h"
#include "shortcrust_files.h"
#include "synth.h"

int main(int argc, char **argv) {
  if (argc != 5 && argc != 6) {
    fprintf(stderr, "usage: %s MESH.ply N SEED MODE [patches|labels]\n",
            argv[0]);
    return 2;
  }
  const size_t n = strtoul(argv[2], NULL, 10);
  const uint64_t seed = strtoull(argv[3], NULL, 10);
  sc_params_t p;
  sc_params_init(&p);
  p.mode = sct_mode_from_name(argv[4]);
  const char *option = argc == 6 ? argv[5] : "";
  if (p.mode == SC_MODE_COUNT_ || n < 100 ||
      (argc == 6 && strcmp(option, "patches") != 0 &&
       strcmp(option, "labels") != 0)) {
    fprintf(stderr, "unknown mode or option, or too few points\n");
    return 2;
  }
  p.watertight_patches = strcmp(option, "patches") == 0;
  p.watertight_labels = strcmp(option, "labels") == 0;
  scf_points_t mesh = {0};
  uint32_t *tri = NULL;
  size_t ntri = 0;
  char msg[512];
  EXPECT_EQ(scf_mesh_read(argv[1], &mesh, &tri, &ntri, msg, sizeof msg), 0);
  double *xyz = malloc(3 * n * sizeof *xyz);
  EXPECT(xyz != NULL && ntri > 0);
  if (!xyz || ntri == 0) {
    fprintf(stderr, "%s\n", msg);
    free(xyz);
    free(tri);
    scf_points_free(&mesh);
    return sct_finish("core_mesh_sample");
  }
  // The mesh's own topology is the answer.
  scs_meshcheck_t truth;
  EXPECT_EQ(scs_meshcheck(mesh.count, mesh.xyz, tri, ntri, NULL, &truth), 0);
  EXPECT(truth.closed && truth.components == 1);
  const int genus = (int)truth.genus_total;
  EXPECT_EQ(scs_sample_mesh(mesh.xyz, mesh.count, tri, ntri, n, seed, xyz), 0);
  char what[512];
  snprintf(what, sizeof what, "%s, %zu random points, %s%s%s", argv[1], n,
           argv[4], argc == 6 ? " --" : "", option);
  sc_mesh_t *one = sct_expect_closed(xyz, n, &p, genus, 1, what);
  /* On two threads (the labelling beside the extraction, the probes of
   * the small handles in slices): the same triangles and cuts. */
  if (one) {
    sc_params_t q = p;
    q.threads = 2;
    sc_mesh_t *two = NULL;
    EXPECT_EQ(sc_reconstruct(xyz, n, &q, &two, msg, sizeof msg), 0);
    EXPECT(two && two->diag.small_handles_cut == one->diag.small_handles_cut &&
           two->triangle_count == one->triangle_count &&
           memcmp(two->triangles, one->triangles,
                  3 * one->triangle_count * sizeof *one->triangles) == 0);
    printf("ok: %llu small handles cut, the same on 2 threads\n",
           (unsigned long long)one->diag.small_handles_cut);
    sc_mesh_free(two);
    /* Auto mode takes each of these samples for a closed one (and does
     * not smooth it), and closes it to watertight mode's mesh. */
    if (p.mode == SC_MODE_AUTO) {
      EXPECT(!one->diag.denoised &&
             (one->diag.path == SC_PATH_WATERTIGHT ||
              one->diag.path == SC_PATH_WATERTIGHT_FILL ||
              (one->diag.path == SC_PATH_COCONE && one->diag.labelled)));
      sc_params_t w = p;
      w.mode = SC_MODE_WATERTIGHT;
      sc_mesh_t *wt = NULL;
      EXPECT_EQ(sc_reconstruct(xyz, n, &w, &wt, msg, sizeof msg), 0);
      EXPECT(wt && wt->triangle_count == one->triangle_count &&
             memcmp(wt->triangles, one->triangles,
                    3 * one->triangle_count * sizeof *one->triangles) == 0);
      printf("ok: watertight mode's triangles\n");
      sc_mesh_free(wt);
    }
  }
  sc_mesh_free(one);
  scs_meshcheck_free(&truth);
  free(xyz);
  free(tri);
  scf_points_free(&mesh);
  return sct_finish("core_mesh_sample");
}
