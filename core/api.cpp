// The C boundary of the core: error tables, defaults, and the functions that
// turn every C++ exception into an error code.
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include "internal.hpp"

#include <climits>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <new>
#include <stdexcept>

#ifdef __GLIBC__
#include <malloc.h>
#endif
#ifdef CGAL_LINKED_WITH_TBB
#include <tbb/scalable_allocator.h>
#endif

extern "C" const char *sc_strerror(int code) {
  switch (code) {
  case SC_OK:
    return "success";
#define SC_ERR_MSG_(name, value, msg)                                           \
  case value:                                                                  \
    return msg;
    SC_ERRNO_MAP(SC_ERR_MSG_)
#undef SC_ERR_MSG_
  }
  return "unknown error";
}

extern "C" const char *sc_err_name(int code) {
  switch (code) {
  case SC_OK:
    return "OK";
#define SC_ERR_NAME_(name, value, msg)                                          \
  case value:                                                                  \
    return #name;
    SC_ERRNO_MAP(SC_ERR_NAME_)
#undef SC_ERR_NAME_
  }
  return "UNKNOWN";
}

extern "C" const char *sc_stage_name(int stage) {
  switch (stage) {
#define SC_STAGE_NAME_(name, value, str, what)                                 \
  case value:                                                                  \
    return str;
    SC_STAGE_MAP(SC_STAGE_NAME_)
#undef SC_STAGE_NAME_
  }
  return "?";
}

extern "C" const char *sc_mode_name(int mode) {
  switch (mode) {
#define SC_MODE_NAME_(name, value, str)                                        \
  case value:                                                                  \
    return str;
    SC_MODE_MAP(SC_MODE_NAME_)
#undef SC_MODE_NAME_
  }
  return "?";
}

extern "C" void sc_params_init(sc_params_t *p) {
  if (p)
    *p = sc::kDefaultParams;
}

extern "C" int sc_params_can_tile(const sc_params_t *p) {
  return p && sc::can_tile(*p);
}

extern "C" int sc_params_check(const sc_params_t *p, char *msg,
                               size_t msg_len) {
  if (!p) {
    sc::set_msg(msg, msg_len, "%s", sc_strerror(SC_EINVALID_ARGUMENT));
    return SC_EINVALID_ARGUMENT;
  }
  return sc::check_params(p, msg, msg_len);
}

extern "C" const char *sc_path_name(int path) {
  switch (path) {
#define SC_PATH_NAME_(name, value, str)                                        \
  case value:                                                                  \
    return str;
    SC_PATH_MAP(SC_PATH_NAME_)
#undef SC_PATH_NAME_
  }
  return "?";
}

