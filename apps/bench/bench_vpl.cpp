// Many-light rendering with virtual point lights, in one process on one scene (the
// occluding-spheres paper's Figures 9-11, Table-style):
//  - exact connections per second, grouped as ray packets against single rays (the images
//    must be bit-identical);
//  - `spheres` visibility at each sphere-set level: time, speed-up over exact, and MSE
//    against the exact image of the same samples (the occluders' bias) and against a
//    reference;
//  - self-shadowing at one level: heuristic, exact and none;
//  - the control variate with the sphere sets as V' (learned probabilities): time, MSE
//    against the reference, efficiency 1 / (MSE x time) over exact's;
//  - occluder disks compared every ball with every connection (linear), against the bounds
//    of clusters of balls first (the default) and against the direction grid, per level:
//    where a structure pays (paper: its k-d tree broke even at about 800 spheres);
//  - the disk loop vectorised against scalar code.
// Every mode renders the same VPLs (--vpl-seed), so clamping cancels out of the errors.
//   visproxy-bench-vpl SCENE [--levels 1000,250,100,25,10] [--spp N] [--reference-spp R]
//                      [--vpls N] [--width W] [--height H] [--cache DIR] [--images DIR]
//                      [--correction-scales 200,50,25]  (control variate: percent)
//                      [--repeat K]  (each timed render K times, the least time kept; default 3)

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/core/process.h"
#include "visproxy/core/random.h"
#include "visproxy/render/scene_proxies.h"
#include "visproxy/image/image.h"
#include "visproxy/render/renderer.h"
#include "visproxy/render/visibility/occluder_disks.h"

