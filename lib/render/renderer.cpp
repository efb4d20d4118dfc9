// Direct illumination (Billen, Lagae, Dutre, eq. 21) with the stochastic visibility
// estimator (eq. 8), adaptive probabilities from probe rays (section 4.1), the cost
// heuristic (eq. 22-24) and visibility splitting per instance (eq. 27).

#include "render/renderer.h"

#include "core/errors.h"
#include "trace/embree_support.h"

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

// splitmix64: a small, fast generator; one stream per (seed, pixel, pass).
class PixelRandom {
 public:
  PixelRandom(std::uint64_t seed, std::uint64_t pixel, std::uint64_t pass)
      : state_(seed * 0x9E3779B97F4A7C15ull ^ (pixel + 1) * 0xD1B54A32D192ED03ull ^ (pass + 1) * 0x8CB92BA72F3D8DD7ull) {
    next();
  }
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }

 private:
  std::uint64_t state_;
};

// Seeds the stochastic estimators' stream apart from the camera and light stream.
constexpr std::uint64_t kChoiceStream = 0x43484F4943455321ull;

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

struct LightSample {
  Vertex position;
  Vertex normal;
  Color radiance;
  bool two_sided;
};

// Every light triangle, chosen with probability proportional to its area: a point is then
// uniform over the total emitting area, with density 1 / total_area.
class LightSampler {
 public:
  explicit LightSampler(const Scene& scene) {
    for (const AreaLight& light : scene.lights)
      for (const auto& t : light.triangles) {
        const Vertex cross = (t[1] - t[0]).cross(t[2] - t[0]);
        const double area = 0.5 * cross.norm();
        if (area <= 0) continue;
        total_ += area;
        cumulative_.push_back(total_);
        triangles_.push_back({t, cross.normalized(), &light});
      }
  }
  double total_area() const { return total_; }
  bool empty() const { return triangles_.empty(); }
  LightSample sample(PixelRandom& random) const {
    const double pick = random.uniform() * total_;
    const auto it = std::upper_bound(cumulative_.begin(), cumulative_.end(), pick);
    const auto& t = triangles_[std::min<std::size_t>(static_cast<std::size_t>(it - cumulative_.begin()), triangles_.size() - 1)];
    double a = random.uniform(), b = random.uniform();
    if (a + b > 1) a = 1 - a, b = 1 - b;
    return {t.corners[0] + a * (t.corners[1] - t.corners[0]) + b * (t.corners[2] - t.corners[0]), t.normal,
            t.light->radiance, t.light->two_sided};
  }

 private:
  struct Entry {
    std::array<Vertex, 3> corners;
    Vertex normal;
    const AreaLight* light;
  };
  std::vector<Entry> triangles_;
  std::vector<double> cumulative_;
  double total_ = 0;
};

// The shaft from a point to every light: the convex hull of the point and the lights'
// corners. meets() is conservative: false only when an instance is provably outside the
// shaft: its box separated along a coordinate axis, or its bounding sphere outside the
// circular cone around the shaft.
class LightShaft {
 public:
  explicit LightShaft(const Scene& scene) {
    for (const AreaLight& light : scene.lights)
      for (const auto& t : light.triangles)
        for (const Vertex& corner : t)
          if (std::find(corners_.begin(), corners_.end(), corner) == corners_.end()) corners_.push_back(corner);
  }

  /// The shaft from one apex: its bounds, and its cone once an instance needs it.
  struct From {
    Vertex apex, lo, hi, axis;
    bool has_cone = false;
    double cos_half = -1, sin_half = 0, reach = 0;
  };
  From from(const Vertex& apex) const {
    From shaft;
    shaft.apex = shaft.lo = shaft.hi = apex;
    for (const Vertex& c : corners_) shaft.lo = shaft.lo.cwiseMin(c), shaft.hi = shaft.hi.cwiseMax(c);
    return shaft;
  }

