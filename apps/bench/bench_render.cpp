// `--visibility bounds` against `--visibility exact` on one scene, in one process: the same
// samples (same seed) rendered alternately, the images checked bit for bit, the wall times
// compared (target: bounds faster than exact at an identical image), and the deterministic
// work of both from a counted render (BVH nodes visited and primitives tested).
//   visproxy-bench-render SCENE [--spp N] [--shadow-rays M] [--repetitions R] [--cache DIR]

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/core/process.h"
#include "visproxy/render/scene_proxies.h"
#include "visproxy/render/renderer.h"

namespace {

using namespace visproxy;

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

int run(int argc, char** argv) {
  std::string scene_path;
  int spp = 32, shadow_rays = 4, repetitions = 5;
  std::filesystem::path cache = default_proxy_cache();
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw Error("missing value after " + arg);
      return argv[++i];
    };
    if (arg == "--spp") spp = std::stoi(value());
    else if (arg == "--shadow-rays") shadow_rays = std::stoi(value());
    else if (arg == "--repetitions") repetitions = std::stoi(value());
    else if (arg == "--cache") cache = value();
    else if (arg.starts_with("--")) throw Error("unknown option " + arg);
    else scene_path = arg;
  }
  if (scene_path.empty())
    throw Error("usage: visproxy-bench-render SCENE [--spp N] [--shadow-rays M] [--repetitions R] [--cache DIR]");
  if (spp < 1 || shadow_rays < 1 || repetitions < 1) throw Error("--spp, --shadow-rays and --repetitions must be positive");

  const Scene scene = load_scene(scene_path);
  const std::vector<MeshProxies> proxies =
      prepare_scene_proxies(scene, {.cache = cache, .stochastic_spec = std::nullopt, .seed = 1, .on_proxy = nullptr});
  const RenderWorld world(scene, proxies);
  std::printf("visproxy-bench-render: %s, %dx%d, %d spp x %d shadow rays, seed 1, %d repetitions (alternating)\n",
              scene_path.c_str(), scene.camera.width, scene.camera.height, spp, shadow_rays, repetitions);
  for (std::size_t i = 0; i < scene.instances.size(); ++i)
    if (proxies[i].outside || proxies[i].inside)
      std::printf("  instance %zu (%s): outside proxy %s, inside proxy %s\n", i, scene.instances[i].mesh.c_str(),
                  proxies[i].outside ? proxies[i].outside->spec.c_str() : "none",
                  proxies[i].inside ? proxies[i].inside->spec.c_str() : "none");

  RenderOptions exact{.spp = spp, .shadow_rays = shadow_rays, .seed = 1};
  RenderOptions bounds = exact;
  bounds.visibility = VisibilityMode::bounds;
  render(scene, world, exact);  // warm-up: page in the BVHs
  std::vector<double> exact_seconds, bounds_seconds, ratios;
  bool identical = true;
  for (int r = 0; r < repetitions; ++r) {
    // Alternate the order so that neither mode always runs on a warmer machine.
    RenderResult a, b;
    if (r % 2 == 0) {
      a = render(scene, world, exact);
      b = render(scene, world, bounds);
    } else {
      b = render(scene, world, bounds);
      a = render(scene, world, exact);
    }
    identical = identical && a.image.pixels == b.image.pixels;
    exact_seconds.push_back(a.stats.seconds);
    bounds_seconds.push_back(b.stats.seconds);
    ratios.push_back(b.stats.seconds / a.stats.seconds);
    std::printf("  run %d: exact %.3f s, bounds %.3f s, bounds / exact %.3f\n", r + 1, a.stats.seconds, b.stats.seconds,
                ratios.back());
  }
  const RenderWorld counting(scene, proxies, {.counting = true});
  RenderOptions counted_exact = exact, counted_bounds = bounds;
  counted_exact.spp = counted_bounds.spp = std::min(spp, 4);
  const RenderStats ce = render(scene, counting, counted_exact).stats, cb = render(scene, counting, counted_bounds).stats;
  std::printf("\n| mode | median s | best s | exact tests per ray | proxy tests per ray | traversal steps per ray | primitive tests per ray |\n");
  std::printf("| --- | ---: | ---: | ---: | ---: | ---: | ---: |\n");
  auto per_ray = [](std::uint64_t n, const RenderStats& s) { return static_cast<double>(n) / static_cast<double>(std::max<std::uint64_t>(s.shadow_rays, 1)); };
  std::printf("| exact | %.3f | %.3f | %.3f | %.3f | %.2f | %.2f |\n", median(exact_seconds),
              *std::min_element(exact_seconds.begin(), exact_seconds.end()), per_ray(ce.exact_tests, ce), per_ray(ce.proxy_tests, ce),
              per_ray(ce.traversal_steps, ce), per_ray(ce.primitive_tests, ce));
  std::printf("| bounds | %.3f | %.3f | %.3f | %.3f | %.2f | %.2f |\n", median(bounds_seconds),
              *std::min_element(bounds_seconds.begin(), bounds_seconds.end()), per_ray(cb.exact_tests, cb), per_ray(cb.proxy_tests, cb),
              per_ray(cb.traversal_steps, cb), per_ray(cb.primitive_tests, cb));
  std::printf("\nbounds / exact wall time: median %.3f (min %.3f, max %.3f); counted traversal steps %.3f, primitive tests %.3f; "
              "images %s\n",
              median(ratios), *std::min_element(ratios.begin(), ratios.end()), *std::max_element(ratios.begin(), ratios.end()),
              static_cast<double>(cb.traversal_steps) / static_cast<double>(std::max<std::uint64_t>(ce.traversal_steps, 1)),
              static_cast<double>(cb.primitive_tests) / static_cast<double>(std::max<std::uint64_t>(ce.primitive_tests, 1)),
              identical ? "bit-identical" : "DIFFERENT");
  return identical ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  visproxy::disable_transparent_huge_pages();  // see visproxy/core/process.h
  try {
    return run(argc, argv);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "visproxy-bench-render: %s\n", error.what());
    return 2;
  }
}
