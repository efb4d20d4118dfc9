#pragma once
// Geometric checks decided with exact predicates (CGAL's filtered kernel), so the
// answers do not depend on rounding: collinear corners and self-intersections.

#include <cstdint>
#include <utility>
#include <vector>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

/// Indices of the triangles whose corners are collinear (zero area), repeated corners included.
std::vector<std::uint32_t> find_degenerate_triangles(const TriangleMesh& mesh);

/// Pairs (i < j) of non-degenerate triangles that intersect anywhere other than in the
/// vertices and edges they share by index: crossing, touching, or overlapping triangles,
/// and triangles that share an edge but fold onto each other. Candidate pairs come from
/// CGAL's box intersection, each is then decided exactly.
/// Vertices with equal coordinates but different indices are not shared: weld first.
std::vector<std::pair<std::uint32_t, std::uint32_t>> find_self_intersections(const TriangleMesh& mesh);

}  // namespace visproxy
