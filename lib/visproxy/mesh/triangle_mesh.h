#pragma once
// The indexed triangle mesh every visproxy module works on.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <span>
#include <string>
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

/// The largest coordinate magnitude visproxy accepts. Geometry in double precision squares
/// and cubes coordinate differences (distances, normals, volumes); beyond 1e100 those
/// would overflow, so such meshes are refused where they are read.
inline constexpr double kMaxCoordinate = 1e100;

/// Whether every coordinate of `p` is finite and of magnitude at most kMaxCoordinate (each
/// tested on its own: Eigen's maxCoeff may step over a NaN).
inline bool within_coordinate_range(const Vertex& p) {
  return std::abs(p.x()) <= kMaxCoordinate && std::abs(p.y()) <= kMaxCoordinate && std::abs(p.z()) <= kMaxCoordinate;
}

/// The first vertex (lowest index) with a coordinate of magnitude above kMaxCoordinate
/// or not finite, if any.
std::optional<std::size_t> first_vertex_out_of_range(const TriangleMesh& mesh);

/// Throws InvalidInputError naming `file` and the first such vertex.
void require_coordinates_in_range(const TriangleMesh& mesh, const std::filesystem::path& file);

/// Bounding box of the vertices that triangles use (unreferenced vertices are ignored).
BoundingBox bounding_box(const TriangleMesh& mesh);

/// The signed volume the triangles enclose (divergence theorem, about the box centre to keep
/// the terms small): the integral of the winding number for a closed mesh, positive when
/// it is oriented outwards. Units cubed.
double signed_volume(const TriangleMesh& mesh);

/// 64-bit FNV-1a over the coordinates' and indices' bytes, as 16 hexadecimal digits: the
/// identity of a mesh's content (cache keys, the files a verify verdict was made on).
/// `extra` bytes (another object's) may be mixed in after the mesh's.
std::string content_hash(const TriangleMesh& mesh, std::span<const unsigned char> extra = {});

/// The positions of the vertices that triangles use, in index order (each once).
std::vector<Vertex> used_positions(const TriangleMesh& mesh);

/// Adds `part`'s vertices and triangles to `mesh` (indices shifted; nothing is welded).
void append_mesh(TriangleMesh& mesh, const TriangleMesh& part);

/// `mesh` with every vertex mapped by `transform`. A mirroring transform (negative
/// determinant) also reverses every triangle's winding, so that a closed mesh's outward
/// normals stay outward (as glTF draws mirrored nodes); otherwise the triangles are as they are.
TriangleMesh transformed_mesh(const TriangleMesh& mesh, const Eigen::Affine3d& transform);

}  // namespace visproxy
