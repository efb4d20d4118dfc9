#pragma once
// A convex polytope with few faces that provably contains a mesh: the exact convex hull
// simplified by removing half-spaces, never by moving a face inward.

#include <cstddef>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

struct BoundedHullOptions {
  /// Most planar faces the result may have; at least 4.
  std::size_t max_faces = 32;
};

struct BoundedHullResult {
  /// Outward-oriented, closed, manifold triangles; each planar face is fanned from one corner.
  TriangleMesh mesh;
  /// Planar faces of the result (<= max_faces).
  std::size_t faces = 0;
  /// Enclosed volume of `mesh` (mesh units cubed).
  double volume = 0.0;
  /// Volume of the exact convex hull of the input (ConvexHullResult::volume).
  double exact_hull_volume = 0.0;
  /// (volume - exact_hull_volume) / exact_hull_volume: the volume added to the exact hull,
  /// relative to it; 0 when the exact hull is flat (both volumes are 0 then).
  double added_volume_fraction() const {
    return exact_hull_volume > 0.0 ? (volume - exact_hull_volume) / exact_hull_volume : 0.0;
  }
};

/// A convex polytope with at most `options.max_faces` planar faces that contains every
/// vertex the triangles of `mesh` reference, with as little added volume as the greedy
/// method finds.
///
/// Method: start from the planes of the exact convex hull's facets (build_convex_hull,
/// coplanar facets merged) and repeatedly remove the plane whose removal adds the least
/// volume; a removal that would leave an unbounded region is never taken (decided
/// exactly). Removing a half-space only grows the polytope, so it contains the hull. The
/// kept planes are then moved out to touch the hull vertices, the polytope's corners are
/// computed exactly from the planes and rounded to double, and containment is checked with
/// exact predicates on the output triangles: every input vertex must lie strictly on the
/// inner side of the plane of every (non-degenerate) output triangle. Where rounding left a
/// vertex outside or on a plane, the offending planes are moved outward by a few units in
/// the last place of the coordinates (doubled each round) and the check is repeated until
/// it passes, so the returned mesh contains every input vertex strictly and no input
/// triangle touches it: `verify` proves it without relying on the output's convexity,
/// which the rounding of its corners breaks.
///
/// Where more than three kept planes meet at one point (often at a hull vertex), the
/// rounded planes meet in several corners a rounding error apart: the mesh then has tiny
/// edges and sliver triangles there, and is convex up to that rounding.
///
/// Returns the exact hull itself when it already has at most max_faces faces.
/// A flat input (all vertices coplanar) is returned as its exact flat hull (see
/// build_convex_hull: two sides, faces = 2, volume = 0) when its polygon has at most
/// max_faces edges.
///
/// Throws InvalidInputError when the input has no hull (build_convex_hull), when
/// max_faces < 4, when a flat input's polygon has more than max_faces edges (a simpler
/// polygon's new corners could not be kept in the input's plane exactly), and when no
/// plane can be removed without leaving an unbounded region before max_faces is reached
/// (by Steinitz's theorem some plane of 7 or more is always removable, so this happens
/// for max_faces 4 or 5 only, e.g. a box asked for 5 faces).
///
/// O(H log H) for H hull facets when the faces have boundedly many neighbours (each removal
/// is cubic in its face's neighbour count), plus O(V_hull * max_faces) for the containment
/// check. Deterministic: the same input and options give the same mesh, bit for bit.
BoundedHullResult build_bounded_hull(const TriangleMesh& mesh, const BoundedHullOptions& options = {});

}  // namespace visproxy
