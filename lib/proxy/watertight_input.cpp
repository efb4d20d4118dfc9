#include "proxy/watertight_input.h"

#include <vector>

#include "core/errors.h"

namespace visproxy {

std::optional<std::string> watertight_defects(const MeshReport& report) {
  if (report.watertight()) return std::nullopt;
  std::vector<std::string> defects;
  const MeshTopology& topology = report.topology;
  auto count = [](std::size_t n, const char* one, const char* many) {
    return std::to_string(n) + " " + (n == 1 ? one : many);
  };
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
