#pragma once
// A non-convex *outside* proxy with a triangle budget: a closed surface of at most N
// triangles that provably contains the input surface, much tighter than its convex hull.

#include <cstddef>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

struct OuterHullOptions {
  std::size_t max_triangles = 512;  ///< triangle budget; must be at least 4
  /// Alpha of the starting wrap, relative to the bounding-box diagonal (see AlphaWrapOptions).
  /// Default 1/30: on the libcgal-demo meshes a wrap of 2,500-3,000 triangles, detailed
  /// enough that the budget of a few hundred triangles, not the wrap, decides what is kept,
  /// coarse enough that wrapping stays within about two seconds.
  double wrap_alpha_relative = 1.0 / 30;
  /// Offset of the starting wrap, relative to the diagonal. Default 1/600 (0.17 %): the gap
  /// between the input and the wrap the decimation starts from.
  double wrap_offset_relative = 1.0 / 600;
  /// Clearance every new triangle keeps from the input, relative to the bounding-box
  /// diagonal (double-precision distances; see InnerHullOptions::clearance_relative): a
  /// proxy that keeps it keeps its proof in single-precision renderers, which use a proxy
  /// that comes within their rounding bound only as a general proxy. If the collapses
  /// cannot reach the budget with it, they are made again without it (clearance_kept then
  /// says whether the result keeps it anyway). 0 asks only that no triangle meets the input.
  double clearance_relative = 1e-4;
};

struct OuterHullResult {
  TriangleMesh mesh;            ///< the proxy, outward-oriented
  bool reached_target = false;  ///< mesh has at most max_triangles triangles
  std::size_t wrap_triangles = 0;   ///< triangles of the alpha wrap decimation started from
  double wrap_alpha_world = 0;      ///< alpha of that wrap, in input units
  double wrap_offset_world = 0;     ///< offset of that wrap, in input units
  /// Upper bound of the distance from any point of the proxy surface to the input: the
  /// largest distance from sample points on every proxy triangle to the input, plus the
  /// distance from any point of that triangle to its nearest sample. A bound, not an
  /// estimate (up to the rounding of the distance computations).
  double max_distance_to_input_world = 0;
  double clearance_world = 0;  ///< clearance_relative x the input's diagonal
  /// Whether every point of the proxy surface is farther than clearance_world from the
  /// input (tested through the input's BVH at least as strictly as surfaces_clear_by; the
  /// exact containment holds either way).
  bool clearance_kept = false;
};

/// Outer hull of at most `max_triangles` triangles: the input is alpha-wrapped
/// (build_alpha_wrap), then edges of the wrap are collapsed greedily, the collapse of least
/// quadric error first (Garland & Heckbert 1997), each merged vertex placed where that
/// error is least or, if the checks below refuse that position, as in progressive hulls
/// (Sander, Gu, Gortler, Hoppe, Snyder 2000) on the outer side of the planes of all the
/// triangles it replaces, at the point that minimises the added volume (a 3-variable LP).
/// When the collapses stall above the budget (every remaining collapse would fold the mesh
/// into itself), every vertex is moved towards the input and the collapses resume, up to
/// three times. Finally every vertex is moved towards the input (along minus its normal, by
/// at most 90 % of its distance to the input) where the checks below allow it. Every new
/// triangle also keeps clearance_relative of the diagonal from the input; if the budget is
/// not reached so, the decimation is made again without that clearance.
///
/// Guarantees, checked with exact predicates (CGAL's filtered kernel) at every step rather
/// than assumed from the construction:
/// - the result is closed, 2-manifold, consistently oriented and free of self-intersections,
///   with no triangle whose corners are collinear;
/// - no proxy triangle touches any input triangle, and every input triangle is strictly
///   inside the proxy (the starting wrap is checked for both; each collapse keeps the link
///   condition, creates no intersection with the input or the rest of the proxy, and
///   swallows no input component, decided by an exact parity test);
/// - never more triangles than the wrap had. If the budget cannot be reached without
///   breaking a guarantee (a budget below what the shape's components allow, or collapses
///   that all stray into the input or the proxy itself), the smallest mesh reached is
///   returned with `reached_target = false`: never a non-conservative one.
/// - deterministic: the same input and options give the same output, bit for bit.
///
/// The input is any triangle soup (holes, non-manifold edges, self-intersections, several
/// components, degenerate triangles); see build_alpha_wrap. If CGAL's wrap ever touches the
/// input (floating-point Steiner points), it is rebuilt with twice the offset, up to three
/// times, before giving up with visproxy::Error.
///
/// Throws InvalidInputError (empty file name) for max_triangles < 4, wrap options that are
/// not positive finite numbers, clearance_relative outside [0, 0.1), and any input
/// build_alpha_wrap rejects.
OuterHullResult build_outer_hull(const TriangleMesh& input, const OuterHullOptions& options);

}  // namespace visproxy
