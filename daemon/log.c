/*
 * Logging on stderr; see log.h.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "log.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

static int log_level = SCD_LOG_INFO;
static int log_journal;

static const char *const level_names[] = {"error", "warn", "info", "debug"};
/* syslog priorities: LOG_ERR, LOG_WARNING, LOG_INFO, LOG_DEBUG. */
static const int level_prio[] = {3, 4, 6, 7};

/* JOURNAL_STREAM is "device:inode" of the journal's stream; it is inherited
 * by children, so it counts only when it still names our own stderr. */
static int stderr_is_journal(void) {
  const char *js = getenv("JOURNAL_STREAM");
  if (!js)
    return 0;
  unsigned long long dev, ino;
  if (sscanf(js, "%llu:%llu", &dev, &ino) != 2)
    return 0;
  struct stat st;
  if (fstat(STDERR_FILENO, &st) != 0)
    return 0;
  return (unsigned long long)st.st_dev == dev &&
         (unsigned long long)st.st_ino == ino;
}

void scd_log_init(int level) {
  if (level >= SCD_LOG_ERROR && level <= SCD_LOG_DEBUG)
    log_level = level;
  log_journal = stderr_is_journal();
}

int scd_log_level_from_name(const char *name) {
  for (int i = 0; i <= SCD_LOG_DEBUG; i++)
    if (strcmp(name, level_names[i]) == 0)
      return i;
  return -1;
}

const char *scd_log_level_name(int level) {
  if (level < SCD_LOG_ERROR || level > SCD_LOG_DEBUG)
    return "?";
  return level_names[level];
}

int scd_log_enabled(int level) { return level <= log_level; }

void scd_log(int level, const char *fmt, ...) {
  if (level > log_level)
    return;
  if (level < SCD_LOG_ERROR)
    level = SCD_LOG_ERROR;
  int saved_errno = errno;
  char line[2048];
  int n;
  if (log_journal) {
    n = snprintf(line, sizeof line, "<%d>", level_prio[level]);
  } else {
    struct timespec ts;
    struct tm tm;
    clock_gettime(CLOCK_REALTIME, &ts);
    gmtime_r(&ts.tv_sec, &tm);
    n = snprintf(line, sizeof line,
                 "%04d-%02d-%02dT%02d:%02d:%02d.%03ldZ %s: ", tm.tm_year + 1900,
                 tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec,
                 ts.tv_nsec / 1000000, level_names[level]);
  }
  if (n < 0)
    n = 0;
  va_list ap;
  va_start(ap, fmt);
  int m = vsnprintf(line + n, sizeof line - (size_t)n - 1, fmt, ap);
  va_end(ap);
  size_t len = (size_t)n;
  if (m > 0)
    len += (size_t)m < sizeof line - len - 1 ? (size_t)m : sizeof line - len - 2;
  line[len++] = '\n';
  /* One write per line; a short write to a pipe this small does not happen,
   * and a logging failure must not take the daemon down. */
  ssize_t w = write(STDERR_FILENO, line, len);
  (void)w;
  errno = saved_errno;
}
