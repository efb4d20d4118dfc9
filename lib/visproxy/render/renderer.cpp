// The render loop (tiles, passes, per-pixel streams, the result) shared by every
// integrator and visibility strategy.

#include "visproxy/render/renderer.h"

#include "visproxy/core/errors.h"
#include "visproxy/render/integrators/integrator.h"
#include "visproxy/render/scene_learning.h"
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

// Everything a render keeps between passes: the per-pixel sums and the strategies' own
// per-pixel state, so that a session continued in several runs draws and answers exactly
// what one run of all its passes would.
struct RenderSession::State {
  State(const Scene& scene_, const RenderWorld& world_, const RenderOptions& options_)
      : scene(scene_),
        world(world_),
        options(options_),
        width(scene_.camera.width),
        height(scene_.camera.height),
        camera(scene_.camera),
        lights(scene_),
        pixels(static_cast<std::size_t>(width) * static_cast<std::size_t>(height)),
        visibility_context{scene_, world_, options, lights, pixels, {}, {}, {}, {}} {}

  const Scene& scene;
  const RenderWorld& world;
  const RenderOptions options;
  const int width, height;
  const CameraRays camera;
  const LightSampler lights;
  const std::size_t pixels;
  VisibilityContext visibility_context;
  bool optimal = false;
  SceneCorrectionCosts correction_costs;
  // Where a gate or the learned rule finds that no instance's proxy can pay: exact
  // visibility itself.
  bool traced_exactly_everywhere = false;
  std::vector<double> eq8_ratios;  // adaptive eq. 8's gate, per instance
  nlohmann::json disk_gate;  // what the VPL control variate's scene-level choice weighed
  nlohmann::json eq8_gate;   // what adaptive eq. 8's choice per instance weighed with VPLs
  std::unique_ptr<Visibility> visibility;
  std::unique_ptr<IntegratorContext> integrator_context;
  std::unique_ptr<Integrator> integrator;
  bool needs_lights = true;
  std::vector<Color> sum;
  std::vector<double> p1_sum, p1_count, tests;
  tbb::enumerable_thread_specific<RenderStats> thread_stats;
  std::unique_ptr<tbb::enumerable_thread_specific<std::unique_ptr<PointVisibility>>> thread_visibility;
  int passes = 0;
  double seconds = 0;  // in the constructor and in run(), not between runs

  // One camera sample; `stats` and `answers` are the calling thread's (looked up once per
  // range of tiles, not per sample).
  void shade(int px, int py, int pass, RenderStats& stats, PointVisibility& answers);
};

void RenderSession::State::shade(int px, int py, int pass, RenderStats& stats, PointVisibility& answers) {
  const std::size_t pixel = static_cast<std::size_t>(py) * static_cast<std::size_t>(width) + static_cast<std::size_t>(px);
  // Camera and light samples come from one stream, the stochastic estimators' choices
  // (terms, corrections, probe rays) from another: every visibility mode traces the same
  // segments for a seed, so images of two modes differ only by their visibility answers.
  PixelRandom random(options.seed, pixel, static_cast<std::uint64_t>(pass));
  PixelRandom choices(options.seed ^ kChoiceStream, pixel, static_cast<std::uint64_t>(pass));
  const bool counting = world.counting();
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
  answers.begin(point);
  sum[pixel] += integrator->shade(point, brdf, random, answers);
  answers.end();
}

