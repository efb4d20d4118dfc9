// Sphere proxies: time of each stage and how often isotropic lines hit the result,
// relative to the mesh (the GSSA ratio), for circumsphere sets merged to several levels
// and for inscribed (inside) spheres.
//
//   visproxy-bench-spheres [--subdivide L] [--tets normals|tetgen] [--pair d1|d2]
//                          [--radius exact|analytic] [--samples S] [--levels 1000,250,...]
//                          [--inside N] [--lines N] [--repeat R] [MESH...]
//
// Without MESH: bunny00.off, armadillo.off and knot1.off from VISPROXY_MESH_DIR. Times are
// wall times, the fastest of R runs (default 3); GSSA ratios are (lines hitting the
// spheres) / (lines hitting the mesh) over N isotropic lines (default 200000, seed 1)
// with 95 % intervals (delta method, measure/proxy_measurement.h).

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "visproxy/core/process.h"
#include "visproxy/measure/proxy_measurement.h"
#include "visproxy/measure/random_lines.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/mesh/subdivide.h"
#include "visproxy/proxy/circumsphere_set.h"
#include "visproxy/proxy/inscribed_spheres.h"
#include "visproxy/proxy/merge_spheres.h"
#include "visproxy/trace/ray_scene.h"

#ifndef VISPROXY_MESH_DIR
#error "VISPROXY_MESH_DIR must name the folder of the extracted libcgal-demo meshes"
#endif

namespace {

using namespace visproxy;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

struct Settings {
  int subdivide = 0;
  CircumsphereOptions circumspheres{.samples = 0};  // 0: default_circumsphere_samples
  MergeSpheresOptions merge;
  std::vector<std::size_t> levels = {1000, 250, 100, 25, 10};
  std::size_t inside = 40;
  std::size_t lines = 200000;
  int repeat = 3;
};

std::vector<std::size_t> parse_levels(const std::string& text) {
  std::vector<std::size_t> levels;
  std::stringstream stream(text);
  for (std::string item; std::getline(stream, item, ',');) levels.push_back(std::stoul(item));
  return levels;
}

void print_ratio(const char* name, const ReferenceRays& reference, std::span<const Sphere> spheres, ProxyKind kind) {
  const RayScene scene(spheres);
  const std::vector<std::uint8_t> blocked = scene.segments_blocked(reference.rays);
  RayTypeCounts counts;
  for (std::size_t i = 0; i < blocked.size(); ++i) counts.add(reference.mesh_blocked[i] != 0, blocked[i] != 0);
  const ProxyMeasurement m = measure_from_counts(counts, kind);
  std::printf("  %-14s %6zu spheres  GSSA ratio %.4f [%.4f, %.4f]  f_hit %.4f  f_miss %.4f\n", name, spheres.size(),
              m.gssa_ratio, m.gssa_ratio_lower, m.gssa_ratio_upper, m.f_hit.fraction(), m.f_miss.fraction());
}

void run(const std::filesystem::path& path, const Settings& settings) {
  TriangleMesh mesh = read_mesh(path);
  if (settings.subdivide > 0) mesh = subdivide_midpoint(mesh, settings.subdivide);
  std::printf("%s%s: %zu triangles; tets %s, pair %s, radius %s, samples %s\n", path.filename().c_str(),
              settings.subdivide > 0 ? (" subdivided " + std::to_string(settings.subdivide) + "x").c_str() : "",
              mesh.triangles.size(), std::string(name_of(settings.circumspheres.tetrahedra)).c_str(),
              std::string(pair_distance_name(settings.merge.pair_distance)).c_str(),
              settings.merge.radius == MergeRadius::exact ? "exact" : "analytic",
              settings.circumspheres.samples > 0 ? std::to_string(settings.circumspheres.samples).c_str() : "default");

  double best_set = std::numeric_limits<double>::infinity(), best_merge = best_set;
  CircumsphereOptions circumsphere_options = settings.circumspheres;
  if (circumsphere_options.samples == 0)
    circumsphere_options.samples = default_circumsphere_samples(*std::max_element(settings.levels.begin(), settings.levels.end()));
  CircumsphereSet set;
  std::vector<std::vector<Sphere>> levels;
  for (int r = 0; r < settings.repeat; ++r) {
    auto start = Clock::now();
    set = build_circumsphere_set(mesh, circumsphere_options);
    best_set = std::min(best_set, seconds_since(start));
    start = Clock::now();
    levels = merge_spheres(set.spheres, settings.levels, settings.merge);
    best_merge = std::min(best_merge, seconds_since(start));
  }
  std::printf("  circumspheres: %zu points, %zu tetrahedra, %zu inner (%zu smallest balls): %.3f s; merge to all levels: %.3f s; total %.3f s\n",
              set.points, set.tetrahedra, set.spheres.size(), set.balls_replaced, best_set, best_merge, best_set + best_merge);

  InscribedSpheres inside;
  double best_inside = std::numeric_limits<double>::infinity();
  if (settings.inside > 0) {
    for (int r = 0; r < settings.repeat; ++r) {
      const auto start = Clock::now();
      inside = build_inscribed_spheres(mesh, {.count = settings.inside});
      best_inside = std::min(best_inside, seconds_since(start));
    }
    std::printf("  inside:%zu: %.3f s, %zu candidates from %zu samples, volume covered %.4f [%.4f, %.4f], "
                "min margin %.3g, shrunk %zu\n",
                settings.inside, best_inside, inside.candidates, inside.surface_samples, inside.covered_volume_fraction,
                inside.covered_volume_lower, inside.covered_volume_upper, inside.min_margin_world, inside.spheres_shrunk);
  }

  if (settings.lines == 0) return;
  const RayScene mesh_scene(mesh);
  const ReferenceRays reference =
      trace_reference(mesh_scene, isotropic_lines(bounding_sphere(mesh), settings.lines, 1), {.rays = 0, .blocks = 0});
  print_ratio("initial", reference, set.spheres, ProxyKind::general);
  for (std::size_t k = 0; k < levels.size(); ++k)
    print_ratio(("spheres-" + std::to_string(settings.levels[k])).c_str(), reference, levels[k], ProxyKind::general);
  if (settings.inside > 0) print_ratio(("inside-" + std::to_string(settings.inside)).c_str(), reference, inside.spheres, ProxyKind::inside);
}

}  // namespace

