#pragma once
// `visproxy info`: everything a user needs to know about a mesh before building proxies
// of it, above all whether it is watertight (inside proxies require that).

#include <nlohmann/json_fwd.hpp>

#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "visproxy/mesh/mesh_topology.h"
#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

struct MeshReport {
  std::size_t vertices = 0;
  std::size_t triangles = 0;
  std::size_t unreferenced_vertices = 0;  ///< vertices no triangle uses
  BoundingBox bounds;                     ///< of the referenced vertices
  MeshTopology topology;
  std::size_t degenerate_triangles = 0;  ///< collinear corners, decided exactly
  std::size_t self_intersecting_pairs = 0;
  std::optional<std::pair<std::uint32_t, std::uint32_t>> first_self_intersection;
  double area = 0;                          ///< surface area, mesh units squared
  std::optional<double> volume;             ///< signed enclosed volume (mesh units cubed) when closed
  std::optional<bool> outward_oriented;     ///< when closed and consistently oriented: volume > 0
  double seconds = 0;                       ///< time inspect_mesh took

  bool self_intersecting() const { return self_intersecting_pairs > 0; }
  /// Closed, manifold, consistently oriented, free of self-intersections and degenerate
  /// triangles: the surface bounds a solid, and inside/outside are well defined.
  bool watertight() const {
    return topology.closed() && topology.manifold() && topology.consistently_oriented() && !self_intersecting() &&
           degenerate_triangles == 0;
  }
};

/// Inspects `mesh`: counts, bounds, topology (mesh_topology.h), degenerate triangles and
/// self-intersections (exact_checks.h), area, and the enclosed volume when closed.
/// O(#F log #F) plus the self-intersection candidate pairs.
MeshReport inspect_mesh(const TriangleMesh& mesh);

/// The report as JSON; the keys are documented in data/schemas/info.schema.json.
nlohmann::json to_json(const MeshReport& report);

}  // namespace visproxy
