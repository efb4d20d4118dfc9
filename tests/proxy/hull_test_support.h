#pragma once
// Checks shared by the convex proxy tests, decided exactly and independently of the code
// under test (CGAL's orientation predicate on every input vertex).

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <gtest/gtest.h>

#include <sstream>
#include <vector>

#include "mesh/mesh_topology.h"
#include "mesh/triangle_mesh.h"

namespace visproxy::testing {

using ExactKernel = CGAL::Exact_predicates_inexact_constructions_kernel;

/// The vertices that `mesh`'s triangles reference, once each, in index order.
inline std::vector<Vertex> referenced_vertices(const TriangleMesh& mesh) {
  std::vector<bool> used(mesh.positions.size(), false);
  for (const Triangle& t : mesh.triangles)
    for (const VertexIndex v : t) used[v] = true;
  std::vector<Vertex> vertices;
  for (std::size_t i = 0; i < used.size(); ++i)
    if (used[i]) vertices.push_back(mesh.positions[i]);
  return vertices;
}

/// Every vertex of `input` is on the inner side of, or on, the plane of every triangle of
/// `outside`, decided exactly (CGAL's orientation predicate) for every pair that a
/// conservative floating-point test cannot clear. With `outside` closed and
/// outward-oriented this means every input vertex is inside or on it.
inline ::testing::AssertionResult contains_every_vertex(const TriangleMesh& outside, const TriangleMesh& input) {
  using Point = ExactKernel::Point_3;
  const std::vector<Vertex> vertices = referenced_vertices(input);
  for (const Triangle& t : outside.triangles) {
    const Vertex& a = outside.positions[t[0]];
    const Vertex& b = outside.positions[t[1]];
    const Vertex& c = outside.positions[t[2]];
    const Vertex normal = (b - a).cross(c - a);
    // A distance below -1e-9 * |normal| * |p - a| is far beyond rounding error.
    const double clear_factor = 1e-9 * normal.norm();
    const Point pa(a.x(), a.y(), a.z()), pb(b.x(), b.y(), b.z()), pc(c.x(), c.y(), c.z());
    for (const Vertex& v : vertices) {
      const Vertex relative = v - a;
      if (normal.dot(relative) < -clear_factor * relative.norm()) continue;
      const Point p(v.x(), v.y(), v.z());
      if (CGAL::orientation(pa, pb, pc, p) == CGAL::POSITIVE) {
        std::ostringstream message;
        message.precision(17);
        message << "vertex (" << p << ") is outside triangle (" << pa << "), (" << pb << "), (" << pc << ")";
        return ::testing::AssertionFailure() << message.str();
      }
    }
  }
  return ::testing::AssertionSuccess();
}

/// Closed, manifold, consistently oriented, one component, sphere topology.
inline ::testing::AssertionResult is_closed_polytope_surface(const TriangleMesh& mesh) {
  const MeshTopology topology = analyze_topology(mesh);
  if (!topology.closed()) return ::testing::AssertionFailure() << topology.boundary_edges << " boundary edges";
  if (!topology.manifold())
    return ::testing::AssertionFailure() << topology.non_manifold_edges << " non-manifold edges, "
                                         << topology.non_manifold_vertices << " non-manifold vertices";
  if (!topology.consistently_oriented())
    return ::testing::AssertionFailure() << topology.inconsistent_edges << " inconsistently oriented edges";
  if (topology.components != 1) return ::testing::AssertionFailure() << topology.components << " components";
  if (topology.euler_characteristic(mesh.triangles.size()) != 2)
    return ::testing::AssertionFailure() << "Euler characteristic " << topology.euler_characteristic(mesh.triangles.size());
  if (topology.referenced_vertices != mesh.positions.size())
    return ::testing::AssertionFailure() << mesh.positions.size() - topology.referenced_vertices << " unreferenced vertices";
  return ::testing::AssertionSuccess();
}

}  // namespace visproxy::testing
