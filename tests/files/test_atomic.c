/*
 * Atomic writes: a target is replaced whole or not at all. A write that
 * fails part-way (the file size limit stops it) or at the rename (the
 * target is a directory) leaves an existing file as it was, with its mode,
 * and no temporary file behind. A replaced file keeps its mode; a new one
 * gets 0666 less the umask.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "tmpdir.h"
#include "shortcrust_files.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>

enum { N = 5000, NT = 4000 };
static double xyz[3 * N];
static uint32_t tri[3 * NT];

static const scf_mesh_format_t formats[] = {
    SCF_MESH_FMT_PLY_BINARY, SCF_MESH_FMT_PLY_ASCII,  SCF_MESH_FMT_OFF,
    SCF_MESH_FMT_OBJ,        SCF_MESH_FMT_STL_BINARY, SCF_MESH_FMT_STL_ASCII};

static void make_mesh(void) {
  for (int i = 0; i < 3 * N; i++)
    xyz[i] = (double)i / 7.0;
  for (int t = 0; t < NT; t++)
    for (int c = 0; c < 3; c++)
      tri[3 * t + c] = (uint32_t)((t + c) % N);
}

static mode_t mode_of(const char *path) {
  struct stat st;
  if (stat(path, &st) != 0)
    ASSERT_FAIL("cannot stat %s", path);
  return st.st_mode & 07777;
}

static int temporaries(void) { return count_entries(tmp_path(""), ".tmp."); }

/* Limits every file this process writes to limit bytes (the soft limit
 * only, so it can be lifted again); writes past it fail with EFBIG. */
static void limit_file_size(rlim_t limit) {
  struct rlimit rl;
  ASSERT(getrlimit(RLIMIT_FSIZE, &rl) == 0);
  rl.rlim_cur = limit;
  ASSERT(setrlimit(RLIMIT_FSIZE, &rl) == 0);
}

static void unlimit_file_size(void) {
  struct rlimit rl;
  ASSERT(getrlimit(RLIMIT_FSIZE, &rl) == 0);
  rl.rlim_cur = rl.rlim_max;
  ASSERT(setrlimit(RLIMIT_FSIZE, &rl) == 0);
}

/* A new file gets 0666 less the umask; a replaced one keeps its mode. */
static void test_modes(void) {
  char msg[256];
  mode_t old = umask(027);
  const char *path = tmp_path("new.ply");
  ASSERT_EQ(scf_mesh_write(path, SCF_MESH_FMT_AUTO, xyz, N, tri, NT, NULL, msg,
                             sizeof msg),
               0);
  ASSERT_EQ(mode_of(path), 0640);
  umask(022);
  ASSERT_EQ(
      scf_write_atomic(tmp_path("new.txt"), "x", 1, msg, sizeof msg), 0);
  ASSERT_EQ(mode_of(tmp_path("new.txt")), 0644);

  /* Replacing keeps an unusual mode, whatever the umask says. */
  ASSERT(chmod(path, 0604) == 0);
  ASSERT_EQ(scf_mesh_write(path, SCF_MESH_FMT_OFF, xyz, 3, tri, 1, NULL, msg,
                             sizeof msg),
               0);
  ASSERT_EQ(mode_of(path), 0604);
  char *s = read_all(path, NULL);
  ASSERT(strncmp(s, "OFF\n3 1 0\n", 10) == 0);
  free(s);
  umask(old);
  ASSERT_EQ(temporaries(), 0);
}

/*
 * The file is replaced, not rewritten: a reader that opened the old file
 * before still reads the old contents to the end, and the target is a new
 * inode.
 */
static void test_replace(void) {
  char msg[256];
  const char *path = tmp_path("replace.txt");
  ASSERT_EQ(
      scf_write_atomic(path, "first version\n", 14, msg, sizeof msg), 0);
  int fd = open(path, O_RDONLY);
  ASSERT(fd >= 0);
  struct stat before, after;
  ASSERT(fstat(fd, &before) == 0);
  ASSERT_EQ(scf_write_atomic(path, "second\n", 7, msg, sizeof msg), 0);
  ASSERT(stat(path, &after) == 0);
  ASSERT(before.st_ino != after.st_ino);
  char buf[32] = {0};
  ASSERT_EQ(read(fd, buf, sizeof buf - 1), 14);
  ASSERT_STR_EQ(buf, "first version\n");
  close(fd);
  char *s = read_all(path, NULL);
  ASSERT_STR_EQ(s, "second\n");
  free(s);

  /* Empty data gives an empty file; data NULL with a length is refused. */
  ASSERT_EQ(scf_write_atomic(path, NULL, 0, msg, sizeof msg), 0);
  ASSERT_EQ(after.st_size, 7);
  ASSERT(stat(path, &after) == 0);
  ASSERT_EQ(after.st_size, 0);
  ASSERT_EQ(scf_write_atomic(path, NULL, 1, msg, sizeof msg),
               SCF_EINVAL);
  ASSERT_EQ(scf_write_atomic(NULL, "x", 1, msg, sizeof msg),
               SCF_EINVAL);
  ASSERT_EQ(temporaries(), 0);

  /* A name near the file system's limit still gets a temporary file. */
  char name[256];
  memset(name, 'n', 250);
  memcpy(name + 250, ".obj", 5);
  path = tmp_path(name);
  ASSERT_EQ(scf_mesh_write(path, SCF_MESH_FMT_AUTO, xyz, 3, tri, 1, NULL, msg,
                             sizeof msg),
               0);
  s = read_all(path, NULL);
  ASSERT(strncmp(s, "# written by shortcrust\nv 0 ", 28) == 0);
  free(s);
  ASSERT_EQ(temporaries(), 0);
}

