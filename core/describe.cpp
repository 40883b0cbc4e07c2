// The topology of a surface (components, boundary loops, genus, manifold
// checks), its summary in the diagnostics, and dropping small components.
//
// SPDX-License-Identifier: GPL-3.0-or-later

#include "edges.hpp"

namespace sc {
namespace {

struct UnionFind {
  std::vector<uint32_t> parent;
  explicit UnionFind(size_t n) : parent(n) {
    std::iota(parent.begin(), parent.end(), 0u);
  }
  uint32_t find(uint32_t x) {
    while (parent[x] != x)
      x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(uint32_t a, uint32_t b) {
    a = find(a), b = find(b);
    if (a != b)
      parent[std::max(a, b)] = std::min(a, b);
  }
};

} // namespace

void describe(const double *xyz, size_t n, std::vector<uint32_t> &res,
              Progress &progress, Surface &out, sc_diag_t &diag,
              const EdgeTable *table, bool check_vertices) {
  const size_t nr = res.size() / 3;
  EdgeTable own;
  if (!table) {
    own.build(xyz, n, res, progress, false);
    table = &own;
  }
  const EdgeTable &rt = *table;
  UnionFind uf(nr);
  for (size_t e = 0; e < rt.edges(); ++e)
    for (uint32_t i = rt.first[e] + 1; i < rt.first[e + 1]; ++i)
      uf.unite(rt.entries[rt.first[e]].tri, rt.entries[i].tri);
  std::vector<int32_t> comp_of(nr, -1), root_comp(nr, -1);
  int32_t nc = 0;
  for (size_t t = 0; t < nr; ++t) {
    uint32_t r = uf.find(uint32_t(t));
    if (root_comp[r] < 0)
      root_comp[r] = nc++;
    comp_of[t] = root_comp[r];
  }
  std::vector<Surface::Part> parts(nc);
  for (size_t t = 0; t < nr; ++t)
    ++parts[comp_of[t]].faces;
  UnionFind bloops(n);
  for (size_t e = 0; e < rt.edges(); ++e) {
    uint32_t cnt = rt.first[e + 1] - rt.first[e];
    Surface::Part &p = parts[comp_of[rt.entries[rt.first[e]].tri]];
    ++p.edges;
    if (cnt == 1) {
      ++p.boundary_edges;
      uint64_t k = rt.entries[rt.first[e]].key;
      bloops.unite(key_lo(k), uint32_t(k));
    } else if (cnt > 2) {
      ++p.nonmanifold_edges;
    }
  }
  std::vector<int32_t> vcomp(n, -1);
  for (size_t t = 0; t < nr; ++t)
    for (int k = 0; k < 3; ++k)
      vcomp[res[3 * t + k]] = comp_of[t];
  // Loops, and their lengths in boundary edges (loops that touch at a
  // vertex count as one).
  std::vector<Surface::Loop> loops;
  std::vector<uint32_t> loop_of(n, UINT32_MAX);
  {
    std::vector<uint64_t> loop_edges(n, 0);
    for (size_t e = 0; e < rt.edges(); ++e)
      if (rt.first[e + 1] - rt.first[e] == 1)
        ++loop_edges[bloops.find(key_lo(rt.entries[rt.first[e]].key))];
    for (uint32_t v = 0; v < n; ++v) {
      if (vcomp[v] < 0)
        continue;
      ++parts[vcomp[v]].vertices;
      if (loop_edges[v] == 0)
        continue;
      loop_of[v] = uint32_t(loops.size());
      loops.push_back({vcomp[v], loop_edges[v]});
    }
    for (size_t e = 0; e < rt.edges(); ++e)
      if (rt.first[e + 1] - rt.first[e] == 1) {
        const uint64_t k = rt.entries[rt.first[e]].key;
        for (uint32_t u : {key_lo(k), uint32_t(k)})
          loop_of[u] = loop_of[bloops.find(u)];
      }
  }
  // A final check of vertex-manifoldness on the result, counted honestly:
  // the corners of triangles at a vertex that share an edge there are one
  // fan; a vertex with two fans is pinched. (Before any triangle is
  // flipped below: corners are positions in res.) Without check_vertices
  // only a closed surface is checked here: an open one is described again
  // once closed.
  bool any_open = false;
  for (const Surface::Part &p : parts)
    any_open = any_open || p.boundary_edges > 0;
  uint64_t pinched = 0;
  if (check_vertices || !any_open) {
    UnionFind corners(3 * nr);
    auto corner = [&](uint32_t t, uint32_t v) {
      const uint32_t *u = &res[3 * size_t(t)];
      return 3 * t + (u[0] == v ? 0 : u[1] == v ? 1 : 2);
    };
    for (size_t e = 0; e < rt.edges(); ++e) {
      const uint64_t k = rt.entries[rt.first[e]].key;
      const uint32_t t0 = rt.entries[rt.first[e]].tri;
      for (uint32_t i = rt.first[e] + 1; i < rt.first[e + 1]; ++i) {
        corners.unite(corner(t0, key_lo(k)),
                      corner(rt.entries[i].tri, key_lo(k)));
        corners.unite(corner(t0, uint32_t(k)),
                      corner(rt.entries[i].tri, uint32_t(k)));
      }
    }
    std::vector<uint8_t> fans(n, 0);
    for (uint32_t c = 0; c < 3 * nr; ++c)
      if (corners.find(c) == c && fans[res[c]] < 2 && ++fans[res[c]] == 2)
        ++pinched;
  }
  // Signed volumes about each component's first vertex, for precision: a
  // closed component facing inward is flipped. (An open one has no inside,
  // and keeps the orientation it has.)
  std::vector<double> vol(nc, 0.0);
  std::vector<uint32_t> origin(nc, UINT32_MAX);
  for (size_t t = 0; t < nr; ++t) {
    int32_t c = comp_of[t];
    if (parts[c].boundary_edges != 0)
      continue;
    if (origin[c] == UINT32_MAX)
      origin[c] = res[3 * t];
    vol[c] += signed_volume6(xyz, &res[3 * t], xyz + 3 * size_t(origin[c]));
  }
  for (size_t t = 0; t < nr; ++t) {
    int32_t c = comp_of[t];
    if (parts[c].boundary_edges == 0 && vol[c] < 0)
      std::swap(res[3 * t + 1], res[3 * t + 2]);
  }

  out.component.swap(comp_of);
  out.parts.swap(parts);
  out.pinched = pinched;
  out.loops.swap(loops);
  out.loop_of.swap(loop_of);
  out.tris.swap(res);
  tally_loops(out);
  summarise(out, diag);
}

void tally_loops(Surface &s) {
  for (Surface::Part &p : s.parts) {
    p.loops = p.longest_loop = 0;
    for (uint64_t &l : p.loops_by_length)
      l = 0;
  }
  for (const Surface::Loop &l : s.loops) {
    if (l.part < 0)
      continue;
    Surface::Part &p = s.parts[size_t(l.part)];
    ++p.loops;
    p.longest_loop = std::max(p.longest_loop, l.length);
    ++p.loops_by_length[l.length <= 10     ? 0
                        : l.length <= 100  ? 1
                        : l.length <= 1000 ? 2
                                           : 3];
  }
}

void summarise(Surface &s, sc_diag_t &diag) {
  diag.triangles = diag.boundary_edges = diag.boundary_loops = 0;
  diag.nonmanifold_edges = 0;
  diag.components = diag.closed_components = 0;
  diag.longest_loop = 0;
  for (uint64_t &l : diag.loops_by_length)
    l = 0;
  diag.euler = 0;
  diag.genus = 0;
  s.component_genus.assign(s.parts.size(), -1);
  uint64_t used_vertices = 0;
  for (size_t c = 0; c < s.parts.size(); ++c) {
    const Surface::Part &p = s.parts[c];
    const int64_t chi = p.vertices - p.edges + p.faces;
    diag.euler += chi;
    if (p.boundary_edges == 0) {
      ++diag.closed_components;
      s.component_genus[c] = int32_t((2 - chi) / 2);
      diag.genus += (2 - chi) / 2;
    }
    diag.boundary_edges += p.boundary_edges;
    diag.boundary_loops += p.loops;
    diag.nonmanifold_edges += p.nonmanifold_edges;
    diag.longest_loop = std::max(diag.longest_loop, p.longest_loop);
    for (int k = 0; k < 4; ++k)
      diag.loops_by_length[k] += p.loops_by_length[k];
    used_vertices += uint64_t(p.vertices);
  }
  diag.nonmanifold_vertices = s.pinched;
  diag.components = s.parts.size();
  diag.triangles = s.tris.size() / 3;
  diag.closed = diag.triangles > 0 && diag.boundary_edges == 0;
  const uint64_t distinct = diag.delaunay_vertices;
  diag.samples_unused = distinct > used_vertices ? distinct - used_vertices : 0;
}

size_t drop_small_closed(const double *xyz, size_t n, Surface &s,
                         size_t min_triangles, bool open_too,
                         Progress &progress, sc_diag_t &diag) {
  const size_t nt = s.tris.size() / 3, nc = s.parts.size();
  if (s.component.size() != nt)
    throw Error(SC_EINTERNAL, "components out of step with the surface");
  std::vector<int32_t> renumber(nc, -1);
  int32_t kept = 0;
  for (size_t c = 0; c < nc; ++c)
    if ((s.parts[c].boundary_edges != 0 && !open_too) ||
        size_t(s.parts[c].faces) >= min_triangles)
      renumber[c] = kept++;
  if (size_t(kept) == nc)
    return 0;
  size_t k = 0;
  for (size_t t = 0; t < nt; ++t) {
    const int32_t c = renumber[s.component[t]];
    if (c < 0)
      continue;
    std::memmove(&s.tris[3 * k], &s.tris[3 * t], 3 * sizeof(uint32_t));
    s.component[k] = c;
    ++k;
  }
  s.tris.resize(3 * k);
  s.component.resize(k);
  if (s.pinched) {
    // A pinched vertex may join components, and its count belongs to one
    // of them: count again.
    std::vector<uint32_t> tris;
    tris.swap(s.tris);
    describe(xyz, n, tris, progress, s, diag);
  } else {
    // Whole components went: every count of the others stands.
    for (size_t c = 0; c < nc; ++c)
      if (renumber[c] >= 0)
        s.parts[size_t(renumber[c])] = s.parts[c];
    s.parts.resize(size_t(kept));
    for (Surface::Loop &l : s.loops)
      l.part = l.part < 0 ? -1 : renumber[size_t(l.part)];
    summarise(s, diag);
  }
  return nt - k;
}

} // namespace sc