RenderSession::RenderSession(const Scene& scene, const RenderWorld& world, const RenderOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  validate(options);
  state_ = std::make_unique<State>(scene, world, options);
  State& s = *state_;
  const bool stochastic = options.visibility == VisibilityMode::stochastic;
  s.optimal = stochastic && options.probabilities == ProbabilityMode::optimal;
  if (s.optimal) s.visibility_context.optimal = scene_optimal_probabilities(s.visibility_context);
  if (stochastic && options.probabilities == ProbabilityMode::learned && options.estimator == StochasticEstimator::control_variate &&
      options.integrator == IntegratorKind::direct) {
    s.correction_costs = scene_correction_costs(s.visibility_context);
    s.visibility_context.correction_costs = s.correction_costs.costs;
    s.visibility_context.correction_priors = s.correction_costs.priors;
    s.traced_exactly_everywhere = !s.correction_costs.costs.empty() && !any_proxy_can_pay(s.visibility_context);
  }
  if (stochastic && options.probabilities == ProbabilityMode::learned && options.estimator == StochasticEstimator::control_variate &&
      options.integrator == IntegratorKind::vpl && options.gate && control_variate_uses_disks(s.visibility_context)) {
    const DiskGate gate = scene_disk_gate(s.visibility_context);
    s.traced_exactly_everywhere = gate.trace_exactly;
    s.disk_gate = gate.to_json();
  }
  // Adaptive eq. 8 with direct light: the points of an instance where eq. 8 cannot pay at
  // the instance's modelled costs, probes included, trace every segment exactly; where no
  // instance's can, the render is exact visibility.
  if (stochastic && options.probabilities == ProbabilityMode::adaptive && options.estimator == StochasticEstimator::term_choice &&
      options.integrator == IntegratorKind::direct && options.gate) {
    s.correction_costs = scene_correction_costs(s.visibility_context);
    if (!s.correction_costs.costs.empty()) {
      s.eq8_ratios = adaptive_eq8_ratios(s.visibility_context, s.correction_costs);
      std::vector<std::uint8_t>& exact = s.visibility_context.trace_exactly_from;
      for (const double ratio : s.eq8_ratios) exact.push_back(ratio >= kLearnedPaysBelow ? 1 : 0);
      s.traced_exactly_everywhere = std::all_of(exact.begin(), exact.end(), [](std::uint8_t e) { return e != 0; });
    }
  }
  // Adaptive eq. 8 with VPLs: the same per instance, weighed on camera samples shaded by
  // the VPL integrator (its connections are what eq. 8 pays for).
  if (stochastic && options.probabilities == ProbabilityMode::adaptive && options.estimator == StochasticEstimator::term_choice &&
      options.integrator == IntegratorKind::vpl && options.gate) {
    const Eq8Gate gate = adaptive_eq8_vpl_gate(s.visibility_context);
    s.eq8_gate = gate.to_json();
    s.eq8_ratios = gate.ratios();
    std::vector<std::uint8_t>& exact = s.visibility_context.trace_exactly_from;
    for (const double ratio : s.eq8_ratios) exact.push_back(ratio >= kLearnedPaysBelow ? 1 : 0);
    s.traced_exactly_everywhere = std::all_of(exact.begin(), exact.end(), [](std::uint8_t e) { return e != 0; });
  }
  // Where no evidence could make any instance's proxy pay at its average modelled costs,
  // the render traces every segment exactly: exact visibility does so from the first
  // segment, without the per-pixel bookkeeping.
  s.visibility = s.traced_exactly_everywhere ? make_exact_visibility(s.visibility_context) : make_visibility(s.visibility_context);
  s.integrator_context = std::make_unique<IntegratorContext>(IntegratorContext{scene, world, s.options, s.lights});
  s.integrator = make_integrator(*s.integrator_context);
  // The VPL integrator shades with its VPLs even where no area light is left.
  s.needs_lights = options.integrator == IntegratorKind::direct;
  s.sum.assign(s.pixels, Color::Zero());
  s.p1_sum.assign(s.pixels, 0.0);
  s.p1_count.assign(s.pixels, 0.0);
  s.tests.assign(s.pixels, 0.0);
  s.thread_visibility = std::make_unique<tbb::enumerable_thread_specific<std::unique_ptr<PointVisibility>>>(
      [&s] { return s.visibility->point_visibility(); });
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

RenderSession::~RenderSession() = default;
RenderSession::RenderSession(RenderSession&&) noexcept = default;
RenderSession& RenderSession::operator=(RenderSession&&) noexcept = default;

int RenderSession::passes() const { return state_->passes; }
double RenderSession::seconds() const { return state_->seconds; }

int RenderSession::run(int passes, double seconds) {
  State& s = *state_;
  const auto start = std::chrono::steady_clock::now();
  const double before = s.seconds;
  constexpr int tile = 16;
  const int tiles_x = (s.width + tile - 1) / tile, tiles_y = (s.height + tile - 1) / tile;
  int done = 0;
  while (done < passes && s.passes < s.options.spp) {
    const int pass = s.passes;
    tbb::parallel_for(tbb::blocked_range<int>(0, tiles_x * tiles_y), [&](const tbb::blocked_range<int>& range) {
      RenderStats& stats = s.thread_stats.local();
      PointVisibility& answers = *s.thread_visibility->local();
      for (int t = range.begin(); t != range.end(); ++t) {
        const int x0 = (t % tiles_x) * tile, y0 = (t / tiles_x) * tile;
        for (int y = y0; y < std::min(y0 + tile, s.height); ++y)
          for (int x = x0; x < std::min(x0 + tile, s.width); ++x) s.shade(x, y, pass, stats, answers);
      }
    });
    ++s.passes, ++done;
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    s.seconds = before + elapsed;
    if (s.options.on_pass) s.options.on_pass(s.passes, s.seconds);
    if (seconds > 0 && elapsed >= seconds) break;
  }
  return done;
}

RenderResult RenderSession::result() const {
  const State& s = *state_;
  const int passes = std::max(s.passes, 1);
  const bool stochastic = s.options.visibility == VisibilityMode::stochastic;
  RenderResult result;
  result.image = Image(s.width, s.height);
  result.cost_map = Image(s.width, s.height);
  if (stochastic) result.p1_map = Image(s.width, s.height);
  for (std::size_t i = 0; i < s.sum.size(); ++i) {
    result.image.pixels[i] = s.sum[i] / passes;
    result.cost_map.pixels[i] = Color::Constant(s.tests[i] / passes);
    if (stochastic) result.p1_map.pixels[i] = Color::Constant(s.p1_count[i] > 0 ? s.p1_sum[i] / s.p1_count[i] : 0.0);
  }
  for (const RenderStats& t : s.thread_stats) result.stats += t;
  result.cut_map = s.integrator->cut_map(passes);
  result.stats.integrator = s.integrator->describe();
  if (s.optimal)
    for (const ProxyKind kind : {ProxyKind::outside, ProxyKind::inside, ProxyKind::general}) {
      const Probabilities& p = s.visibility_context.optimal[static_cast<std::size_t>(kind)];
      result.stats.optimal_probabilities[std::string(kind_name(kind))] = {p.p1, p.p2, p.p3};
    }
  if (s.traced_exactly_everywhere)
    (s.options.estimator == StochasticEstimator::term_choice ? result.stats.eq8.traced_exactly : result.stats.control_variate.traced_exactly) =
        result.stats.exact_tests;
  result.stats.disk_gate = s.disk_gate;
  result.stats.eq8_gate = s.eq8_gate;
  const SceneCorrectionCosts& costs = s.correction_costs;
  if (!costs.costs.empty()) {
    nlohmann::json instances = nlohmann::json::array();
    for (std::size_t i = 0; i < costs.work.size(); ++i) {
      const SegmentQueryCosts& w = costs.work[i];
      instances.push_back({{"instance", i},
                           {"mesh", s.scene.instances[i].mesh},
                           {"camera_work", w.camera},
                           {"exact_work", w.exact},
                           {"proxy_work", w.proxy},
                           {"correction_work", w.correction},
                           {"proxy_blocks_share", costs.priors[i].share[1]},
                           {"wrong_when_letting_through", costs.priors[i].disagreeing[0]},
                           {"wrong_when_blocking", costs.priors[i].disagreeing[1]}});
      if (i < s.eq8_ratios.size())
        instances.back()["eq8_predicted_ratio"] =
            std::isfinite(s.eq8_ratios[i]) ? nlohmann::json(s.eq8_ratios[i]) : nlohmann::json(nullptr);
    }
    result.stats.learned_costs = {
        {"noise_per_segment", costs.noise}, {"instances", instances}, {"traced_exactly_everywhere", s.traced_exactly_everywhere}};
  }
  result.stats.passes = s.passes;
  result.stats.counted = s.world.counting();
  result.stats.seconds = s.seconds;
  return result;
}

RenderResult render(const Scene& scene, const RenderWorld& world, const RenderOptions& options) {
  RenderSession session(scene, world, options);
  // options.seconds counts from the start, the work before the first pass included.
  const double budget = options.seconds > 0 ? std::max(options.seconds - session.seconds(), 1e-9) : 0;
  session.run(options.spp, budget);
  return session.result();
}

}  // namespace visproxy
