#pragma once
// The renderer: Lambertian surfaces lit by area lights, through an integrator (direct
// illumination, Billen et al. eq. 21; or instant radiosity with virtual point lights) whose
// shadow segments a visibility strategy answers: exact, stochastic (eq. 8 or the control
// variate, visibility splitting eq. 27), bounds, or occluder disks of sphere sets.

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string_view>

#include "visproxy/image/image.h"
#include "visproxy/render/options/render_options.h"
#include "visproxy/render/options/render_stats.h"
#include "visproxy/render/world/render_world.h"
#include "visproxy/render/world/virtual_point_lights.h"

namespace visproxy {

struct RenderResult {
  Image image;     ///< linear radiance
  /// Stochastic only (else empty), grey: per pixel the mean probability that a shadow ray
  /// traces the proxy alone (eq. 8: p1; control variate: 1 - q of the proxy's answer).
  Image p1_map;
  /// lightcuts only (else empty), grey: per pixel the mean number of clusters in the cut.
  Image cut_map;
  Image cost_map;  ///< per pixel per camera sample: traversal steps + primitive tests when counted, else segment queries
  RenderStats stats;
};

/// Renders `scene` as seen through `world`. Each pixel has its own random stream, seeded
/// by (seed, pixel, pass), so the image does not depend on the number of threads.
RenderResult render(const Scene& scene, const RenderWorld& world, const RenderOptions& options);

/// A render that goes on where it stopped: run() adds passes, and the passes of several
/// runs are the passes of one render (pass p draws from the (seed, pixel, p) streams, and
/// the strategies keep what their pixels learned), so that result() after runs of 3 and 5
/// passes is render() of 8 passes, bit for bit. Renders of several modes can so take turns
/// on a machine whose speed drifts, and each be timed over the same stretches of it.
/// `scene`, `world` and the callbacks in `options` must outlive the session.
class RenderSession {
 public:
  /// Does the work before the first pass (optimal probabilities, learned costs), timed.
  RenderSession(const Scene& scene, const RenderWorld& world, const RenderOptions& options);
  ~RenderSession();
  RenderSession(RenderSession&&) noexcept;
  RenderSession& operator=(RenderSession&&) noexcept;

  /// Renders up to `passes` more passes, stopping early at options.spp in all or after the
  /// pass that crosses `seconds` of this run (0: no limit). Returns the passes it rendered.
  /// (options.seconds is render()'s budget; a session's runs take theirs here.)
  int run(int passes, double seconds = 0);
  int passes() const;
  /// The session's own time: the work before the first pass and every run, not the time
  /// between runs.
  double seconds() const;
  /// The image and stats of the passes so far (stats.seconds: seconds()).
  RenderResult result() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

/// Shadow segments as a renderer traces them, for measuring proxies on a scene: from points
/// the camera sees (uniform over the image, jittered) to points sampled on the lights by
/// area, the segments a Lambertian surface would trace (light in front of both). Points on
/// instances in `exclude` (visibility splitting traces those exactly) and on lights are
/// skipped. Deterministic for a seed; stops after 100 x count camera samples.
struct ShadowSegment {
  Vertex from, to;
  int instance = -1;  ///< the instance `from` lies on
};
std::vector<ShadowSegment> scene_shadow_segments(const Scene& scene, const RenderWorld& world, std::size_t count,
                                                 std::uint64_t seed, const std::vector<bool>& exclude);

/// One camera sample as a render with direct light and one shadow segment per sample takes
/// it (visproxy render's defaults): what the camera ray met on a light, or the sample's
/// segment with what the sample adds to its pixel when the segment is unoccluded.
struct CameraSample {
  Color emitted = Color::Zero();       ///< the camera ray met a light's emitting side
  Color contribution = Color::Zero();  ///< brdf x radiance x cos x cos / distance^2 x light area
  bool has_segment = false;
  ShadowSegment segment;  ///< when has_segment
};

/// `pairs` pairs of camera samples, each pair from one pixel (uniform over the image) with
/// its own jitter and light sample: the difference within a pair shows a render's noise
/// per pixel, which differences between pixels would not. Deterministic for a seed.
std::vector<std::array<CameraSample, 2>> scene_sample_pairs(const Scene& scene, const RenderWorld& world, std::size_t pairs,
                                                            std::uint64_t seed);

}  // namespace visproxy