namespace sc {

void set_msg(char *msg, size_t len, const char *fmt, ...) {
  if (!msg || len == 0)
    return;
  va_list ap;
  va_start(ap, fmt);
  std::vsnprintf(msg, len, fmt, ap);
  va_end(ap);
}

// The value of a field as a number, for the range checks: a C caller may
// store any int in the enum, and in C++ loading a value outside the enum's
// range is undefined, so the mode is read from its bytes.
static double as_number(const sc_mode_t &mode) {
  static_assert(sizeof(sc_mode_t) == sizeof(int), "mode is an int");
  int v;
  std::memcpy(&v, &mode, sizeof v);
  return v;
}
static double as_number(double v) { return v; }
static double as_number(int v) { return v; }

// The message for a field out of range, worded per kind.
static void range_msg(char *msg, size_t len, const char *kind,
                      const char *field, const char *text, int range,
                      double v) {
  const char *zero = (range & SC_RANGE_ZERO_DEFAULT) ? " or 0" : "";
  if (std::strcmp(kind, "MODE") == 0)
    set_msg(msg, len, "unknown mode %d", (int)v);
  else if (std::strcmp(kind, "INT") == 0 || std::strcmp(kind, "FLAG") == 0)
    set_msg(msg, len, "%s must be %s%s, got %d", field, text, zero, (int)v);
  else
    set_msg(msg, len, "%s must be %s%s, got %g", field, text, zero, v);
}

int check_params(const sc_params_t *p, char *msg, size_t len) {
#define SC_CHECK_(field, type, kind, dflt, lo, hi, range, text, ...)           \
  {                                                                            \
    double v = as_number(p->field);                                            \
    if (!SC_IN_RANGE(v, (double)(lo), (double)(hi), range)) {                  \
      range_msg(msg, len, #kind, #field, text, range, v);                      \
      return SC_EINVALID_ARGUMENT;                                             \
    }                                                                          \
  }
  SC_PARAM_MAP(SC_CHECK_)
#undef SC_CHECK_
  if (p->memory_limit > 0 && as_number(p->mode) != SC_MODE_COCONE &&
      as_number(p->mode) != SC_MODE_SHORTCRUST) {
    set_msg(msg, len,
            "memory_limit works in the cocone and shortcrust modes only (the "
            "%s mode needs one triangulation of all the points)",
            sc_mode_name(int(as_number(p->mode))));
    return SC_EINVALID_ARGUMENT;
  }
  if (p->tile_count > 0 && as_number(p->mode) != SC_MODE_COCONE &&
      as_number(p->mode) != SC_MODE_SHORTCRUST) {
    set_msg(msg, len,
            "tile_count works in the cocone and shortcrust modes only (the "
            "%s mode needs one triangulation of all the points)",
            sc_mode_name(int(as_number(p->mode))));
    return SC_EINVALID_ARGUMENT;
  }
  if (p->tile_index > 0 && p->tile_count == 0) {
    set_msg(msg, len, "tile_index needs tile_count, got tile_index %d",
            p->tile_index);
    return SC_EINVALID_ARGUMENT;
  }
  if (p->tile_count > 0 && p->tile_index >= p->tile_count) {
    set_msg(msg, len, "tile_index must be below tile_count (%d), got %d",
            p->tile_count, p->tile_index);
    return SC_EINVALID_ARGUMENT;
  }
  return SC_OK;
}

} // namespace sc

using sc::set_msg;

// Runs f, turning any exception into an error code and a message.
template <class F> static int guarded(char *msg, size_t len, F &&f) {
  try {
    return f();
  } catch (const sc::Error &e) {
    set_msg(msg, len, "%s", e.what());
    return e.code;
  } catch (const std::bad_alloc &) {
    set_msg(msg, len, "%s", sc_strerror(SC_ENO_MEMORY));
    return SC_ENO_MEMORY;
  } catch (const std::exception &e) {
    set_msg(msg, len, "internal error: %s", e.what());
    return SC_EINTERNAL;
  } catch (...) {
    set_msg(msg, len, "internal error: unknown exception");
    return SC_EINTERNAL;
  }
}

struct sc_recon {
  sc::Recon impl;
  int failed = 0;
  int finished = 0;
};

extern "C" int sc_recon_new(const sc_params_t *params, sc_recon_t **out) {
  if (!out)
    return SC_EINVALID_ARGUMENT;
  *out = nullptr;
  sc_params_t p;
  if (params)
    p = *params;
  else
    sc_params_init(&p);
  int rc = sc::check_params(&p, nullptr, 0);
  if (rc)
    return rc;
  return guarded(nullptr, 0, [&] {
    *out = new sc_recon{sc::Recon(p)};
    return SC_OK;
  });
}

extern "C" int sc_recon_add(sc_recon_t *r, const double *xyz, size_t n,
                            char *msg, size_t msg_len) {
  if (!r || (!xyz && n)) {
    set_msg(msg, msg_len, "%s", sc_strerror(SC_EINVALID_ARGUMENT));
    return SC_EINVALID_ARGUMENT;
  }
  if (r->failed || r->finished) {
    set_msg(msg, msg_len, "%s", sc_strerror(SC_EBAD_STATE));
    return SC_EBAD_STATE;
  }
  int rc = guarded(msg, msg_len, [&] {
    r->impl.add(xyz, n);
    return SC_OK;
  });
  if (rc)
    r->failed = 1;
  return rc;
}

extern "C" int sc_recon_finish(sc_recon_t *r, sc_mesh_t **out, char *msg,
                               size_t msg_len) {
  if (out)
    *out = nullptr;
  if (!r || !out) {
    set_msg(msg, msg_len, "%s", sc_strerror(SC_EINVALID_ARGUMENT));
    return SC_EINVALID_ARGUMENT;
  }
  if (r->failed || r->finished) {
    set_msg(msg, msg_len, "%s", sc_strerror(SC_EBAD_STATE));
    return SC_EBAD_STATE;
  }
  r->finished = 1;
  return guarded(msg, msg_len, [&] {
    *out = r->impl.finish();
    return SC_OK;
  });
}

extern "C" void sc_recon_free(sc_recon_t *r) { delete r; }

// The one-call reconstructions: the points, the parameters checked (once
// `adjust` has had its say: 0, or an error with msg set), and, for a merge,
// the results of the job's tiles.
template <class Adjust>
static int reconstruct(const double *xyz, size_t n, const sc_params_t *params,
                       const sc_mesh_t *const *tiles, size_t count,
                       sc_mesh_t **out, char *msg, size_t msg_len,
                       Adjust &&adjust) {
  if (out)
    *out = nullptr;
  if (!out || (!xyz && n)) {
    set_msg(msg, msg_len, "%s", sc_strerror(SC_EINVALID_ARGUMENT));
    return SC_EINVALID_ARGUMENT;
  }
  sc_params_t p;
  if (params)
    p = *params;
  else
    sc_params_init(&p);
  int rc = adjust(p);
  if (!rc)
    rc = sc::check_params(&p, msg, msg_len);
  if (rc)
    return rc;
  // A merge is checked as its tile jobs were, and then runs untiled.
  if (tiles)
    p.tile_count = 0;
  return guarded(msg, msg_len, [&] {
    sc::Recon r(p);
    if (tiles)
      r.merge_from(tiles, count);
    r.borrow(xyz, n);
    *out = r.finish();
    return SC_OK;
  });
}

extern "C" int sc_reconstruct(const double *xyz, size_t n,
                              const sc_params_t *params, sc_mesh_t **out,
                              char *msg, size_t msg_len) {
  return reconstruct(xyz, n, params, nullptr, 0, out, msg, msg_len,
                     [](sc_params_t &) { return SC_OK; });
}

extern "C" int sc_reconstruct_merge(const double *xyz, size_t n,
                                    const sc_params_t *params,
                                    const sc_mesh_t *const *tiles, size_t count,
                                    sc_mesh_t **out, char *msg,
                                    size_t msg_len) {
  if (!tiles) {
    if (out)
      *out = nullptr;
    set_msg(msg, msg_len, "%s", sc_strerror(SC_EINVALID_ARGUMENT));
    return SC_EINVALID_ARGUMENT;
  }
  return reconstruct(
      xyz, n, params, tiles, count, out, msg, msg_len, [&](sc_params_t &p) {
        if (count < 2 || count > 4096) {
          set_msg(msg, msg_len, "a job is split into 2 to 4096 tiles, got %zu",
                  count);
          return int(SC_EINVALID_ARGUMENT);
        }
        for (size_t i = 0; i < count; ++i)
          if (!tiles[i] || tiles[i]->point_count != n ||
              (tiles[i]->triangle_count && !tiles[i]->triangles)) {
            set_msg(msg, msg_len, "tile %zu: %s", i,
                    !tiles[i] ? "no result"
                              : "not a result of these points (another "
                                "point count)");
            return int(SC_EINVALID_ARGUMENT);
          }
        // The job's parameters, checked as its tile jobs' were.
        p.tile_count = int(count);
        p.tile_index = 0;
        return int(SC_OK);
      });
}

extern "C" void sc_mesh_free(sc_mesh_t *mesh) {
  if (!mesh)
    return;
  std::free(mesh->triangles);
  std::free(mesh->normals);
  std::free(mesh->component_genus);
  std::free(mesh->smoothed);
  std::free(mesh);
}

extern "C" uint64_t sc_estimate_bytes(uint64_t n) {
  return sc::kBytesPerPoint * n + (1u << 20);
}

extern "C" void sc_release_memory(void) {
#ifdef CGAL_LINKED_WITH_TBB
  // CGAL's k-d trees (the noise estimate, the smoothing) keep their nodes
  // in TBB's scalable allocator, which holds on to freed blocks. The
  // command reads the allocator's state without setting it up, and crashes
  // in a process that has not yet allocated from it (a job that built no
  // k-d tree): one allocation first sets it up.
  scalable_free(scalable_malloc(1));
  (void)scalable_allocation_command(TBBMALLOC_CLEAN_ALL_BUFFERS, nullptr);
#endif
#ifdef __GLIBC__
  (void)malloc_trim(0);
#endif
}

extern "C" int sc_tune_allocator(void) {
#ifdef __GLIBC__
  // Large blocks from the heap rather than from mmap(), and the heap's top
  // kept when freed: a later allocation reuses pages already faulted in.
  if (mallopt(M_MMAP_MAX, 0) == 1 && mallopt(M_TRIM_THRESHOLD, INT_MAX) == 1)
    return SC_OK;
#endif
  return SC_EINTERNAL;
}