int main(int argc, char** argv) {
  visproxy::disable_transparent_huge_pages();  // see visproxy/core/process.h
  Settings settings;
  std::vector<std::filesystem::path> paths;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string argument = argv[i];
      const bool has_value = i + 1 < argc;
      if (argument == "--subdivide" && has_value) settings.subdivide = std::atoi(argv[++i]);
      else if (argument == "--tets" && has_value)
        settings.circumspheres.tetrahedra = std::string(argv[++i]) == "tetgen" ? InnerTetrahedra::tetgen : InnerTetrahedra::normals;
      else if (argument == "--pair" && has_value)
        settings.merge.pair_distance = std::string(argv[++i]) == "d1" ? PairDistance::d1 : PairDistance::d2;
      else if (argument == "--radius" && has_value)
        settings.merge.radius = std::string(argv[++i]) == "analytic" ? MergeRadius::analytic : MergeRadius::exact;
      else if (argument == "--samples" && has_value) settings.circumspheres.samples = std::stoul(argv[++i]);
      else if (argument == "--levels" && has_value) settings.levels = parse_levels(argv[++i]);
      else if (argument == "--inside" && has_value) settings.inside = std::stoul(argv[++i]);
      else if (argument == "--lines" && has_value) settings.lines = std::stoul(argv[++i]);
      else if (argument == "--repeat" && has_value) settings.repeat = std::max(1, std::atoi(argv[++i]));
      else if (argument == "--help" || argument == "-h") {
        std::printf("usage: visproxy-bench-spheres [--subdivide L] [--tets normals|tetgen] [--pair d1|d2] "
                    "[--radius exact|analytic] [--samples S] [--levels 1000,250,...] [--inside N] [--lines N] "
                    "[--repeat R] [MESH...]\n");
        return 0;
      } else {
        paths.emplace_back(argument);
      }
    }
    if (paths.empty())
      for (const char* name : {"bunny00.off", "armadillo.off", "knot1.off"})
        paths.push_back(std::filesystem::path(VISPROXY_MESH_DIR) / name);
    for (const auto& path : paths) {
      run(path, settings);
      std::fflush(stdout);
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "visproxy-bench-spheres: %s\n", error.what());
    return 2;
  }
  return 0;
}
