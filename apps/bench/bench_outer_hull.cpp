// Outside proxies on real meshes: build time, triangle count and f_miss (the fraction of
// isotropic lines missing the mesh that also miss the proxy) of the convex hull, the alpha
// wrap and outer:N, measured on the same lines.
//   visproxy-bench-outer-hull [--lines COUNT] [--budget N] [MESH...]

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "surface_mesh.h"
#include "visproxy/core/process.h"
#include "visproxy/measure/proportion.h"
#include "visproxy/measure/random_lines.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/proxy/alpha_wrap.h"
#include "visproxy/proxy/outer_hull.h"
#include "visproxy/trace/ray_scene.h"

namespace {

using namespace visproxy;
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;

TriangleMesh convex_hull(const TriangleMesh& mesh) {
  std::vector<Kernel::Point_3> points;
  for (const Vertex& p : mesh.positions) points.emplace_back(p.x(), p.y(), p.z());
  CGAL::Surface_mesh<Kernel::Point_3> hull;
  CGAL::convex_hull_3(points.begin(), points.end(), hull);
  return bench::from_surface_mesh(hull);
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void report(const char* name, const TriangleMesh& proxy, double seconds, const std::vector<Segment>& lines,
            const std::vector<std::uint8_t>& mesh_blocked) {
  const std::vector<std::uint8_t> blocked = RayScene(proxy).segments_blocked(lines);
  Proportion miss;
  std::size_t proxy_misses_mesh_hits = 0;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (mesh_blocked[i]) {
      proxy_misses_mesh_hits += blocked[i] ? 0 : 1;
      continue;
    }
    ++miss.trials;
    miss.successes += blocked[i] ? 0 : 1;
  }
  std::printf("  %-22s %7zu triangles %8.3f s   f_miss %.4f [%.4f, %.4f]%s\n", name, proxy.triangles.size(), seconds,
              miss.fraction(), miss.lower(), miss.upper(),
              proxy_misses_mesh_hits ? "   (some lines hit the mesh but miss the proxy!)" : "");
}

}  // namespace

int main(int argc, char** argv) {
  visproxy::disable_transparent_huge_pages();  // see visproxy/core/process.h
  std::size_t line_count = 100000;
  std::size_t budget = 512;
  std::vector<std::string> meshes;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--lines" && i + 1 < argc)
      line_count = std::stoul(argv[++i]);
    else if (arg == "--budget" && i + 1 < argc)
      budget = std::stoul(argv[++i]);
    else
      meshes.push_back(arg);
  }
  if (meshes.empty())
    meshes = {std::string(VISPROXY_MESH_DIR) + "/armadillo.off", std::string(VISPROXY_MESH_DIR) + "/bunny00.off"};
  try {
    for (const std::string& path : meshes) {
      const TriangleMesh mesh = read_mesh(path);
      std::printf("%s: %zu triangles, %zu lines\n", path.c_str(), mesh.triangles.size(), line_count);
      const std::vector<Segment> lines = isotropic_lines(bounding_sphere(mesh), line_count, 20240601);
      const std::vector<std::uint8_t> mesh_blocked = RayScene(mesh).segments_blocked(lines);

      auto start = std::chrono::steady_clock::now();
      const TriangleMesh hull = convex_hull(mesh);
      report("convex hull", hull, seconds_since(start), lines, mesh_blocked);

      start = std::chrono::steady_clock::now();
      const AlphaWrapResult wrap = build_alpha_wrap(mesh, {});
      report("wrap (defaults)", wrap.mesh, seconds_since(start), lines, mesh_blocked);

      start = std::chrono::steady_clock::now();
      const OuterHullOptions defaults;
      const AlphaWrapResult outer_wrap = build_alpha_wrap(
          mesh, {.alpha_relative = defaults.wrap_alpha_relative, .offset_relative = defaults.wrap_offset_relative});
      report("wrap (outer:N start)", outer_wrap.mesh, seconds_since(start), lines, mesh_blocked);

      start = std::chrono::steady_clock::now();
      const OuterHullResult outer = build_outer_hull(mesh, {.max_triangles = budget});
      const std::string name = "outer:" + std::to_string(budget);
      report(name.c_str(), outer.mesh, seconds_since(start), lines, mesh_blocked);
      std::printf("  %-22s reached_target %d, wrap %zu triangles, distance bound %.4g (%.3f %% of diagonal)\n", "",
                  outer.reached_target ? 1 : 0, outer.wrap_triangles, outer.max_distance_to_input_world,
                  100 * outer.max_distance_to_input_world / bounding_box(mesh).diagonal());
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "%s\n", error.what());
    return 1;
  }
  return 0;
}
