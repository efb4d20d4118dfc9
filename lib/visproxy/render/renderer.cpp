// The render loop (tiles, passes, per-pixel streams, the result) shared by every
// integrator and visibility strategy.

#include "visproxy/render/renderer.h"

#include "visproxy/core/errors.h"
#include "visproxy/render/integrators/integrator.h"
#include "visproxy/render/visibility/visibility.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <optional>
#include <utility>

namespace visproxy {
namespace {

// Runs a callable when the scope ends, on every return path.
template <typename F>
class ScopeExit {
 public:
  explicit ScopeExit(F f) : f_(std::move(f)) {}
  ~ScopeExit() { f_(); }
  ScopeExit(const ScopeExit&) = delete;
  ScopeExit& operator=(const ScopeExit&) = delete;

 private:
  F f_;
};

}  // namespace


std::vector<ShadowSegment> scene_shadow_segments(const Scene& scene, const RenderWorld& world, std::size_t count,
                                                 std::uint64_t seed, const std::vector<bool>& exclude) {
  const CameraRays camera(scene.camera);
  const LightSampler lights(scene);
  std::vector<ShadowSegment> segments;
  if (lights.empty()) return segments;
  PixelRandom random(seed, 0, 0);
  for (std::size_t attempt = 0; attempt < 100 * count && segments.size() < count; ++attempt) {
    const double u = random.uniform(), v = random.uniform();
    const std::optional<SurfaceHit> hit = world.intersect(camera.origin(), camera.direction_at(u, v));
    const LightSample y = lights.sample(random);
    if (!hit || hit->light >= 0 || exclude[static_cast<std::size_t>(hit->instance)]) continue;
    const Vertex x = hit->position + world.surface_offset(hit->position, hit->distance) * hit->normal;
    if (!light_geometry(x, hit->normal, y)) continue;
    segments.push_back({x, light_end(world, y, x), hit->instance});
  }
  return segments;
}

std::vector<std::array<CameraSample, 2>> scene_sample_pairs(const Scene& scene, const RenderWorld& world, std::size_t pairs,
                                                            std::uint64_t seed) {
  const CameraRays camera(scene.camera);
  const LightSampler lights(scene);
  std::vector<std::array<CameraSample, 2>> samples(pairs);
  PixelRandom random(seed, 0, 0);
  const int width = scene.camera.width, height = scene.camera.height;
  for (std::array<CameraSample, 2>& pair : samples) {
    const int px = std::min(width - 1, static_cast<int>(random.uniform() * width));
    const int py = std::min(height - 1, static_cast<int>(random.uniform() * height));
    for (CameraSample& sample : pair) {
      const double jx = random.uniform(), jy = random.uniform();
      const std::optional<SurfaceHit> hit = world.intersect(camera.origin(), camera.direction(px + jx, py + jy));
      if (!hit) continue;
      if (hit->light >= 0) {
        const AreaLight& light = scene.lights[static_cast<std::size_t>(hit->light)];
        if (hit->light_front || light.two_sided) sample.emitted = light.radiance;
        continue;
      }
      if (lights.empty()) continue;
      // As direct_light() draws it: one point on the lights by area.
      const LightSample y = lights.sample(random);
      const Vertex x = hit->position + world.surface_offset(hit->position, hit->distance) * hit->normal;
      const std::optional<LightGeometry> g = light_geometry(x, hit->normal, y);
      if (!g) continue;
      const Color brdf = scene.instances[static_cast<std::size_t>(hit->instance)].albedo / std::numbers::pi;
      sample.contribution = brdf.cwiseProduct(y.radiance) * (g->cos_x * g->cos_y / g->distance2 * lights.total_area());
      sample.has_segment = true;
      sample.segment = {x, light_end(world, y, x), hit->instance};
    }
  }
  return samples;
}

namespace {

// ProbabilityMode::optimal: eq. 8's optimal probabilities for each form of the rest of the
// scene, from the ray types of the scene's own shadow segments (20 000, seeded from the
// render's seed), each traced against the proxies and meshes of the instances its estimate
// would see (all but its own with visibility splitting), as the probe rays of adaptive are.
std::array<Probabilities, 3> scene_optimal_probabilities(const VisibilityContext& context) {
  const Scene& scene = context.scene;
  const RenderWorld& world = context.world;
  const RenderOptions& options = context.options;
  std::array<RayTypeCounts, 3> counts;
  const std::vector<bool> none(scene.instances.size(), false);
  const std::vector<ProxyKind> kinds = stochastic_kinds(context);
  for (const ShadowSegment& s : scene_shadow_segments(scene, world, 20000, options.seed ^ 0x6F7074696D616CULL, none)) {
    const InstanceFilter rest{.skip = options.split ? s.instance : -1, .only = -1};
    const bool mesh = world.mesh_blocks(s.from, s.to, rest), proxy = world.proxy_blocks(s.from, s.to, rest);
    counts[static_cast<std::size_t>(kinds[static_cast<std::size_t>(s.instance)])].add(mesh, proxy);
    if (kinds[static_cast<std::size_t>(s.instance)] != ProxyKind::general)
      counts[static_cast<std::size_t>(ProxyKind::general)].add(mesh, proxy);  // connections use the general form
  }
  std::array<Probabilities, 3> optimal;
  for (const ProxyKind kind : {ProxyKind::outside, ProxyKind::inside, ProxyKind::general})
    optimal[static_cast<std::size_t>(kind)] =
        optimal_probabilities(kind, RayTypeFractions::from(counts[static_cast<std::size_t>(kind)]), {.floor = options.probability_floor});
  return optimal;
}

}  // namespace

RenderResult render(const Scene& scene, const RenderWorld& world, const RenderOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const int width = scene.camera.width, height = scene.camera.height;
  validate(options);
  const CameraRays camera(scene.camera);
  const LightSampler lights(scene);
  const bool stochastic = options.visibility == VisibilityMode::stochastic;
  const bool counting = world.counting();
  const std::size_t pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);

