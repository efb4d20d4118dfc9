// Rendering cost against the number of instances: every visibility mode on forests of
// growing size (`visproxy generate forest --trees N`), each (scene, mode) in a fresh
// process of this program (fork and exec), so that its peak resident memory is its own.
//
//   visproxy-bench-forest SCENE... [--width W] [--height H] [--spp N] [--shadow-rays M]
//                         [--vpls V] [--seed S] [--csv FILE]
//
// Per scene and mode: instances, the time to read the scene and its proxies and build the
// RenderWorld, the render time, the shadow rays (for --integrator vpl: the VPL connections),
// the render time per shadow ray, its ratio to the first scene's, log2(instances)'s ratio
// beside it (the growth the time per ray must stay under), the peak memory (getrusage of
// the child), and for occluder disks the clusters of balls their tree gave each ray (the
// work that follows how far a ray runs before a ball hides it). Every scene is checked:
// bounds must give exact's image bit for bit (hashes of the pixels). The stochastic modes
// use the proxy named by --proxy of each row, as `visproxy render --proxy` does.

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <new>
#include <string>
#include <vector>

#include "child_process.h"
#include "visproxy/core/errors.h"
#include "visproxy/core/files.h"
#include "visproxy/core/process.h"
#include "visproxy/render/scene_proxies.h"
#include "visproxy/render/renderer.h"