namespace {

using namespace visproxy;

double mse(const Image& a, const Image& b) {
  double sum = 0;
  for (std::size_t i = 0; i < a.pixels.size(); ++i) sum += (a.pixels[i] - b.pixels[i]).squaredNorm();
  return sum / (3.0 * static_cast<double>(a.pixels.size()));
}

std::vector<int> parse_levels(const std::string& text) {
  std::vector<int> levels;
  std::size_t start = 0;
  while (start < text.size()) {
    const std::size_t comma = text.find(',', start);
    levels.push_back(std::stoi(text.substr(start, comma == std::string::npos ? std::string::npos : comma - start)));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  for (const int level : levels)
    if (level < 1) throw Error("--levels: sphere counts must be positive");
  return levels;
}

// The disk loop alone: `count` random disks, 2^20 random directions, vectorised and scalar.
void disk_loop_benchmark() {
  std::printf("\nOccluder-disk loop, one thread, 2^20 segments against N disks (ns per segment; answers compared):\n\n");
  std::printf("| disks | vectorised ns | scalar ns | scalar / vectorised | occluded |\n| ---: | ---: | ---: | ---: | ---: |\n");
  for (const std::size_t count : {16u, 64u, 256u, 1024u}) {
    Random random(count);
    std::vector<float> ux(count), uy(count), uz(count), c(count), t(count);
    for (std::size_t j = 0; j < count; ++j) {
      Vertex u;
      do u = Vertex(2 * random.uniform() - 1, 2 * random.uniform() - 1, 2 * random.uniform() - 1);
      while (u.squaredNorm() > 1 || u.squaredNorm() < 1e-6);
      u.normalize();
      ux[j] = static_cast<float>(u.x()), uy[j] = static_cast<float>(u.y()), uz[j] = static_cast<float>(u.z());
      // Small caps, as far-away spheres give: most segments pass every disk.
      c[j] = static_cast<float>(1 - 2e-4 * random.uniform());
      t[j] = static_cast<float>(2 * random.uniform());
    }
    constexpr std::size_t queries = 1 << 20;
    std::vector<float> d(3 * queries), z(queries);
    for (std::size_t q = 0; q < queries; ++q) {
      Vertex v;
      do v = Vertex(2 * random.uniform() - 1, 2 * random.uniform() - 1, 2 * random.uniform() - 1);
      while (v.squaredNorm() > 1 || v.squaredNorm() < 1e-6);
      v.normalize();
      z[q] = static_cast<float>(3 * random.uniform());
      d[3 * q] = static_cast<float>(v.x()) * z[q], d[3 * q + 1] = static_cast<float>(v.y()) * z[q], d[3 * q + 2] = static_cast<float>(v.z()) * z[q];
    }
    auto time = [&](auto&& loop, int& hits) {
      const auto start = std::chrono::steady_clock::now();
      hits = 0;
      for (std::size_t q = 0; q < queries; ++q)
        hits += loop(ux.data(), uy.data(), uz.data(), c.data(), t.data(), count, d[3 * q], d[3 * q + 1], d[3 * q + 2], z[q]) ? 1 : 0;
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() * 1e9 / queries;
    };
    int vector_hits = 0, scalar_hits = 0;
    const double vectorised = time(any_disk_occludes, vector_hits), scalar = time(any_disk_occludes_scalar, scalar_hits);
    std::printf("| %zu | %.1f | %.1f | %.2f | %.1f %% (%s) |\n", count, vectorised, scalar, scalar / vectorised,
                100.0 * vector_hits / queries, vector_hits == scalar_hits ? "same" : "DIFFERENT counts");
  }
}

int run(int argc, char** argv) {
  std::string scene_path;
  std::vector<int> levels = {1000, 250, 100, 25, 10};
  std::vector<double> scales = {2, 0.5, 0.25};
  int spp = 2, reference_spp = 8, vpls = 1024, width = 0, height = 0, repeat = 3;
  std::filesystem::path cache = default_proxy_cache(), images;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw Error("missing value after " + arg);
      return argv[++i];
    };
    if (arg == "--levels") levels = parse_levels(value());
    else if (arg == "--correction-scales") {
      scales.clear();
      for (const int percent : parse_levels(value())) scales.push_back(percent / 100.0);
    }
    else if (arg == "--spp") spp = std::stoi(value());
    else if (arg == "--reference-spp") reference_spp = std::stoi(value());
    else if (arg == "--vpls") vpls = std::stoi(value());
    else if (arg == "--width") width = std::stoi(value());
    else if (arg == "--height") height = std::stoi(value());
    else if (arg == "--cache") cache = value();
    else if (arg == "--images") images = value();
    else if (arg == "--repeat") repeat = std::stoi(value());
    else if (arg.starts_with("--")) throw Error("unknown option " + arg);
    else scene_path = arg;
  }
  if (scene_path.empty())
    throw Error("usage: visproxy-bench-vpl SCENE [--levels 1000,250,100,25,10] [--spp N] [--reference-spp R] [--vpls N] "
                "[--width W] [--height H] [--cache DIR] [--images DIR] [--correction-scales P,...] [--repeat K]");
  if (spp < 1 || reference_spp < 1 || vpls < 1 || repeat < 1)
    throw Error("--spp, --reference-spp, --vpls and --repeat must be positive");
  Scene scene = load_scene(scene_path);
  if (width > 0) scene.camera.width = width;
  if (height > 0) scene.camera.height = height;
  std::size_t triangles = 0;
  for (const SceneInstance& instance : scene.instances) triangles += scene.mesh(instance.mesh).mesh.triangles.size();
  if (!images.empty()) std::filesystem::create_directories(images);

