// CGAL's scale-space reconstruction (weighted-PCA smoothing, then the
// advancing front over the smoothed points), as the tables run it beside
// shortcrust: the parameters the CGAL manual advises (30 neighbours, 200
// samples for the scale, 4 iterations). Its facets index the input order.
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include "peer_scale_space.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Scale_space_reconstruction_3/Advancing_front_mesher.h>
#include <CGAL/Scale_space_reconstruction_3/Weighted_PCA_smoother.h>
#include <CGAL/Scale_space_surface_reconstruction_3.h>

#include <cstdlib>
#include <vector>

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef CGAL::Scale_space_surface_reconstruction_3<K> Reconstruction;

extern "C" int peer_scale_space(const double *xyz, size_t n, uint32_t **tri,
                                size_t *ntri) {
  *tri = nullptr;
  *ntri = 0;
  try {
    std::vector<K::Point_3> pts;
    pts.reserve(n);
    for (size_t i = 0; i < n; ++i)
      pts.emplace_back(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    Reconstruction r(pts.begin(), pts.end());
    r.increase_scale(
        4,
        CGAL::Scale_space_reconstruction_3::Weighted_PCA_smoother<K>(30, 200));
    r.reconstruct_surface(
        CGAL::Scale_space_reconstruction_3::Advancing_front_mesher<K>());
    const size_t count = r.number_of_facets();
    uint32_t *out =
        static_cast<uint32_t *>(std::malloc((3 * count + 1) * sizeof *out));
    if (!out)
      return -1;
    size_t k = 0;
    for (auto it = r.facets_begin(); it != r.facets_end(); ++it)
      for (size_t v : *it)
        out[k++] = uint32_t(v);
    *tri = out;
    *ntri = count;
    return 0;
  } catch (...) {
    return -1;
  }
}
