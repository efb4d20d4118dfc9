#pragma once
// The indexed triangle mesh every visproxy module works on.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <limits>
#include <cstdint>
#include <vector>

namespace visproxy {

using Vertex = Eigen::Vector3d;
using VertexIndex = std::uint32_t;
using Triangle = std::array<VertexIndex, 3>;

/// An indexed triangle mesh: `positions` is #V points, `triangles` is #F index triples
/// into `positions`, counter-clockwise seen from outside when the mesh is oriented.
/// Coordinates are double so that single-precision inputs are held exactly.
struct TriangleMesh {
  std::vector<Vertex> positions;
  std::vector<Triangle> triangles;

  friend bool operator==(const TriangleMesh&, const TriangleMesh&) = default;
};

/// Axis-aligned bounding box; empty (min > max) until a point is added.
struct BoundingBox {
  Vertex min = Vertex::Constant(std::numeric_limits<double>::infinity());
  Vertex max = Vertex::Constant(-std::numeric_limits<double>::infinity());

  bool empty() const { return (min.array() > max.array()).any(); }
  void extend(const Vertex& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  /// Length of the diagonal; 0 for an empty box.
  double diagonal() const { return empty() ? 0.0 : (max - min).norm(); }
};

/// Bounding box of the vertices that triangles use (unreferenced vertices are ignored).
BoundingBox bounding_box(const TriangleMesh& mesh);

/// The positions of the vertices that triangles use, in index order (each once).
std::vector<Vertex> used_positions(const TriangleMesh& mesh);

/// Adds `part`'s vertices and triangles to `mesh` (indices shifted; nothing is welded).
void append_mesh(TriangleMesh& mesh, const TriangleMesh& part);

}  // namespace visproxy