/*
 * Writes that fail part-way: with a file size limit far below the mesh's
 * size, each format runs out while writing. The old file must survive
 * byte for byte, with its mode.
 */
static void test_failed_write(void) {
  static const char old_text[] = "the previous contents\n";
  /* Past the limit a write fails with EFBIG, instead of the signal. */
  signal(SIGXFSZ, SIG_IGN);
  for (size_t f = 0; f < sizeof formats / sizeof formats[0]; f++) {
    char name[32], msg[256];
    snprintf(name, sizeof name, "fail%zu.mesh", f);
    const char *path = tmp_path(name);
    write_text(path, old_text);
    ASSERT(chmod(path, 0640) == 0);
    struct stat before, after;
    ASSERT(stat(path, &before) == 0);
    limit_file_size(4096);
    int rc =
        scf_mesh_write(path, formats[f], xyz, N, tri, NT, NULL, msg, sizeof msg);
    unlimit_file_size();
    ASSERT_EQ(rc, SCF_EIO);
    ASSERT_STR_CONTAINS(msg, path);
    ASSERT_STR_CONTAINS(msg, "failed");
    char *s = read_all(path, NULL);
    ASSERT_STR_EQ(s, old_text);
    free(s);
    ASSERT(stat(path, &after) == 0);
    ASSERT(before.st_ino == after.st_ino);
    ASSERT_EQ(mode_of(path), 0640);
    ASSERT_EQ(temporaries(), 0);
  }

  /* The same for plain data, and for a target that did not exist. */
  size_t len = 100000;
  char *data = malloc(len);
  ASSERT(data != NULL);
  memset(data, 'd', len);
  const char *path = tmp_path("fail.txt");
  write_text(path, old_text);
  char msg[256];
  limit_file_size(4096);
  int rc = scf_write_atomic(path, data, len, msg, sizeof msg);
  int rc_new =
      scf_write_atomic(tmp_path("never.txt"), data, len, msg, sizeof msg);
  unlimit_file_size();
  free(data);
  ASSERT_EQ(rc, SCF_EIO);
  ASSERT_EQ(rc_new, SCF_EIO);
  char *s = read_all(path, NULL);
  ASSERT_STR_EQ(s, old_text);
  free(s);
  ASSERT_EQ(count_entries(tmp_path(""), "never"), 0);
  ASSERT_EQ(temporaries(), 0);
  signal(SIGXFSZ, SIG_DFL);
}

/* Failures at the rename and at the creation of the temporary file. */
static void test_failed_rename(void) {
  char msg[256];
  /* A directory in the way: everything is written, the rename fails. */
  const char *dir = tmp_path("taken.ply");
  ASSERT(mkdir(dir, 0700) == 0);
  ASSERT(mkdir(tmp_path("taken.ply/inside"), 0700) == 0);
  ASSERT_EQ(scf_mesh_write(dir, SCF_MESH_FMT_AUTO, xyz, N, tri, NT, NULL, msg,
                             sizeof msg),
               SCF_EIO);
  ASSERT_STR_CONTAINS(msg, dir);
  ASSERT_STR_CONTAINS(msg, "rename");
  struct stat st;
  ASSERT(stat(tmp_path("taken.ply/inside"), &st) == 0 && S_ISDIR(st.st_mode));
  ASSERT_EQ(temporaries(), 0);

  /* No directory to put it in. */
  const char *path = tmp_path("nowhere/out.ply");
  ASSERT_EQ(scf_mesh_write(path, SCF_MESH_FMT_AUTO, xyz, 3, tri, 1, NULL, msg,
                             sizeof msg),
               SCF_EIO);
  ASSERT_STR_CONTAINS(msg, "cannot create a temporary file");
  ASSERT(stat(tmp_path("nowhere"), &st) != 0);
  ASSERT_EQ(scf_write_atomic(path, "x", 1, msg, sizeof msg),
               SCF_EIO);
  ASSERT_EQ(temporaries(), 0);
}

int main(void) {
  tmp_init();
  make_mesh();
  test_modes();
  test_replace();
  test_failed_write();
  test_failed_rename();
  return sct_finish("files_atomic");
}
