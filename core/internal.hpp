// Internals of the core, shared by its translation units. Nothing here is
// visible outside core/.
//
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef SC_CORE_INTERNAL_HPP
#define SC_CORE_INTERNAL_HPP

#include "shortcrust.h"

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace sc {

// Measured peak bytes per input point of a whole reconstruction (the
// triangulation dominates); used for admission control by the daemon.
constexpr uint64_t kBytesPerPoint = 1100;

// An error with a code from the public table, thrown inside the core and
// turned into a return value at the C boundary.
struct Error : std::runtime_error {
  int code;
  Error(int c, const std::string &what) : std::runtime_error(what), code(c) {}
};

void set_msg(char *msg, size_t len, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
int check_params(const sc_params_t *p, char *msg, size_t len);

// Reports progress of one stage and turns a cancel request into an Error.
class Progress {
public:
  Progress(sc_progress_fn fn, void *user) : fn_(fn), user_(user) {}
  void stage(sc_stage_t s) {
    stage_ = s;
    report(0.0);
  }
  void report(double fraction) {
    if (fn_ && fn_(user_, stage_, fraction))
      throw Error(SC_ECANCELLED, "cancelled during stage " +
                                     std::string(sc_stage_name(stage_)));
  }
  // For loops: report every `every` iterations (a power of two).
  void tick(size_t i, size_t n, size_t every = 1u << 15) {
    if (fn_ && (i & (every - 1)) == 0)
      report(n ? double(i) / double(n) : 1.0);
  }

private:
  sc_progress_fn fn_;
  void *user_;
  sc_stage_t stage_ = SC_STAGE_INPUT;
};

// What the triangulation stages hand to the rest of the pipeline; the
// triangulation itself is gone by then.
// Vertices are numbered 0 .. m-1 in the triangulation's (spatially sorted)
// order; to_input maps them back to input indices.
struct Filtered {
  std::vector<uint32_t> tris;     // candidate triangles, 3 vertex numbers each
  std::vector<double> poles;      // 3 per vertex: unit pole direction
  std::vector<uint32_t> to_input; // vertex number -> input index
  std::vector<std::pair<uint32_t, uint32_t>> dups; // (duplicate, first), input
};

// The Delaunay-dependent stages, behind an interface so that the sequential
// and the parallel triangulation share the rest of the pipeline.
class Triangulator {
public:
  virtual ~Triangulator() = default;
  // Inserts points [first, first + n) of xyz (which holds every point so far).
  virtual void insert(const double *xyz, size_t first, size_t n,
                      Progress &progress) = 0;
  virtual int dimension() const = 0;
  // Resolves duplicates, then runs poles and candidates, filling diag.
  virtual void filter(const double *xyz, size_t n, const sc_params_t &params,
                      Progress &progress, Filtered &out, sc_diag_t &diag,
                      double seconds[SC_STAGE_COUNT]) = 0;
};

std::unique_ptr<Triangulator> make_triangulator(int threads,
                                                const double *bbox6);

// Pruning and manifold extraction over the candidates (surface.cpp).
// Returns the oriented output triangles and fills the output diagnostics.
struct Surface {
  std::vector<uint32_t> tris;
  std::vector<int32_t> component_genus;
};
void prune(const double *xyz, size_t n, const std::vector<uint32_t> &cand,
           bool erode_single, std::vector<uint8_t> &alive, Progress &progress,
           sc_diag_t &diag);
void extract(const double *xyz, size_t n, const std::vector<uint32_t> &cand,
             const std::vector<uint8_t> &alive, size_t max_hole,
             Progress &progress, Surface &out, sc_diag_t &diag);

// One reconstruction, fed all at once or in chunks.
class Recon {
public:
  explicit Recon(const sc_params_t &p) : params_(p) {}
  void add(const double *xyz, size_t n);
  void borrow(const double *xyz, size_t n);
  sc_mesh_t *finish();

private:
  void insert_range(size_t first, size_t n);
  sc_params_t params_;
  std::vector<double> own_;
  const double *xyz_ = nullptr;
  size_t n_ = 0;
  std::unique_ptr<Triangulator> dt_;
  double seconds_[SC_STAGE_COUNT] = {};
};

class Stopwatch {
public:
  Stopwatch() : t0_(std::chrono::steady_clock::now()) {}
  double lap() {
    auto t = std::chrono::steady_clock::now();
    double s = std::chrono::duration<double>(t - t0_).count();
    t0_ = t;
    return s;
  }

private:
  std::chrono::steady_clock::time_point t0_;
};

} // namespace sc

#endif
