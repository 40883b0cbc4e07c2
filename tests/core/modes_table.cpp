// shortcrust-modes-table: every mode of the core, boundary and watertight
// modes with denoising too, and CGAL's advancing-front reconstruction
// beside them, on real point files; prints one Markdown table.
//
//   shortcrust-modes-table DATA_DIR [FILE ...]
//   shortcrust-modes-table --closed DATA_DIR [FILE ...]
//
// --closed is the table of closed models (the vertex sets of closed meshes,
// NAME_points.ply beside NAME_gt_mesh.ply): the modes meant for closed
// surfaces, each row with the components and genus of the ground truth
// and whether the output is that surface (closed, every sample used, the
// same components and genus), and a count of the models each method gets
// right.
//
// FILE names a point file in DATA_DIR without its .ply extension; the
// default is the list below. For each file and method: triangles, samples
// used (vertices / distinct points), non-manifold edges and vertices,
// orientation errors, boundary loops, components, closed or not, genus
// summed over the components (open ones included), the distance from the output
// to the ground-truth mesh where there is one (RMS and maximum over the
// triangle centroids and vertices, point to triangle, in units of the file's
// median sample spacing), and the time beside CGAL's Delaunay triangulation of
// the same points.
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Advancing_front_surface_reconstruction.h>
#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include <dirent.h>
#include <sys/mman.h>
#include <sys/wait.h>
#include <unistd.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif

#include "shortcrust.h"
#include "shortcrust_files.h"
#include "synth.h"

