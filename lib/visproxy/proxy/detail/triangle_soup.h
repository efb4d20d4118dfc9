#pragma once
// The point sets that the triangles of a soup stand for: triangles with collinear corners
// are segments or points, and the proxy builders must enclose those too.

#include <cstdint>
#include <utility>
#include <vector>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

struct SoupPrimitives {
  std::vector<std::uint32_t> triangle_indices;      ///< triangles with non-collinear corners (indices)
  std::vector<std::pair<Vertex, Vertex>> segments;  ///< collinear corners: the two extreme ones
  std::vector<Vertex> points;                       ///< three equal corners
};

/// Sorts `mesh.triangles` (indices assumed valid) into the three kinds, deciding
/// collinearity and the extreme corners exactly (CGAL's filtered predicates). Order is kept.
SoupPrimitives soup_primitives(const TriangleMesh& mesh);

}  // namespace visproxy
