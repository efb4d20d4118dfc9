#pragma once
// A BVH over the boxes of a mesh's triangles, built by Embree's builder in parallel and
// traversed by our own code with the caller's tests: for exact intersection queries whose
// shape (a tetrahedron, a ball, a triangle) prunes far better than its bounding sphere.

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

/// The triangles `triangles` (indices into mesh.triangles) of `mesh`. The mesh must outlive
/// the tree and not change. Queries are const and may run on several threads at once.
class TriangleBoxTree {
 public:
  TriangleBoxTree(const TriangleMesh& mesh, std::vector<std::uint32_t> triangles);
  ~TriangleBoxTree();
  TriangleBoxTree(const TriangleBoxTree&) = delete;
  TriangleBoxTree& operator=(const TriangleBoxTree&) = delete;

  /// Whether test(t) holds for some triangle t (an index into mesh.triangles) reached
  /// through nodes whose boxes pass may_meet; stops at the first. Every node's box holds
  /// the corners of its triangles, in double precision: the tree is built in single
  /// precision about the triangles' centre with boxes rounded outwards, and each box is
  /// grown by 2^-40 of the coordinates' magnitude when it is moved back. So a may_meet that
  /// is false only for boxes a query cannot meet never drops a triangle the query meets.
  bool any(const std::function<bool(const BoundingBox&)>& may_meet,
           const std::function<bool(std::uint32_t)>& test) const;

  /// The point of the triangles nearest to p (point_triangle_nearest_point in double
  /// precision), the index into mesh.triangles of its triangle, and their squared distance;
  /// among triangles at equal distance, the one of smallest index, so that the answer does
  /// not depend on the tree's order. Nodes are visited nearest first and skipped when their
  /// box is further than the nearest triangle found. With no triangle, the distance is
  /// infinite.
  struct Nearest {
    Vertex point = Vertex::Zero();
    std::uint32_t triangle = 0;
    double squared_distance = 0;
  };
  Nearest nearest(const Vertex& p) const;

  std::size_t size() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace visproxy
