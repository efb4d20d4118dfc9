#pragma once
// The renderer: Lambertian surfaces lit by area lights, through an integrator (direct
// illumination, Billen et al. eq. 21; or instant radiosity with virtual point lights) whose
// shadow segments a visibility strategy answers: exact, stochastic (eq. 8 or the control
// variate, visibility splitting eq. 27), bounds, or occluder disks of sphere sets.

#include <atomic>
#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <string_view>

#include "visproxy/estimator/probabilities.h"
#include "visproxy/render/image.h"
#include "visproxy/render/lightcuts.h"
#include "visproxy/render/render_world.h"
#include "visproxy/render/virtual_point_lights.h"

namespace visproxy {

/// spheres: each instance's sphere-set proxy as occluder disks (occluding-spheres paper §2,
/// biased by design); instances without one are traced exactly.
enum class VisibilityMode { exact, stochastic, bounds, spheres };
/// direct: M area-light samples per camera sample; vpl: those plus every virtual point light;
/// lightcuts: K point lights per area light (and the VPLs, if asked) shaded through a
/// lightcut (render/lightcuts.h).
enum class IntegratorKind { direct, vpl, lightcuts };
std::string_view integrator_name(IntegratorKind integrator);
std::string_view visibility_bounds_name(VisibilityBounds bounds);
/// spheres: how the shading point's own instance shadows it (occluding-spheres §4.2).
/// heuristic: its spheres count except those closer than twice their radius (t < 2R);
/// exact: its mesh is traced and its spheres are left out; none: all its spheres count.
enum class SelfShadow { heuristic, exact, none };
std::string_view self_shadow_name(SelfShadow self_shadow);
/// equal; adaptive: from K probe rays per shading point (or per pixel, probe_passes);
/// learned (control variate only): from the corrections each pixel traced in earlier samples.
enum class ProbabilityMode { equal, adaptive, learned };
std::string_view probability_mode_name(ProbabilityMode mode);
/// How `stochastic` combines proxy and mesh: eq. 8 (a term drawn first, the paper), or the
/// proxy as a control variate corrected under Russian roulette (CorrectionProbabilities).
enum class StochasticEstimator { term_choice, control_variate };
std::string_view stochastic_estimator_name(StochasticEstimator estimator);
std::string_view visibility_mode_name(VisibilityMode mode);

struct RenderOptions {
  IntegratorKind integrator = IntegratorKind::direct;
  VisibilityMode visibility = VisibilityMode::exact;
  ProbabilityMode probabilities = ProbabilityMode::equal;
  StochasticEstimator estimator = StochasticEstimator::term_choice;
  bool cost_heuristic = false;     ///< eq. 22-24 on the adaptive probabilities (eq. 8 only)
  int probe_rays = 16;             ///< K: probe segments per shading point (adaptive)
  /// adaptive: 0 probes every shading point (the paper); P > 0 probes only in each pixel's
  /// first P passes and keeps the ray types seen per pixel for every later pass, which
  /// stays unbiased (a pass's probabilities depend only on draws made before its shadow rays).
  int probe_passes = 0;
  double probability_floor = 0.05; ///< least probability of each needed term (adaptive, learned): in (0, 1/3]
  double correction_scale = 2;     ///< control variate, adaptive or learned: CorrectionOptions::scale
  bool split = true;               ///< eq. 27: the shading point's own instance traced exactly
  int spp = 16;                    ///< camera samples per pixel (passes)
  int shadow_rays = 1;             ///< M: light samples per camera sample
  std::uint64_t seed = 1;
  // vpl integrator
  int vpls = 1024;                 ///< N: light paths traced from the area lights
  int bounces = 1;                 ///< B: VPLs left per path (1: one-bounce indirect light)
  std::uint64_t vpl_seed = 1;      ///< seed of the light paths (apart from `seed`, so that a reference can share the VPLs)
  /// The VPLs' geometric term cos cos / d^2 is clamped to 1 / (vpl_clamp x D)^2, D the
  /// diagonal of the scene's bounds: the energy of connections shorter than about
  /// vpl_clamp x D is dropped (RenderStats::integrator: clamped_energy_fraction). 0: no clamp.
  double vpl_clamp = 0.05;
  // lightcuts integrator
  int light_points = 1024;         ///< K: point lights per area light
  bool lightcut_vpls = false;      ///< also the VPLs of `vpls` light paths (clamped as the vpl integrator's)
  /// The cut: error fraction, largest cut, visibility bounds (need a world made with
  /// keep_solids), and the proofs' self-check (CutOptions).
  CutOptions lightcut = {};
  /// Use these VPLs instead of tracing light paths (a renderer's own, or a test's).
  const std::vector<VirtualPointLight>* virtual_point_lights = nullptr;
  /// Connections from a shading point to its VPLs traced as groups of rays from one origin
  /// (Embree ray packets) where the strategy can; false: one ray at a time.
  bool group_connections = true;
  SelfShadow self_shadow = SelfShadow::heuristic;  ///< spheres visibility
  /// Occluder disks (spheres visibility, and the control variate's V' with VPLs): sort a
  /// shading point's disks into a grid over the directions (OccluderDisks::finish) when it
  /// has at least this many; fewer are compared one block after another.
  std::size_t disk_grid_from = 4096;
  /// Occluder disks: test the bound of each cluster of an instance's balls
  /// (RenderWorld::occluder_clusters) before its balls; same answers, fewer comparisons.
  bool disk_clusters = true;
  /// Occluder disks: from this many instances with a sphere set on, a shading point makes
  /// an instance's disks only when one of its segments may meet the instance's balls
  /// (PointDisks), so that its cost follows the instances its segments pass, not all of
  /// them; same answers.
  std::size_t disk_lazy_from = 32;
  double seconds = 0;              ///< stop after the pass that crosses this time (0: no limit)
  /// Called after each pass with the passes done and the time so far (progress display).
  std::function<void(int passes, double seconds)> on_pass = nullptr;
};

/// Throws visproxy::Error naming the option when `options` cannot give a correct image:
/// no samples or shadow rays, a negative or non-finite time or count, a probability floor
/// outside [0, 1/3], a non-positive correction scale, learned probabilities with eq. 8,
/// adaptive probabilities without probe rays, and a zero floor with adaptive or learned
/// probabilities (a term never drawn for rays that occur makes the estimate biased; the
/// kind's unneeded terms get 0 whatever the floor). render() calls it first.
void validate(const RenderOptions& options);

struct RenderStats {
  double seconds = 0;
  int passes = 0;  ///< camera samples per pixel reached
  std::uint64_t camera_samples = 0, shading_points = 0, shadow_rays = 0;
  std::uint64_t exact_tests = 0;  ///< segment queries against exact meshes
  std::uint64_t proxy_tests = 0;  ///< segment queries against proxies
  std::uint64_t probe_rays = 0;   ///< adaptive probe segments (each tests proxy and mesh)
  std::uint64_t term_counts[3] = {0, 0, 0};  ///< stochastic eq. 8: times terms (a), (b), (c) were chosen
  /// stochastic control variate: exact corrections traced after the proxy missed / was hit
  std::uint64_t corrections_after_miss = 0, corrections_after_hit = 0;
  std::uint64_t bounds_unoccluded = 0, bounds_occluded = 0, bounds_traced = 0;
  std::uint64_t shafts_culled = 0;  ///< bounds: shading points whose light shaft missed every other instance
  std::uint64_t vpl_connections = 0;  ///< vpl: segments from shading points to VPLs (not in shadow_rays)
  std::uint64_t disk_tests = 0;       ///< spheres: sphere disks compared with a segment
  /// spheres, from RenderOptions::disk_lazy_from instances with sphere sets: clusters of
  /// balls the tree over them gave a segment (each tested by its bound's cone)
  std::uint64_t disk_clusters = 0;
  nlohmann::json integrator;          ///< what the integrator reports (vpl: the VPLs, the clamp, the energy it dropped)
  bool counted = false;               ///< the world was a counting one: the two below are set
  std::uint64_t traversal_steps = 0;  ///< BVH nodes visited by shadow queries (and probes)
  std::uint64_t primitive_tests = 0;  ///< triangles and balls tested by shadow queries
  nlohmann::json to_json() const;
};

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

/// Shadow segments as a renderer traces them, for measuring proxies on a scene: from points
/// the camera sees (uniform over the image, jittered) to points sampled on the lights by
/// area, the segments a Lambertian surface would trace (light in front of both). Points on
/// instances in `exclude` (visibility splitting traces those exactly) and on lights are
/// skipped. Deterministic for a seed; stops after 100 x count camera samples.
struct ShadowSegment {
  Vertex from, to;
};
std::vector<ShadowSegment> scene_shadow_segments(const Scene& scene, const RenderWorld& world, std::size_t count,
                                                 std::uint64_t seed, const std::vector<bool>& exclude);

/// The stochastic visibility of one shadow segment, eq. 8 with the given probabilities;
/// `u` in [0, 1) chooses the term. Counts its queries into `stats`. With `split`, the own
/// instance is traced exactly first, unless `own_cannot_block` (SurfaceHit::own_mesh_clear_of),
/// and the rest of the scene stochastically.
double stochastic_visibility(const RenderWorld& world, const Vertex& from, const Vertex& to, int own_instance,
                             const Probabilities& probabilities, double u, bool split, RenderStats& stats,
                             bool own_cannot_block = false);

/// One shadow segment through the control-variate estimator: V' + (V - V') [u < q] / q.
struct ControlVariateSample {
  double visibility = 0;
  bool proxy_traced = false;  ///< false when the own instance blocked the segment first
  bool proxy_blocked = false;
  double trace_probability = 0;  ///< the q the proxy's answer chose
  bool mesh_traced = false;
  bool mesh_blocked = false;
};
ControlVariateSample control_variate_visibility(const RenderWorld& world, const Vertex& from, const Vertex& to, int own_instance,
                                                const CorrectionProbabilities& q, double u, bool split, RenderStats& stats,
                                                bool own_cannot_block = false);

}  // namespace visproxy
