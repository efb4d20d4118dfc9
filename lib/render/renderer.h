#pragma once
// Direct illumination from area lights on Lambertian surfaces (Billen et al. eq. 21), with
// exact, stochastic (eq. 8, visibility splitting eq. 27) or bounded shadow tests.

#include <atomic>
#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <string_view>

#include "estimator/probabilities.h"
#include "render/image.h"
#include "render/render_world.h"

namespace visproxy {

enum class VisibilityMode { exact, stochastic, bounds };
enum class ProbabilityMode { equal, adaptive };
std::string_view visibility_mode_name(VisibilityMode mode);

struct RenderOptions {
  VisibilityMode visibility = VisibilityMode::exact;
  ProbabilityMode probabilities = ProbabilityMode::equal;
  bool cost_heuristic = false;     ///< eq. 22-24 on the adaptive probabilities
  int probe_rays = 16;             ///< K: probe segments per shading point (adaptive)
  double probability_floor = 0.05; ///< least probability of each needed term (adaptive)
  bool split = true;               ///< eq. 27: the shading point's own instance traced exactly
  int spp = 16;                    ///< camera samples per pixel (passes)
  int shadow_rays = 1;             ///< M: light samples per camera sample
  std::uint64_t seed = 1;
  double seconds = 0;              ///< stop after the pass that crosses this time (0: no limit)
  /// Called after each pass with the passes done and the time so far (progress display).
  std::function<void(int passes, double seconds)> on_pass = nullptr;
};

struct RenderStats {
  double seconds = 0;
  int passes = 0;  ///< camera samples per pixel reached
  std::uint64_t camera_samples = 0, shading_points = 0, shadow_rays = 0;
  std::uint64_t exact_tests = 0;  ///< segment queries against exact meshes
  std::uint64_t proxy_tests = 0;  ///< segment queries against proxies
  std::uint64_t probe_rays = 0;   ///< adaptive probe segments (each tests proxy and mesh)
  std::uint64_t term_counts[3] = {0, 0, 0};  ///< stochastic: times terms (a), (b), (c) were chosen
  std::uint64_t bounds_unoccluded = 0, bounds_occluded = 0, bounds_traced = 0;
  nlohmann::json to_json() const;
};

struct RenderResult {
  Image image;     ///< linear radiance
  Image p1_map;    ///< per pixel mean p1 of the stochastic estimator (grey), else empty
  Image cost_map;  ///< per pixel segment queries per camera sample (grey)
  RenderStats stats;
};

/// Renders `scene` as seen through `world`. Each pixel has its own random stream, seeded
/// by (seed, pixel, pass), so the image does not depend on the number of threads.
RenderResult render(const Scene& scene, const RenderWorld& world, const RenderOptions& options);

/// The irradiance-based estimate for one shading point's shadow segment, exposed for
/// tests: eq. 8 with the given probabilities. `u` chooses the term. Returns the estimate
/// and counts tests into `stats`.
double stochastic_visibility(const RenderWorld& world, const Vertex& from, const Vertex& to, int own_instance,
                             const Probabilities& probabilities, double u, bool split, RenderStats& stats);

}  // namespace visproxy
