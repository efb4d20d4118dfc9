#pragma once
// Checks shared by the convex proxy tests, decided exactly and independently of the code
// under test (CGAL's orientation predicate on every input vertex).

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <sstream>
#include <vector>

#include "visproxy/mesh/mesh_topology.h"
#include "visproxy/mesh/triangle_mesh.h"

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
  BoundingBox box;
  for (const Vertex& v : vertices) box.extend(v);
  for (const Vertex& v : outside.positions) box.extend(v);
  const double reach = box.diagonal();  // bounds |p - a| for every vertex p and corner a
  for (const Triangle& t : outside.triangles) {
    const Vertex& a = outside.positions[t[0]];
    const Vertex& b = outside.positions[t[1]];
    const Vertex& c = outside.positions[t[2]];
    const Vertex normal = (b - a).cross(c - a);
    // normal . (p - a) is computed with an error far below 1e-9 * |b - a| |c - a| |p - a|;
    // below minus that, p is clearly inside and the exact predicate is not needed.
    const double clearly_inside = -1e-9 * (b - a).norm() * (c - a).norm() * reach;
    const Point pa(a.x(), a.y(), a.z()), pb(b.x(), b.y(), b.z()), pc(c.x(), c.y(), c.z());
    for (const Vertex& v : vertices) {
      if (normal.dot(v - a) < clearly_inside) continue;
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

/// Every vertex of `mesh` is at most `tolerance` outside the plane of every triangle of it
/// whose plane is well defined: convex up to the rounding of its corners. Slivers (area
/// below 1e-6 of the squared longest edge) are skipped: where more than three planes meet,
/// rounding splits the corner into nearby ones joined by slivers whose planes mean nothing.
inline ::testing::AssertionResult is_convex_within(const TriangleMesh& mesh, double tolerance) {
  for (const Triangle& t : mesh.triangles) {
    const Vertex& a = mesh.positions[t[0]];
    const Vertex& b = mesh.positions[t[1]];
    const Vertex& c = mesh.positions[t[2]];
    const Vertex normal = (b - a).cross(c - a);
    const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    if (normal.norm() < 2e-6 * longest * longest) continue;
    const Vertex unit = normal.normalized();
    for (const Vertex& p : mesh.positions)
      if (unit.dot(p - a) > tolerance)
        return ::testing::AssertionFailure() << "a corner is " << unit.dot(p - a) << " outside a triangle's plane";
  }
  return ::testing::AssertionSuccess();
}

/// Finite corners; closed, manifold, consistently oriented, one component, sphere topology.
inline ::testing::AssertionResult is_closed_polytope_surface(const TriangleMesh& mesh) {
  for (const Vertex& p : mesh.positions)
    if (!p.allFinite()) return ::testing::AssertionFailure() << "a corner has a non-finite coordinate";
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
