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

std::string_view stochastic_estimator_name(StochasticEstimator estimator) {
  return estimator == StochasticEstimator::control_variate ? "control-variate" : "eq8";
}

std::string_view probability_mode_name(ProbabilityMode mode) {
  switch (mode) {
    case ProbabilityMode::equal: return "equal";
    case ProbabilityMode::adaptive: return "adaptive";
    case ProbabilityMode::learned: return "learned";
  }
  return "equal";
}

std::string_view visibility_mode_name(VisibilityMode mode) {
  switch (mode) {
    case VisibilityMode::exact: return "exact";
    case VisibilityMode::stochastic: return "stochastic";
    case VisibilityMode::bounds: return "bounds";
    case VisibilityMode::spheres: return "spheres";
  }
  return "exact";
}

std::string_view integrator_name(IntegratorKind integrator) {
  switch (integrator) {
    case IntegratorKind::direct: return "direct";
    case IntegratorKind::vpl: return "vpl";
    case IntegratorKind::lightcuts: return "lightcuts";
  }
  return "direct";
}

std::string_view visibility_bounds_name(VisibilityBounds bounds) {
  switch (bounds) {
    case VisibilityBounds::none: return "none";
    case VisibilityBounds::lower: return "lower";
    case VisibilityBounds::upper: return "upper";
    case VisibilityBounds::both: return "both";
  }
  return "none";
}

std::string_view self_shadow_name(SelfShadow self_shadow) {
  switch (self_shadow) {
    case SelfShadow::heuristic: return "heuristic";
    case SelfShadow::exact: return "exact";
    case SelfShadow::none: return "none";
  }
  return "heuristic";
}

void validate(const RenderOptions& options) {
  auto fail = [](const std::string& problem) { throw Error("render options: " + problem); };
  if (options.spp < 1) fail("spp (camera samples per pixel) must be at least 1, not " + std::to_string(options.spp));
  if (options.shadow_rays < 1) fail("shadow_rays must be at least 1, not " + std::to_string(options.shadow_rays));
  if (options.probe_passes < 0) fail("probe_passes must not be negative");
  if (!(options.seconds >= 0) || !std::isfinite(options.seconds)) fail("seconds must be a finite number, 0 or more");
  if (!(options.probability_floor >= 0 && options.probability_floor <= 1.0 / 3))
    fail("probability_floor must lie in [0, 1/3]");
  if (!(options.correction_scale > 0) || !std::isfinite(options.correction_scale)) fail("correction_scale must be positive");
  if (options.integrator == IntegratorKind::lightcuts) {
    if (options.visibility != VisibilityMode::exact)
      fail("lightcuts traces its representatives exactly: use visibility exact (its proofs are the visibility bounds)");
    if (options.light_points < 1) fail("light_points must be at least 1, not " + std::to_string(options.light_points));
    if (!(options.lightcut.error >= 0) || !std::isfinite(options.lightcut.error)) fail("the lightcut error must be a finite number, 0 or more");
    if (options.lightcut.max_cut < 1) fail("max_cut must be at least 1, not " + std::to_string(options.lightcut.max_cut));
  }
  if (options.integrator == IntegratorKind::vpl || (options.integrator == IntegratorKind::lightcuts && options.lightcut_vpls)) {
    if (!options.virtual_point_lights && options.vpls < 1) fail("vpls (light paths) must be at least 1, not " + std::to_string(options.vpls));
    if (options.bounces < 1) fail("bounces must be at least 1, not " + std::to_string(options.bounces));
    if (!(options.vpl_clamp >= 0) || !std::isfinite(options.vpl_clamp)) fail("vpl_clamp must be a finite number, 0 or more");
    if (options.virtual_point_lights)
      for (const VirtualPointLight& light : *options.virtual_point_lights)
        if (!light.position.allFinite() || !light.power.allFinite() || !light.brdf.allFinite() || (light.power.array() < 0).any() ||
            (light.brdf.array() < 0).any() || !(std::abs(light.normal.norm() - 1) < 1e-6) || light.bounce < 1 ||
            !(light.distance >= 0) || !std::isfinite(light.distance))
          fail("virtual point lights need finite positions, unit normals, finite, non-negative power and BRDF, a bounce "
               "of at least 1 and a finite, non-negative distance");
  }
  if (options.visibility != VisibilityMode::stochastic) return;
  const bool control_variate = options.estimator == StochasticEstimator::control_variate;
  if (options.probabilities == ProbabilityMode::learned && !control_variate)
    fail("learned probabilities need the control-variate estimator");
  if (options.probabilities == ProbabilityMode::adaptive && options.probe_rays < 1)
    fail("adaptive probabilities need at least one probe ray");
  if (options.probabilities != ProbabilityMode::equal && !(options.probability_floor > 0))
    fail("probability_floor must be positive with adaptive or learned probabilities: a ray type the probes or a "
         "pixel's corrections have not seen would get probability 0, and the estimate would be biased wherever it occurs");
}

