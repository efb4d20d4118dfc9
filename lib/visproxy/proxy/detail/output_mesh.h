#pragma once
// The mesh a simplifier hands back: its surviving triangles, cleaned the same way for
// every simplifier.

#include <span>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy::detail {

/// `triangles` (indices into `positions`) without those with a repeated index or exactly
/// collinear corners (CGAL's exact predicate) and without repeats of the same three
/// vertices in any order (the first is kept), over the vertices they use, numbered in
/// order of first use.
TriangleMesh clean_output_mesh(std::span<const Vertex> positions, std::span<const Triangle> triangles);

}  // namespace visproxy::detail
