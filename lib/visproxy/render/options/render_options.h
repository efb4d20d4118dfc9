#pragma once
// What a render is asked to do: the integrator, the visibility strategy and every option
// of both, with the one table of the names each choice has (the CLI, the Python module and
// the stats all use it) and the one validation a render makes first.

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "visproxy/core/choices.h"
#include "visproxy/core/errors.h"
#include "visproxy/render/world/virtual_point_lights.h"

namespace visproxy {

/// spheres: each instance's sphere-set proxy as occluder disks (occluding-spheres paper §2,
/// biased by design); instances without one are traced exactly.
enum class VisibilityMode { exact, stochastic, bounds, spheres };
/// direct: M area-light samples per camera sample; vpl: those plus every virtual point light;
/// lightcuts: K point lights per area light (and the VPLs, if asked) shaded through a
/// lightcut (render/integrators/light_tree.h).
enum class IntegratorKind { direct, vpl, lightcuts };
/// spheres: how the shading point's own instance shadows it (occluding-spheres §4.2).
/// heuristic: its spheres count except those closer than twice their radius (t < 2R);
/// exact: its mesh is traced and its spheres are left out; none: all its spheres count.
enum class SelfShadow { heuristic, exact, none };
/// equal; adaptive: from K probe rays per shading point (or per pixel, probe_passes);
/// learned (control variate only): from the corrections each pixel traced in earlier samples
/// (with direct light, weighed against the modelled costs and the render's noise found
/// before the render, and traced exactly where the proxy does not pay: learned_choice());
/// optimal (eq. 8 only): one set for the whole image, eq. 8's optimum for the ray types of
/// the scene's own shadow segments, traced against proxies and meshes before the render
/// (the probabilities `visproxy measure --scene` finds and `report` predicts eq. 8 with).
enum class ProbabilityMode { equal, adaptive, learned, optimal };
/// How `stochastic` combines proxy and mesh: eq. 8 (a term drawn first, the paper), or the
/// proxy as a control variate corrected under Russian roulette (CorrectionProbabilities).
enum class StochasticEstimator { term_choice, control_variate };

/// Lightcuts' visibility bounds: none, lower (clusters proved unoccluded), upper (proved
/// occluded), both.
enum class VisibilityBounds { none, lower, upper, both };

struct CutOptions {
  /// Each cluster's error bound at most this fraction of the cut's total (luminance). 0:
  /// the exact sum over every light (each cluster refined until it is one light or
  /// contributes nothing for certain), whatever max_cut says.
  double error = 0.02;
  /// Most clusters in a cut (error > 0); a cut stopped by it says so (CutResult::stopped_at_max_cut).
  int max_cut = 1000;
  VisibilityBounds bounds = VisibilityBounds::none;
  /// Trace the representative of every proved cluster too and count where the traced
  /// answer differs from the proof (CutResult::disagreements): a self-check of the proofs.
  bool check_proofs = false;
};

struct RenderOptions {
  IntegratorKind integrator = IntegratorKind::direct;
  VisibilityMode visibility = VisibilityMode::exact;
  ProbabilityMode probabilities = ProbabilityMode::equal;
  StochasticEstimator estimator = StochasticEstimator::term_choice;
  bool cost_heuristic = false;  ///< eq. 22-24 on the adaptive probabilities (eq. 8 only)
  int probe_rays = 16;          ///< K: probe segments per shading point (adaptive)
  /// adaptive: 0 probes every shading point (the paper); P > 0 probes only in each pixel's
  /// first P passes and keeps the ray types seen per pixel for every later pass, which
  /// stays unbiased (a pass's probabilities depend only on draws made before its shadow rays).
  int probe_passes = 0;
  double probability_floor = 0.05;  ///< least probability of each needed term (adaptive, learned): in (0, 1/3]
  double correction_scale = 2;      ///< control variate, adaptive or learned: CorrectionOptions::scale
  bool split = true;                ///< eq. 27: the shading point's own instance traced exactly
  int spp = 16;                     ///< camera samples per pixel (passes)
  int shadow_rays = 1;              ///< M: light samples per camera sample
  std::uint64_t seed = 1;
  // vpl integrator
  int vpls = 1024;             ///< N: light paths traced from the area lights
  int bounces = 1;             ///< B: VPLs left per path (1: one-bounce indirect light)
  std::uint64_t vpl_seed = 1;  ///< seed of the light paths (apart from `seed`, so that a reference can share the VPLs)
  /// The VPLs' geometric term cos cos / d^2 is clamped to 1 / (vpl_clamp x D)^2, D the
  /// diagonal of the scene's bounds: the energy of connections shorter than about
  /// vpl_clamp x D is dropped (RenderStats::integrator: clamped_energy_fraction). 0: no clamp.
  double vpl_clamp = 0.05;
  // lightcuts integrator
  int light_points = 1024;     ///< K: point lights per area light
  bool lightcut_vpls = false;  ///< also the VPLs of `vpls` light paths (clamped as the vpl integrator's)
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
  /// The gates before the render, which trace segments exactly where an estimator cannot
  /// beat exact visibility: the learned control variate with occluder disks decides for
  /// the whole scene (RenderStats::disk_gate), adaptive eq. 8 for the points of each
  /// instance (with direct light adaptive_eq8_ratios(), RenderStats::learned_costs; with
  /// VPLs adaptive_eq8_vpl_gate(), RenderStats::eq8_gate). false:
  /// the estimator everywhere (to test the estimator itself, or to compare with it).
  bool gate = true;
  double seconds = 0;  ///< stop after the pass that crosses this time (0: no limit)
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

template <>
const std::vector<std::pair<std::string_view, VisibilityMode>>& choice_names<VisibilityMode>();
template <>
const std::vector<std::pair<std::string_view, IntegratorKind>>& choice_names<IntegratorKind>();
template <>
const std::vector<std::pair<std::string_view, SelfShadow>>& choice_names<SelfShadow>();
template <>
const std::vector<std::pair<std::string_view, ProbabilityMode>>& choice_names<ProbabilityMode>();
template <>
const std::vector<std::pair<std::string_view, StochasticEstimator>>& choice_names<StochasticEstimator>();
template <>
const std::vector<std::pair<std::string_view, VisibilityBounds>>& choice_names<VisibilityBounds>();

}  // namespace visproxy
