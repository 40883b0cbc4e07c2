/*
 * The listening socket: its mode, the default path, a stale socket file
 * left by a dead daemon, a second daemon on the same path, a path that is
 * not a socket, systemd socket activation, and the command line.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include "daemontest.h"
#include "synth.h"

#define T_MS 120000

static double *sphere; /* 2000 points */

static void check_job(const char *sock, const char *when) {
  scdt_conn_t *c;
  int rc = scdt_open(sock, 1u << 20, &c);
  EXPECT_MSG(rc == 0, "%s: cannot connect to %s: %d", when, sock, rc);
  if (rc != 0)
    return;
  scdt_job_t j;
  scdt_job_init(&j, 1, sphere, 2000);
  scdt_job_t *pj = &j;
  char why[512] = "";
  EXPECT_MSG(scdt_job_send(c, &j) == 0, "%s: send", when);
  EXPECT_MSG(scdt_collect(c, &pj, 1, T_MS, why, sizeof why) == 0, "%s: %s",
             when, why);
  EXPECT_MSG(scdt_mesh_ok(SCS_SURF_SPHERE, &j, why, sizeof why), "%s: %s", when,
             why);
  scdt_job_reset(&j);
  scdt_close(c);
}

/* A socket bound at path; listening or not. */
static int bound_socket(const char *path, int listening) {
  struct sockaddr_un sa;
  memset(&sa, 0, sizeof sa);
  sa.sun_family = AF_UNIX;
  snprintf(sa.sun_path, sizeof sa.sun_path, "%s", path);
  int fd = socket(AF_UNIX, SOCK_STREAM, 0);
  if (fd < 0 || bind(fd, (struct sockaddr *)&sa, sizeof sa) != 0)
    return -1;
  if (listening && listen(fd, 8) != 0)
    return -1;
  return fd;
}

static unsigned mode_of(const char *path) {
  struct stat st;
  return lstat(path, &st) == 0 ? (unsigned)(st.st_mode & 0777) : 0;
}

/* Runs the daemon with exactly these arguments and environment additions
 * (NAME=VALUE, NULL-terminated), optionally handing it fd as systemd would.
 * Returns the pid; stderr goes to log. */
static pid_t spawn(const char *const *args, const char *const *env, int fd,
                   const char *log) {
  const char *argv[32];
  int n = 0;
  argv[n++] = scdt_daemon_binary();
  for (int i = 0; args && args[i]; i++)
    argv[n++] = args[i];
  argv[n] = NULL;
  int logfd = open(log, O_WRONLY | O_CREAT | O_APPEND, 0644);
  pid_t pid = fork();
  if (pid == 0) {
    dup2(logfd, STDERR_FILENO);
    int null = open("/dev/null", O_WRONLY);
    if (null >= 0)
      dup2(null, STDOUT_FILENO);
    for (int i = 0; env && env[i]; i++) {
      char name[64];
      const char *eq = strchr(env[i], '=');
      snprintf(name, sizeof name, "%.*s", (int)(eq - env[i]), env[i]);
      setenv(name, eq + 1, 1);
    }
    if (fd >= 0) {
      if (fd != 3) {
        dup2(fd, 3);
        close(fd);
      }
      char pidbuf[32];
      snprintf(pidbuf, sizeof pidbuf, "%d", (int)getpid());
      setenv("LISTEN_PID", pidbuf, 1);
      setenv("LISTEN_FDS", "1", 1);
    }
    execv(argv[0], (char *const *)argv);
    _exit(127);
  }
  close(logfd);
  return pid;
}

static int wait_exit(pid_t pid, int timeout_ms) {
  uint64_t deadline = scdt_now_ms() + (uint64_t)timeout_ms;
  for (;;) {
    int st;
    if (waitpid(pid, &st, WNOHANG) == pid)
      return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
    if (scdt_now_ms() >= deadline) {
      kill(pid, SIGKILL);
      waitpid(pid, NULL, 0);
      return -1;
    }
    scdt_sleep_ms(5);
  }
}

static int wait_ready(const char *sock) {
  uint64_t deadline = scdt_now_ms() + 30000;
  while (scdt_now_ms() < deadline) {
    scdt_conn_t *c;
    if (scdt_connect(sock, &c) == 0) {
      scdt_close(c);
      return 0;
    }
    scdt_sleep_ms(10);
  }
  return -1;
}

