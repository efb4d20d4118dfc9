#pragma once
// Exact containment checks: does a closed mesh contain points, or a whole surface?
// Everything here is decided with exact predicates on the double coordinates as stored:
// no tolerance, no rounding.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "mesh/triangle_mesh.h"

namespace visproxy {

/// Where a point lies relative to a closed, outward-oriented container mesh.
enum class PointLocation : std::uint8_t { inside, on_boundary, outside };

/// Location of each point (#P entries) relative to `container`, by the winding number of
/// the container around the point: a point is inside when the winding number is not zero,
/// so a container made of several overlapping closed parts (one proxy per component)
/// contains the union of their volumes. Points on a triangle are `on_boundary`.
/// The winding number is counted along a ray with exact orientation predicates; rays
/// that meet an edge or a vertex are replaced by another seeded direction.
/// Precondition: `container` is closed (every edge has as many triangles using it one way
/// as the other); for an open container the answer depends on the ray.
std::vector<PointLocation> locate_points(const TriangleMesh& container, std::span<const Vertex> points);

/// Pairs (container triangle, contents triangle) that intersect, exactly (touching counts).
std::vector<std::pair<std::uint32_t, std::uint32_t>> find_crossing_triangles(const TriangleMesh& container,
                                                                              const TriangleMesh& contents);

struct ContainmentOptions {
  /// Also require that no triangle of the contents meets a triangle of the container.
  /// With it, a closed container provably contains the whole contents surface, not only
  /// its vertices (for convex containers the vertex test alone already implies that).
  bool check_surface = true;
  /// The container's connected components are each convex (one box or hull per
  /// component of the input). Then a contents triangle is contained exactly when one
  /// component contains its three vertices, which is checked instead of the surface
  /// (check_surface is ignored): convex containers touch what they hold, so the surface
  /// test would reject them.
  bool convex_components = false;
};

struct Containment {
  std::size_t vertices_checked = 0;      ///< vertices the contents' triangles use
  std::size_t vertices_outside = 0;      ///< strictly outside the container
  std::size_t vertices_on_boundary = 0;  ///< exactly on a container triangle (still contained)
  std::size_t crossing_triangle_pairs = 0;  ///< 0 unless check_surface found some
  /// With convex_components: triangles whose vertices are all contained but in no single
  /// component together.
  std::size_t triangles_split = 0;
  bool surface_checked = false;
  std::optional<VertexIndex> first_vertex_outside;  ///< lowest index of a vertex outside
  /// Lowest (container triangle, contents triangle) pair that meets.
  std::optional<std::pair<std::uint32_t, std::uint32_t>> first_crossing;
  std::optional<std::uint32_t> first_triangle_split;  ///< lowest contents triangle split
  /// Vertices inside or on, and (when checked) no surface crossings.
  bool contained() const { return vertices_outside == 0 && crossing_triangle_pairs == 0 && triangles_split == 0; }
};

/// Whether closed mesh `container` contains `contents` (see ContainmentOptions).
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

}  // namespace visproxy
