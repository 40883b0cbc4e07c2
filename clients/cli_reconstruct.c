/*
 * `shortcrust reconstruct`: read a point file, reconstruct here, write the
 * mesh.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "cli_commands.h"
#include "shortcrust_files.h"

static void usage(FILE *f) {
  fputs(
      "usage: shortcrust reconstruct IN -o OUT [options]\n\n"
      "Reconstructs a triangle mesh from the points of IN and writes it to\n"
      "OUT. IN may be .ply (ascii or binary), .xyz/.txt/.pts/.csv, .off,\n"
      ".obj (a mesh file gives its vertices) or .las (LAS 1.0 to 1.4; for\n"
      ".laz, decompress first: laszip -i in.laz -o out.las); a PLY input's\n"
      "other vertex properties (colours, normals, ...) go unchanged onto the\n"
      "mesh's vertices in PLY, colours in OBJ. OUT's extension picks the\n"
      "format: .ply (binary unless --ascii), .off, .obj or .stl. Every input\n"
      "point is written, in input order, so triangle indices refer to IN.\n"
      "IN may be - for standard input (PLY, told by its first line, or else\n"
      "the points of a text file) and OUT - for standard output (PLY; the\n"
      "summary then goes to stderr).\n\n"
      "options:\n",
      f);
  sc_cli_job_usage_params(f, 1);
  sc_cli_job_usage_output(f);
  fputs("Progress goes to stderr when it is a terminal; the summary goes to\n"
        "stdout (stderr with -o -). Exit status: 0 done, 1 failed (the message "
        "says why), 2 bad\n"
        "command line. A mesh that is empty or leaves most samples in no\n"
        "triangle is written with status 0 and a warning line on stderr.\n",
        f);
}

static const struct option own_options[] = {
    {"help", no_argument, NULL, 'h'},
    {NULL, 0, NULL, 0},
};

int sc_cmd_reconstruct(int argc, char **argv) {
  sc_cli_job_opts_t o;
  sc_cli_job_init(&o);
  sc_params_t *params = &o.params;
  sc_cli_getopt_t g;
  if (sc_cli_job_getopt(&g, 1, own_options, "h") < 0) {
    sc_cli_error("reconstruct: too many options");
    return SC_EXIT_FAILURE;
  }

  opterr = 0;
  int c;
  while ((c = getopt_long(argc, argv, g.short_options, g.long_options,
                          NULL)) != -1) {
    int shared = sc_cli_job_option(&o, c, optarg);
    if (shared < 0)
      return SC_EXIT_USAGE;
    if (shared > 0)
      continue;
    switch (c) {
    case 'h':
      usage(stdout);
      return SC_EXIT_OK;
    default:
      return sc_cli_bad_option("reconstruct", c, argv);
    }
  }
  if (sc_cli_job_files("reconstruct", &o, argc, argv) < 0)
    return SC_EXIT_USAGE;
  const char *in_path = o.in_path, *out_path = o.out_path;

  sc_cli_progress_t progress;
  scf_mesh_format_t fmt;
  scf_points_t pts;
  scf_attrs_t attrs;
  double t_read;
  /* A hint, before the first large allocation; see shortcrust.h. */
  (void)sc_tune_allocator();
  int status = sc_cli_job_read(&o, &progress, &fmt, &pts, &attrs, &t_read);
  if (status != SC_EXIT_OK)
    return status;
  params->progress = sc_cli_progress_fn;
  params->progress_user = &progress;

  char msg[1024];
  sc_mesh_t *mesh = NULL;
  int rc = sc_reconstruct(pts.xyz, pts.count, params, &mesh, msg, sizeof msg);
  if (rc < 0) {
    sc_cli_progress_done(&progress);
    scf_points_free(&pts);
    scf_attrs_free(&attrs);
    /* A parameter out of range is the command line's fault, not the file's. */
    if (rc == SC_EINVALID_ARGUMENT) {
      sc_cli_error("reconstruct: %s", msg);
      return SC_EXIT_USAGE;
    }
    sc_cli_error("%s: %s", in_path, msg);
    return SC_EXIT_FAILURE;
  }

  sc_cli_result_t res = {
      .command = "reconstruct",
      .input = in_path,
      .output = out_path,
      .params = *params,
      .diag = &mesh->diag,
      .component_genus = mesh->component_genus,
      .component_count = mesh->component_count,
      .seconds_read = t_read,
  };
  /* --smoothed-vertices: the mesh over the smoothed positions. */
  if (mesh->smoothed)
    memcpy(pts.xyz, mesh->smoothed, 3 * pts.count * sizeof *pts.xyz);
  status = sc_cli_job_write(&o, &progress, fmt, &pts, &attrs, mesh->triangles,
                            mesh->triangle_count, mesh->normals, &res);
  sc_mesh_free(mesh);
  scf_points_free(&pts);
  scf_attrs_free(&attrs);
  return status;
}