nlohmann::json RenderStats::to_json() const {
  const double rays = static_cast<double>(std::max<std::uint64_t>(shadow_rays, 1));
  return {{"seconds", seconds},
          {"passes", passes},
          {"camera_samples", camera_samples},
          {"shading_points", shading_points},
          {"shadow_rays", shadow_rays},
          {"exact_tests", exact_tests},
          {"proxy_tests", proxy_tests},
          {"probe_rays", probe_rays},
          {"exact_tests_per_shadow_ray", static_cast<double>(exact_tests) / rays},
          {"proxy_tests_per_shadow_ray", static_cast<double>(proxy_tests) / rays},
          {"stochastic_terms", {{"a_proxy_only", term_counts[0]}, {"b_mesh_if_proxy_hit", term_counts[1]}, {"c_mesh_if_proxy_missed", term_counts[2]}}},
          {"control_variate_corrections", {{"after_proxy_missed", corrections_after_miss}, {"after_proxy_hit", corrections_after_hit}}},
          {"bounds", {{"unoccluded_by_outside_proxies", bounds_unoccluded}, {"occluded_by_inside_proxies", bounds_occluded}, {"traced_exactly", bounds_traced}, {"shading_points_with_culled_shaft", shafts_culled}}},
          {"vpl_connections", vpl_connections},
          {"disk_tests", disk_tests},
          {"disk_clusters", disk_clusters},
          {"integrator", integrator.is_null() ? nlohmann::json::object() : integrator},
          {"counted", counted},
          {"traversal_steps", counted ? nlohmann::json(traversal_steps) : nlohmann::json(nullptr)},
          {"primitive_tests", counted ? nlohmann::json(primitive_tests) : nlohmann::json(nullptr)},
          {"traversal_steps_per_shadow_ray", counted ? nlohmann::json(static_cast<double>(traversal_steps) / rays) : nlohmann::json(nullptr)},
          {"primitive_tests_per_shadow_ray", counted ? nlohmann::json(static_cast<double>(primitive_tests) / rays) : nlohmann::json(nullptr)}};
}

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
    const Vertex to_light = y.position - x;
    double cos_y = -y.normal.dot(to_light);
    if (y.two_sided) cos_y = std::abs(cos_y);
    if (hit->normal.dot(to_light) <= 0 || cos_y <= 0) continue;
    segments.push_back({x, light_end(world, y, x)});
  }
  return segments;
}

RenderResult render(const Scene& scene, const RenderWorld& world, const RenderOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const int width = scene.camera.width, height = scene.camera.height;
  validate(options);
  const CameraRays camera(scene.camera);
  const LightSampler lights(scene);
  const bool stochastic = options.visibility == VisibilityMode::stochastic;
  const bool counting = world.counting();
  const std::size_t pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);

  const std::unique_ptr<Visibility> visibility = make_visibility({scene, world, options, lights, pixels});
  const IntegratorContext integrator_context{scene, world, options, lights};
  const std::unique_ptr<Integrator> integrator = options.integrator == IntegratorKind::vpl ? make_vpl_integrator(integrator_context)
                                                 : options.integrator == IntegratorKind::lightcuts
                                                     ? make_lightcuts_integrator(integrator_context)
                                                     : make_direct_integrator(integrator_context);
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
  for (const RenderStats& s : thread_stats) {
    RenderStats& r = result.stats;
    r.camera_samples += s.camera_samples, r.shading_points += s.shading_points, r.shadow_rays += s.shadow_rays;
    r.exact_tests += s.exact_tests, r.proxy_tests += s.proxy_tests, r.probe_rays += s.probe_rays;
    for (int i = 0; i < 3; ++i) r.term_counts[i] += s.term_counts[i];
    r.corrections_after_miss += s.corrections_after_miss, r.corrections_after_hit += s.corrections_after_hit;
    r.bounds_unoccluded += s.bounds_unoccluded, r.bounds_occluded += s.bounds_occluded, r.bounds_traced += s.bounds_traced;
    r.traversal_steps += s.traversal_steps, r.primitive_tests += s.primitive_tests;
    r.shafts_culled += s.shafts_culled;
    r.vpl_connections += s.vpl_connections, r.disk_tests += s.disk_tests, r.disk_clusters += s.disk_clusters;
  }
  integrator->fill_maps(result, std::max(passes, 1));
  result.stats.integrator = integrator->describe();
  result.stats.passes = passes;
  result.stats.counted = counting;
  result.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace visproxy