  bool meets(From& shaft, const BoundingBox& box, const Sphere& sphere) const {
    if (box.empty()) return false;
    // Separating coordinate axes: the shaft's extent is that of its points.
    if ((shaft.hi.array() < box.min.array()).any() || (shaft.lo.array() > box.max.array()).any()) return false;
    // The cone from the apex around the corners against the instance's bounding sphere.
    if (!shaft.has_cone) cone(shaft);
    if (shaft.cos_half <= 0) return true;  // wider than a half-space: no cone test
    const Vertex v = sphere.center - shaft.apex;
    const double distance = v.norm();
    if (distance <= sphere.radius) return true;
    if (distance - sphere.radius > shaft.reach) return false;
    // Within the cone grown by the sphere's angular radius beta: angle(axis, v) <= half + beta,
    // compared through cosines (half + beta < pi here since both are below pi / 2).
    const double sin_beta = sphere.radius / distance, cos_beta = std::sqrt(std::max(0.0, 1 - sin_beta * sin_beta));
    const double cos_limit = shaft.cos_half * cos_beta - shaft.sin_half * sin_beta;
    return shaft.axis.dot(v) / distance >= cos_limit - 1e-12;
  }

 private:
  void cone(From& shaft) const {
    shaft.has_cone = true;
    shaft.axis = Vertex::Zero();
    for (const Vertex& c : corners_) shaft.axis += (c - shaft.apex).normalized();
    shaft.cos_half = -1;
    if (shaft.axis.norm() == 0) return;
    shaft.axis.normalize();
    shaft.cos_half = 1, shaft.reach = 0;
    for (const Vertex& c : corners_) {
      shaft.cos_half = std::min(shaft.cos_half, shaft.axis.dot((c - shaft.apex).normalized()));
      shaft.reach = std::max(shaft.reach, (c - shaft.apex).norm());
    }
    shaft.sin_half = std::sqrt(std::max(0.0, 1 - shaft.cos_half * shaft.cos_half));
  }

  std::vector<Vertex> corners_;
};

// The light end of a shadow segment: the sample moved off the light's plane, towards the
// side the shading point is on, by the world's rounding offset (a light lying on a wall or
// a ceiling must not be shadowed by that surface through float rounding).
Vertex light_end(const RenderWorld& world, const LightSample& y, const Vertex& x) {
  const double side = y.normal.dot(x - y.position) >= 0 ? 1.0 : -1.0;
  return y.position + side * world.surface_offset(y.position, 0.0) * y.normal;
}

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
  }
  return "exact";
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
          {"counted", counted},
          {"traversal_steps", counted ? nlohmann::json(traversal_steps) : nlohmann::json(nullptr)},
          {"primitive_tests", counted ? nlohmann::json(primitive_tests) : nlohmann::json(nullptr)},
          {"traversal_steps_per_shadow_ray", counted ? nlohmann::json(static_cast<double>(traversal_steps) / rays) : nlohmann::json(nullptr)},
          {"primitive_tests_per_shadow_ray", counted ? nlohmann::json(static_cast<double>(primitive_tests) / rays) : nlohmann::json(nullptr)}};
}

// With splitting, the own instance first (exactly); returns the filter for the rest of the
// scene, or nullopt when the own instance blocks the segment.
std::optional<InstanceFilter> trace_own_instance(const RenderWorld& world, const Vertex& from, const Vertex& to, int own_instance,
                                                 bool split, RenderStats& stats, bool own_cannot_block) {
  InstanceFilter rest;
  if (!split) return rest;
  if (!own_cannot_block) {
    ++stats.exact_tests;
    if (world.mesh_blocks(from, to, {.skip = -1, .only = own_instance})) return std::nullopt;
  }
  rest.skip = own_instance;
  return rest;
}

double stochastic_visibility(const RenderWorld& world, const Vertex& from, const Vertex& to, int own_instance,
                             const Probabilities& p, double u, bool split, RenderStats& stats, bool own_cannot_block) {
  const std::optional<InstanceFilter> rest = trace_own_instance(world, from, to, own_instance, split, stats, own_cannot_block);
  if (!rest) return 0.0;
  ++stats.proxy_tests;
  const bool proxy_free = !world.proxy_blocks(from, to, *rest);
  if (u < p.p1) {
    ++stats.term_counts[0];
    return proxy_free ? 1.0 / p.p1 : 0.0;
  }
  if (u < p.p1 + p.p2) {
    ++stats.term_counts[1];
    if (proxy_free) return 0.0;
    ++stats.exact_tests;
    return world.mesh_blocks(from, to, *rest) ? 0.0 : 1.0 / p.p2;
  }
  ++stats.term_counts[2];
  if (!proxy_free) return 0.0;
  ++stats.exact_tests;
  return world.mesh_blocks(from, to, *rest) ? -1.0 / p.p3 : 0.0;
}

