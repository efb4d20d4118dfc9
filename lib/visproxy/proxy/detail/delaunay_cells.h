#pragma once
// The tetrahedra of a 3D Delaunay triangulation with their circumscribed spheres: shared
// by the sphere-set builders (circumsphere sets and medial-axis poles).

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "visproxy/mesh/sphere_set.h"
#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

struct DelaunayCell {
  std::array<std::uint32_t, 4> corners{};  ///< indices into the points
  Sphere circumsphere;                     ///< computed in double precision
};

/// Every finite cell of the Delaunay triangulation of `points` (CGAL Delaunay_triangulation_3,
/// exact predicates), with its circumsphere. Repeated points are triangulated once (the
/// cells use the first index). Cells whose circumsphere cannot be computed in doubles
/// (flat to rounding) are left out. Points all on one plane give no cells. Deterministic.
std::vector<DelaunayCell> delaunay_cells(std::span<const Vertex> points);

/// The circumscribed sphere of a tetrahedron in double precision; radius 0 and the centroid
/// as centre when the corners are flat to rounding.
Sphere tetrahedron_circumsphere(const Vertex& a, const Vertex& b, const Vertex& c, const Vertex& d);

/// The smallest ball holding the four points (the circumsphere when its centre is inside
/// the tetrahedron, otherwise the smallest ball through two or three of them that holds
/// the rest), in double precision; the radius is enlarged by a relative 1e-12 so that
/// rounding never leaves a corner outside.
Sphere smallest_enclosing_ball(const Vertex& a, const Vertex& b, const Vertex& c, const Vertex& d);

}  // namespace visproxy
