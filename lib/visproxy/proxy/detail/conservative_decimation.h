#pragma once
// Private to lib/visproxy/proxy (detail/, not installed): conservative edge-collapse decimation of a closed
// surface that keeps clear of an input, shared by outer:N (the surface encloses the input)
// and inner:N (the surface lies inside the input's solid). CGAL stays in the .cpp.

#include <cstddef>
#include <memory>
#include <vector>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {
class TriangleBoxTree;
struct SoupPrimitives;
}

namespace visproxy::detail {

/// Where the input lies relative to a surface that keeps clear of it.
enum class InputSide {
  inside,   ///< the surface encloses every input component (outer hulls)
  outside,  ///< every input component lies outside the surface (inner hulls)
};

/// The input of a conservative surface: its triangles (exact intersection tests), one point
/// per connected component (side tests) and distance queries. The input must outlive it.
class ConservativeInput {
 public:
  explicit ConservativeInput(const TriangleMesh& input);
  ~ConservativeInput();
  ConservativeInput(const ConservativeInput&) = delete;
  ConservativeInput& operator=(const ConservativeInput&) = delete;

  /// Whether `surface` can start a decimation, decided with exact predicates: closed,
  /// 2-manifold, consistently oriented, free of self-intersections and of triangles whose
  /// corners are collinear, meeting no input triangle, with every input component on
  /// `side` (exact ray parity). For InputSide::inside also every component of `surface`
  /// encloses a positive volume (outward orientation); for InputSide::outside the whole
  /// surface encloses a negative one (its normals face inwards, away from the input).
  bool starts_conservative(const TriangleMesh& surface, InputSide side) const;

  /// Indices of the triangles of `surface` that meet an input triangle, decided exactly
  /// (touching counts; a triangle with collinear corners as its sides, one with equal
  /// corners always), in increasing order.
  std::vector<std::size_t> triangles_meeting(const TriangleMesh& surface) const;

  /// The BVH of the input's triangles with non-collinear corners (soup_primitives'
  /// triangle_indices), for the alpha wrap that starts an outer hull.
  const TriangleBoxTree& triangles() const;
  /// The segments and points the input's other triangles span (soup_primitives; its
  /// triangle_indices are in triangles()).
  const SoupPrimitives& degenerate() const;

  /// Whether no triangle of `surface` meets the input (exact) or comes within `clearance`
  /// of it, through the input's BVH: double-precision distances against `clearance`
  /// enlarged as surfaces_clear_by enlarges it (1e-9 relative and 2^-40 of the coordinates'
  /// magnitude), so at least as strict as surfaces_clear_by(surface, input, clearance)
  /// without its pass over every input triangle. A triangle with collinear corners counts
  /// as not clear.
  bool keeps_clear(const TriangleMesh& surface, double clearance) const;

  /// Euclidean distance from `p` to the input (double precision, BVH over its triangles).
  double distance(const Vertex& p) const;

  /// An upper bound of the distance from any point of `surface` to the input: the distance
  /// is 1-Lipschitz, so over a triangle split into similar pieces no longer than
  /// `resolution` it is at most the largest distance at the piece corners plus their side.
  double distance_bound(const TriangleMesh& surface, double resolution) const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
  friend class ConservativeDecimator;
};

/// Edge collapses and vertex moves on a surface that starts_conservative accepted, each
/// checked exactly before it is made so that the surface stays closed, 2-manifold,
/// self-intersection-free and clear of the input, with every input component on the side
/// it started on. The surface's normals must face away from the input (outward for outer
/// hulls, inward for inner hulls): a merged vertex that fails the checks where the quadric
/// error is least is tried again on the far side of the planes of the triangles it
/// replaces, as in progressive hulls, and vertex moves go along minus the normal, towards
/// the input.
class ConservativeDecimator {
 public:
  ConservativeDecimator(const TriangleMesh& surface, const ConservativeInput& input);
  ~ConservativeDecimator();
  ConservativeDecimator(const ConservativeDecimator&) = delete;
  ConservativeDecimator& operator=(const ConservativeDecimator&) = delete;

  std::size_t triangle_count() const;
  /// From now on every new triangle must also keep `clearance` (world units, double
  /// precision distances) from the input, on either side; 0 (the default) asks only that
  /// it does not meet the input.
  void keep_clear_by(double clearance);
  /// Collapses edges, the one of least quadric error first (Garland & Heckbert: the area-
  /// weighted squared distances to the planes of the surface at the start or after the
  /// last move_towards_input, summed over the merged vertices), until at most
  /// `max_triangles` remain or no collapse passes the checks. Once at most twice
  /// `max_triangles` remain, the merged vertex goes to the quadric's minimiser first; before
  /// that, and when the minimiser fails the checks, to the position beyond the planes of
  /// the star that adds the least volume (progressive hulls), at that position's error.
  void collapse_edges(std::size_t max_triangles);
  /// Moves each vertex towards the input, along minus its normal, by 90 %, 60 % or 30 % of
  /// its distance to the input less the clearance (keep_clear_by): the first that passes
  /// the checks. A vertex then stays at least 0.1 x its distance + 0.9 x the clearance away.
  /// The quadrics are then made again from the moved surface.
  void move_towards_input();
  /// The current surface, with unused vertices dropped.
  TriangleMesh result() const;

  class Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace visproxy::detail