namespace {

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef K::Point_3 Point;
typedef K::Triangle_3 Triangle;
typedef std::vector<Triangle>::const_iterator TriIt;
typedef CGAL::AABB_triangle_primitive<K, TriIt> Primitive;
typedef CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>> Tree;

double now() {
  return std::chrono::duration<double>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// Gives the memory that earlier runs freed back to the system, so that
// every timed run starts as in a fresh process and pays for the pages it
// touches. Without it a run after a larger one finds its pages mapped
// already: the yardstick measured 2.1 s cold on the merged scans and
// 1.6 s right after a watertight run.
void cold_heap() {
#ifdef __GLIBC__
  malloc_trim(0);
#endif
}

struct Reference {
  std::vector<Triangle> tris;
  std::unique_ptr<Tree> tree;
};

// Distance of the output (its vertices and triangle centroids) to the
// reference mesh.
void distance(const Reference &ref, const double *xyz, const uint32_t *t,
              size_t nt, double &rms, double &max) {
  double sum = 0;
  size_t count = 0;
  max = 0;
  std::vector<uint8_t> seen;
  auto add = [&](const Point &p) {
    double d2 = ref.tree->squared_distance(p);
    sum += d2;
    ++count;
    max = std::max(max, std::sqrt(d2));
  };
  for (size_t i = 0; i < nt; ++i) {
    const double *a = xyz + 3 * size_t(t[3 * i]),
                 *b = xyz + 3 * size_t(t[3 * i + 1]),
                 *c = xyz + 3 * size_t(t[3 * i + 2]);
    add(Point((a[0] + b[0] + c[0]) / 3, (a[1] + b[1] + c[1]) / 3,
              (a[2] + b[2] + c[2]) / 3));
    for (int k = 0; k < 3; ++k) {
      uint32_t v = t[3 * i + k];
      if (v >= seen.size())
        seen.resize(size_t(v) + 1, 0);
      if (!seen[v]) {
        seen[v] = 1;
        add(Point(xyz[3 * size_t(v)], xyz[3 * size_t(v) + 1],
                  xyz[3 * size_t(v) + 2]));
      }
    }
  }
  rms = count ? std::sqrt(sum / double(count)) : 0;
}

double median_spacing(const std::vector<Point> &pts) {
  typedef CGAL::Delaunay_triangulation_3<K> Dt;
  Dt dt(pts.begin(), pts.end());
  std::vector<double> nn;
  for (auto v = dt.finite_vertices_begin(); v != dt.finite_vertices_end();
       ++v) {
    std::vector<Dt::Vertex_handle> adj;
    dt.finite_adjacent_vertices(v, std::back_inserter(adj));
    double best = HUGE_VAL;
    for (auto w : adj)
      best = std::min(best, CGAL::squared_distance(v->point(), w->point()));
    nn.push_back(std::sqrt(best));
  }
  std::nth_element(nn.begin(), nn.begin() + nn.size() / 2, nn.end());
  return nn.empty() ? 1 : nn[nn.size() / 2];
}

// Genus summed over the components, open ones included (a component with
// boundary has genus (2 - chi - b) / 2), so that handles show whether or
// not the surface is closed.
long long genus_sum(const scs_meshcheck_t &c) {
  long long genus = 0;
  for (size_t i = 0; i < c.component_count; ++i)
    if (c.comp[i].genus > 0)
      genus += c.comp[i].genus;
  return genus;
}

// The topology a closed model's output must have: the ground truth's.
struct Expected {
  bool known = false;
  uint64_t components = 0;
  long long genus = 0;
};

// Prints one row; true when the output is the expected closed surface
// (closed, at least 99.9% of the samples used, the expected components
// and genus).
bool row(const char *file, const char *method, const char *path, size_t points,
         const uint32_t *t, size_t nt, const double *xyz, const Reference *ref,
         double spacing, double seconds, double dt_seconds,
         const Expected *expected = nullptr) {
  scs_meshcheck_t c;
  if (scs_meshcheck(points, xyz, t, nt, nullptr, &c) != 0) {
    std::printf("| %s | %s | meshcheck failed |\n", file, method);
    return false;
  }
  const long long genus = genus_sum(c);
  char dist[64] = "-";
  if (ref) {
    double rms, max;
    distance(*ref, xyz, t, nt, rms, max);
    std::snprintf(dist, sizeof dist, "%.2f / %.1f", rms / spacing,
                  max / spacing);
  }
  std::printf(
      "| %s | %s | %s | %zu | %.2f%% | %llu / %llu | %llu | %llu | "
      "%llu | %s | %lld | %s | %.2f s | %.2f |",
      file, method, path, nt, 100.0 * double(c.vertices_used) / double(points),
      (unsigned long long)c.nonmanifold_edges,
      (unsigned long long)c.nonmanifold_vertices,
      (unsigned long long)c.orientation_errors,
      (unsigned long long)c.boundary_loops, (unsigned long long)c.components,
      c.closed ? "yes" : "no", genus, dist, seconds, seconds / dt_seconds);
  bool right = false;
  if (expected) {
    right = expected->known && c.closed &&
            double(c.vertices_used) >= 0.999 * double(points) &&
            c.components == expected->components && genus == expected->genus;
    if (expected->known)
      std::printf(" %llu / %lld | %s |\n",
                  (unsigned long long)expected->components, expected->genus,
                  right ? "yes" : "**no**");
    else
      std::printf(" - | - |\n");
  } else {
    std::printf("\n");
  }
  std::fflush(stdout);
  scs_meshcheck_free(&c);
  return right;
}

// Measures one file and prints its rows; 0 on success. With `closed`, the
// closed models' methods and columns, and right[m] counts the models
// method m got right (the advancing front last).
int measure(const std::string &dir, const std::string &name, int repeat,
            int threads, bool afsr, bool closed, int *right) {
  // (Rounds: see main(). A file of a few hundred points takes a
  // millisecond, so small files get rounds until the yardstick has taken
  // kMinYardstick seconds.)
  const double kMinYardstick = 0.25;
  const int kMaxRounds = 1000;
  // Every mode, and the modes for scans again with denoising (section 16
  // of docs/algorithm.md: multi-view scans need it).
  struct Method {
    sc_mode_t mode;
    int denoise;
    const char *name;
  };
  const Method scans[] = {{SC_MODE_COCONE, 0, "cocone"},
                          {SC_MODE_BOUNDARY, 0, "boundary"},
                          {SC_MODE_WATERTIGHT, 0, "watertight"},
                          {SC_MODE_AUTO, 0, "auto"},
                          {SC_MODE_BOUNDARY, 1, "boundary --denoise"},
                          {SC_MODE_WATERTIGHT, 1, "watertight --denoise"}};
  const Method models[] = {{SC_MODE_COCONE, 0, "cocone"},
                           {SC_MODE_SHORTCRUST, 0, "shortcrust"},
                           {SC_MODE_WATERTIGHT, 0, "watertight"},
                           {SC_MODE_AUTO, 0, "auto"}};
  const Method *methods = closed ? models : scans;
  char msg[512];
  scf_points_t pts;
  std::string path = dir + "/" + name + ".ply";
  if (scf_points_read(path.c_str(), &pts, msg, sizeof msg) != 0) {
    std::fprintf(stderr, "%s\n", msg);
    return 1;
  }
  std::vector<Point> points;
  points.reserve(pts.count);
  for (size_t i = 0; i < pts.count; ++i)
    points.emplace_back(pts.xyz[3 * i], pts.xyz[3 * i + 1], pts.xyz[3 * i + 2]);

  // The yardstick, CGAL's Delaunay triangulation of the same points
  // inserted as a range, and every mode, in rounds.
  const size_t nmodes = closed ? std::size(models) : std::size(scans);
  double t0 = 0, dt_seconds = HUGE_VAL, dt_total = 0;
  std::vector<double> best(nmodes, HUGE_VAL);
  std::vector<sc_mesh_t *> meshes(nmodes, nullptr);
  std::vector<int> rc(nmodes, 0);
  std::vector<std::string> failure(nmodes);
  for (int r = 0; r < repeat || (dt_total < kMinYardstick && r < kMaxRounds);
       ++r) {
    cold_heap();
    t0 = now();
    {
      CGAL::Delaunay_triangulation_3<K> dt(points.begin(), points.end());
      if (dt.number_of_vertices() == 0)
        return 1;
    }
    const double t = now() - t0;
    dt_seconds = std::min(dt_seconds, t);
    dt_total += t;
    for (size_t m = 0; m < nmodes; ++m) {
      if (rc[m] != 0)
        continue;
      sc_params_t p;
      sc_params_init(&p);
      p.mode = methods[m].mode;
      p.denoise = methods[m].denoise;
      p.threads = threads;
      sc_mesh_free(meshes[m]);
      meshes[m] = nullptr;
      cold_heap();
      t0 = now();
      rc[m] =
          sc_reconstruct(pts.xyz, pts.count, &p, &meshes[m], msg, sizeof msg);
      best[m] = std::min(best[m], now() - t0);
      if (rc[m] != 0)
        failure[m] = msg;
    }
  }
  const double spacing = median_spacing(points);

  // The ground truth, where there is one.
  std::unique_ptr<Reference> ref;
  // NAME_points.ply has NAME_gt_mesh.ply beside it.
  const std::string suffix = "_points";
  const bool points_file =
      name.size() > suffix.size() &&
      name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0;
  std::string gt =
      points_file ? name.substr(0, name.size() - suffix.size()) + "_gt_mesh"
      : name.rfind("bunny", 0) == 0       ? "bunny_gt_mesh"
      : name.rfind("cgal_kitten", 0) == 0 ? "kitten_gt_mesh"
                                          : "";
  Expected expected;
  if (!gt.empty()) {
    scf_points_t gp;
    uint32_t *gt_tri = nullptr;
    size_t gnt = 0;
    std::string gpath = dir + "/" + gt + ".ply";
    if (scf_mesh_read(gpath.c_str(), &gp, &gt_tri, &gnt, msg, sizeof msg) ==
        0) {
      ref = std::make_unique<Reference>();
      for (size_t i = 0; i < gnt; ++i) {
        Point p[3];
        for (int k = 0; k < 3; ++k) {
          const double *q = gp.xyz + 3 * size_t(gt_tri[3 * i + k]);
          p[k] = Point(q[0], q[1], q[2]);
        }
        ref->tris.emplace_back(p[0], p[1], p[2]);
      }
      ref->tree = std::make_unique<Tree>(ref->tris.begin(), ref->tris.end());
      ref->tree->accelerate_distance_queries();
      scs_meshcheck_t c;
      if (scs_meshcheck(gp.count, gp.xyz, gt_tri, gnt, nullptr, &c) == 0 &&
          c.closed) {
        expected.known = true;
        expected.components = c.components;
        expected.genus = genus_sum(c);
      }
      scs_meshcheck_free(&c);
      std::free(gt_tri);
      scf_points_free(&gp);
    } else {
      std::fprintf(stderr, "%s (no distances)\n", msg);
    }
  }

  for (size_t m = 0; m < nmodes; ++m) {
    if (rc[m] != 0) {
      std::printf("| %s | %s | failed: %s |\n", name.c_str(), methods[m].name,
                  failure[m].c_str());
      continue;
    }
    const sc_mesh_t *mesh = meshes[m];
    // Shortcrust mode's check (docs/algorithm.md section 6.5): the path
    // says when it finds the topology in doubt.
    const std::string shown =
        std::string(sc_path_name(mesh->diag.path)) +
        (mesh->diag.topology_doubt ? " (topology in doubt)" : "");
    if (row(name.c_str(), methods[m].name, shown.c_str(), pts.count,
            mesh->triangles, mesh->triangle_count, pts.xyz, ref.get(), spacing,
            best[m], dt_seconds, closed ? &expected : nullptr))
      ++right[m];
    sc_mesh_free(meshes[m]);
  }

  if (!afsr) {
    scf_points_free(&pts);
    return 0;
  }
  // CGAL's advancing-front reconstruction with its defaults.
  std::vector<std::array<std::size_t, 3>> facets;
  t0 = now();
  CGAL::advancing_front_surface_reconstruction(points.begin(), points.end(),
                                               std::back_inserter(facets));
  double sec = now() - t0;
  std::vector<uint32_t> t;
  t.reserve(3 * facets.size());
  for (const auto &f : facets)
    for (int k = 0; k < 3; ++k)
      t.push_back(uint32_t(f[k]));
  if (row(name.c_str(), "CGAL AFSR", "-", pts.count, t.data(), facets.size(),
          pts.xyz, ref.get(), spacing, sec, dt_seconds,
          closed ? &expected : nullptr))
    ++right[nmodes];
  scf_points_free(&pts);
  return 0;
}

} // namespace

int main(int argc, char **argv) {
  // As the command line does: freed memory is kept for reuse (and
  // cold_heap() gives it back before every timed run).
  (void)sc_tune_allocator();
  bool closed = argc >= 2 && std::strcmp(argv[1], "--closed") == 0;
  if (closed) {
    --argc;
    ++argv;
  }
  if (argc < 2 || argv[1][0] == '-') {
    bool help = argc >= 2 && (std::strcmp(argv[1], "--help") == 0 ||
                              std::strcmp(argv[1], "-h") == 0);
    std::fprintf(help ? stdout : stderr,
                 "usage: %s [--closed] DATA_DIR [--repeat N] [--threads N] "
                 "[--no-afsr] [FILE ...]\n\n"
                 "Runs every mode (boundary and watertight also with --denoise)"
                 "\nand CGAL's advancing front on the point "
                 "files\nDATA_DIR/FILE.ply (default: the bunny scans, "
                 "cgal_kitten_normals\nand cgal_half) and prints one "
                 "Markdown table. Each mode's time and that\nof CGAL's "
                 "Delaunay construction is the best of N rounds (default\n"
                 "3; small files get more, until the Delaunay construction "
                 "has\ntaken 0.25 s in all), each round running the "
                 "construction and then\nevery mode, so that all see the "
                 "same load. The advancing front\nruns once; --no-afsr "
                 "leaves it out (it takes minutes on the\nmerged scans). "
                 "--threads N runs every mode on N threads\n(default 1); "
                 "the construction always runs on one.\n\n"
                 "--closed: the closed models, FILE_points.ply beside their\n"
                 "FILE_gt_mesh.ply (default: every such pair in DATA_DIR),\n"
                 "in the modes for closed surfaces, each row with the\n"
                 "ground truth's components and genus and whether the "
                 "output is\nthat surface (closed, 99.9%% of the samples "
                 "used, the same\ncomponents and genus), and a count of "
                 "the models each method\ngets right.\n",
                 argv[0]);
    return help ? 0 : 2;
  }
  const std::string dir = argv[1];
  std::vector<std::string> files;
  // Times are the best of `repeat` rounds or more, the yardstick's as well
  // as each mode's: the machines are shared, and one run can be slowed by
  // anything. A round runs the yardstick and then every mode, so that a
  // slow spell slows both sides of a ratio.
  int repeat = 3, threads = 1;
  bool afsr = true;
  for (int i = 2; i < argc; ++i) {
    if (std::strcmp(argv[i], "--repeat") == 0 && i + 1 < argc) {
      repeat = std::atoi(argv[++i]);
      if (repeat < 1) {
        std::fprintf(stderr, "--repeat needs a count of at least 1\n");
        return 2;
      }
    } else if (std::strcmp(argv[i], "--threads") == 0 && i + 1 < argc) {
      threads = std::atoi(argv[++i]);
      if (threads < 1 || threads > 1024) {
        std::fprintf(stderr, "--threads needs a count in [1, 1024]\n");
        return 2;
      }
    } else if (std::strcmp(argv[i], "--no-afsr") == 0) {
      afsr = false;
    } else {
      files.push_back(argv[i]);
    }
  }
  if (files.empty() && closed) {
    // Every NAME_points.ply with its NAME_gt_mesh.ply, in name order.
    std::unique_ptr<DIR, int (*)(DIR *)> d(opendir(dir.c_str()), closedir);
    if (!d) {
      std::fprintf(stderr, "%s: %s\n", dir.c_str(), std::strerror(errno));
      return 2;
    }
    const std::string tail = "_points.ply";
    while (const dirent *e = readdir(d.get())) {
      const std::string f = e->d_name;
      if (f.size() <= tail.size() ||
          f.compare(f.size() - tail.size(), tail.size(), tail) != 0)
        continue;
      const std::string base = f.substr(0, f.size() - tail.size());
      if (access((dir + "/" + base + "_gt_mesh.ply").c_str(), R_OK) == 0)
        files.push_back(base + "_points");
    }
    std::sort(files.begin(), files.end());
  }
  if (files.empty())
    files = {"bunny_points",         "bunny_rawscan_bun000",
             "bunny_rawscan_bun045", "bunny_rawscans_merged10",
             "cgal_kitten_normals",  "cgal_half"};

  std::printf("| file | method | path | triangles | samples used | "
              "non-manifold edges / vertices | orientation errors | "
              "boundary loops | components | closed | genus (sum) | "
              "distance to GT, RMS / max (spacings) | time | time / CGAL "
              "Delaunay |%s\n",
              closed ? " expected components / genus | right |" : "");
  std::printf("|---|---|---|--:|--:|--:|--:|--:|--:|---|---|--:|--:|--:|%s\n",
              closed ? "--:|---|" : "");
  // The models each method got right, counted by the measuring processes.
  constexpr size_t kMethods = 5;
  int *right = static_cast<int *>(mmap(nullptr, kMethods * sizeof(int),
                                       PROT_READ | PROT_WRITE,
                                       MAP_SHARED | MAP_ANONYMOUS, -1, 0));
  if (right == MAP_FAILED) {
    std::perror("mmap");
    return 1;
  }
  std::fill(right, right + kMethods, 0);
  for (const std::string &name : files) {
    // Each file in a process of its own: one that follows a larger file
    // would find the heap that file left (pages of it stay mapped however
    // it is trimmed), which made the yardstick of a file of a few hundred
    // points 15% faster after the merged scans than on its own.
    std::fflush(stdout);
    const pid_t pid = fork();
    if (pid < 0) {
      std::perror("fork");
      return 1;
    }
    if (pid == 0) {
      const int rc = measure(dir, name, repeat, threads, afsr, closed, right);
      std::fflush(stdout);
      std::_Exit(rc);
    }
    int status = 0;
    if (waitpid(pid, &status, 0) != pid || !WIFEXITED(status) ||
        WEXITSTATUS(status) != 0) {
      std::fprintf(stderr, "%s: the measurement failed\n", name.c_str());
      return 1;
    }
  }
  if (closed) {
    const char *names[kMethods] = {"cocone", "shortcrust", "watertight", "auto",
                                   "CGAL AFSR"};
    std::printf("\nRight (closed, >= 99.9%% of the samples, the ground "
                "truth's components and genus), of %zu models:",
                files.size());
    for (size_t m = 0; m < kMethods; ++m)
      if (m + 1 < kMethods || afsr)
        std::printf(" %s %d%s", names[m], right[m],
                    m + 1 < kMethods && (m + 2 < kMethods || afsr) ? "," : "");
    std::printf("\n");
  }
  munmap(right, kMethods * sizeof(int));
  return 0;
}
