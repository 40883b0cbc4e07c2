// SPDX-License-Identifier: GPL-3.0-or-later

#include "prefault.hpp"

#include <cstdint>
#include <new>

#include <sys/mman.h>
#include <unistd.h>

void sc::prefault(void *p, size_t bytes) {
#ifdef MADV_POPULATE_WRITE
  // (Small blocks are not worth a system call: the first blocks of a
  // container, and whatever else CGAL allocates with its default
  // allocator in the same file.)
  constexpr size_t kMinBytes = 64 * 1024;
  if (bytes < kMinBytes)
    return;
  static const uintptr_t page = [] {
    const long size = sysconf(_SC_PAGESIZE);
    return size > 0 ? uintptr_t(size) : uintptr_t(4096);
  }();
  const uintptr_t lo = (uintptr_t(p) + page - 1) & ~(page - 1),
                  hi = (uintptr_t(p) + bytes) & ~(page - 1);
  if (hi > lo)
    (void)madvise(reinterpret_cast<void *>(lo), hi - lo, MADV_POPULATE_WRITE);
#else
  (void)p;
  (void)bytes;
#endif
}

void *sc::map_pages(size_t bytes) {
  void *p = mmap(nullptr, bytes, PROT_READ | PROT_WRITE,
                 MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (p == MAP_FAILED)
    throw std::bad_alloc();
  prefault(p, bytes);
  return p;
}

void sc::unmap_pages(void *p, size_t bytes) { (void)munmap(p, bytes); }
