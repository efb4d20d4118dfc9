#pragma once
// The preconditions of the builders that need a solid: a closed input mesh (inside
// proxies), or a watertight one (TetGen).

#include <optional>
#include <string>
#include <string_view>

#include "visproxy/inspect/mesh_report.h"

namespace visproxy {

/// What keeps the inspected mesh from being watertight, in words ("12 boundary edges,
/// 3 self-intersecting triangle pairs"), or nothing when MeshReport::watertight() holds.
std::optional<std::string> watertight_defects(const MeshReport& report);

/// Inspects `mesh` (inspect_mesh: topology, degenerate triangles, exact self-intersections)
/// and returns the report; throws InvalidInputError (empty file name) reading
/// "the mesh is not watertight (DEFECTS): WHY" when it is not, with `why` saying what needs a
/// watertight input and why.
MeshReport require_watertight(const TriangleMesh& mesh, std::string_view why);

/// What keeps `mesh` from being closed, in words ("12 boundary edges", "3 edges with
/// inconsistent orientation"), or nothing when every edge is used as often in one direction
/// as in the other (EdgeBalance). A closed mesh bounds a solid, {winding number != 0},
/// even where it self-intersects or has non-manifold edges.
std::optional<std::string> closed_defects(const TriangleMesh& mesh);

/// Throws InvalidInputError (empty file name) reading "the mesh is not closed (DEFECTS): WHY"
/// when closed_defects finds any, or "the mesh has no triangles: WHY".
void require_closed(const TriangleMesh& mesh, std::string_view why);

}  // namespace visproxy
