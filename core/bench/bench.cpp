// shortcrust-bench: times each stage of the reconstruction on generated
// samples and compares it, in the same run and on the same points, with
// CGAL's Delaunay construction alone (time and peak memory) and with CGAL's
// advancing-front reconstruction (the peer). Each measurement runs in a
// forked child, so every peak-memory figure is that measurement's own.
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include <CGAL/Advancing_front_surface_reconstruction.h>
#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include "shortcrust.h"
#include "shortcrust_files.h"
#include "synth.h"

namespace {

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef K::Point_3 Point;

struct Result {
  int ok;
  double seconds;
  double cpu_seconds; // user + system time of the measurement's process
  double stage[SC_STAGE_COUNT];
  double peak_bytes; // above the resident set at the start
  double base_bytes; // the resident set at the start
  uint64_t triangles, unused, components, boundary_edges;
  int closed, manifold;
  int64_t genus;
  int mesh; // the fields above describe an output mesh
  uint64_t tiles, foreign, vertices; // tiled runs: the overhead
  uint64_t hash; // of the triangles, to tell a different mesh
  char msg[240]; // why the reconstruction failed
};

double now() {
  using namespace std::chrono;
  return duration<double>(steady_clock::now().time_since_epoch()).count();
}

double cpu_now() {
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  return double(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
         1e-6 * double(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

long status_kb(const char *key) {
  FILE *f = std::fopen("/proc/self/status", "r");
  if (!f)
    return -1;
  char line[256];
  long v = -1;
  size_t k = std::strlen(key);
  while (std::fgets(line, sizeof line, f))
    if (std::strncmp(line, key, k) == 0 && line[k] == ':')
      v = std::strtol(line + k + 1, nullptr, 10);
  std::fclose(f);
  return v;
}

// Resets the peak resident set to the current one (Linux 4.0+), so that
// VmHWM then measures only what follows.
void reset_peak() {
  FILE *f = std::fopen("/proc/self/clear_refs", "w");
  if (f) {
    std::fputs("5", f);
    std::fclose(f);
  }
}

// Runs f in a child process and returns what it reported through a pipe.
template <class F> Result in_child(F f) {
  Result r{};
  int fd[2];
  if (pipe(fd) != 0)
    return r;
  std::fflush(nullptr);
  pid_t pid = fork();
  if (pid == 0) {
    close(fd[0]);
    reset_peak();
    long base = status_kb("VmRSS");
    double cpu0 = cpu_now();
    Result res{};
    f(res);
    res.cpu_seconds = cpu_now() - cpu0;
    res.peak_bytes = 1024.0 * double(status_kb("VmHWM") - base);
    res.base_bytes = 1024.0 * double(base);
    ssize_t w = write(fd[1], &res, sizeof res);
    _exit(w == sizeof res ? 0 : 1);
  }
  close(fd[1]);
  ssize_t got = read(fd[0], &r, sizeof r);
  close(fd[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  if (got != sizeof r || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
    r.ok = 0;
  return r;
}

void check_mesh(size_t n, const double *xyz, const uint32_t *tri, size_t nt,
                Result &r) {
  scs_meshcheck_t c;
  if (scs_meshcheck(n, xyz, tri, nt, nullptr, &c) != 0)
    return;
  r.triangles = c.faces;
  r.unused = c.samples_unused;
  r.components = c.components;
  r.boundary_edges = c.boundary_edges;
  r.closed = c.closed;
  r.manifold = c.manifold;
  r.genus = c.genus_total;
  r.mesh = 1;
  scs_meshcheck_free(&c);
}

// The points as CGAL wants them; the copy is part of what a CGAL user pays.
std::vector<Point> to_points(const double *xyz, size_t n) {
  std::vector<Point> pts;
  pts.reserve(n);
  for (size_t i = 0; i < n; ++i)
    pts.emplace_back(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
  return pts;
}

Result run_cgal_delaunay(const double *xyz, size_t n) {
  return in_child([&](Result &r) {
    double t0 = now();
    std::vector<Point> pts = to_points(xyz, n);
    CGAL::Delaunay_triangulation_3<K> dt(pts.begin(), pts.end());
    r.seconds = now() - t0;
    r.ok = dt.dimension() == 3;
  });
}

// What the shortcrust runs are asked for besides the threads.
struct Job {
  int mode = SC_MODE_COCONE;
  int denoise = 0;
  int tiles = 1;
  double memory_limit = 0; // bytes
};

Result run_shortcrust(const double *xyz, size_t n, int threads,
                      const Job &job) {
  return in_child([&](Result &r) {
    sc_params_t p;
    sc_params_init(&p);
    p.threads = threads;
    p.tiles = job.tiles;
    p.mode = sc_mode_t(job.mode);
    p.denoise = job.denoise;
    p.memory_limit = job.memory_limit;
    sc_mesh_t *m = nullptr;
    double t0 = now();
    int rc = sc_reconstruct(xyz, n, &p, &m, r.msg, sizeof r.msg);
    r.seconds = now() - t0;
    if (rc != 0)
      return; // r.msg says why
    for (int s = 0; s < SC_STAGE_COUNT; ++s)
      r.stage[s] = m->diag.seconds[s];
    check_mesh(n, xyz, m->triangles, m->triangle_count, r);
    r.hash = 1469598103934665603ull;
    for (size_t i = 0; i < 3 * m->triangle_count; ++i)
      r.hash = (r.hash ^ m->triangles[i]) * 1099511628211ull;
    r.tiles = m->diag.tiles;
    r.foreign = m->diag.tile_points_foreign;
    r.vertices = m->diag.delaunay_vertices;
    r.ok = 1;
    sc_mesh_free(m);
  });
}

Result run_advancing_front(const double *xyz, size_t n) {
  return in_child([&](Result &r) {
    double t0 = now();
    std::vector<Point> pts = to_points(xyz, n);
    std::vector<std::array<std::size_t, 3>> facets;
    CGAL::advancing_front_surface_reconstruction(pts.begin(), pts.end(),
                                                 std::back_inserter(facets));
    r.seconds = now() - t0;
    std::vector<uint32_t> tri;
    tri.reserve(3 * facets.size());
    for (const auto &f : facets)
      for (std::size_t v : f)
        tri.push_back(uint32_t(v));
    check_mesh(n, xyz, tri.data(), facets.size(), r);
    r.ok = 1;
  });
}

void usage(FILE *f) {
  std::fprintf(
      f,
      "usage: shortcrust-bench [--sizes N,N,...] [--surface NAME] "
      "[--density NAME]\n"
      "                        [--noise SIGMA] [--input FILE] [--mode MODE] "
      "[--denoise]\n"
      "                        [--threads N] [--tiles N] "
      "[--memory-limit F] [--no-peer]\n"
      "                        [--peer-max N] [--seed S] [--repeat N]\n\n"
      "Times the reconstruction stage by stage on generated samples and "
      "prints, per size,\n"
      "its time and peak memory against CGAL's Delaunay construction of "
      "the same points\n"
      "alone, the gain of more threads (the smoothing's; with --tiles, "
      "the tiles'),\nand CGAL's advancing-front reconstruction of the same "
      "points (time, and\nwhether it is closed).\n\n"
      "  --sizes      point counts (default 100000,1000000)\n"
      "  --surface    sphere, ellipsoid, torus, genus2, two-spheres, "
      "nested-spheres\n"
      "               (default torus)\n"
      "  --density    uniform-random, uniform, adaptive (default "
      "uniform-random)\n"
      "  --threads    threads for the parallel run (default: one per core)\n"
      "  --tiles      also run with N tiles (docs/algorithm.md section 17) on "
      "1 thread\n"
      "               and on --threads, and compare their meshes with the "
      "single\n"
      "               triangulation's\n"
      "  --memory-limit  also run with --memory-limit at F times the peak "
      "resident\n"
      "               memory of the untiled run (one thread; F in (0, 1)), "
      "and compare\n"
      "               its mesh and peak with it (docs/algorithm.md section "
      "17.5)\n"
      "  --no-peer    skip the advancing front\n"
      "  --peer-max   run the advancing front only up to this many points\n"
      "               (default 1000000)\n"
      "  --seed       sample seed (default 1)\n"
      "  --noise      move each sample by Gaussian noise of SIGMA sample "
      "spacings\n"
      "  --input      the points of FILE instead of samples (--sizes, "
      "--surface,\n"
      "               --density and --noise are then ignored)\n"
      "  --mode       shortcrust's mode (default cocone)\n"
      "  --denoise    shortcrust denoises (docs/algorithm.md section 16)\n"
      "  --repeat     time CGAL's construction alone and the one-thread run "
      "N times,\n"
      "               in turn, and report the round of the median ratio "
      "(default 1,\n"
      "               at most 99)\n");
}

void print_row(const char *name, const Result &r, size_t n) {
  if (!r.ok) {
    std::printf("  %-28s failed\n", name);
    return;
  }
  std::printf("  %-24s %8.3f s (cpu %7.3f s)  peak %5.0f B/point", name,
              r.seconds, r.cpu_seconds, r.peak_bytes / double(n));
  if (r.mesh)
    std::printf("  %llu triangles, %s, %llu component%s, genus %lld, %llu "
                "unused",
                (unsigned long long)r.triangles,
                r.closed ? "closed" : r.manifold ? "open" : "not manifold",
                (unsigned long long)r.components,
                r.components == 1 ? "" : "s", (long long)r.genus,
                (unsigned long long)r.unused);
  std::printf("\n");
}

} // namespace

int main(int argc, char **argv) {
  (void)sc_tune_allocator(); // as the command line does
  std::vector<size_t> sizes{100000, 1000000};
  int surface = SCS_SURF_TORUS, density = SCS_DENSITY_UNIFORM_RANDOM;
  int threads = int(std::thread::hardware_concurrency());
  int tiles = 1;
  double limit_fraction = 0;
  bool peer = true;
  size_t peer_max = 1000000;
  uint64_t seed = 1;
  double noise = 0;
  int repeat = 1;
  const char *input = nullptr;
  Job job;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    auto value = [&]() -> const char * {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "shortcrust-bench: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--sizes") {
      sizes.clear();
      std::string s = value();
      for (size_t at = 0; at <= s.size();) {
        size_t comma = s.find(',', at);
        if (comma == std::string::npos)
          comma = s.size();
        long v = std::atol(s.substr(at, comma - at).c_str());
        if (v < 4) {
          std::fprintf(stderr, "shortcrust-bench: bad size in '%s'\n",
                       s.c_str());
          return 2;
        }
        sizes.push_back(size_t(v));
        at = comma + 1;
      }
    } else if (a == "--surface") {
      surface = scs_surface_from_name(value());
    } else if (a == "--density") {
      density = scs_density_from_name(value());
    } else if (a == "--threads") {
      threads = std::atoi(value());
    } else if (a == "--tiles") {
      tiles = std::atoi(value());
    } else if (a == "--memory-limit") {
      limit_fraction = std::atof(value());
      if (!(limit_fraction > 0 && limit_fraction < 1)) {
        std::fprintf(stderr, "shortcrust-bench: --memory-limit takes a "
                             "fraction in (0, 1)\n");
        return 2;
      }
    } else if (a == "--no-peer") {
      peer = false;
    } else if (a == "--peer-max") {
      peer_max = size_t(std::atol(value()));
    } else if (a == "--seed") {
      seed = std::strtoull(value(), nullptr, 10);
    } else if (a == "--noise") {
      noise = std::atof(value());
    } else if (a == "--input") {
      input = value();
    } else if (a == "--mode") {
      const char *m = value();
      job.mode = -1;
      for (int k = 0; k < SC_MODE_COUNT_; ++k)
        if (std::strcmp(m, sc_mode_name(k)) == 0)
          job.mode = k;
    } else if (a == "--denoise") {
      job.denoise = 1;
    } else if (a == "--repeat") {
      repeat = std::atoi(value());
    } else if (a == "-h" || a == "--help") {
      usage(stdout);
      return 0;
    } else {
      std::fprintf(stderr, "shortcrust-bench: unknown option '%s'\n",
                   a.c_str());
      usage(stderr);
      return 2;
    }
  }
  if (surface < 0 || density < 0 || threads < 1 || job.mode < 0 ||
      !(noise >= 0) || tiles < 1 || repeat < 1 || repeat > 99) {
    std::fprintf(stderr, "shortcrust-bench: bad --surface, --density, "
                         "--threads, --tiles, --mode, --noise or --repeat\n");
    return 2;
  }
  if (input)
    sizes.assign(1, 0);

  bool failed = false;
  for (size_t n : sizes) {
    std::vector<double> xyz;
    double t0 = now();
    if (input) {
      scf_points_t pts;
      char msg[512];
      if (scf_points_read(input, &pts, msg, sizeof msg) < 0) {
        std::fprintf(stderr, "shortcrust-bench: %s\n", msg);
        return 1;
      }
      n = pts.count;
      xyz.assign(pts.xyz, pts.xyz + 3 * n);
      scf_points_free(&pts);
      std::printf("%zu points of %s (read in %.1f s)\n", n, input,
                  now() - t0);
    } else {
      xyz.resize(3 * n);
      if (scs_sample_surface(scs_surface_t(surface), density, n, seed,
                             xyz.data()) != 0) {
        std::fprintf(stderr, "shortcrust-bench: sampling failed\n");
        return 1;
      }
      scs_add_noise(xyz.data(), n,
                    noise * scs_surface_spacing(scs_surface_t(surface), n),
                    seed + 1000);
      std::printf("%zu points, %s, %s, noise %g spacings (sampled in %.1f "
                  "s)\n",
                  n, scs_surface_name(scs_surface_t(surface)),
                  scs_density_name(density), noise, now() - t0);
    }
    std::printf("  shortcrust: mode %s%s\n", sc_mode_name(job.mode),
                job.denoise ? ", --denoise" : "");
    // CGAL's construction alone and the reconstruction on one thread,
    // --repeat times, one after the other; the round whose ratio is the
    // median stands for them (a busy machine slows single runs by up to
    // half, and not both of a pair alike).
    std::vector<std::pair<Result, Result>> rounds;
    for (int k = 0; k < repeat; ++k) {
      Result d = run_cgal_delaunay(xyz.data(), n);
      Result o = run_shortcrust(xyz.data(), n, 1, job);
      if (repeat > 1)
        std::printf("  round %d: cgal delaunay alone %.3f s, shortcrust "
                    "%.3f s, ratio %.2f\n",
                    k + 1, d.seconds, o.seconds,
                    d.ok && o.ok ? o.seconds / d.seconds : 0.0);
      if (!d.ok || !o.ok) {
        rounds.assign(1, {d, o});
        break;
      }
      rounds.emplace_back(d, o);
    }
    std::sort(rounds.begin(), rounds.end(), [](const auto &a, const auto &b) {
      return a.second.seconds / a.first.seconds <
             b.second.seconds / b.first.seconds;
    });
    const Result dt = rounds[rounds.size() / 2].first;
    const Result one = rounds[rounds.size() / 2].second;
    if (rounds.size() > 1)
      std::printf("  the median round of %zu (ratios %.2f to %.2f):\n",
                  rounds.size(),
                  rounds.front().second.seconds / rounds.front().first.seconds,
                  rounds.back().second.seconds / rounds.back().first.seconds);
    print_row("cgal delaunay alone", dt, n);
    print_row("shortcrust, 1 thread", one, n);
    if (one.ok) {
      std::printf("    stages:");
      for (int s = 0; s < SC_STAGE_COUNT; ++s)
        std::printf(" %s %.3f s%s", sc_stage_name(s), one.stage[s],
                    s + 1 < SC_STAGE_COUNT ? "," : "\n");
    }
    Result par{};
    if (threads > 1) {
      par = run_shortcrust(xyz.data(), n, threads, job);
      char name[64];
      std::snprintf(name, sizeof name, "shortcrust, %d threads", threads);
      print_row(name, par, n);
    }
    // Tiles: on one thread (the overhead) and on all (the gain), against
    // the single triangulation on one thread and CGAL's construction.
    for (int t = 1; tiles > 1 && one.ok && t <= threads;
         t = t == 1 ? threads : t + 1) {
      Job tj = job;
      tj.tiles = tiles;
      Result tr = run_shortcrust(xyz.data(), n, t, tj);
      char name[64];
      std::snprintf(name, sizeof name, "%d tiles, %d thread%s", tiles, t,
                    t == 1 ? "" : "s");
      print_row(name, tr, n);
      if (!tr.ok)
        continue;
      const bool same = tr.triangles == one.triangles && tr.hash == one.hash;
      std::printf("    %llu tiles, %llu points triangulated twice (%.1f%%), "
                  "time / 1 thread untiled %.2f, / cgal delaunay %.2f, "
                  "peak / cgal delaunay %.2f, %s\n",
                  (unsigned long long)tr.tiles, (unsigned long long)tr.foreign,
                  100.0 * double(tr.foreign) / double(tr.vertices),
                  tr.seconds / one.seconds,
                  dt.ok ? tr.seconds / dt.seconds : 0.0,
                  dt.ok ? tr.peak_bytes / dt.peak_bytes : 0.0,
                  same ? "same mesh" : "A DIFFERENT MESH");
      if (!same)
        failed = true;
    }
    // Within a memory limit, a fraction of the untiled run's peak (the
    // whole process's, as the limit counts it).
    if (limit_fraction > 0 && one.ok) {
      Job lj = job;
      const double untiled = one.base_bytes + one.peak_bytes;
      lj.memory_limit = limit_fraction * untiled;
      Result lr = run_shortcrust(xyz.data(), n, 1, lj);
      char name[64];
      std::snprintf(name, sizeof name, "memory limit %.2f", limit_fraction);
      if (!lr.ok && lr.msg[0]) {
        std::printf("  %-24s %.1f MB of the untiled %.1f MB: refused: %s\n",
                    name, lj.memory_limit / 1048576, untiled / 1048576, lr.msg);
      } else {
        print_row(name, lr, n);
        if (lr.ok) {
          const bool same =
              lr.triangles == one.triangles && lr.hash == one.hash;
          const double peak = lr.base_bytes + lr.peak_bytes;
          std::printf("    limit %.1f MB (untiled peak %.1f MB): %llu tiles, "
                      "peak %.1f MB = %.2f of the limit (target <= 1.3), "
                      "time / untiled %.2f, %s\n",
                      lj.memory_limit / 1048576, untiled / 1048576,
                      (unsigned long long)lr.tiles, peak / 1048576,
                      peak / lj.memory_limit, lr.seconds / one.seconds,
                      same ? "same mesh" : "A DIFFERENT MESH");
          if (!same)
            failed = true;
        }
      }
    }
    Result af{};
    if (peer && n <= peer_max) {
      af = run_advancing_front(xyz.data(), n);
      print_row("cgal advancing front", af, n);
    }
    if (dt.ok && one.ok) {
      // CPU time is what a busy machine disturbs least; the single-thread
      // runs use one core, so it is their cost.
      // The targets: the plain modes 1.5x at 1M points and 1.3x the
      // memory; denoising 2.5x and 1.5x the memory.
      std::printf("  ratios: time / cgal delaunay %.2f (cpu %.2f; target <= "
                  "%s), peak memory / cgal delaunay %.2f (target <= %s)",
                  one.seconds / dt.seconds, one.cpu_seconds / dt.cpu_seconds,
                  job.denoise ? "2.5" : "1.5 at 1M",
                  one.peak_bytes / dt.peak_bytes, job.denoise ? "1.5" : "1.3");
      if (par.ok)
        std::printf(", %d threads / 1 thread %.2f", threads,
                    par.seconds / one.seconds);
      if (af.ok)
        std::printf(", advancing front / shortcrust %.1f",
                    af.seconds / one.seconds);
      std::printf("\n\n");
    }
  }
  return failed ? 1 : 0;
}
