// Vertex-manifoldness: the fans of triangles around each vertex, keeping the
// largest where there are several, and dropping the triangles of edges
// with more than two.
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include "edges.hpp"

namespace sc {
namespace {

// The fans of triangles around vertex v: connected pieces of its link.
// Writes a fan number per incident triangle into fan_of (same order as the
// star's list) and returns the number of fans.
int count_fans(uint32_t v, const std::vector<uint32_t> &star,
               const std::vector<uint32_t> &tris, std::vector<int> &fan_of) {
  const size_t m = star.size();
  fan_of.assign(m, -1);
  // Triangles around v are adjacent when they share an edge at v, that is
  // one of their two other vertices. Stars are small: quadratic is fine.
  // The scratch lives on between calls: this runs once per vertex.
  thread_local std::vector<uint32_t> other;
  thread_local std::vector<size_t> stack;
  other.resize(2 * m);
  for (size_t i = 0; i < m; ++i) {
    const uint32_t *t = &tris[3 * size_t(star[i])];
    int j = 0;
    for (int k = 0; k < 3; ++k)
      if (t[k] != v)
        other[2 * i + j++] = t[k];
  }
  int fans = 0;
  for (size_t s = 0; s < m; ++s) {
    if (fan_of[s] >= 0)
      continue;
    fan_of[s] = fans;
    stack.assign(1, s);
    while (!stack.empty()) {
      size_t i = stack.back();
      stack.pop_back();
      for (size_t j = 0; j < m; ++j) {
        if (fan_of[j] >= 0)
          continue;
        if (other[2 * i] == other[2 * j] || other[2 * i] == other[2 * j + 1] ||
            other[2 * i + 1] == other[2 * j] ||
            other[2 * i + 1] == other[2 * j + 1]) {
          fan_of[j] = fans;
          stack.push_back(j);
        }
      }
    }
    ++fans;
  }
  return fans;
}

// Whether the triangles around vertex v are one fan, shown by a chain
// through all of them, each sharing with the next its edge at v that the
// orientation puts last in the one and first in the next (from a triangle
// that no other one precedes, if there is one). It nearly always is; when
// no such chain is found, count_fans() decides.
bool one_fan(uint32_t v, const std::vector<uint32_t> &star,
             const std::vector<uint32_t> &tris) {
  constexpr size_t kMax = 32;
  const size_t m = star.size();
  if (m <= 1)
    return true;
  if (m > kMax)
    return false;
  uint32_t a[kMax], b[kMax]; // triangle i runs v -> a[i] -> b[i]
  for (size_t i = 0; i < m; ++i) {
    const uint32_t *t = &tris[3 * size_t(star[i])];
    const int k = t[0] == v ? 0 : t[1] == v ? 1 : 2;
    a[i] = t[(k + 1) % 3];
    b[i] = t[(k + 2) % 3];
  }
  size_t i = 0;
  for (size_t s = 0; s < m; ++s) {
    bool preceded = false;
    for (size_t j = 0; j < m && !preceded; ++j)
      preceded = b[j] == a[s];
    if (!preceded) {
      i = s;
      break;
    }
  }
  uint32_t done = 1u << i;
  size_t chained = 1;
  for (;;) {
    size_t next = m;
    for (size_t j = 0; j < m && next == m; ++j)
      if (!(done >> j & 1) && a[j] == b[i])
        next = j;
    if (next == m)
      break;
    done |= 1u << next;
    ++chained;
    i = next;
  }
  return chained == m;
}

} // namespace

void fix_fans_in(const VertexStar &ostar, const std::vector<uint32_t> &otri,
                 std::vector<uint8_t> &in, std::vector<uint32_t> work) {
  std::sort(work.begin(), work.end()); // popped from the back
  work.erase(std::unique(work.begin(), work.end()), work.end());
  // A vertex is looked at again only if it lost a triangle since it was
  // last looked at: that look left it one fan, and nothing changed. (A
  // vertex that loses several triangles is pushed for each; the first
  // pop looks, the others pass.)
  std::vector<uint8_t> changed(ostar.first.size() - 1, 0);
  for (uint32_t v : work)
    changed[v] = 1;
  std::vector<uint32_t> cur;
  std::vector<int> fan_of;
  while (!work.empty()) {
    uint32_t v = work.back();
    work.pop_back();
    if (!changed[v])
      continue;
    changed[v] = 0;
    // The triangles of the vertices next in line are scattered: ask for
    // those a few places on while this one is looked at.
    constexpr size_t kAhead = 4;
    if (work.size() >= kAhead) {
      const uint32_t w = work[work.size() - kAhead];
      for (uint32_t i = ostar.first[w]; i < ostar.first[w + 1]; ++i) {
        __builtin_prefetch(&in[ostar.tris[i]]);
        __builtin_prefetch(&otri[3 * size_t(ostar.tris[i])]);
      }
    }
    cur.clear();
    for (uint32_t i = ostar.first[v]; i < ostar.first[v + 1]; ++i)
      if (in[ostar.tris[i]])
        cur.push_back(ostar.tris[i]);
    if (one_fan(v, cur, otri))
      continue;
    int fans = count_fans(v, cur, otri, fan_of);
    if (fans <= 1)
      continue;
    std::vector<size_t> size(fans, 0);
    for (int f : fan_of)
      ++size[f];
    int keep = int(std::max_element(size.begin(), size.end()) - size.begin());
    for (size_t i = 0; i < cur.size(); ++i) {
      if (fan_of[i] == keep)
        continue;
      in[cur[i]] = 0;
      for (int k = 0; k < 3; ++k) {
        const uint32_t w = otri[3 * size_t(cur[i]) + k];
        if (w != v) {
          changed[w] = 1;
          work.push_back(w);
        }
      }
    }
  }
}

void fix_fans(size_t n, const std::vector<uint32_t> &otri,
              std::vector<uint8_t> &in, bool one_fan_before) {
  std::vector<uint32_t> work;
  if (one_fan_before) {
    // Only a vertex that lost a triangle can have more than one fan now.
    for (size_t t = 0; t < in.size(); ++t)
      if (!in[t])
        work.insert(work.end(), &otri[3 * t], &otri[3 * t] + 3);
    if (work.empty())
      return;
  }
  VertexStar ostar;
  ostar.build(n, otri, [&](size_t t) { return in[t] != 0; });
  if (!one_fan_before)
    for (uint32_t v = 0; v < n; ++v)
      if (ostar.first[v + 1] > ostar.first[v])
        work.push_back(v);
  fix_fans_in(ostar, otri, in, std::move(work));
}

void drop_nonmanifold(const double *xyz, size_t n, std::vector<uint32_t> &tris,
                      Progress &progress) {
  const size_t nt = tris.size() / 3;
  EdgeTable et;
  et.build(xyz, n, tris, progress, false);
  std::vector<uint8_t> in(nt, 1);
  for (size_t e = 0; e < et.edges(); ++e)
    if (et.first[e + 1] - et.first[e] > 2)
      for (uint32_t i = et.first[e]; i < et.first[e + 1]; ++i)
        in[et.entries[i].tri] = 0;
  fix_fans(n, tris, in);
  std::vector<uint32_t> res;
  for (size_t t = 0; t < nt; ++t)
    if (in[t])
      res.insert(res.end(), &tris[3 * t], &tris[3 * t] + 3);
  tris.swap(res);
}

} // namespace sc
