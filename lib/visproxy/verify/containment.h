#pragma once
// Exact containment checks: does a closed mesh contain points, or a whole surface?
// Everything here is decided with exact predicates on the double coordinates as stored:
// no tolerance, no rounding.
//
// A closed mesh (every edge used as often in one direction as in the other, EdgeBalance)
// has a winding number that is constant off its surface; its solid is where that number
// is not zero. The solid is well defined even where the surface self-intersects, has
// non-manifold edges or consists of several overlapping parts (one proxy per component).

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "visproxy/mesh/mesh_topology.h"
#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

/// Where a point lies relative to a closed container mesh.
enum class PointLocation : std::uint8_t { inside, on_boundary, outside };

/// Location of each point (#P entries) relative to `container`, by the winding number of
/// the container around the point: a point is inside when the winding number is not zero,
/// so a container made of several overlapping closed parts (one proxy per component)
/// contains the union of their volumes. Points on a triangle are `on_boundary`.
/// The winding number is counted along a ray with exact orientation predicates; rays
/// that meet an edge or a vertex are replaced by another seeded direction. Degenerate
/// (zero-area) triangles do not separate anything and are ignored. The first rays share one
/// direction and are met with the triangles in one parallel pass (the points binned across
/// that direction): linear in the triangles, with no tree to build; the answer does not
/// depend on the number of threads.
/// Precondition: `container` is closed (EdgeBalance); for an open container the answer
/// depends on the ray. Throws InvalidInputError (empty file name) for coordinates beyond
/// kMaxCoordinate.
std::vector<PointLocation> locate_points(const TriangleMesh& container, std::span<const Vertex> points);

/// For each point, whether it lies strictly beyond the plane of some non-degenerate triangle
/// of `mesh`, on the side its normal (right-handed winding) points to; decided exactly. For
/// a closed convex mesh with outward faces, the points not marked are those of its solid.
/// The points are boxed in a tree and each plane passes over whole boxes it is proved not
/// to cut (interval arithmetic), so a tight convex mesh of m faces costs about
/// m log n + n, not m * n, orientation tests. Throws InvalidInputError (empty file name)
/// for coordinates beyond kMaxCoordinate.
std::vector<std::uint8_t> beyond_face_planes(const TriangleMesh& mesh, std::span<const Vertex> points);

/// Pairs (container triangle, contents triangle) that meet, exactly (touching counts).
/// Degenerate contents triangles are tested as the segment or point they are; degenerate
/// container triangles are skipped (they bound nothing).
std::vector<std::pair<std::uint32_t, std::uint32_t>> find_crossing_triangles(const TriangleMesh& container,
                                                                              const TriangleMesh& contents);

struct ContainmentOptions {
  /// Prove the whole contents surface contained, not only its vertices.
  bool check_surface = true;
  /// Also prove the contents' solid inside the container's: the contents closed, no
  /// contents triangle meeting the container's surface (touching is not allowed, the
  /// convex-part argument is not used) and no container vertex inside the contents.
  /// This is what an inside proxy made of triangles claims.
  bool contents_solid = false;
};

struct Containment {
  /// The container is not closed: how many edges are unbalanced, and the first one
  /// (nothing else is decided then: the container has no solid).
  EdgeBalance container_edges;
  EdgeBalance contents_edges;  ///< contents_solid only
  std::size_t vertices_checked = 0;      ///< vertices the contents' triangles use
  std::size_t vertices_outside = 0;      ///< strictly outside the container
  std::size_t vertices_on_boundary = 0;  ///< exactly on a container triangle (still contained)
  bool surface_checked = false;
  /// Contents triangles that meet the container's surface. Each must lie in one convex
  /// part of the container (below), else it is unproved.
  std::size_t triangles_touching = 0;
  /// Touching triangles proved inside a convex part: a connected component of the
  /// container whose own vertices all lie behind or on every one of its face planes, with
  /// the triangle's corners behind or on them too. The intersection of the inner
  /// half-spaces of a closed, consistently oriented surface lies in its solid (every face
  /// adds a non-negative solid angle there, at least one a positive one, and the total is
  /// an integer), so such a triangle lies in the container's solid.
  std::size_t triangles_in_convex_parts = 0;
  std::size_t triangles_unproved = 0;   ///< touching and in no convex part
  /// The container is one closed convex part (tested, as for triangles_in_convex_parts),
  /// and it was decided by its face planes alone: vertices by their side of every plane
  /// (on_boundary: on some plane, behind the others), triangles by their corners. Then
  /// triangles_touching counts the contents triangles with a corner on the surface (a
  /// triangle with its corners in a convex solid meets its surface only there), all of them
  /// in the convex part. Only a proof that holds is decided so: with a vertex outside, the
  /// general check runs and reports what it finds.
  bool convex_container = false;
  std::size_t container_vertices_inside_contents = 0;  ///< contents_solid only
  std::optional<VertexIndex> first_vertex_outside;  ///< lowest index of a vertex outside
  /// Lowest (container triangle, contents triangle) pair of an unproved triangle.
  std::optional<std::pair<std::uint32_t, std::uint32_t>> first_unproved;
  std::optional<VertexIndex> first_container_vertex_inside;  ///< contents_solid only
  /// Every claim checked holds.
  bool contained() const {
    return container_edges.balanced() && contents_edges.balanced() && vertices_outside == 0 &&
           triangles_unproved == 0 && container_vertices_inside_contents == 0;
  }
};

/// Whether `container` contains `contents` (see ContainmentOptions), proved exactly:
///  1. the container is closed (Containment::container_edges), else nothing else is tested;
///  2. every contents vertex is inside or on the container (locate_points);
///  3. (check_surface) every contents triangle either meets no container triangle, so that
///     with its corners inside it stays inside (the winding number only changes across the
///     surface), or lies in one convex part of the container (triangles_in_convex_parts).
/// A container that is one convex part holding every contents vertex (unless
/// contents_solid) is decided by its face planes alone (Containment::convex_container):
/// about m log n orientation tests for m faces and n vertices, no rays or triangle pairs.
/// Nothing is read from how the container was made: convexity is tested, not assumed.
Containment check_containment(const TriangleMesh& container, const TriangleMesh& contents,
                              const ContainmentOptions& options = {});

struct ClosestDistance {
  double distance = 0;     ///< world units; +infinity when there are no points or no triangles
  std::size_t point = 0;   ///< index of the point that attains it
};

/// The smallest Euclidean distance from any of `points` to the surface of `mesh` (its
/// triangles, closest points computed in double precision by CGAL's AABB tree; accurate
/// to rounding, not exact). For a proxy that contains the mesh, the distance from the
/// mesh's vertices to the proxy's surface is the margin by which it contains them.
ClosestDistance closest_distance_to_surface(const TriangleMesh& mesh, std::span<const Vertex> points);

/// Whether no point of `a`'s surface lies within `distance` of `b`'s surface (both
/// triangle meshes; degenerate triangles count as the segments or points they are).
/// Triangle pairs whose boxes come within `distance` are compared by their exact
/// intersection test and then by the smallest of their vertex-triangle and edge-edge
/// distances computed in double precision, with `distance` enlarged by 1e-12 relative so
/// that rounding cannot pass a pair that is closer. Used to check that a proof made in
/// double survives the conversion of both surfaces to float (renderers).
bool surfaces_clear_by(const TriangleMesh& a, const TriangleMesh& b, double distance);

}  // namespace visproxy
