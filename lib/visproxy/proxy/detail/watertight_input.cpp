#include "visproxy/proxy/detail/watertight_input.h"

#include <algorithm>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/mesh/mesh_topology.h"

namespace visproxy {

namespace {

std::string count(std::size_t n, const char* one, const char* many) { return std::to_string(n) + " " + (n == 1 ? one : many); }

}  // namespace

std::optional<std::string> closed_defects(const TriangleMesh& mesh) {
  const EdgeBalance balance = check_edge_balance(mesh);
  if (balance.balanced()) return std::nullopt;
  const MeshTopology topology = analyze_topology(mesh);
  std::vector<std::string> defects;
  if (topology.boundary_edges > 0) defects.push_back(count(topology.boundary_edges, "boundary edge", "boundary edges"));
  if (topology.inconsistent_edges > 0)
    defects.push_back(count(topology.inconsistent_edges, "edge with inconsistent orientation", "edges with inconsistent orientation"));
  const std::size_t other = balance.unbalanced_edges - std::min(balance.unbalanced_edges, topology.boundary_edges + topology.inconsistent_edges);
  if (other > 0)
    defects.push_back(count(other, "other edge used unequally often in its two directions",
                            "other edges used unequally often in their two directions"));
  std::string text;
  for (const std::string& defect : defects) text += (text.empty() ? "" : ", ") + defect;
  return text;
}

void require_closed(const TriangleMesh& mesh, std::string_view why) {
  if (mesh.triangles.empty()) throw InvalidInputError("", "the mesh has no triangles: " + std::string(why));
  if (const std::optional<std::string> defects = closed_defects(mesh))
    throw InvalidInputError("", "the mesh is not closed (" + *defects + "): " + std::string(why));
}

std::optional<std::string> watertight_defects(const MeshReport& report) {
  if (report.watertight()) return std::nullopt;
  std::vector<std::string> defects;
  const MeshTopology& topology = report.topology;
  if (report.triangles == 0) defects.push_back("no triangles");
  if (topology.boundary_edges > 0) defects.push_back(count(topology.boundary_edges, "boundary edge", "boundary edges"));
  if (topology.non_manifold_edges > 0)
    defects.push_back(count(topology.non_manifold_edges, "non-manifold edge", "non-manifold edges"));
  if (topology.non_manifold_vertices > 0)
    defects.push_back(count(topology.non_manifold_vertices, "non-manifold vertex", "non-manifold vertices"));
  if (topology.inconsistent_edges > 0)
    defects.push_back(count(topology.inconsistent_edges, "edge with inconsistent orientation",
                            "edges with inconsistent orientation"));
  if (report.self_intersecting_pairs > 0)
    defects.push_back(count(report.self_intersecting_pairs, "self-intersecting triangle pair",
                            "self-intersecting triangle pairs"));
  if (report.degenerate_triangles > 0)
    defects.push_back(count(report.degenerate_triangles, "degenerate (zero-area) triangle",
                            "degenerate (zero-area) triangles"));
  std::string text;
  for (const std::string& defect : defects) text += (text.empty() ? "" : ", ") + defect;
  return text.empty() ? std::string("not watertight") : text;
}

MeshReport require_watertight(const TriangleMesh& mesh, std::string_view why) {
  if (mesh.triangles.empty()) throw InvalidInputError("", "the mesh has no triangles: " + std::string(why));
  MeshReport report = inspect_mesh(mesh);
  if (const std::optional<std::string> defects = watertight_defects(report))
    throw InvalidInputError("", "the mesh is not watertight (" + *defects + "): " + std::string(why));
  return report;
}

}  // namespace visproxy
