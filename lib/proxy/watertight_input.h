#pragma once
// The precondition of the builders that need a solid: a watertight input mesh.

#include <optional>
#include <string>
#include <string_view>

#include "inspect/mesh_report.h"

namespace visproxy {

/// What keeps the inspected mesh from being watertight, in words ("12 boundary edges,
/// 3 self-intersecting triangle pairs"), or nothing when MeshReport::watertight() holds.
std::optional<std::string> watertight_defects(const MeshReport& report);

/// Inspects `mesh` (inspect_mesh: topology, degenerate triangles, exact self-intersections)
/// and returns the report; throws InvalidInputError (empty file name) reading
/// "the mesh is not watertight (DEFECTS): WHY" when it is not, with `why` saying what needs a
/// watertight input and why.
MeshReport require_watertight(const TriangleMesh& mesh, std::string_view why);

}  // namespace visproxy
