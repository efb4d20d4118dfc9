#pragma once
// The exact convex hull of a triangle mesh, the tightest convex outside proxy.

#include <cstddef>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

struct ConvexHullResult {
  /// Outward-oriented, closed, manifold triangles over the hull's corners only (no
  /// unreferenced vertices). Coplanar facets are triangulated. Every position is an input
  /// position, bit for bit.
  TriangleMesh mesh;
  /// Planar facets: triangles that share an edge and lie in one plane (decided exactly)
  /// count once. 2 for a flat hull (its two sides).
  std::size_t faces = 0;
  /// Enclosed volume in mesh units cubed; 0 for a flat hull.
  double volume = 0.0;
};

/// Convex hull of the vertices that `mesh`'s triangles reference (unreferenced vertices
/// are ignored; duplicated vertices are harmless). Decided with exact predicates (CGAL's
/// convex_hull_3), so every input vertex is inside the output or on it, exactly: on the
/// inner side of, or on, the plane of every output triangle.
///
/// Flat input (all referenced vertices coplanar, e.g. one triangle): the hull is the
/// convex polygon of the vertices, a zero-volume "hull" that still contains every vertex.
/// It is returned closed, as two triangulated sides facing away from each other (each
/// side fanned from a different corner, so no edge has more than two triangles), with
/// faces = 2 and volume = 0.
///
/// Throws InvalidInputError when there is nothing to hull: no triangles, or all
/// referenced vertices at one point or on one line.
/// O(#V log #V) expected.
ConvexHullResult build_convex_hull(const TriangleMesh& mesh);

}  // namespace visproxy
