#pragma once
// Internal to lib/proxy (not installed, not a public API): what the convex builders share
// about closed triangulated polytopes.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "mesh/triangle_mesh.h"

namespace visproxy::hull_detail {

/// Convex hull of `points`, which must not all be coplanar, decided with exact
/// predicates (CGAL's quickhull with its exact-predicate traits): its corners, each an
/// input point bit for bit, and its triangles over them, outward-oriented. Points that
/// are not corners (inside, or on a face or an edge) are left out, most of the time.
TriangleMesh exact_convex_hull(const std::vector<Vertex>& points);

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