namespace {

using namespace visproxy;

struct Mode {
  const char* name;
  const char* proxy;  // the stochastic proxy ("" for the scene's first)
  RenderOptions options;
};

std::vector<Mode> modes(int spp, int shadow_rays, int vpls, std::uint64_t seed) {
  const RenderOptions direct{.spp = spp, .shadow_rays = shadow_rays, .seed = seed};
  RenderOptions bounds = direct, eq8 = direct, adaptive = direct, learned = direct;
  bounds.visibility = VisibilityMode::bounds;
  eq8.visibility = adaptive.visibility = learned.visibility = VisibilityMode::stochastic;
  adaptive.probabilities = ProbabilityMode::adaptive;
  learned.probabilities = ProbabilityMode::learned, learned.estimator = StochasticEstimator::control_variate;
  RenderOptions vpl{.integrator = IntegratorKind::vpl, .spp = std::max(1, spp / 4), .shadow_rays = 1, .seed = seed, .vpls = vpls};
  RenderOptions disks = vpl, vpl_learned = vpl;
  disks.visibility = VisibilityMode::spheres;
  vpl_learned.visibility = VisibilityMode::stochastic, vpl_learned.probabilities = ProbabilityMode::learned;
  vpl_learned.estimator = StochasticEstimator::control_variate;
  return {{"exact", "", direct},
          {"bounds", "", bounds},
          {"eq8 equal, aabb", "aabb", eq8},
          {"eq8 adaptive, hull:32", "hull:32", adaptive},
          {"control variate learned, hull:32", "hull:32", learned},
          {"vpl exact", "", vpl},
          {"vpl occluder disks, spheres:100", "spheres:100", disks},
          {"vpl control variate learned, spheres:100", "spheres:100", vpl_learned}};
}

// What a child reports through its pipe.
struct ChildReport {
  int ok = 0;
  std::size_t instances = 0;
  double load_seconds = 0, render_seconds = 0;
  std::uint64_t rays = 0;        // shadow rays, or VPL connections
  std::uint64_t disk_clusters = 0;  // clusters of balls the occluder disks' tree gave the segments
  std::uint64_t image_hash = 0;  // FNV-1a over the pixels' bytes
  char message[400] = {};
};

std::uint64_t fnv1a(const void* data, std::size_t size) {
  std::uint64_t hash = 14695981039346656037ull;
  for (std::size_t i = 0; i < size; ++i) hash = (hash ^ static_cast<const unsigned char*>(data)[i]) * 1099511628211ull;
  return hash;
}

struct Settings {
  int width = 320, height = 180, spp = 8, shadow_rays = 4, vpls = 256;
  std::uint64_t seed = 1;
};

// The hidden --one mode: render SCENE in mode INDEX, write a ChildReport to descriptor 3.
int render_one(const std::string& scene_path, std::size_t index, const Settings& s) {
  ChildReport report;
  return bench::report_to_parent(report, [&] {
    const Mode mode = modes(s.spp, s.shadow_rays, s.vpls, s.seed).at(index);
    const auto start = std::chrono::steady_clock::now();
    Scene scene = load_scene(scene_path);
    scene.camera.width = s.width, scene.camera.height = s.height;
    SceneProxyOptions options{.cache = default_proxy_cache(), .stochastic_spec = std::nullopt, .seed = 1, .on_proxy = nullptr};
    if (*mode.proxy) options.stochastic_spec = mode.proxy;
    const std::vector<MeshProxies> proxies = prepare_scene_proxies(scene, options);
    const RenderWorld world(scene, proxies);
    report.load_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const RenderResult result = render(scene, world, mode.options);
    report.instances = scene.instances.size();
    report.render_seconds = result.stats.seconds;
    report.rays = mode.options.integrator == IntegratorKind::vpl ? result.stats.vpl_connections : result.stats.shadow_rays;
    report.disk_clusters = result.stats.disks.clusters;
    report.image_hash = fnv1a(result.image.pixels.data(), result.image.pixels.size() * sizeof(Color));
    report.ok = 1;
  });
}

struct Run {
  ChildReport report;
  double peak_mb = std::nan("");
  std::string status = "ok";
};

Run run_child(const std::string& scene, std::size_t mode, const Settings& s) {
  Run run;
  const bench::ChildRun child = bench::run_self(
      {"visproxy-bench-forest", "--one", scene, std::to_string(mode), std::to_string(s.width), std::to_string(s.height),
       std::to_string(s.spp), std::to_string(s.shadow_rays), std::to_string(s.vpls), std::to_string(s.seed)},
      &run.report, sizeof run.report);
  run.peak_mb = child.peak_mb;
  if (!child.reported)
    run.status = bench::child_failure(child, 0);
  else if (!run.report.ok)
    run.status = run.report.message;
  return run;
}

int run(int argc, char** argv) {
  Settings s;
  std::vector<std::string> scenes;
  std::string csv_path;
  if (argc == 10 && std::strcmp(argv[1], "--one") == 0) {
    s.width = std::atoi(argv[4]), s.height = std::atoi(argv[5]), s.spp = std::atoi(argv[6]);
    s.shadow_rays = std::atoi(argv[7]), s.vpls = std::atoi(argv[8]), s.seed = std::strtoull(argv[9], nullptr, 10);
    return render_one(argv[2], static_cast<std::size_t>(std::atoi(argv[3])), s);
  }
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw Error("missing value after " + arg);
      return argv[++i];
    };
    if (arg == "--width") s.width = std::stoi(value());
    else if (arg == "--height") s.height = std::stoi(value());
    else if (arg == "--spp") s.spp = std::stoi(value());
    else if (arg == "--shadow-rays") s.shadow_rays = std::stoi(value());
    else if (arg == "--vpls") s.vpls = std::stoi(value());
    else if (arg == "--seed") s.seed = std::stoull(value());
    else if (arg == "--csv") csv_path = value();
    else if (arg.starts_with("--")) throw Error("unknown option " + arg);
    else scenes.push_back(arg);
  }
  if (scenes.empty())
    throw Error("usage: visproxy-bench-forest SCENE... [--width W] [--height H] [--spp N] [--shadow-rays M] [--vpls V] "
                "[--seed S] [--csv FILE]");
  if (s.width < 1 || s.height < 1 || s.spp < 1 || s.shadow_rays < 1 || s.vpls < 1)
    throw Error("--width, --height, --spp, --shadow-rays and --vpls must be positive");

  const std::vector<Mode> all = modes(s.spp, s.shadow_rays, s.vpls, s.seed);
  std::printf("visproxy-bench-forest: %dx%d; direct: %d spp x %d shadow rays; vpl: %d spp, %d VPLs; seed %llu; each scene "
              "and mode in its own process\n",
              s.width, s.height, s.spp, s.shadow_rays, std::max(1, s.spp / 4), s.vpls, static_cast<unsigned long long>(s.seed));
  std::printf("%10s  %-42s %9s %9s %12s %10s %9s %9s %9s %10s  %s\n", "instances", "mode", "load s", "render s", "rays", "ns / ray",
              "/ first", "log2 /", "peak MB", "clusters", "status");
  std::string csv = "scene,instances,mode,load_seconds,render_seconds,rays,ns_per_ray,peak_mb,disk_clusters_per_ray,status\n";
  std::vector<double> first_ns(all.size(), std::nan(""));
  std::size_t first_instances = 0;
  bool identical = true;
  for (const std::string& scene : scenes) {
    std::uint64_t exact_hash = 0, bounds_hash = 0;
    for (std::size_t m = 0; m < all.size(); ++m) {
      const Run r = run_child(scene, m, s);
      const ChildReport& c = r.report;
      const double ns = r.status == "ok" ? c.render_seconds * 1e9 / static_cast<double>(std::max<std::uint64_t>(c.rays, 1))
                                         : std::nan("");
      if (first_instances == 0 && r.status == "ok") first_instances = c.instances;
      if (std::isnan(first_ns[m])) first_ns[m] = ns;
      const double log_ratio = std::log2(static_cast<double>(c.instances)) / std::log2(static_cast<double>(first_instances));
      const double clusters = static_cast<double>(c.disk_clusters) / static_cast<double>(std::max<std::uint64_t>(c.rays, 1));
      std::printf("%10zu  %-42s %9.2f %9.3f %12llu %10.1f %9.2f %9.2f %9.0f %10.2f  %s\n", c.instances, all[m].name, c.load_seconds,
                  c.render_seconds, static_cast<unsigned long long>(c.rays), ns, ns / first_ns[m], log_ratio, r.peak_mb, clusters,
                  r.status.c_str());
      std::fflush(stdout);
      char line[512];
      std::snprintf(line, sizeof line, "%s,%zu,%s,%.4f,%.4f,%llu,%.2f,%.1f,%.3f,%s\n", scene.c_str(), c.instances, all[m].name,
                    c.load_seconds, c.render_seconds, static_cast<unsigned long long>(c.rays), ns, r.peak_mb, clusters, r.status.c_str());
      csv += line;
      if (m == 0) exact_hash = c.image_hash;
      if (m == 1) bounds_hash = c.image_hash;
    }
    const bool same = exact_hash == bounds_hash && exact_hash != 0;
    identical = identical && same;
    std::printf("%10s  bounds against exact on %s: %s\n", "", scene.c_str(),
                same ? "bit-identical images" : "DIFFERENT IMAGES");
  }
  std::printf("(ns / ray: render time over shadow rays, or over VPL connections for vpl; / first: against the first "
              "scene's; log2 /: log2 of the instances against the first scene's; clusters: clusters of sphere-set balls the "
              "occluder disks' tree gave each ray, tested by their bound's cone)\n");
  if (!csv_path.empty()) {
    write_file_atomically(csv_path, csv);
    std::printf("wrote %s\n", csv_path.c_str());
  }
  return identical ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  visproxy::disable_transparent_huge_pages();  // see visproxy/core/process.h
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "visproxy-bench-forest: %s\n", e.what());
    return 2;
  }
}
