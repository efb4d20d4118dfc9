#pragma once
// visproxy's triangle meshes to and from CGAL's Surface_mesh, for the benchmarks that run
// CGAL's algorithms beside visproxy's.

#include <CGAL/Surface_mesh.h>

#include <cstddef>
#include <vector>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy::bench {

template <class Point>
CGAL::Surface_mesh<Point> to_surface_mesh(const TriangleMesh& mesh) {
  CGAL::Surface_mesh<Point> result;
  std::vector<typename CGAL::Surface_mesh<Point>::Vertex_index> vertices;
  vertices.reserve(mesh.positions.size());
  for (const Vertex& p : mesh.positions) vertices.push_back(result.add_vertex(Point(p.x(), p.y(), p.z())));
  for (const Triangle& t : mesh.triangles) result.add_face(vertices[t[0]], vertices[t[1]], vertices[t[2]]);
  return result;
}

/// A Surface_mesh of triangles without removed elements (vertex indices are dense).
template <class Point>
TriangleMesh from_surface_mesh(const CGAL::Surface_mesh<Point>& mesh) {
  TriangleMesh result;
  for (const auto v : mesh.vertices()) result.positions.emplace_back(mesh.point(v).x(), mesh.point(v).y(), mesh.point(v).z());
  for (const auto f : mesh.faces()) {
    Triangle t{};
    std::size_t i = 0;
    for (const auto v : mesh.vertices_around_face(mesh.halfedge(f))) t[i++] = static_cast<VertexIndex>(v.idx());
    result.triangles.push_back(t);
  }
  return result;
}

}  // namespace visproxy::bench
