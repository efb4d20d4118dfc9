#pragma once
// Quadric edge-collapse decimation to a triangle budget: a *general* proxy (neither inside
// nor outside the input).

#include <cstddef>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

struct QuadricSimplifyOptions {
  std::size_t max_triangles = 512;  ///< triangle budget of the result; must be at least 1
};

struct QuadricSimplifyResult {
  TriangleMesh mesh;
  /// Square root of the largest quadric error of any collapse made, relative to the input's
  /// bounding-box diagonal. A vertex's quadric is normalised by the area it stands for, so
  /// this is the area-weighted RMS distance from the merged vertex to the planes of the
  /// triangles it replaced (border planes included): a measure of the error, not a bound
  /// on the Hausdorff distance (measure that with sampled_hausdorff_distance).
  double max_quadric_error_relative = 0;
  std::size_t collapses = 0;  ///< edge collapses made
};

/// Collapses edges, cheapest first by the quadric error metric, until at most
/// `options.max_triangles` triangles remain (Garland & Heckbert 1997). Border edges carry an
/// extra plane quadric perpendicular to their triangle, so holes and open borders keep their
/// shape. Each merged vertex goes to the point that minimises its quadric, or, where that
/// system is ill-conditioned, to the best of the two end points and the midpoint. Collapses
/// are made in passes (each rates all edges once and collapses in that order, one collapse
/// per vertex per pass), so the order is greedy within a pass, not across the whole run.
///
/// Guarantees, for any input with at least one triangle:
/// - at most `max_triangles` triangles, always; no NaN or infinite coordinate;
/// - no triangle with a repeated index or with collinear corners (decided exactly), no two
///   triangles over the same three vertices (in either orientation: the first is kept), no
///   unreferenced vertex; these removals can leave fewer triangles than the budget;
/// - vertices that never moved keep their input coordinates exactly;
/// - deterministic: the same input and options give the same output, bit for bit.
///
/// Quality rules: a collapse is refused if it would flip a triangle (turn its normal by 90
/// degrees or more), break the link condition (make the surface non-manifold), join two
/// border vertices across the interior, duplicate a triangle, or leave no triangle. When no
/// allowed collapse is left above the budget (tiny budgets, non-manifold input, triangle
/// soups), the rules are relaxed one at a time instead of stopping short: first flips are
/// allowed, then every collapse but the last; as a last resort the smallest triangles are
/// dropped. The result then may fold or self-intersect, and the dropped triangles are not in
/// `max_quadric_error_relative`.
///
/// Input: triangles may index any vertex; vertices with identical coordinates are treated as
/// one, so soups and split seams simplify as connected surfaces. Non-manifold edges, borders
/// and several components are accepted. Triangles with a repeated index (after merging equal
/// vertices) are ignored, so a mesh of only such triangles gives an empty result.
///
/// Throws InvalidInputError (empty file name) if `max_triangles` is 0, the mesh has no
/// triangle, an index is out of range, or a used coordinate is not finite.
QuadricSimplifyResult simplify_quadric(const TriangleMesh& mesh, const QuadricSimplifyOptions& options);

}  // namespace visproxy
