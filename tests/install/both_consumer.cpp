// Both public headers in one C++ program, linked with shortcrust::core and
// shortcrust::client: the headers are C++-clean and the two libraries go
// together without clashing.
// SPDX-License-Identifier: GPL-3.0-or-later
#include <shortcrust.h>
#include <shortcrust_client.h>

#include <cstdio>
#include <cstring>

int main() {
  sc_params_t p;
  sc_params_init(&p);
  sc_client_params_t cp;
  sc_client_params_init(&cp);
  if (static_cast<int>(p.mode) != cp.mode || p.r != cp.r) {
    std::fprintf(stderr, "both_consumer: FAIL: defaults differ\n");
    return 1;
  }
  if (std::strcmp(sc_stage_name(SC_STAGE_DELAUNAY), "delaunay") != 0 ||
      std::strcmp(sc_client_stage_name(SC_STAGE_DELAUNAY), "delaunay") != 0) {
    std::fprintf(stderr, "both_consumer: FAIL: stage names\n");
    return 1;
  }
  std::printf("both_consumer: core and client defaults agree\n");
  return 0;
}
