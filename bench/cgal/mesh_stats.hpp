// Statistics of a CGAL Complex_2_in_triangulation_3 (the restricted Delaunay surface mesh).
#pragma once

#include <CGAL/IO/Complex_2_in_triangulation_3_file_writer.h>

#include <algorithm>
#include <array>
#include <fstream>
#include <map>
#include <set>
#include <string>

#include "common.hpp"

namespace bench {

struct MeshStats {
  long long vertices = 0;       // vertices incident to at least one surface facet
  long long tr_vertices = 0;    // all vertices of the 3D triangulation
  long long facets = 0;
  long long edges = 0;
  long long boundary_edges = 0;      // edges with exactly one incident facet
  long long nonmanifold_edges = 0;   // edges with three or more incident facets
  long long euler = 0;               // V - E + F
};

template <class C2t3>
MeshStats mesh_stats(const C2t3& c2t3) {
  typedef typename C2t3::Triangulation Tr;
  typedef typename Tr::Vertex_handle VH;
  MeshStats s;
  const Tr& tr = c2t3.triangulation();
  s.tr_vertices = static_cast<long long>(tr.number_of_vertices());
  std::set<VH> verts;
  std::map<std::pair<VH, VH>, int> edge_count;
  for (auto fit = c2t3.facets_begin(); fit != c2t3.facets_end(); ++fit) {
    auto c = fit->first;
    int i = fit->second;
    std::array<VH, 3> v = {c->vertex((i + 1) & 3), c->vertex((i + 2) & 3),
                           c->vertex((i + 3) & 3)};
    ++s.facets;
    for (int k = 0; k < 3; ++k) {
      verts.insert(v[k]);
      VH a = v[k], b = v[(k + 1) % 3];
      if (b < a) std::swap(a, b);
      ++edge_count[{a, b}];
    }
  }
  s.vertices = static_cast<long long>(verts.size());
  s.edges = static_cast<long long>(edge_count.size());
  for (const auto& e : edge_count) {
    if (e.second == 1) ++s.boundary_edges;
    if (e.second >= 3) ++s.nonmanifold_edges;
  }
  s.euler = s.vertices - s.edges + s.facets;
  return s;
}

inline void add_stats(Json& j, const MeshStats& s) {
  j.i("vertices", s.vertices).i("facets", s.facets).i("edges", s.edges);
  j.i("euler", s.euler).i("boundary_edges", s.boundary_edges);
  j.i("nonmanifold_edges", s.nonmanifold_edges).i("triangulation_vertices", s.tr_vertices);
}

template <class C2t3>
void write_off(const C2t3& c2t3, const std::string& path) {
  std::ofstream out(path);
  if (!out) fail("cannot create --output file '" + path + "'");
  // Orients the facets consistently when the surface is an orientable manifold.
  // Note: the OFF vertex list is all triangulation vertices.
  out.precision(17);
  CGAL::output_surface_facets_to_off(out, c2t3);
  if (!out) fail("write error on --output file '" + path + "'");
}

}  // namespace bench
