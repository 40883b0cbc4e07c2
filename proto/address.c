/*
 * Addresses of daemons: "unix://PATH" or a plain path, and
 * "tcp://HOST:PORT" (scproto.h), and sizes in bytes, as the command lines
 * give them. Only text: resolving a host and connecting are the caller's.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "scproto.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int parse_port(const char *s, uint16_t *out) {
  if (!*s || strlen(s) > 5)
    return SCP_ERANGE;
  unsigned long v = 0;
  for (const char *p = s; *p; p++) {
    if (*p < '0' || *p > '9')
      return SCP_ERANGE;
    v = v * 10 + (unsigned long)(*p - '0');
  }
  if (v > 65535)
    return SCP_ERANGE;
  *out = (uint16_t)v;
  return 0;
}

/* A host name or address literal: no room for anything that would make
 * it mean more than one host (spaces, a path, user information). */
static int host_ok(const char *h, size_t n) {
  if (n == 0 || n > SCP_ADDR_HOST_MAX)
    return 0;
  for (size_t i = 0; i < n; i++) {
    unsigned char ch = (unsigned char)h[i];
    if (ch <= ' ' || ch >= 0x7f || ch == '/' || ch == '@' || ch == '[' ||
        ch == ']')
      return 0;
  }
  return 1;
}

static int parse_tcp(const char *s, scp_address_t *out) {
  const char *host = s, *colon;
  size_t n;
  if (*s == '[') {
    const char *close = strchr(s, ']');
    if (!close || close[1] != ':')
      return SCP_ERANGE;
    host = s + 1;
    n = (size_t)(close - host);
    colon = close + 1;
    /* Brackets are for IPv6 literals only, which have colons. */
    if (!memchr(host, ':', n))
      return SCP_ERANGE;
  } else {
    colon = strrchr(s, ':');
    if (!colon)
      return SCP_ERANGE;
    n = (size_t)(colon - s);
    /* An IPv6 literal must be in brackets, or its port is ambiguous. */
    if (memchr(s, ':', n))
      return SCP_ERANGE;
  }
  if (!host_ok(host, n) || parse_port(colon + 1, &out->port) != 0)
    return SCP_ERANGE;
  out->kind = SCP_ADDR_TCP;
  memcpy(out->host, host, n);
  out->host[n] = '\0';
  return 0;
}

int scp_address_parse(const char *text, scp_address_t *out) {
  if (!text || !out)
    return SCP_EINVAL;
  memset(out, 0, sizeof *out);
  const char *path = text;
  const char *sep = strstr(text, "://");
  if (sep) {
    if (strncmp(text, "tcp://", 6) == 0)
      return parse_tcp(text + 6, out);
    if (strncmp(text, "unix://", 7) != 0)
      return SCP_ERANGE;
    path = text + 7;
  }
  size_t n = strlen(path);
  if (n == 0 || n >= SCP_ADDR_PATH_MAX)
    return SCP_ERANGE;
  out->kind = SCP_ADDR_UNIX;
  memcpy(out->path, path, n + 1);
  return 0;
}

char *scp_address_format(const scp_address_t *a, char *buf, size_t len) {
  if (!buf || len == 0)
    return buf;
  int rc;
  if (a->kind == SCP_ADDR_TCP)
    rc = strchr(a->host, ':')
             ? snprintf(buf, len, "tcp://[%s]:%u", a->host, (unsigned)a->port)
             : snprintf(buf, len, "tcp://%s:%u", a->host, (unsigned)a->port);
  else
    rc = snprintf(buf, len, "unix://%s", a->path);
  if (rc < 0)
    buf[0] = '\0';
  return buf;
}

int scp_bytes_parse(const char *text, uint64_t *out) {
  if (!text || !out)
    return SCP_EINVAL;
  if (text[0] < '0' || text[0] > '9')
    return SCP_ERANGE;
  char *end;
  errno = 0;
  unsigned long long v = strtoull(text, &end, 10);
  if (errno)
    return SCP_ERANGE;
  /* A fraction, with a unit only ("1.5G"): its digits, read by hand so
   * that the locale's decimal point does not matter. */
  const char *frac = NULL;
  size_t frac_digits = 0;
  if (*end == '.') {
    frac = end + 1;
    while (frac[frac_digits] >= '0' && frac[frac_digits] <= '9')
      ++frac_digits;
    if (frac_digits == 0)
      return SCP_ERANGE;
    end = (char *)frac + frac_digits;
  }
  unsigned shift = 0;
  switch (*end) {
  case '\0':
    break;
  case 'k':
  case 'K':
    shift = 10;
    break;
  case 'M':
    shift = 20;
    break;
  case 'G':
    shift = 30;
    break;
  case 'T':
    shift = 40;
    break;
  default:
    return SCP_ERANGE;
  }
  if (*end && end[1] != '\0' && strcmp(end + 1, "iB") != 0 &&
      strcmp(end + 1, "B") != 0)
    return SCP_ERANGE;
  if (frac && shift == 0)
    return SCP_ERANGE; /* no fraction of a byte */
  if (shift && v > (UINT64_MAX >> shift))
    return SCP_ERANGE;
  uint64_t bytes = (uint64_t)v << shift;
  if (frac) {
    /* The fraction of the unit, to the byte, rounded up: 2^shift times
     * the digits over 10^digits (the first 6 digits: a millionth of a
     * unit). */
    uint64_t num = 0, den = 1;
    for (size_t i = 0; i < frac_digits && i < 6; ++i) {
      num = 10 * num + (uint64_t)(frac[i] - '0');
      den *= 10;
    }
    const uint64_t unit = (uint64_t)1 << shift;
    /* num < den <= 10^6 and unit <= 2^40: each product fits in 64
     * bits. */
    const uint64_t part = unit / den * num + (unit % den * num + den - 1) / den;
    if (bytes > UINT64_MAX - part)
      return SCP_ERANGE;
    bytes += part;
  }
  if (bytes == 0)
    return SCP_ERANGE;
  *out = bytes;
  return 0;
}