static void stale_and_second(void) {
  scdt_daemon_t d;
  ASSERT_MSG(scdt_daemon_prepare(&d) == 0, "prepare");
  /* A dead daemon's socket: bound, then the process is gone. */
  int fd = bound_socket(d.sock, 1);
  ASSERT_MSG(fd >= 0, "bind %s: %s", d.sock, strerror(errno));
  close(fd);
  ASSERT_MSG(scdt_daemon_spawn(&d, NULL, 1) == 0, "daemon did not start");
  EXPECT_MSG(scdt_log_contains(&d, "removing stale socket"), "no log line");
  EXPECT_MSG(mode_of(d.sock) == 0660, "mode %o, want 0660", mode_of(d.sock));
  check_job(d.sock, "after replacing a stale socket");

  /* A second daemon on the same path refuses to start. */
  scdt_daemon_t second = d;
  second.pid = 0;
  snprintf(second.log, sizeof second.log, "%s/second.log", d.dir);
  ASSERT_MSG(scdt_daemon_spawn(&second, NULL, 0) == 0, "spawn");
  int st = scdt_daemon_wait(&second, T_MS);
  EXPECT_MSG(st != 0 && st > 0, "second daemon exited with %d", st);
  EXPECT_MSG(scdt_log_contains(&second, "refusing to start"),
             "second daemon gave no clear message");
  /* The first one is untouched. */
  check_job(d.sock, "after a second daemon tried");
  EXPECT_EQ(scdt_daemon_stop(&d), 0);
}

static void not_a_socket_and_foreign(void) {
  scdt_daemon_t d;
  ASSERT_MSG(scdt_daemon_prepare(&d) == 0, "prepare");
  int f = open(d.sock, O_WRONLY | O_CREAT, 0644);
  close(f);
  ASSERT_MSG(scdt_daemon_spawn(&d, NULL, 0) == 0, "spawn");
  EXPECT_MSG(scdt_daemon_wait(&d, T_MS) > 0, "started over a regular file");
  EXPECT_MSG(scdt_log_contains(&d, "is not a socket"), "no clear message");
  unlink(d.sock);

  /* Something alive listens there, and holds no lock of ours. */
  int fd = bound_socket(d.sock, 1);
  ASSERT_MSG(fd >= 0, "bind");
  ASSERT_MSG(scdt_daemon_spawn(&d, NULL, 0) == 0, "spawn");
  EXPECT_MSG(scdt_daemon_wait(&d, T_MS) > 0, "started over a live socket");
  EXPECT_MSG(scdt_log_contains(&d, "another daemon is listening"),
             "no clear message");
  EXPECT_MSG(mode_of(d.sock) != 0, "the live socket was removed");
  close(fd);
  unlink(d.sock);
}

static void modes_and_defaults(void) {
  scdt_daemon_t d;
  ASSERT_MSG(scdt_daemon_prepare(&d) == 0, "prepare");
  /* --socket-mode, and the default path under XDG_RUNTIME_DIR. */
  char env[200], sock[200];
  snprintf(env, sizeof env, "XDG_RUNTIME_DIR=%s", d.dir);
  snprintf(sock, sizeof sock, "%s/shortcrust.sock", d.dir);
  const char *args[] = {"--socket-mode", "0600", NULL};
  const char *envs[] = {env, NULL};
  pid_t pid = spawn(args, envs, -1, d.log);
  EXPECT_MSG(wait_ready(sock) == 0, "no socket at %s", sock);
  EXPECT_MSG(mode_of(sock) == 0600, "mode %o, want 0600", mode_of(sock));
  check_job(sock, "default path");
  kill(pid, SIGTERM);
  EXPECT_EQ(wait_exit(pid, T_MS), 0);
  EXPECT_MSG(mode_of(sock) == 0, "socket left behind");

  /* The command line. */
  const char *help[] = {"--help", NULL};
  pid = spawn(help, NULL, -1, d.log);
  EXPECT_EQ(wait_exit(pid, T_MS), 0);
  const char *bad[] = {"--workers", "0", NULL};
  pid = spawn(bad, NULL, -1, d.log);
  EXPECT_EQ(wait_exit(pid, T_MS), 2);
  EXPECT_MSG(scdt_log_contains(&d, "invalid --workers"), "no message");
  const char *unknown[] = {"--frobnicate", NULL};
  pid = spawn(unknown, NULL, -1, d.log);
  EXPECT_EQ(wait_exit(pid, T_MS), 2);
}

static void socket_activation(void) {
  scdt_daemon_t d;
  ASSERT_MSG(scdt_daemon_prepare(&d) == 0, "prepare");
  int fd = bound_socket(d.sock, 1);
  ASSERT_MSG(fd >= 0, "bind");
  /* --socket names another path, which must be ignored. */
  char other[200];
  snprintf(other, sizeof other, "%s/other.sock", d.dir);
  const char *args[] = {"--socket", other, NULL};
  pid_t pid = spawn(args, NULL, fd, d.log);
  close(fd);
  check_job(d.sock, "socket activation");
  EXPECT_MSG(mode_of(other) == 0, "bound --socket under socket activation");
  kill(pid, SIGTERM);
  EXPECT_EQ(wait_exit(pid, T_MS), 0);
  /* The socket is systemd's: it stays. */
  EXPECT_MSG(mode_of(d.sock) != 0, "removed the socket systemd owns");
  EXPECT_MSG(scdt_log_contains(&d, "using the socket systemd passed"),
             "no log line");
  unlink(d.sock);
}

int main(int argc, char **argv) {
  scdt_init(argc, argv);
  sphere = scdt_sample(SCS_SURF_SPHERE, 2000, 5);
  stale_and_second();
  not_a_socket_and_foreign();
  modes_and_defaults();
  socket_activation();
  free(sphere);
  return scdt_finish();
}
