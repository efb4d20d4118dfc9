#include "visproxy/inspect/mesh_report.h"

#include <nlohmann/json.hpp>

#include <chrono>

#include "visproxy/inspect/exact_checks.h"

namespace visproxy {

MeshReport inspect_mesh(const TriangleMesh& mesh) {
  const auto start = std::chrono::steady_clock::now();
  MeshReport report;
  report.vertices = mesh.positions.size();
  report.triangles = mesh.triangles.size();
  report.bounds = bounding_box(mesh);
  report.topology = analyze_topology(mesh);
  report.unreferenced_vertices = report.vertices - report.topology.referenced_vertices;
  report.degenerate_triangles = find_degenerate_triangles(mesh).size();
  const auto intersections = find_self_intersections(mesh);
  report.self_intersecting_pairs = intersections.size();
  if (!intersections.empty()) report.first_self_intersection = intersections.front();

  // Volume by the divergence theorem, about the box centre to keep the terms small.
  const Vertex centre = report.bounds.empty() ? Vertex::Zero() : Vertex(0.5 * (report.bounds.min + report.bounds.max));
  double twice_area = 0;
  double six_volume = 0;
  for (const Triangle& t : mesh.triangles) {
    const Vertex a = mesh.positions[t[0]] - centre;
    const Vertex b = mesh.positions[t[1]] - centre;
    const Vertex c = mesh.positions[t[2]] - centre;
    twice_area += (b - a).cross(c - a).norm();
    six_volume += a.dot(b.cross(c));
  }
  report.area = 0.5 * twice_area;
  if (report.topology.closed()) report.volume = six_volume / 6.0;
  if (report.topology.closed() && report.topology.consistently_oriented()) report.outward_oriented = six_volume > 0;
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

nlohmann::json to_json(const MeshReport& report) {
  auto point = [](const Vertex& p) { return nlohmann::json::array({p.x(), p.y(), p.z()}); };
  auto optional = [](const auto& value) { return value ? nlohmann::json(*value) : nlohmann::json(nullptr); };
  const MeshTopology& topology = report.topology;
  nlohmann::json json = {
      {"vertices", report.vertices},
      {"triangles", report.triangles},
      {"unreferenced_vertices", report.unreferenced_vertices},
      {"bbox_min", point(report.bounds.min)},
      {"bbox_max", point(report.bounds.max)},
      {"diagonal", report.bounds.diagonal()},
      {"components", topology.components},
      {"edges", topology.edges},
      {"euler_characteristic", topology.euler_characteristic(report.triangles)},
      {"boundary_edges", topology.boundary_edges},
      {"non_manifold_edges", topology.non_manifold_edges},
      {"non_manifold_vertices", topology.non_manifold_vertices},
      {"inconsistent_edges", topology.inconsistent_edges},
      {"closed", topology.closed()},
      {"manifold", topology.manifold()},
      {"consistently_oriented", topology.consistently_oriented()},
      {"outward_oriented", optional(report.outward_oriented)},
      {"degenerate_triangles", report.degenerate_triangles},
      {"self_intersecting", report.self_intersecting()},
      {"self_intersecting_pairs", report.self_intersecting_pairs},
      {"area", report.area},
      {"volume", optional(report.volume)},
      {"watertight", report.watertight()},
      {"unbalanced_edges", topology.unbalanced_edges},
      {"bounds_solid", topology.unbalanced_edges == 0 && report.triangles > 0},
      {"inspect_seconds", report.seconds},
  };
  json["first_self_intersection"] =
      report.first_self_intersection
          ? nlohmann::json::array({report.first_self_intersection->first, report.first_self_intersection->second})
          : nlohmann::json(nullptr);
  return json;
}

}  // namespace visproxy
