/*
 * Shared pieces of the client library's tests; see common.h.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "common.h"

#include <string.h>

sc_client_t *scct_open(const char *sock, uint32_t max_frame) {
  sc_client_options_t o;
  sc_client_options_init(&o);
  o.socket_path = sock;
  if (max_frame)
    o.max_frame = max_frame;
  sc_client_t *c = NULL;
  char msg[512] = "";
  int rc = sc_client_connect(&o, &c, msg, sizeof msg);
  ASSERT_MSG(rc == 0 && c, "connect to %s: %s: %s", sock,
             sc_client_err_name(rc), msg);
  return c;
}

void scct_check_mesh(const char *what, int surface, const double *xyz,
                     uint64_t n, const sc_client_job_t *job) {
  sc_client_mesh_t m;
  int rc = sc_client_job_mesh(job, &m);
  EXPECT_MSG(rc == 0, "%s: job status %s: %s", what, sc_client_err_name(rc),
             sc_client_job_message(job));
  if (rc != 0)
    return;
  EXPECT_EQ(m.point_count, n);
  EXPECT_MSG(m.triangles != NULL, "%s: no triangles kept", what);
  scs_meshcheck_t mc;
  ASSERT_MSG(scs_meshcheck((size_t)n, xyz, m.triangles,
                           (size_t)m.triangle_count, NULL, &mc) == SCS_OK,
             "%s: mesh check", what);
  char why[512] = "", sum[512];
  EXPECT_MSG(scs_meshcheck_expect(&mc, (scs_surface_t)surface,
                                  SCS_EXPECT_OUTWARD, why, sizeof why),
             "%s: %s; %s", what, why,
             scs_meshcheck_summary(&mc, sum, sizeof sum));
  /* What the daemon says about the mesh is what arrived. */
  EXPECT_EQ(sc_client_value_get(m.values, m.value_count, "triangles", -1),
            m.triangle_count);
  EXPECT_EQ(sc_client_value_get(m.values, m.value_count, "points_in", -1), n);
  EXPECT_EQ(sc_client_value_get(m.values, m.value_count, "genus", -1),
            mc.genus_total);
  EXPECT_EQ(m.component_count, mc.components);
  int64_t genus = 0;
  for (uint64_t i = 0; m.genus && i < m.component_count; i++)
    genus += m.genus[i] > 0 ? m.genus[i] : 0;
  EXPECT_EQ(genus, mc.genus_total);
  EXPECT_MSG(m.seconds_total > 0 && m.seconds_upload >= 0 &&
                 m.seconds_upload <= m.seconds_total,
             "%s: times upload %g total %g", what, m.seconds_upload,
             m.seconds_total);
  scs_meshcheck_free(&mc);
}
