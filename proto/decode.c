/*
 * The incremental decoder: bytes in, whole frames out.
 *
 * The decoder keeps one buffer of unread bytes. feed() only appends to it;
 * next() looks at the header at the front, checks it, and hands out the
 * frame once all of its bytes are in. The header is checked lazily, in
 * next(), rather than when its bytes are fed, because the frame size limit
 * changes between frames: a client that reads WELCOME and the first
 * TRIANGLES in one read must raise the limit after WELCOME and before the
 * TRIANGLES header is judged.
 *
 * Nothing is ever allocated on the strength of a length field: the buffer
 * grows only with the bytes the caller feeds, and a header whose length is
 * over the limit is refused as soon as its eight bytes are in. Ignorable
 * frames that are not for this reader are discarded as their bytes arrive
 * and never buffered whole.
 *
 * Copyright (C) 2026 the shortcrust authors.
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include <stdlib.h>
#include <string.h>

#include "scproto.h"
#include "wire.h"

/* An idle decoder whose buffer grew beyond this gives the memory back, so
 * that a connection that once received a large frame does not keep its
 * peak forever. */
#define DECODER_KEEP (64 * 1024)

struct scp_decoder {
  uint8_t *buf;
  size_t cap;
  /* Unread bytes are buf[start, end). */
  size_t start;
  size_t end;
  /* Size of the frame that next() returned last; its bytes stay at the
   * front until the next call, so that frame.payload remains valid. */
  size_t held;
  /* Bytes of an ignorable frame still to be thrown away as they arrive. */
  uint64_t skip;
  uint32_t max_frame;
  int role;
  /* Set once HELLO (server role) or WELCOME (client role) was returned. */
  int handshake_done;
  int err;
  scp_decoder_counters_t counters;
};

void scp_limits_init(scp_limits_t *l) {
  l->max_frame = SCP_FRAME_MIN;
  l->role = SCP_ROLE_ANY;
}

scp_decoder_t *scp_decoder_new(const scp_limits_t *limits) {
  scp_limits_t def;
  if (!limits) {
    scp_limits_init(&def);
    limits = &def;
  }
  if (limits->max_frame < SCP_FRAME_MIN ||
      limits->max_frame > SCP_FRAME_CEILING)
    return NULL;
  if (limits->role != SCP_ROLE_ANY && limits->role != SCP_ROLE_SERVER &&
      limits->role != SCP_ROLE_CLIENT)
    return NULL;
  scp_decoder_t *d = calloc(1, sizeof *d);
  if (!d)
    return NULL;
  d->max_frame = limits->max_frame;
  d->role = limits->role;
  return d;
}

void scp_decoder_free(scp_decoder_t *d) {
  if (!d)
    return;
  free(d->buf);
  free(d);
}

/* Drops the frame handed out last: the caller is done with it. */
static void release_held(scp_decoder_t *d) {
  d->start += d->held;
  d->held = 0;
  if (d->start == d->end)
    d->start = d->end = 0;
}

/* Throws away bytes of an ignorable frame that are already buffered. */
static void discard_skipped(scp_decoder_t *d) {
  size_t avail = d->end - d->start;
  size_t n = d->skip < avail ? (size_t)d->skip : avail;
  d->start += n;
  d->skip -= n;
  if (d->start == d->end)
    d->start = d->end = 0;
}

static int fail(scp_decoder_t *d, int code) {
  d->err = code;
  return code;
}

int scp_decoder_feed(scp_decoder_t *d, const void *bytes, size_t len) {
  if (d->err)
    return d->err;
  if (len == 0)
    return 0;
  if (!bytes)
    return SCP_EINVAL;
  release_held(d);
  d->counters.bytes += len;
  /* Bytes of a frame being skipped never reach the buffer. */
  if (d->skip) {
    size_t n = d->skip < len ? (size_t)d->skip : len;
    d->skip -= n;
    bytes = (const uint8_t *)bytes + n;
    len -= n;
    if (len == 0)
      return 0;
  }
  if (d->start == d->end && d->cap > DECODER_KEEP && len < d->cap / 4) {
    free(d->buf);
    d->buf = NULL;
    d->cap = 0;
  }
  size_t unread = d->end - d->start;
  if (d->cap - d->end < len) {
    if (d->start > 0) {
      memmove(d->buf, d->buf + d->start, unread);
      d->start = 0;
      d->end = unread;
    }
    if (d->cap - d->end < len) {
      if (len > SIZE_MAX - unread)
        return fail(d, SCP_ENOMEM);
      size_t need = unread + len;
      size_t cap = d->cap ? d->cap : SCP_FRAME_MIN;
      while (cap < need)
        cap = cap > SIZE_MAX / 2 ? need : cap * 2;
      uint8_t *p = realloc(d->buf, cap);
      if (!p)
        return fail(d, SCP_ENOMEM);
      d->buf = p;
      d->cap = cap;
    }
  }
  memcpy(d->buf + d->end, bytes, len);
  d->end += len;
  return 0;
}

