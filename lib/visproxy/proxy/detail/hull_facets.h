#pragma once
// Private to lib/visproxy/proxy (detail/, not installed): what the convex builders share
// about closed triangulated polytopes.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy::hull_detail {

/// Convex hull of `points`, which must not all be coplanar, decided with exact
/// predicates (CGAL's quickhull with its exact-predicate traits), in a canonical form that
/// does not depend on the order in which CGAL works: outward triangles over indices into
/// `points` (the lowest index among equal points); only the hull's corners are used
/// (points inside, on a face or on an edge are left out); each planar facet is fanned
/// from its lowest-index corner; the triangles are sorted.
std::vector<Triangle> exact_convex_hull(const std::vector<Vertex>& points);

/// The oriented plane through a, b and c, with the test hull_candidates() drops points by:
/// a point p within `reach` of a is certainly strictly below it (opposite to (b - a) x
/// (c - a)) when (b - a) x (c - a) . (p - a), computed in double, is below -slack, with
/// slack = 1e-12 |b - a| |c - a| reach. The rounding of the differences, the cross product
/// and the dot product stays under 1e-14 of that, relative to the differences (so far from
/// the origin too), and products that fall below the normal numbers err by less than the
/// smallest normal slack.
struct CertainPlane {
  Vertex a = Vertex::Zero(), normal = Vertex::Zero();
  double slack = 0;
  /// No plane when the slack is not a normal number, |b - a| |c - a| reach is above 1e300
  /// or the normal is not finite (coordinates so small or so large that the products
  /// underflow or could overflow).
  static std::optional<CertainPlane> through(const Vertex& a, const Vertex& b, const Vertex& c, double reach);
  bool certainly_below(const Vertex& p) const { return normal.dot(p - a) < -slack; }
};

/// The points exact_convex_hull() looks at among many (indices, ascending): all but those
/// certainly strictly inside the hull of the points extreme along the 26 directions of a
/// cube's faces, edges and corners (Akl and Toussaint's heuristic); all of them when that
/// hull is flat or its planes do not fit in double precision.
std::vector<std::size_t> hull_candidates(const std::vector<Vertex>& points);

/// Planar facet of each triangle of a closed, manifold triangle mesh (#F entries, numbered
/// 0.. in order of first appearance): two triangles that share an edge are in one facet
/// when their four corners are coplanar, decided exactly. `facet_count` receives the number
/// of facets.
std::vector<std::uint32_t> planar_facets(const TriangleMesh& mesh, std::size_t& facet_count);

/// Volume enclosed by a closed, outward-oriented triangle mesh (negative when inward):
/// the sum of the determinants of the triangles' corners relative to the first position,
/// divided by 6 once at the end, so that meshes with small integer coordinates get their
/// exact volume.
double enclosed_volume(const TriangleMesh& mesh);

}  // namespace visproxy::hull_detail