ControlVariateSample control_variate_visibility(const RenderWorld& world, const Vertex& from, const Vertex& to, int own_instance,
                                                const CorrectionProbabilities& q, double u, bool split, RenderStats& stats,
                                                bool own_cannot_block) {
  ControlVariateSample sample;
  const std::optional<InstanceFilter> rest = trace_own_instance(world, from, to, own_instance, split, stats, own_cannot_block);
  if (!rest) return sample;
  ++stats.proxy_tests;
  sample.proxy_traced = true;
  sample.proxy_blocked = world.proxy_blocks(from, to, *rest);
  const double proxy = sample.proxy_blocked ? 0.0 : 1.0;
  sample.trace_probability = sample.proxy_blocked ? q.after_hit : q.after_miss;
  sample.visibility = proxy;
  if (!(u < sample.trace_probability)) return sample;
  ++(sample.proxy_blocked ? stats.corrections_after_hit : stats.corrections_after_miss);
  ++stats.exact_tests;
  sample.mesh_traced = true;
  sample.mesh_blocked = world.mesh_blocks(from, to, *rest);
  sample.visibility = proxy + ((sample.mesh_blocked ? 0.0 : 1.0) - proxy) / sample.trace_probability;
  return sample;
}

std::vector<ShadowSegment> scene_shadow_segments(const Scene& scene, const RenderWorld& world, std::size_t count,
                                                 std::uint64_t seed, const std::vector<bool>& exclude) {
  const Camera& camera = scene.camera;
  const Vertex forward = (camera.at - camera.from).normalized();
  const Vertex right = forward.cross(camera.up).normalized();
  const Vertex up = right.cross(forward);
  const double tan_half = std::tan(camera.fov_degrees * std::numbers::pi / 360.0);
  const double aspect = static_cast<double>(camera.width) / camera.height;
  const LightSampler lights(scene);
  std::vector<ShadowSegment> segments;
  if (lights.empty()) return segments;
  PixelRandom random(seed, 0, 0);
  for (std::size_t attempt = 0; attempt < 100 * count && segments.size() < count; ++attempt) {
    const double sx = (2 * random.uniform() - 1) * tan_half * aspect, sy = (1 - 2 * random.uniform()) * tan_half;
    const std::optional<SurfaceHit> hit = world.intersect(camera.from, (forward + sx * right + sy * up).normalized());
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
  const Camera& camera = scene.camera;
  const int width = camera.width, height = camera.height;
  const Vertex forward = (camera.at - camera.from).normalized();
  const Vertex right = forward.cross(camera.up).normalized();
  const Vertex up = right.cross(forward);
  const double tan_half = std::tan(camera.fov_degrees * std::numbers::pi / 360.0);
  const double aspect = static_cast<double>(width) / height;
  validate(options);
  const LightSampler lights(scene);
  const LightShaft shaft(scene);
  const bool stochastic = options.visibility == VisibilityMode::stochastic;
  const bool counting = world.counting();

  std::vector<ProxyKind> kinds;  // per instance: the estimator's form for the rest of the scene
  for (std::size_t i = 0; i < scene.instances.size(); ++i)
    kinds.push_back(world.stochastic_kind(options.split ? static_cast<int>(i) : -1));

  std::vector<Color> sum(static_cast<std::size_t>(width) * static_cast<std::size_t>(height), Color::Zero());
  std::vector<double> p1_sum(sum.size(), 0.0), p1_count(sum.size(), 0.0), tests(sum.size(), 0.0);
  const bool control_variate = stochastic && options.estimator == StochasticEstimator::control_variate;
  const CorrectionOptions correction_options{.scale = options.correction_scale, .floor = options.probability_floor};
  // adaptive with probe_passes > 0: the ray types each pixel's probes saw so far.
  std::vector<RayTypeCounts> pixel_probes(options.probe_passes > 0 ? sum.size() : 0);
  // bounds: passes in a row in which a proof of the rest of the scene failed, per pixel.
  std::vector<std::uint8_t> proof_failures(options.visibility == VisibilityMode::bounds ? sum.size() : 0, 0);
  // learned: what each pixel's traced corrections showed so far.
  std::vector<CorrectionEvidence> pixel_evidence(stochastic && options.probabilities == ProbabilityMode::learned ? sum.size() : 0);
  tbb::enumerable_thread_specific<RenderStats> thread_stats;

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
    const double sx = (2 * (px + random.uniform()) / width - 1) * tan_half * aspect;
    const double sy = (1 - 2 * (py + random.uniform()) / height) * tan_half;
    const Vertex direction = (forward + sx * right + sy * up).normalized();
    const std::optional<SurfaceHit> hit = world.intersect(camera.from, direction);
    if (!hit) return;
    if (hit->light >= 0) {
      const AreaLight& light = scene.lights[static_cast<std::size_t>(hit->light)];
      if (hit->light_front || light.two_sided) sum[pixel] += light.radiance;
      return;
    }
    if (lights.empty()) return;
    ++stats.shading_points;
    const int own = hit->instance;
    const Vertex x = hit->position + world.surface_offset(hit->position, hit->distance) * hit->normal;
    const Color brdf = scene.instances[static_cast<std::size_t>(own)].albedo / std::numbers::pi;

    const ProxyKind kind = kinds[static_cast<std::size_t>(own)];
    Probabilities probabilities = equal_probabilities(kind);
    CorrectionProbabilities corrections = equal_correction_probabilities(kind);
    if (stochastic && options.probabilities == ProbabilityMode::adaptive) {
      // Probe rays of this shading point, or (probe_passes > 0) of this pixel's first passes.
      RayTypeCounts local;
      RayTypeCounts& counts = options.probe_passes > 0 ? pixel_probes[pixel] : local;
      if (options.probe_passes == 0 || pass < options.probe_passes) {
        const InstanceFilter rest{.skip = options.split ? own : -1, .only = -1};
        for (int k = 0; k < options.probe_rays; ++k) {
          const LightSample y = lights.sample(choices);
          if (hit->normal.dot(y.position - x) <= 0) continue;  // below the surface: never traced
          ++stats.probe_rays;
          const Vertex end = light_end(world, y, x);
          counts.add(world.mesh_blocks(x, end, rest), world.proxy_blocks(x, end, rest));
        }
      }
      const RayTypeFractions fractions = RayTypeFractions::from(counts);
      if (control_variate) {
        corrections = correction_probabilities(kind, CorrectionEvidence::from(counts), correction_options);
      } else {
        probabilities = optimal_probabilities(kind, fractions, {.floor = options.probability_floor});
        if (options.cost_heuristic)
          probabilities = apply_cost_heuristic(kind, probabilities, fractions, options.probability_floor);
      }
    }
    if (control_variate && options.probabilities == ProbabilityMode::learned)
      corrections = correction_probabilities(kind, pixel_evidence[pixel], correction_options);
    if (stochastic && !control_variate) {
      p1_sum[pixel] += probabilities.p1;
      p1_count[pixel] += 1;
    }

    // bounds: the instances (other than the own) that the shaft from x to the lights meets.
    thread_local std::vector<std::size_t> shaft_instances;
    shaft_instances.clear();
    bool traced_before = false;  // a proof failed here: the next segments go straight to the exact query
    bool proof_failed = false, proof_tried = false;
    if (options.visibility == VisibilityMode::bounds) {
      LightShaft::From shaft_from = shaft.from(x);
      for (std::size_t i = 0; i < scene.instances.size(); ++i)
        if (static_cast<int>(i) != own && shaft.meets(shaft_from, world.instance_bounds(i), world.instance_sphere(i)))
          shaft_instances.push_back(i);
      if (shaft_instances.empty()) ++stats.shafts_culled;
      // Where proofs failed in the last passes of this pixel, skip them but every 8th pass.
      traced_before = proof_failures[pixel] >= 2 && pass % 8 != 0;
    }

    Color radiance = Color::Zero();
    for (int s = 0; s < options.shadow_rays; ++s) {
      const LightSample y = lights.sample(random);
      const Vertex to_light = y.position - x;
      const double distance2 = to_light.squaredNorm();
      const double distance = std::sqrt(distance2);
      const double cos_x = hit->normal.dot(to_light) / distance;
      double cos_y = -y.normal.dot(to_light) / distance;
      if (y.two_sided) cos_y = std::abs(cos_y);
      if (cos_x <= 0 || cos_y <= 0 || distance2 == 0) continue;
      ++stats.shadow_rays;
      const Vertex end = light_end(world, y, x);
      double visibility = 0;
      switch (options.visibility) {
        case VisibilityMode::exact:
          ++stats.exact_tests;
          visibility = world.mesh_blocks(x, end) ? 0 : 1;
          break;
        case VisibilityMode::stochastic:
          if (control_variate) {
            const ControlVariateSample sample = control_variate_visibility(world, x, end, own, corrections, choices.uniform(),
                                                                           options.split, stats, hit->own_mesh_behind);
            visibility = sample.visibility;
            if (sample.proxy_traced) {
              p1_sum[pixel] += 1 - sample.trace_probability;
              p1_count[pixel] += 1;
            }
            if (sample.mesh_traced && !pixel_evidence.empty()) {
              pixel_evidence[pixel].add(sample.proxy_blocked, sample.mesh_blocked);
              corrections = correction_probabilities(kind, pixel_evidence[pixel], correction_options);
            }
            break;
          }
          visibility = stochastic_visibility(world, x, end, own, probabilities, choices.uniform(), options.split, stats,
                                             hit->own_mesh_behind);
          break;
        case VisibilityMode::bounds: {
          // The rest of the scene first: free if the segment misses every other instance's
          // outside proxy (only those the light shaft meets can be hit), blocked if it meets
          // an inside proxy; otherwise one exact query over everything. When the rest is
          // free, the own instance is traced unless it lies behind the tangent plane.
          // After a segment from this point needed the exact query, the next ones go straight
          // to it: the proxies rarely prove anything where they just failed to.
          // Only the instances in the shaft whose bounding sphere this segment meets can block it.
          unsigned bits = 0;
          for (const std::size_t i : shaft_instances)
            if (segment_meets_ball(world.instance_sphere(i), x, end - x, 0.0, 1.0)) bits |= instance_bit(i);
          const InstanceFilter rest{.skip = own, .only = -1, .bits = bits};
          bool rest_free = bits == 0;
          if (!rest_free && !traced_before) {
            ++stats.proxy_tests;
            proof_tried = true;
            rest_free = !world.outside_blocks(x, end, rest);
          }
          if (rest_free) {
            ++stats.bounds_unoccluded;
            visibility = 1;
            if (!hit->own_mesh_behind) {
              ++stats.exact_tests;
              visibility = world.mesh_blocks(x, end, {.skip = -1, .only = own}) ? 0 : 1;
            }
            break;
          }
          if (world.has_inside_proxies() && !traced_before) {
            ++stats.proxy_tests;
            if (world.inside_blocks(x, end, rest)) {
              ++stats.bounds_occluded;
              break;
            }
          }
          proof_failed = proof_failed || !traced_before;
          traced_before = true;
          ++stats.bounds_traced;
          ++stats.exact_tests;
          visibility = world.mesh_blocks(x, end) ? 0 : 1;
          break;
        }
      }
      if (visibility != 0) radiance += (visibility * cos_x * cos_y / distance2 * lights.total_area()) * y.radiance;
    }
    if (proof_tried) proof_failures[pixel] = proof_failed ? static_cast<std::uint8_t>(std::min(proof_failures[pixel] + 1, 255)) : 0;
    sum[pixel] += brdf.cwiseProduct(radiance) / options.shadow_rays;
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
  }
  result.stats.passes = passes;
  result.stats.counted = counting;
  result.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace visproxy