  const RenderOptions base{.integrator = IntegratorKind::vpl, .spp = spp, .shadow_rays = 1, .seed = 1, .vpls = vpls, .vpl_seed = 1};
  // The control variate: each correction scale with visibility splitting (the own instance
  // traced exactly), and the smaller ones without (the own instance's disks, with the
  // self-shadowing heuristic, corrected like the others).
  std::vector<std::pair<double, bool>> cv_variants;
  for (const double scale : scales) cv_variants.push_back({scale, true});
  for (const double scale : scales)
    if (scale < 1) cv_variants.push_back({scale, false});
  std::printf("visproxy-bench-vpl: %s, %zu triangles, %dx%d, %d spp x (1 light sample + %d light paths' VPLs), seed 1, VPL seed 1; "
              "reference: exact, %d spp, seed 2; times: the least of %d renders\n",
              scene_path.c_str(), triangles, scene.camera.width, scene.camera.height, spp, vpls, reference_spp, repeat);
  // Renders `repeat` times (the images are the same every time: every choice is seeded) and
  // keeps the least time, which a shared machine's noise can only lengthen.
  auto timed = [&](const RenderWorld& world, const RenderOptions& options) {
    RenderResult best = render(scene, world, options);
    for (int r = 1; r < repeat; ++r) {
      const RenderResult again = render(scene, world, options);
      if (again.image.pixels != best.image.pixels) throw Error("a repeated render gave another image");
      best.stats.seconds = std::min(best.stats.seconds, again.stats.seconds);
    }
    return best;
  };
  const RenderWorld exact_world(scene, std::vector<MeshProxies>(scene.instances.size()));
  RenderOptions reference_options = base;
  reference_options.spp = reference_spp;
  reference_options.seed = 2;
  const RenderResult reference = render(scene, exact_world, reference_options);
  std::printf("  reference: %.1f s, %s VPLs, clamping dropped %.3f %% of their energy\n", reference.stats.seconds,
              reference.stats.integrator["virtual_point_lights"].dump().c_str(),
              100 * reference.stats.integrator["clamped_energy_fraction"].get<double>());

  RenderOptions single = base;
  single.group_connections = false;
  const RenderResult grouped_result = timed(exact_world, base), single_result = timed(exact_world, single);
  const double connections = static_cast<double>(grouped_result.stats.vpl_connections + grouped_result.stats.shadow_rays);
  const double exact_seconds = grouped_result.stats.seconds, exact_mse = mse(grouped_result.image, reference.image);
  bool identical = grouped_result.image.pixels == single_result.image.pixels;
  std::printf("\nExact connections (2 threads), packets of %d against single rays:\n\n", exact_world.packet_width());
  std::printf("| exact | s | million segments / s | ratio |\n| --- | ---: | ---: | ---: |\n");
  std::printf("| single rays | %.2f | %.2f | 1.00 |\n", single_result.stats.seconds, connections / single_result.stats.seconds / 1e6);
  std::printf("| packets | %.2f | %.2f | %.2f |\n", exact_seconds, connections / exact_seconds / 1e6,
              single_result.stats.seconds / exact_seconds);
  std::printf("images %s\n", identical ? "bit-identical" : "DIFFERENT");
  if (!images.empty()) write_png(images / "exact.png", grouped_result.image);

