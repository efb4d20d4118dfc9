// Direct illumination (Billen, Lagae, Dutre, eq. 21) with the stochastic visibility
// estimator (eq. 8), adaptive probabilities from probe rays (section 4.1), the cost
// heuristic (eq. 22-24) and visibility splitting per instance (eq. 27).

#include "render/renderer.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>

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

double scene_scale(const Scene& scene) {
  BoundingBox box;
  for (const SceneInstance& instance : scene.instances) {
    const BoundingBox local = bounding_box(scene.mesh(instance.mesh).mesh);
    for (int corner = 0; corner < 8; ++corner)
      box.extend(instance.transform * Vertex(corner & 1 ? local.max.x() : local.min.x(),
                                             corner & 2 ? local.max.y() : local.min.y(),
                                             corner & 4 ? local.max.z() : local.min.z()));
  }
  return std::max(box.diagonal(), 1e-30);
}

}  // namespace

std::string_view visibility_mode_name(VisibilityMode mode) {
  switch (mode) {
    case VisibilityMode::exact: return "exact";
    case VisibilityMode::stochastic: return "stochastic";
    case VisibilityMode::bounds: return "bounds";
  }
  return "exact";
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
          {"bounds", {{"unoccluded_by_outside_proxies", bounds_unoccluded}, {"occluded_by_inside_proxies", bounds_occluded}, {"traced_exactly", bounds_traced}}}};
}

double stochastic_visibility(const RenderWorld& world, const Vertex& from, const Vertex& to, int own_instance,
                             const Probabilities& p, double u, bool split, RenderStats& stats) {
  InstanceFilter rest;
  if (split) {
    ++stats.exact_tests;
    if (world.mesh_blocks(from, to, {.skip = -1, .only = own_instance})) return 0.0;
    rest.skip = own_instance;
  }
  ++stats.proxy_tests;
  const bool proxy_free = !world.proxy_blocks(from, to, rest);
  if (u < p.p1) {
    ++stats.term_counts[0];
    return proxy_free ? 1.0 / p.p1 : 0.0;
  }
  if (u < p.p1 + p.p2) {
    ++stats.term_counts[1];
    if (proxy_free) return 0.0;
    ++stats.exact_tests;
    return world.mesh_blocks(from, to, rest) ? 0.0 : 1.0 / p.p2;
  }
  ++stats.term_counts[2];
  if (!proxy_free) return 0.0;
  ++stats.exact_tests;
  return world.mesh_blocks(from, to, rest) ? -1.0 / p.p3 : 0.0;
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
  const double offset = 1e-6 * scene_scale(scene);
  const LightSampler lights(scene);
  const bool stochastic = options.visibility == VisibilityMode::stochastic;

  std::vector<ProxyKind> kinds;  // per instance: the estimator's form for the rest of the scene
  for (std::size_t i = 0; i < scene.instances.size(); ++i)
    kinds.push_back(world.stochastic_kind(options.split ? static_cast<int>(i) : -1));

  std::vector<Color> sum(static_cast<std::size_t>(width) * static_cast<std::size_t>(height), Color::Zero());
  std::vector<double> p1_sum(sum.size(), 0.0), p1_count(sum.size(), 0.0), tests(sum.size(), 0.0);
  tbb::enumerable_thread_specific<RenderStats> thread_stats;

  auto shade = [&](int px, int py, int pass) {
    const std::size_t pixel = static_cast<std::size_t>(py) * static_cast<std::size_t>(width) + static_cast<std::size_t>(px);
    PixelRandom random(options.seed, pixel, static_cast<std::uint64_t>(pass));
    RenderStats& stats = thread_stats.local();
    const std::uint64_t tests_before = stats.exact_tests + stats.proxy_tests;
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
    const Vertex x = hit->position + offset * hit->normal;
    const Color brdf = scene.instances[static_cast<std::size_t>(own)].albedo / std::numbers::pi;

    Probabilities probabilities = equal_probabilities(kinds[static_cast<std::size_t>(own)]);
    if (stochastic && options.probabilities == ProbabilityMode::adaptive) {
      RayTypeCounts counts;
      const InstanceFilter rest{.skip = options.split ? own : -1, .only = -1};
      for (int k = 0; k < options.probe_rays; ++k) {
        const LightSample y = lights.sample(random);
        if (hit->normal.dot(y.position - x) <= 0) continue;  // below the surface: never traced
        ++stats.probe_rays;
        counts.add(world.mesh_blocks(x, y.position, rest), world.proxy_blocks(x, y.position, rest));
      }
      const RayTypeFractions fractions = RayTypeFractions::from(counts);
      const ProxyKind kind = kinds[static_cast<std::size_t>(own)];
      probabilities = optimal_probabilities(kind, fractions, {.floor = options.probability_floor});
      if (options.cost_heuristic)
        probabilities = apply_cost_heuristic(kind, probabilities, fractions, options.probability_floor);
    }
    if (stochastic) {
      p1_sum[pixel] += probabilities.p1;
      p1_count[pixel] += 1;
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
      double visibility = 0;
      switch (options.visibility) {
        case VisibilityMode::exact:
          ++stats.exact_tests;
          visibility = world.mesh_blocks(x, y.position) ? 0 : 1;
          break;
        case VisibilityMode::stochastic:
          visibility = stochastic_visibility(world, x, y.position, own, probabilities, random.uniform(), options.split, stats);
          break;
        case VisibilityMode::bounds: {
          // The rest of the scene first: free if the segment misses every other instance's
          // outside proxy (then only the own instance is traced), blocked if it meets an
          // inside proxy; otherwise one exact query over everything.
          const InstanceFilter rest{.skip = own, .only = -1};
          ++stats.proxy_tests;
          if (!world.outside_blocks(x, y.position, rest)) {
            ++stats.bounds_unoccluded;
            ++stats.exact_tests;
            visibility = world.mesh_blocks(x, y.position, {.skip = -1, .only = own}) ? 0 : 1;
            break;
          }
          if (world.has_inside_proxies()) {
            ++stats.proxy_tests;
            if (world.inside_blocks(x, y.position, rest)) {
              ++stats.bounds_occluded;
              break;
            }
          }
          ++stats.bounds_traced;
          ++stats.exact_tests;
          visibility = world.mesh_blocks(x, y.position) ? 0 : 1;
          break;
        }
      }
      if (visibility != 0) radiance += (visibility * cos_x * cos_y / distance2 * lights.total_area()) * y.radiance;
    }
    sum[pixel] += brdf.cwiseProduct(radiance) / options.shadow_rays;
    tests[pixel] += static_cast<double>(stats.exact_tests + stats.proxy_tests - tests_before);
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
    r.bounds_unoccluded += s.bounds_unoccluded, r.bounds_occluded += s.bounds_occluded, r.bounds_traced += s.bounds_traced;
  }
  result.stats.passes = passes;
  result.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace visproxy