/* Is this an ignorable frame to drop unread? PROTOCOL.md 3.2 treats a type
 * that travels the wrong way like an unknown one, so a server skips
 * VERTICES just as it skips a type it has never heard of. */
static int skipped_type(const scp_decoder_t *d, uint16_t type) {
  if (!(type & SCP_TYPE_IGNORABLE))
    return 0;
  int senders = scp_type_senders(type);
  switch (d->role) {
  case SCP_ROLE_SERVER:
    return !(senders & SCP_FROM_CLIENT);
  case SCP_ROLE_CLIENT:
    return !(senders & SCP_FROM_SERVER);
  }
  return senders == 0;
}

/* Is a frame of this type allowed at this point of the stream? */
static int position_ok(const scp_decoder_t *d, uint16_t type) {
  int handshake = type == SCP_HELLO || type == SCP_WELCOME;
  switch (d->role) {
  case SCP_ROLE_SERVER:
    return d->handshake_done ? !handshake : type == SCP_HELLO;
  case SCP_ROLE_CLIENT:
    return d->handshake_done ? !handshake
                             : type == SCP_WELCOME || type == SCP_ERROR;
  }
  return 1;
}

int scp_decoder_next(scp_decoder_t *d, scp_frame_t *frame) {
  if (d->err)
    return d->err;
  release_held(d);
  for (;;) {
    if (d->skip) {
      discard_skipped(d);
      if (d->skip)
        return 0;
    }
    size_t avail = d->end - d->start;
    if (avail < SCP_HEADER_SIZE)
      return 0;
    const uint8_t *h = d->buf + d->start;
    uint16_t type = scp__ld16(h);
    uint16_t flags = scp__ld16(h + 2);
    uint32_t length = scp__ld32(h + 4);
    if (!position_ok(d, type))
      return fail(d, SCP_EHANDSHAKE);
    if (flags != 0)
      return fail(d, SCP_ERESERVED);
    /* Compared as frame sizes in 64 bits: a length near 2^32 must not wrap
     * around when the header is added. */
    if ((uint64_t)length + SCP_HEADER_SIZE > d->max_frame)
      return fail(d, SCP_ETOOBIG);
    if (skipped_type(d, type)) {
      d->skip = (uint64_t)length + SCP_HEADER_SIZE;
      d->counters.skipped++;
      continue;
    }
    int handshake = type == SCP_HELLO || type == SCP_WELCOME;
    /* The magic is judged as soon as it is in, so that a peer speaking
     * another protocol is turned away before it sends a whole frame. */
    if (handshake && length >= SCP_MAGIC_LEN &&
        avail >= SCP_HEADER_SIZE + SCP_MAGIC_LEN &&
        memcmp(h + SCP_HEADER_SIZE, SCP_MAGIC, SCP_MAGIC_LEN) != 0)
      return fail(d, SCP_EBADMAGIC);
    if (avail - SCP_HEADER_SIZE < length)
      return 0;
    frame->type = type;
    frame->length = length;
    frame->payload = h + SCP_HEADER_SIZE;
    d->held = SCP_HEADER_SIZE + (size_t)length;
    d->counters.frames++;
    if (handshake)
      d->handshake_done = 1;
    return 1;
  }
}

int scp_decoder_eof(scp_decoder_t *d) {
  if (d->err)
    return d->err;
  release_held(d);
  if (d->skip || d->end > d->start)
    return fail(d, SCP_ETRUNCATED);
  return 0;
}

int scp_decoder_error(const scp_decoder_t *d) { return d->err; }

size_t scp_decoder_pending(const scp_decoder_t *d) {
  return d->end - d->start - d->held;
}

int scp_decoder_set_max_frame(scp_decoder_t *d, uint32_t max_frame) {
  if (max_frame < SCP_FRAME_MIN || max_frame > SCP_FRAME_CEILING)
    return SCP_EINVAL;
  d->max_frame = max_frame;
  return 0;
}

uint32_t scp_decoder_max_frame(const scp_decoder_t *d) { return d->max_frame; }

void scp_decoder_get_counters(const scp_decoder_t *d,
                              scp_decoder_counters_t *out) {
  *out = d->counters;
  out->buffer = d->cap;
}
