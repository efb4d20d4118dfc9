#pragma once
// Box proxies: the axis-aligned and the oriented bounding box of a mesh.

#include <array>
#include <cstdint>
#include <vector>

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

/// The exact bounds of the vertices that triangles use, as a closed mesh of 12 triangles
/// with the bounds' exact coordinates as corners. Along an axis where the bounds are
/// thinner than 2 flat_box_half_thickness (a flat card or quad), the box is that thick,
/// centred on the mesh: two coincident faces would bound no solid, and the outside claim
/// is that the mesh lies in the box's solid. Throws InvalidInputError (file "") when the
/// mesh has no triangles or its vertices are collinear.
TriangleMesh axis_aligned_box_mesh(const TriangleMesh& mesh);

/// Half the thickness a box gets along an axis where its input is flat: 2^-21 of the
/// input's bounding-box diagonal.
double flat_box_half_thickness(double diagonal);

struct OrientedBoxOptions {
  std::uint32_t seed = 1;  ///< seed of CGAL's optimisation (Chang et al. 2011, as in CGAL)
  /// CGAL's optimisation searches the axes over the hull corners extreme along this many
  /// directions spread over the sphere (0: over every hull corner); the box is then fitted
  /// to every corner. Its cost grows with the points searched.
  std::size_t search_directions = 512;
};

struct OrientedBoxResult {
  OrientedBox box;
  TriangleMesh mesh;        ///< the box as a closed triangle mesh, as axis_aligned_box_mesh
  double inflation_world;   ///< how far the faces were pushed out so that rounding cannot cut a vertex
  const char* axes_from;    ///< which candidate won: "cgal", "principal axes", "axis-aligned", "plane"
};

/// The smallest-volume box among CGAL's optimal bounding box (its search run on the
/// corners of the exact convex hull extreme along options.search_directions directions),
/// the principal-axes box and the axis-aligned box (for a flat input: the smallest-area
/// rectangle in its plane, given the thickness axis_aligned_box_mesh gives a flat input),
/// each fitted to every hull corner; the first two are then turned
/// about their axes, in steps from 2 degrees down to about 0.004, while the box shrinks.
/// On the libcgal-demo meshes the box is within 0.05 % of the volume of the search over
/// every corner, and 3.5x faster on bunny00 (2632 hull corners).
/// Every vertex is proved inside or on the resulting mesh with exact predicates; when
/// rounding of the corners would leave one outside, the box grows by a few ulps of the
/// diagonal until none is. Same errors as axis_aligned_box_mesh.
OrientedBoxResult build_oriented_box(const TriangleMesh& mesh, const OrientedBoxOptions& options = {});

/// A box as a closed, outward-oriented triangle mesh (corners welded, zero-area
/// triangles dropped).
TriangleMesh box_mesh(const std::array<Vertex, 8>& corners);

/// Whether every point is inside or on the closed, outward-oriented mesh `box` (exact
/// predicates): the oriented box's containment proof, for boxes whose faces rounding may
/// leave slightly bent. Points on or behind every triangle's plane and strictly behind one
/// are held without more ado; the others are located by winding numbers, unless the mesh is
/// convex.
bool holds_every_point(const TriangleMesh& box, const std::vector<Vertex>& points);

}  // namespace visproxy
