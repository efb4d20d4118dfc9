#pragma once
// Midpoint subdivision: more triangles over the same surface, for making large test inputs.

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

/// Splits every triangle into four at its edge midpoints, `levels` times (levels >= 0), so
/// the triangle count grows by 4^levels. Triangles that share an edge by index share its
/// midpoint vertex, so a watertight (closed, manifold) mesh stays watertight and keeps its
/// orientation; the shape does not change (the new vertices lie on the old triangles).
/// Vertices keep their indices; each level appends one vertex per distinct edge. An edge
/// whose ends are one index (a degenerate triangle) gets no new vertex.
///
/// Throws InvalidInputError (empty file name) if an index is out of range or the result
/// would have more than 2^32 - 1 vertices or triangles.
TriangleMesh subdivide_midpoint(const TriangleMesh& mesh, int levels);

}  // namespace visproxy
