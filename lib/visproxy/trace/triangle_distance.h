#pragma once
// Distances from points to the triangles of a mesh, in double precision, through an Embree
// BVH whose boxes hold the double-precision triangles (bounds rounded outwards), so that
// culling never drops a triangle nearer than the answer.

#include <cstdint>
#include <memory>
#include <vector>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

/// Squared distance from p to the triangle (a, b, c), in double precision: the distance to
/// the nearest point of the closed triangle (its corners, sides or inside). A triangle with
/// collinear corners is measured as the segments it spans.
double point_triangle_squared_distance(const Vertex& p, const Vertex& a, const Vertex& b, const Vertex& c);

/// The point of the closed triangle (a, b, c) nearest to p, in double precision; for a
/// triangle with collinear corners, the nearest point of the segments they span.
Vertex point_triangle_nearest_point(const Vertex& p, const Vertex& a, const Vertex& b, const Vertex& c);

/// The triangles `triangles` (indices into mesh.triangles) of `mesh` in a BVH (Embree user
/// geometry; built in parallel). The mesh must outlive it and not change. Queries are
/// const and may run on several threads at once.
class TriangleDistance {
 public:
  TriangleDistance(const TriangleMesh& mesh, std::vector<std::uint32_t> triangles);
  ~TriangleDistance();
  TriangleDistance(const TriangleDistance&) = delete;
  TriangleDistance& operator=(const TriangleDistance&) = delete;

  /// The smallest point_triangle_squared_distance from p to the triangles (infinity when
  /// there are none): every triangle whose box may hold a nearer point is measured. The BVH
  /// holds the triangles moved to be centred on the origin; the search radius Embree culls
  /// with (single precision, about p moved the same way and rounded to single precision) is
  /// the distance found so far plus 2^-18 of the moved coordinates' magnitude and 2^-40 of
  /// the absolute ones, far above the rounding of those tests and of the move.
  double squared_distance(const Vertex& p) const;

  /// Whether some triangle has a point_triangle_squared_distance below `squared_radius`
  /// from p (the search stops at the first).
  bool within(const Vertex& p, double squared_radius) const;

  std::size_t size() const;
  /// The triangles' indices into mesh.triangles, as given.
  const std::vector<std::uint32_t>& triangles() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace visproxy
