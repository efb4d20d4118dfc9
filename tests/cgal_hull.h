#pragma once
// CGAL's convex hull of a mesh's vertices, as a triangle mesh: the reference the tests
// compare visproxy's own hulls and proofs against.

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>

#include <cstddef>
#include <vector>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy::testing {

/// The exact convex hull (CGAL's convex_hull_3) of every vertex of `mesh`, outward faces.
inline TriangleMesh cgal_convex_hull(const TriangleMesh& mesh) {
  using Point = CGAL::Exact_predicates_inexact_constructions_kernel::Point_3;
  std::vector<Point> points;
  for (const Vertex& p : mesh.positions) points.emplace_back(p.x(), p.y(), p.z());
  CGAL::Surface_mesh<Point> hull;
  CGAL::convex_hull_3(points.begin(), points.end(), hull);
  TriangleMesh result;
  for (const auto v : hull.vertices()) result.positions.emplace_back(hull.point(v).x(), hull.point(v).y(), hull.point(v).z());
  for (const auto f : hull.faces()) {
    Triangle t{};
    std::size_t i = 0;
    for (const auto v : hull.vertices_around_face(hull.halfedge(f))) t[i++] = static_cast<VertexIndex>(v.idx());
    result.triangles.push_back(t);
  }
  return result;
}

}  // namespace visproxy::testing
