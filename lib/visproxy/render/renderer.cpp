// The render loop (tiles, passes, per-pixel streams, the result) shared by every
// integrator and visibility strategy.

#include "visproxy/render/renderer.h"

#include "visproxy/core/errors.h"
#include "visproxy/render/integrators/integrator.h"
#include "visproxy/render/visibility/visibility.h"
#include "visproxy/render/world/query_costs.h"

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

// ProbabilityMode::learned with the control variate and direct light: per instance, the
// modelled costs of a segment from its points (render/world/query_costs.h, averaged over the
// segments of 4000 pairs of camera samples seeded from the render's seed; the camera ray's
// and shading's work shared among the sample's shadow rays), and the exact render's noise
// relative to a segment's squared contribution: within each pair (one pixel) the luminance
// difference of the two samples traced exactly, sum (x_a - x_b)^2 / 2 over sum (c_a^2 +
// c_b^2) / 2, c a segment's unoccluded contribution. The same segments, traced against the
// proxies the control variate would ask too, give each instance its prior: the share of its
// segments the proxy answers each way and how often wrongly, worth kPriorSegments of a
// pixel's own. An instance none of whose points was met gets what all of them had together.
// Empty when no sample found a lit segment.
constexpr double kPriorSegments = 16;

struct SceneCorrectionCosts {
  std::vector<CorrectionCosts> costs;
  std::vector<CorrectionPrior> priors;
  std::vector<SegmentQueryCosts> work;  // per instance, the averages the costs come from
  double noise = 0;
};

SceneCorrectionCosts scene_correction_costs(const VisibilityContext& context) {
  const Scene& scene = context.scene;
  const RenderWorld& world = context.world;
  const RenderOptions& options = context.options;
  const std::size_t n = scene.instances.size();
  const Vertex camera = CameraRays(scene.camera).origin();
  const double per_segment = 1.0 / std::max(options.shadow_rays, 1);  // a camera sample's share
  std::vector<SegmentQueryCosts> sums(n + 1);  // the last: every instance
  std::vector<double> counts(n + 1, 0.0);
  std::vector<CorrectionEvidence> evidence(n + 1);
  RenderStats uncounted;  // the proxy queries below are not the render's
  double noise = 0, squares = 0;
  auto luminance = [](const Color& c) { return c.mean(); };
  for (const std::array<CameraSample, 2>& pair : scene_sample_pairs(scene, world, 4000, options.seed ^ 0x636F737473ULL)) {
    std::array<double, 2> value{};
    for (std::size_t k = 0; k < 2; ++k) {
      const CameraSample& sample = pair[k];
      value[k] = luminance(sample.emitted);
      if (!sample.has_segment) continue;
      const ShadowSegment& s = sample.segment;
      const double c = luminance(sample.contribution);
      squares += c * c / 2;
      const SegmentQueryCosts q = segment_query_costs(world, camera, s.from, s.to, s.instance, options.split);
      // The exact answer: the own mesh (which the split answer traced exactly), else the rest.
      const ProxyAnswer answer = proxy_answer(world, s.from, s.to, s.instance, options.split, uncounted, false);
      const bool mesh = !answer.own_blocks && world.mesh_blocks(s.from, s.to, answer.rest);
      if (!answer.own_blocks && !mesh) value[k] += c;
      for (const std::size_t i : {static_cast<std::size_t>(s.instance), n}) {
        sums[i].camera += q.camera * per_segment, sums[i].exact += q.exact, sums[i].proxy += q.proxy;
        sums[i].correction += q.correction;
        counts[i] += 1;
        if (!answer.own_blocks) evidence[i].answer(answer.proxy_blocked), evidence[i].add(answer.proxy_blocked, mesh);
      }
    }
    noise += (value[0] - value[1]) * (value[0] - value[1]) / 2;
  }
  SceneCorrectionCosts result;
  if (!(counts[n] > 0) || !(squares > 0) || !(noise > 0)) return result;  // nothing to weigh: the cost-blind rule
  result.noise = noise / squares;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t from = counts[i] > 0 ? i : n;
    const double m = counts[from];
    result.priors.push_back(CorrectionPrior::from(evidence[from], kPriorSegments));
    const SegmentQueryCosts w{sums[from].camera / m, sums[from].exact / m, sums[from].proxy / m, sums[from].correction / m};
    result.work.push_back(w);
    result.costs.push_back({.base = w.camera + w.proxy, .correction = w.correction, .exact = w.camera + w.exact, .variance = result.noise});
  }
  return result;
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

  VisibilityContext visibility_context{scene, world, options, lights, pixels, {}, {}, {}};
  const bool optimal = stochastic && options.probabilities == ProbabilityMode::optimal;
  if (optimal) visibility_context.optimal = scene_optimal_probabilities(visibility_context);
  SceneCorrectionCosts correction_costs;
  if (stochastic && options.probabilities == ProbabilityMode::learned && options.estimator == StochasticEstimator::control_variate &&
      options.integrator == IntegratorKind::direct) {
    correction_costs = scene_correction_costs(visibility_context);
    visibility_context.correction_costs = correction_costs.costs;
    visibility_context.correction_priors = correction_costs.priors;
  }
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
  if (!correction_costs.costs.empty()) {
    nlohmann::json instances = nlohmann::json::array();
    for (std::size_t i = 0; i < correction_costs.work.size(); ++i) {
      const SegmentQueryCosts& w = correction_costs.work[i];
      instances.push_back({{"instance", i},
                           {"mesh", scene.instances[i].mesh},
                           {"camera_work", w.camera},
                           {"exact_work", w.exact},
                           {"proxy_work", w.proxy},
                           {"correction_work", w.correction},
                           {"proxy_blocks_share", correction_costs.priors[i].share[1]},
                           {"wrong_when_letting_through", correction_costs.priors[i].disagreeing[0]},
                           {"wrong_when_blocking", correction_costs.priors[i].disagreeing[1]}});
    }
    result.stats.learned_costs = {{"noise_per_segment", correction_costs.noise}, {"instances", instances}};
  }
  result.stats.passes = passes;
  result.stats.counted = counting;
  result.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace visproxy
