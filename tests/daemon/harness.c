/*
 * The daemon harness; see harness.h.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "harness.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "synth.h"

static const char *daemon_path;
/* What scdt_finish() needs of every daemon, copied: tests keep their
 * scdt_daemon_t wherever they like, on the stack too. */
#define SCDT_MAX_DAEMONS 32
static struct record {
  char dir[128];
  char log[160];
  pid_t pid;
} records[SCDT_MAX_DAEMONS];
static int nrecords;

void scdt_setup(int argc, char **argv) {
  signal(SIGPIPE, SIG_IGN);
  if (argc < 2) {
    fprintf(stderr, "usage: %s PATH-TO-SHORTCRUSTD\n", argv[0]);
    exit(2);
  }
  daemon_path = argv[1];
  /* Each test's output in order, even when it goes to a pipe. */
  setvbuf(stdout, NULL, _IOLBF, 0);
}

const char *scdt_daemon_binary(void) { return daemon_path; }

uint64_t scdt_rss(pid_t pid) {
  char path[64], line[256];
  snprintf(path, sizeof path, "/proc/%d/status", (int)pid);
  FILE *f = fopen(path, "r");
  if (!f)
    return 0;
  uint64_t kb = 0;
  while (fgets(line, sizeof line, f))
    if (sscanf(line, "VmRSS: %llu kB", (unsigned long long *)&kb) == 1)
      break;
  fclose(f);
  return kb * 1024;
}

void scdt_sleep_ms(unsigned ms) {
  struct timespec ts = {.tv_sec = ms / 1000, .tv_nsec = (ms % 1000) * 1000000L};
  while (nanosleep(&ts, &ts) != 0 && errno == EINTR)
    ;
}

static void print_log(const char *log) {
  FILE *f = fopen(log, "r");
  if (!f)
    return;
  fprintf(stderr, "---- %s\n", log);
  char line[4096];
  while (fgets(line, sizeof line, f))
    fputs(line, stderr);
  fprintf(stderr, "----\n");
  fclose(f);
}

static void remove_dir(const char *dir) {
  DIR *dh = opendir(dir);
  if (!dh)
    return;
  struct dirent *e;
  char path[512];
  while ((e = readdir(dh)) != NULL) {
    if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0)
      continue;
    snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
    unlink(path);
  }
  closedir(dh);
  rmdir(dir);
}

void scdt_cleanup(int show_logs) {
  for (int i = 0; i < nrecords; i++) {
    struct record *r = &records[i];
    if (r->pid > 0) {
      kill(r->pid, SIGKILL);
      waitpid(r->pid, NULL, 0);
      r->pid = 0;
    }
    if (show_logs || getenv("SCDT_SHOW_LOGS"))
      print_log(r->log);
    remove_dir(r->dir);
  }
  nrecords = 0;
}

int scdt_daemon_prepare(scdt_daemon_t *d) {
  memset(d, 0, sizeof *d);
  d->status = -1;
  d->slot = -1;
  const char *tmp = getenv("TMPDIR");
  /* A socket path must fit in 108 bytes. */
  if (!tmp || !*tmp || strlen(tmp) > 60)
    tmp = "/tmp";
  snprintf(d->dir, sizeof d->dir, "%s/scd-test.XXXXXX", tmp);
  if (!mkdtemp(d->dir)) {
    fprintf(stderr, "mkdtemp %s: %s\n", d->dir, strerror(errno));
    return -1;
  }
  snprintf(d->sock, sizeof d->sock, "%s/d.sock", d->dir);
  snprintf(d->log, sizeof d->log, "%s/daemon.log", d->dir);
  if (nrecords < SCDT_MAX_DAEMONS) {
    d->slot = nrecords++;
    struct record *r = &records[d->slot];
    snprintf(r->dir, sizeof r->dir, "%s", d->dir);
    snprintf(r->log, sizeof r->log, "%s", d->log);
    r->pid = 0;
  }
  return 0;
}

