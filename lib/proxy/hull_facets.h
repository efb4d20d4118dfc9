#pragma once
// Internal to lib/proxy (not installed, not a public API): what the convex builders share
// about closed triangulated polytopes.

#include <cstddef>
#include <cstdint>
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
