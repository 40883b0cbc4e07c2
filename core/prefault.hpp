// The allocator of the triangulation's cells and vertices: CGAL's
// Compact_container writes to every element of a block as soon as it has
// allocated it (threading its free list), so every page of the block is
// touched at once. Asking the kernel for those pages in one call
// (MADV_POPULATE_WRITE, Linux 5.14) instead of one page fault each saves a
// trap per page: about 10 us on a virtual machine (where the
// triangulation of 362k points went from 1.92 to 1.63 s), around 1 us on
// bare metal. Included before any CGAL header, for CGAL_ALLOCATOR() to
// name it.
//
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef SC_CORE_PREFAULT_HPP
#define SC_CORE_PREFAULT_HPP

#include <cstddef>
#include <memory>
#include <vector>

namespace sc {

// Makes the whole pages of [p, p + bytes) resident and writable, when they
// are many enough to be worth a call; where the kernel cannot, they are
// faulted in as they are touched, as before (prefault.cpp).
void prefault(void *p, size_t bytes);

template <class T> struct PrefaultAllocator {
  typedef T value_type;
  PrefaultAllocator() = default;
  template <class U> PrefaultAllocator(const PrefaultAllocator<U> &) {}
  T *allocate(size_t n) {
    T *p = std::allocator<T>().allocate(n);
    prefault(p, n * sizeof(T));
    return p;
  }
  void deallocate(T *p, size_t n) { std::allocator<T>().deallocate(p, n); }
};
template <class T, class U>
bool operator==(const PrefaultAllocator<T> &, const PrefaultAllocator<U> &) {
  return true;
}
template <class T, class U>
bool operator!=(const PrefaultAllocator<T> &, const PrefaultAllocator<U> &) {
  return false;
}

// Room in v for m elements, the pages beyond its size resident at once:
// for a vector about to be resized or filled to m.
template <class T, class A>
void reserve_resident(std::vector<T, A> &v, size_t m) {
  if (v.capacity() >= m)
    return;
  v.reserve(m);
  prefault(v.data() + v.size(), (m - v.size()) * sizeof(T));
}

// A vector whose large buffers come resident in one call.
template <class T> using PrefaultVector = std::vector<T, PrefaultAllocator<T>>;

// Pages mapped for [bytes] (resident at once), and given back to the
// kernel; map_pages() throws std::bad_alloc when it cannot (prefault.cpp).
void *map_pages(size_t bytes);
void unmap_pages(void *p, size_t bytes);

// Large buffers mapped apart and unmapped when freed, small ones from the
// heap: for work on a thread beside the main one. Freed, such a thread's
// heap keeps its pages, which the main thread's later allocations (the
// triangulation's) cannot reuse: the noise estimate beside the merged
// scans' triangulation raised the peak from 670 to 692 bytes a point.
template <class T> struct MappedAllocator {
  static constexpr size_t kMapBytes = size_t(1) << 20;
  typedef T value_type;
  MappedAllocator() = default;
  template <class U> MappedAllocator(const MappedAllocator<U> &) {}
  T *allocate(size_t n) {
    if (n * sizeof(T) < kMapBytes)
      return std::allocator<T>().allocate(n);
    return static_cast<T *>(map_pages(n * sizeof(T)));
  }
  void deallocate(T *p, size_t n) {
    if (n * sizeof(T) < kMapBytes)
      std::allocator<T>().deallocate(p, n);
    else
      unmap_pages(p, n * sizeof(T));
  }
};
template <class T, class U>
bool operator==(const MappedAllocator<T> &, const MappedAllocator<U> &) {
  return true;
}
template <class T, class U>
bool operator!=(const MappedAllocator<T> &, const MappedAllocator<U> &) {
  return false;
}
template <class T> using MappedVector = std::vector<T, MappedAllocator<T>>;

} // namespace sc

#endif
