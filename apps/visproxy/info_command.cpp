// visproxy info MESH [--json] [--weld MODE]

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "commands.h"
#include "visproxy/inspect/mesh_report.h"
#include "visproxy/mesh/asset_parts.h"
#include "visproxy/mesh/read_mesh.h"

namespace visproxy::cli {
namespace {

struct InfoOptions {
  std::filesystem::path mesh;
  bool json = false;
  Weld weld = Weld::automatic;
};

std::string format_point(const Vertex& p) {
  char text[128];
  std::snprintf(text, sizeof text, "(%.6g, %.6g, %.6g)", p.x(), p.y(), p.z());
  return text;
}

void print_report(const InfoOptions& options, MeshFormat format, double read_seconds, const MeshReport& report) {
  const MeshTopology& topology = report.topology;
  auto row = [](const char* label, const std::string& value) { std::printf("  %-22s %s\n", label, value.c_str()); };
  auto count = [](std::size_t n) { return std::to_string(n); };
  auto number = [](double value) {
    char text[64];
    std::snprintf(text, sizeof text, "%.6g", value);
    return std::string(text);
  };

  std::string format_text(format_name(format));
  if (format == MeshFormat::assimp) {
    const auto part = split_part_path(options.mesh);  // ASSET:MESH
    format_text += " " + (part ? part->first : options.mesh).extension().string().substr(1);
    if (part) format_text += ", its mesh " + part->second;
  }
  std::printf("mesh %s (%s, read in %.1f ms)\n", options.mesh.string().c_str(), format_text.c_str(), 1e3 * read_seconds);
  row("vertices", count(report.vertices) +
                      (report.unreferenced_vertices ? " (" + count(report.unreferenced_vertices) + " unreferenced)" : ""));
  row("triangles", count(report.triangles));
  row("bounding box", format_point(report.bounds.min) + " to " + format_point(report.bounds.max));
  row("diagonal", number(report.bounds.diagonal()) + " mesh units");
  row("components", count(topology.components));
  row("edges", count(topology.edges) + " (Euler characteristic " +
                   std::to_string(topology.euler_characteristic(report.triangles)) + ")");
  row("boundary edges", count(topology.boundary_edges));
  row("non-manifold edges", count(topology.non_manifold_edges));
  row("non-manifold vertices", count(topology.non_manifold_vertices));
  std::string orientation = topology.consistently_oriented()
                                ? "consistent"
                                : "inconsistent (" + count(topology.inconsistent_edges) + " edges)";
  if (report.outward_oriented) orientation += *report.outward_oriented ? ", outward" : ", inward";
  else orientation += ", outward unknown (not closed and consistent)";
  row("orientation", orientation);
  row("degenerate triangles", count(report.degenerate_triangles));
  row("self-intersections",
      report.self_intersecting()
          ? count(report.self_intersecting_pairs) + " triangle pairs (first: " +
                std::to_string(report.first_self_intersection->first) + " and " +
                std::to_string(report.first_self_intersection->second) + ")"
          : std::string("none"));
  row("surface area", number(report.area) + " mesh units^2");
  row("enclosed volume", report.volume ? number(*report.volume) + " mesh units^3" : std::string("n/a (not closed)"));
  std::string verdict = report.watertight() ? "yes" : "no:";
  if (!report.watertight()) {
    if (!topology.closed()) verdict += " boundary edges,";
    if (!topology.manifold()) verdict += " non-manifold,";
    if (!topology.consistently_oriented()) verdict += " inconsistent orientation,";
    if (report.self_intersecting()) verdict += " self-intersecting,";
    if (report.degenerate_triangles > 0) verdict += " degenerate triangles,";
    verdict.pop_back();
  }
  row("watertight", verdict);
  row("bounds a solid", topology.unbalanced_edges == 0 && report.triangles > 0
                            ? std::string("yes (every edge used as often in each direction; inside proxies need this)")
                            : "no: " + count(topology.unbalanced_edges) + " edges used unequally often in their two directions");
  std::printf("  %-22s %.3f s\n", "inspected in", report.seconds);
}

}  // namespace

void add_info_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<InfoOptions>();
  CLI::App* command = app.add_subcommand(
      "info", "Validate a mesh: counts, bounds, components, boundary and non-manifold edges and vertices, "
              "orientation, degenerate triangles, self-intersections, area, volume, a watertight verdict, and whether it bounds "
              "a solid (closed: every edge used as often in each direction, which inside proxies need).");
  command->add_option("mesh", options->mesh, "Mesh file (.obj, .ply, .off, .stl, or through Assimp .gltf, .glb, .fbx, .dae, .3ds, ...)")->required();
  command->add_flag("--json", options->json, "Print one JSON object (schema: data/schemas/info.schema.json)");
  as_choice<Weld>(command->add_option(
      "--weld", options->weld,
      "Merge vertices with identical coordinates: auto (STL and Assimp's formats only), never, always [default: auto]"));

  command->callback([options, &exit_code] {
    const auto start = std::chrono::steady_clock::now();
    const TriangleMesh mesh = read_mesh(options->mesh, {.weld = options->weld, .on_warning = print_warning});
    const double read_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const MeshFormat format = *format_from_extension(options->mesh);
    const MeshReport report = inspect_mesh(mesh);
    if (options->json) {
      nlohmann::json json = to_json(report);
      json["file"] = options->mesh.string();
      json["format"] = format_name(format);
      json["read_seconds"] = read_seconds;
      std::cout << json.dump(2) << "\n";
    } else {
      print_report(*options, format, read_seconds, report);
    }
    exit_code = kSuccess;
  });
}

}  // namespace visproxy::cli
