#pragma once
// Closed convex meshes as intersections of half-spaces, tested against segments by
// clipping (Cyrus-Beck): a few dot products per face and no acceleration structure, far
// cheaper than a BVH query for boxes and bounded hulls of a few dozen faces.

#include <Eigen/Geometry>
#include <optional>
#include <vector>

#include "visproxy/mesh/sphere_set.h"
#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

/// The solid bounded by a closed convex mesh: points x with normal . x <= offset for every
/// face plane. Solid, not surface: a segment inside it meets it.
class ConvexPolytope {
 public:
  struct Plane {
    Vertex normal;  ///< unit, pointing out of the solid
    double offset = 0;
  };

  /// The polytope of `mesh` when the mesh is a closed convex solid with outward faces and
  /// at most `max_planes` distinct face planes: every vertex lies behind (or within
  /// `tolerance` of) every face's plane, the winding's normals enclose a positive volume.
  /// Each plane is pushed out by `tolerance` (default: 1e-9 of the bounding-box diagonal),
  /// so the solid holds the mesh's own solid despite rounding. nullopt otherwise (not
  /// closed convex, degenerate, too many planes).
  static std::optional<ConvexPolytope> from_mesh(const TriangleMesh& mesh, std::size_t max_planes = 64);

  /// The image of the polytope under an affine map (planes mapped exactly, renormalised).
  ConvexPolytope transformed(const Eigen::Affine3d& transform) const;

  /// The polytope with every plane pushed out by `distance` (world units), and its
  /// bounding ball grown to hold the result: for rounding bounds of the tests that use it.
  ConvexPolytope grown(double distance) const;

  /// The smallest distance from `point` (inside) to a face plane: the radius of the
  /// largest ball about it that the polytope holds. Negative when the point is outside.
  double inner_distance(const Vertex& point) const;

  /// Whether the closed segment from `from` to `to` meets the solid.
  bool meets_segment(const Vertex& from, const Vertex& to) const;

  const std::vector<Plane>& planes() const { return planes_; }

  /// A ball holding the solid: a segment that misses it misses the solid.
  Sphere bounding_ball() const { return {center_, radius_}; }

 private:
  void pack();  ///< fills packed_ from planes_

  std::vector<Plane> planes_;
  /// The planes in blocks of four, each block nx[4] ny[4] nz[4] offset[4] (padded with
  /// planes that hold everything), so that the clipping loop runs branch-free four at a time.
  std::vector<double> packed_;
  Vertex center_ = Vertex::Zero();  ///< a ball holding the solid: segments that miss it are rejected first
  double radius_ = 0;
};

/// Scales a closed convex `mesh` (at most `max_planes` face planes, as from_mesh) about
/// the centroid of its vertices so that its solid holds every point within `distance` of
/// its solid before: a convex body holding a ball of radius r about c holds, scaled by
/// 1 + distance / r about c, every point within distance of it. Returns false, and leaves
/// the mesh as it is, when it is not closed convex or its centroid is not inside it.
bool grow_convex_mesh(TriangleMesh& mesh, double distance, std::size_t max_planes);

}  // namespace visproxy
