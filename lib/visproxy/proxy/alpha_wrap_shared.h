#pragma once
// Private to lib/visproxy/proxy (not installed): the alpha wrap of an input whose triangles are
// already in a BVH, for builders that keep that BVH for checks of their own (outer:N).

#include "visproxy/proxy/alpha_wrap.h"
#include "visproxy/proxy/detail/triangle_soup.h"

namespace visproxy {
class TriangleBoxTree;
}

namespace visproxy::detail {

/// The checks build_alpha_wrap makes of its input and options; throws as it does.
void check_alpha_wrap_input(const TriangleMesh& mesh, const AlphaWrapOptions& options);

/// build_alpha_wrap of an input that passed check_alpha_wrap_input, whose triangles with
/// non-collinear corners (soup_primitives' triangle_indices) are in `triangles`, and whose
/// other triangles span the segments and points of `degenerate` (its triangle_indices are
/// not read).
AlphaWrapResult build_alpha_wrap(const TriangleMesh& mesh, const AlphaWrapOptions& options,
                                 const TriangleBoxTree& triangles, const SoupPrimitives& degenerate);

}  // namespace visproxy::detail