  VisibilityContext visibility_context{scene, world, options, lights, pixels};
  const bool optimal = stochastic && options.probabilities == ProbabilityMode::optimal;
  if (optimal) visibility_context.optimal = scene_optimal_probabilities(visibility_context);
  const std::unique_ptr<Visibility> visibility = make_visibility(visibility_context);
  const IntegratorContext integrator_context{scene, world, options, lights};
  const std::unique_ptr<Integrator> integrator = make_integrator(integrator_context);
  // The VPL integrator shades with its VPLs even where no area light is left.
  const bool needs_lights = options.integrator == IntegratorKind::direct;

  std::vector<Color> sum(pixels, Color::Zero());
  std::vector<double> p1_sum(sum.size(), 0.0), p1_count(sum.size(), 0.0), tests(sum.size(), 0.0);
  tbb::enumerable_thread_specific<RenderStats> thread_stats;
  tbb::enumerable_thread_specific<std::unique_ptr<PointVisibility>> thread_visibility([&] { return visibility->point_visibility(); });

  auto shade = [&](int px, int py, int pass) {
    const std::size_t pixel = static_cast<std::size_t>(py) * static_cast<std::size_t>(width) + static_cast<std::size_t>(px);
    // Camera and light samples come from one stream, the stochastic estimators' choices
    // (terms, corrections, probe rays) from another: every visibility mode traces the same
    // segments for a seed, so images of two modes differ only by their visibility answers.
    PixelRandom random(options.seed, pixel, static_cast<std::uint64_t>(pass));
    PixelRandom choices(options.seed ^ kChoiceStream, pixel, static_cast<std::uint64_t>(pass));
    RenderStats& stats = thread_stats.local();
    const std::uint64_t tests_before = stats.exact_tests + stats.proxy_tests;
    const TraversalCounts counts_before = RenderWorld::thread_counts();
    // Whatever path the sample takes, its work lands in the stats and the cost map.
    const ScopeExit account([&] {
      const TraversalCounts& now = RenderWorld::thread_counts();
      const std::uint64_t steps = now.nodes - counts_before.nodes, primitives = now.primitives - counts_before.primitives;
      stats.traversal_steps += steps;
      stats.primitive_tests += primitives;
      tests[pixel] += counting ? static_cast<double>(steps + primitives)
                               : static_cast<double>(stats.exact_tests + stats.proxy_tests - tests_before);
    });
    ++stats.camera_samples;
    const double jx = random.uniform();
    const double jy = random.uniform();
    const std::optional<SurfaceHit> hit = world.intersect(camera.origin(), camera.direction(px + jx, py + jy));
    if (!hit) return;
    if (hit->light >= 0) {
      const AreaLight& light = scene.lights[static_cast<std::size_t>(hit->light)];
      if (hit->light_front || light.two_sided) sum[pixel] += light.radiance;
      return;
    }
    if (needs_lights && lights.empty()) return;
    ++stats.shading_points;
    const ShadingPoint point{.pixel = pixel,
                             .pass = pass,
                             .hit = &*hit,
                             .position = hit->position + world.surface_offset(hit->position, hit->distance) * hit->normal,
                             .choices = &choices,
                             .stats = &stats,
                             .p1_sum = &p1_sum[pixel],
                             .p1_count = &p1_count[pixel]};
    const Color brdf = scene.instances[static_cast<std::size_t>(hit->instance)].albedo / std::numbers::pi;
    PointVisibility& answers = *thread_visibility.local();
    answers.begin(point);
    sum[pixel] += integrator->shade(point, brdf, random, answers);
    answers.end();
  };

