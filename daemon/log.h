/*
 * Logging for shortcrustd: one line per event on stderr, with a level.
 *
 * Under systemd (stderr is the journal stream named by JOURNAL_STREAM) each
 * line starts with the sd-daemon priority prefix ("<6>") and no timestamp,
 * since the journal keeps both; otherwise a line reads
 * "2026-11-23T10:00:00.123Z info: ...". Every line is one write(2), so
 * lines from different threads never interleave.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef SCD_LOG_H
#define SCD_LOG_H

typedef enum scd_log_level {
  SCD_LOG_ERROR = 0,
  SCD_LOG_WARN = 1,
  SCD_LOG_INFO = 2,
  SCD_LOG_DEBUG = 3
} scd_log_level_t;

/* Sets the level and picks the line format. Call once, before any thread
 * starts; the level is read-only afterwards. */
void scd_log_init(int level);
/* "error", "warn", "info", "debug"; -1 for other names. */
int scd_log_level_from_name(const char *name);
const char *scd_log_level_name(int level);
/* 1 when lines of this level are written. */
int scd_log_enabled(int level);

void scd_log(int level, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

#define scd_error(...) scd_log(SCD_LOG_ERROR, __VA_ARGS__)
#define scd_warn(...) scd_log(SCD_LOG_WARN, __VA_ARGS__)
#define scd_info(...) scd_log(SCD_LOG_INFO, __VA_ARGS__)
#define scd_debug(...) scd_log(SCD_LOG_DEBUG, __VA_ARGS__)

#endif /* SCD_LOG_H */