int scdt_daemon_spawn(scdt_daemon_t *d, const char *const *args,
                      int wait_ready) {
  const char *argv[64];
  int n = 0;
  argv[n++] = daemon_path;
  argv[n++] = "--socket";
  argv[n++] = d->sock;
  argv[n++] = "--log-level";
  argv[n++] = "debug";
  for (int i = 0; args && args[i] && n < 63; i++)
    argv[n++] = args[i];
  argv[n] = NULL;
  int logfd = open(d->log, O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (logfd < 0)
    return -1;
  pid_t pid = fork();
  if (pid < 0) {
    close(logfd);
    return -1;
  }
  if (pid == 0) {
    dup2(logfd, STDERR_FILENO);
    int null = open("/dev/null", O_RDWR);
    if (null >= 0) {
      dup2(null, STDIN_FILENO);
      dup2(null, STDOUT_FILENO);
    }
    execv(daemon_path, (char *const *)argv);
    _exit(127);
  }
  close(logfd);
  d->pid = pid;
  d->status = -1;
  if (d->slot >= 0)
    records[d->slot].pid = pid;
  if (!wait_ready)
    return 0;
  /* Sanitizer builds start slowly. */
  uint64_t deadline = scdt_now_ms() + 30000;
  while (scdt_now_ms() < deadline) {
    scdt_conn_t *c;
    if (scdt_connect(d->sock, &c) == 0) {
      /* A connection that goes away at once costs the daemon nothing. */
      scdt_close(c);
      return 0;
    }
    if (scdt_daemon_wait(d, 0) >= 0) {
      fprintf(stderr, "daemon exited with status %d before it was ready\n",
              d->status);
      return -1;
    }
    scdt_sleep_ms(10);
  }
  fprintf(stderr, "daemon not ready after 30 s\n");
  return -1;
}

int scdt_daemon_start(scdt_daemon_t *d, const char *const *args) {
  if (scdt_daemon_prepare(d) != 0)
    return -1;
  return scdt_daemon_spawn(d, args, 1);
}

int scdt_daemon_wait(scdt_daemon_t *d, int timeout_ms) {
  if (d->pid <= 0)
    return d->status;
  uint64_t deadline = scdt_now_ms() + (uint64_t)timeout_ms;
  for (;;) {
    int st;
    pid_t r = waitpid(d->pid, &st, WNOHANG);
    if (r == d->pid) {
      if (d->slot >= 0 && records[d->slot].pid == d->pid)
        records[d->slot].pid = 0;
      d->pid = 0;
      d->status = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
      return d->status;
    }
    if (scdt_now_ms() >= deadline)
      return -1;
    scdt_sleep_ms(5);
  }
}

int scdt_daemon_stop(scdt_daemon_t *d) {
  if (d->pid > 0)
    kill(d->pid, SIGTERM);
  return scdt_daemon_wait(d, 60000);
}

static int log_scan(const scdt_daemon_t *d, const char *text, int count_all) {
  FILE *f = fopen(d->log, "r");
  if (!f)
    return 0;
  char line[8192];
  int n = 0;
  while (fgets(line, sizeof line, f)) {
    if (strstr(line, text)) {
      n++;
      if (!count_all)
        break;
    }
  }
  fclose(f);
  return n;
}

int scdt_log_contains(const scdt_daemon_t *d, const char *text) {
  return log_scan(d, text, 0) > 0;
}

int scdt_log_wait(const scdt_daemon_t *d, const char *text, int timeout_ms) {
  uint64_t deadline = scdt_now_ms() + (uint64_t)timeout_ms;
  while (!scdt_log_contains(d, text)) {
    if (scdt_now_ms() >= deadline)
      return 0;
    scdt_sleep_ms(20);
  }
  return 1;
}

int scdt_log_count(const scdt_daemon_t *d, const char *text) {
  return log_scan(d, text, 1);
}

int scdt_log_tcp_address(const scdt_daemon_t *d, int timeout_ms, char *out,
                         size_t len) {
  out[0] = '\0';
  if (!scdt_log_wait(d, "listening on tcp://", timeout_ms))
    return 0;
  FILE *f = fopen(d->log, "r");
  if (!f)
    return 0;
  char line[512], fmt[32];
  snprintf(fmt, sizeof fmt, "listening on %%%zus", len - 1);
  while (fgets(line, sizeof line, f)) {
    const char *p = strstr(line, "listening on tcp://");
    if (p && sscanf(p, fmt, out) == 1)
      break;
  }
  fclose(f);
  return out[0] != '\0';
}

int scdt_write_file(const char *path, const char *text, mode_t mode) {
  int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0600);
  if (fd < 0)
    return -1;
  const size_t n = strlen(text);
  const int ok = write(fd, text, n) == (ssize_t)n;
  close(fd);
  return ok && chmod(path, mode) == 0 ? 0 : -1;
}

