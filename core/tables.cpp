// The parameter and diagnostic tables of shortcrust.h as data, for the
// programs that walk them instead of naming each field.
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include "internal.hpp"

#include <cstddef>

namespace {

const sc_param_info_t kParams[] = {
#define SC_PARAM_ROW_(field, type, kind, dflt, lo, hi, range, text, wire,      \
                      sopt, lopt, metavar, help)                               \
  {#field,        SC_PARAM_##kind, offsetof(sc_params_t, field),               \
   double(dflt),  double(lo),      double(hi),                                 \
   range,         text,            SC_PARAM_##wire,                            \
   sopt,          lopt,            metavar,                                    \
   help},
    SC_PARAM_MAP(SC_PARAM_ROW_)
#undef SC_PARAM_ROW_
};

// The elements of a field: 1, or the length of an array.
template <class T> constexpr size_t elements(const T &) { return 1; }
template <class T, size_t N> constexpr size_t elements(const T (&)[N]) {
  return N;
}

const sc_diag_t kDiag{};
const sc_diag_info_t kDiags[] = {
#define SC_DIAG_ROW_(field, type, dim, kind, wire, help)                       \
  {#field, SC_DIAG_##kind, offsetof(sc_diag_t, field), elements(kDiag.field),  \
   wire, help},
    SC_DIAG_MAP(SC_DIAG_ROW_)
#undef SC_DIAG_ROW_
};

} // namespace

extern "C" const sc_param_info_t *sc_param_table(size_t *count) {
  if (count)
    *count = sizeof kParams / sizeof kParams[0];
  return kParams;
}

extern "C" const sc_diag_info_t *sc_diag_table(size_t *count) {
  if (count)
    *count = sizeof kDiags / sizeof kDiags[0];
  return kDiags;
}

extern "C" const char *sc_diag_element_name(const sc_diag_info_t *row,
                                            size_t i) {
  static const char *const bins[SC_LOOP_BINS] = {
#define SC_LOOP_BIN_NAME_(index, suffix, least, most) suffix,
      SC_LOOP_BIN_MAP(SC_LOOP_BIN_NAME_)
#undef SC_LOOP_BIN_NAME_
  };
  if (!row || i >= row->count)
    return nullptr;
  if (row->kind == SC_DIAG_STAGE_SECONDS)
    return sc_stage_name(int(i));
  if (row->kind == SC_DIAG_LOOPS)
    return bins[i];
  return nullptr;
}