  struct Row {
    std::string mode;
    double seconds, mse_exact_image, mse_reference;
  };
  std::vector<Row> rows = {{"exact", exact_seconds, 0, exact_mse}};
  struct Crossover {
    int level;
    double linear, clusters, grid;  // seconds
  };
  std::vector<Crossover> crossover;
  std::vector<Row> control_variates;
  for (const int level : levels) {
    const std::string spec = "spheres:" + std::to_string(level);
    const std::vector<MeshProxies> proxies =
        prepare_scene_proxies(scene, {.cache = cache, .stochastic_spec = spec, .seed = 1, .on_proxy = nullptr});
    const RenderWorld world(scene, proxies);
    RenderOptions spheres = base;
    spheres.visibility = VisibilityMode::spheres;
    const RenderResult s = timed(world, spheres);
    rows.push_back({spec + " occluder disks", s.stats.seconds, mse(s.image, grouped_result.image), mse(s.image, reference.image)});
    if (!images.empty()) write_png(images / ("spheres-" + std::to_string(level) + ".png"), s.image);
    // Every ball against every connection, the clusters' bounds first (the render above),
    // and the grid: the same image, three timings.
    RenderOptions linear = spheres, grid = spheres;
    linear.disk_grid_from = static_cast<std::size_t>(-1);
    linear.disk_clusters = false;
    grid.disk_grid_from = 0;
    const RenderResult l = timed(world, linear), g = timed(world, grid);
    if (l.image.pixels != s.image.pixels || g.image.pixels != s.image.pixels) {
      std::printf("  %s: linear, clustered and grid images DIFFER\n", spec.c_str());
      identical = false;
    }
    crossover.push_back({level, l.stats.seconds, s.stats.seconds, g.stats.seconds});
    if (level == levels.back() || level == 100) {
      for (const SelfShadow self : {SelfShadow::none, SelfShadow::exact}) {
        RenderOptions o = spheres;
        o.self_shadow = self;
        const RenderResult r = timed(world, o);
        rows.push_back({spec + " occluder disks, self-shadow " + std::string(name_of(self)), r.stats.seconds,
                        mse(r.image, grouped_result.image), mse(r.image, reference.image)});
        if (!images.empty())
          write_png(images / ("spheres-" + std::to_string(level) + "-self-" + std::string(name_of(self)) + ".png"), r.image);
      }
    }
    for (const auto& [scale, split] : cv_variants) {
      RenderOptions cv = base;
      cv.split = split;
      cv.visibility = VisibilityMode::stochastic;
      cv.estimator = StochasticEstimator::control_variate;
      cv.probabilities = ProbabilityMode::learned;
      cv.correction_scale = scale;
      const RenderResult c = timed(world, cv);
      char label[96];
      std::snprintf(label, sizeof label, " control variate, learned, scale %g%s", scale, split ? "" : ", no split");
      control_variates.push_back({spec + label, c.stats.seconds, mse(c.image, grouped_result.image), mse(c.image, reference.image)});
      if (!images.empty() && scale == scales.back() && !split) write_png(images / ("control-variate-" + std::to_string(level) + ".png"), c.image);
      std::printf("  %s: occluder disks %.2f s; control variate (scale %g%s) %.2f s, exact corrections per connection %.3f\n",
                  spec.c_str(), s.stats.seconds, scale, split ? "" : ", no split", c.stats.seconds,
                  static_cast<double>(c.stats.control_variate.after_hit + c.stats.control_variate.after_miss) /
                      static_cast<double>(std::max<std::uint64_t>(c.stats.vpl_connections + c.stats.shadow_rays, 1)));
    }
  }

  std::printf("\nVisibility of the VPL connections (same samples and VPLs in every mode; MSE over pixels and RGB):\n\n");
  std::printf("| mode | s | speed-up over exact | MSE against the exact image | MSE against the reference | efficiency / exact |\n");
  std::printf("| --- | ---: | ---: | ---: | ---: | ---: |\n");
  auto print = [&](const Row& r) {
    std::printf("| %s | %.2f | %.2f | %.3g | %.3g | %.2f |\n", r.mode.c_str(), r.seconds, exact_seconds / r.seconds, r.mse_exact_image,
                r.mse_reference, (exact_mse * exact_seconds) / (r.mse_reference * r.seconds));
  };
  for (const Row& r : rows) print(r);
  for (const Row& r : control_variates) print(r);
  std::printf("\n(efficiency: 1 / (MSE against the reference x time); exact's MSE is its own noise, %.3g)\n", exact_mse);

  std::printf("\nOccluder disks, spheres visibility (whole renders): every ball against every connection (linear), the bounds of "
              "clusters of balls first (default), and the direction grid; same images:\n\n");
  std::printf("| spheres | linear s | clusters s | grid s | linear / clusters | linear / grid |\n| ---: | ---: | ---: | ---: | ---: | ---: |\n");
  std::sort(crossover.begin(), crossover.end(), [](const Crossover& a, const Crossover& b) { return a.level < b.level; });
  for (const Crossover& c : crossover)
    std::printf("| %d | %.2f | %.2f | %.2f | %.2f | %.2f |\n", c.level, c.linear, c.clusters, c.grid, c.linear / c.clusters,
                c.linear / c.grid);
  disk_loop_benchmark();
  return identical ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  visproxy::disable_transparent_huge_pages();  // see visproxy/core/process.h
  try {
    return run(argc, argv);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "visproxy-bench-vpl: %s\n", error.what());
    return 2;
  }
}