static double *sample(int surface, int density, size_t n, uint64_t seed) {
  double *xyz = malloc(n * 3 * sizeof(double));
  if (!xyz)
    return NULL;
  if (scs_sample_surface((scs_surface_t)surface, density, n, seed, xyz) !=
      SCS_OK) {
    free(xyz);
    return NULL;
  }
  return xyz;
}

double *scdt_sample(int surface, size_t n, uint64_t seed) {
  return sample(surface, SCS_DENSITY_UNIFORM, n, seed);
}

double *scdt_sample_random(int surface, size_t n, uint64_t seed) {
  return sample(surface, SCS_DENSITY_UNIFORM_RANDOM, n, seed);
}

int scdt_mesh_ok(int surface, const scdt_job_t *j, char *why, size_t len) {
  if (!j->done) {
    snprintf(why, len, "job %u did not finish: error %s: %s", j->id,
             scp_wire_name(j->error_code), j->error_msg);
    return 0;
  }
  scs_meshcheck_t mc;
  if (scs_meshcheck(j->n, j->xyz, j->tri, j->ntri, NULL, &mc) != SCS_OK) {
    snprintf(why, len, "job %u: mesh check failed to run", j->id);
    return 0;
  }
  char reason[512];
  int ok = scs_meshcheck_expect(&mc, (scs_surface_t)surface, SCS_EXPECT_OUTWARD,
                                reason, sizeof reason);
  if (!ok) {
    char sum[512];
    snprintf(why, len, "job %u (%s, %llu points): %s; %s", j->id,
             scs_surface_name((scs_surface_t)surface), (unsigned long long)j->n,
             reason, scs_meshcheck_summary(&mc, sum, sizeof sum));
  } else if (j->diag_triangles != j->ntri) {
    snprintf(why, len, "job %u: JOB_DONE diagnostics say %llu triangles, "
             "%llu came",
             j->id, (unsigned long long)j->diag_triangles,
             (unsigned long long)j->ntri);
    ok = 0;
  } else if ((int64_t)mc.genus_total != j->diag_genus) {
    snprintf(why, len, "job %u: diagnostics genus %lld, mesh genus %lld",
             j->id, (long long)j->diag_genus, (long long)mc.genus_total);
    ok = 0;
  }
  scs_meshcheck_free(&mc);
  return ok;
}

int scdt_mesh_closed(const scdt_job_t *j, char *why, size_t len) {
  if (!j->done) {
    snprintf(why, len, "job %u did not finish: error %s: %s", j->id,
             scp_wire_name(j->error_code), j->error_msg);
    return 0;
  }
  scs_meshcheck_t mc;
  if (scs_meshcheck(j->n, j->xyz, j->tri, j->ntri, NULL, &mc) != SCS_OK) {
    snprintf(why, len, "job %u: mesh check failed to run", j->id);
    return 0;
  }
  int ok = mc.closed && mc.oriented;
  if (!ok) {
    char sum[512];
    snprintf(why, len, "job %u: not a closed oriented manifold: %s", j->id,
             scs_meshcheck_summary(&mc, sum, sizeof sum));
  }
  scs_meshcheck_free(&mc);
  return ok;
}

uint64_t scdt_stat_fresh(const char *sock, const char *name) {
  scdt_conn_t *c;
  if (scdt_open(sock, SCP_FRAME_MIN, &c) != 0)
    return UINT64_MAX;
  uint64_t v;
  int rc = scdt_stat(c, name, &v);
  scdt_close(c);
  return rc == 0 ? v : UINT64_MAX;
}

uint64_t scdt_stat_wait(const char *sock, const char *name, uint64_t want,
                        int timeout_ms) {
  uint64_t deadline = scdt_now_ms() + (uint64_t)timeout_ms;
  uint64_t v;
  for (;;) {
    v = scdt_stat_fresh(sock, name);
    if (v == want || scdt_now_ms() >= deadline)
      return v;
    scdt_sleep_ms(20);
  }
}
