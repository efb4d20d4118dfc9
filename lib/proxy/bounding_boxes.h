#pragma once
// Box proxies: the axis-aligned and the oriented bounding box of a mesh.

#include <array>
#include <cstdint>

#include <Eigen/Core>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

/// The box { center + axes * t : |t_i| <= half_extents_i }. `axes` has the box's unit
/// axes as columns (orthonormal, right-handed).
struct OrientedBox {
  Vertex center = Vertex::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
  Vertex half_extents = Vertex::Zero();
  std::array<Vertex, 8> corners() const;  ///< corner i takes +half_extents_k where bit k of i is set
  double volume() const { return 8.0 * half_extents.prod(); }
};

/// The exact bounds of the vertices that triangles use, as a closed mesh of up to 12
/// triangles with the bounds' exact coordinates as corners. A box that is flat in one
/// axis keeps only its two coincident faces. Throws InvalidInputError (file "") when the
/// mesh has no triangles or its vertices are collinear.
TriangleMesh axis_aligned_box_mesh(const TriangleMesh& mesh);

struct OrientedBoxOptions {
  std::uint32_t seed = 1;  ///< seed of CGAL's optimisation (Chang et al. 2011, as in CGAL)
};

struct OrientedBoxResult {
  OrientedBox box;
  TriangleMesh mesh;        ///< the box as a closed triangle mesh, as axis_aligned_box_mesh
  double inflation_world;   ///< how far the faces were pushed out so that rounding cannot cut a vertex
  const char* axes_from;    ///< which candidate won: "cgal", "principal axes", "axis-aligned", "plane"
};

/// The smallest-volume box among CGAL's optimal bounding box (run on the corners of the
/// exact convex hull), the principal-axes box and the axis-aligned box (for a flat input:
/// the smallest-area rectangle in its plane), each fitted to the hull's corners.
/// Every vertex is proved inside or on the resulting mesh with exact predicates; when
/// rounding of the corners would leave one outside, the box grows by a few ulps of the
/// diagonal until none is. Same errors as axis_aligned_box_mesh.
OrientedBoxResult build_oriented_box(const TriangleMesh& mesh, const OrientedBoxOptions& options = {});

/// A box as a closed, outward-oriented triangle mesh (corners welded, zero-area
/// triangles dropped).
TriangleMesh box_mesh(const std::array<Vertex, 8>& corners);

}  // namespace visproxy