  constexpr int tile = 16;
  const int tiles_x = (width + tile - 1) / tile, tiles_y = (height + tile - 1) / tile;
  int passes = 0;
  for (; passes < options.spp; ++passes) {
    tbb::parallel_for(tbb::blocked_range<int>(0, tiles_x * tiles_y), [&](const tbb::blocked_range<int>& range) {
      for (int t = range.begin(); t != range.end(); ++t) {
        const int x0 = (t % tiles_x) * tile, y0 = (t / tiles_x) * tile;
        for (int y = y0; y < std::min(y0 + tile, height); ++y)
          for (int x = x0; x < std::min(x0 + tile, width); ++x) shade(x, y, passes);
      }
    });
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (options.on_pass) options.on_pass(passes + 1, elapsed);
    if (options.seconds > 0 && elapsed >= options.seconds) {
      ++passes;
      break;
    }
  }

  RenderResult result;
  result.image = Image(width, height);
  result.cost_map = Image(width, height);
  if (stochastic) result.p1_map = Image(width, height);
  for (std::size_t i = 0; i < sum.size(); ++i) {
    result.image.pixels[i] = sum[i] / std::max(passes, 1);
    result.cost_map.pixels[i] = Color::Constant(tests[i] / std::max(passes, 1));
    if (stochastic) result.p1_map.pixels[i] = Color::Constant(p1_count[i] > 0 ? p1_sum[i] / p1_count[i] : 0.0);
  }
  for (const RenderStats& s : thread_stats) result.stats += s;
  result.cut_map = integrator->cut_map(std::max(passes, 1));
  result.stats.integrator = integrator->describe();
  if (optimal)
    for (const ProxyKind kind : {ProxyKind::outside, ProxyKind::inside, ProxyKind::general}) {
      const Probabilities& p = visibility_context.optimal[static_cast<std::size_t>(kind)];
      result.stats.optimal_probabilities[std::string(kind_name(kind))] = {p.p1, p.p2, p.p3};
    }
  result.stats.passes = passes;
  result.stats.counted = counting;
  result.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace visproxy
