#pragma once
// What a render learns from the scene's own samples before its first pass: eq. 8's optimal
// probabilities, the learned control variate's modelled costs and priors (direct light),
// from the same costs where adaptive eq. 8 can pay (direct light, per instance), and, with
// VPLs, whether the learned control variate with occluder disks can pay at all and where
// adaptive eq. 8 can (per instance). Each
// is seeded from the render's seed, so that the image stays a function of the options.

#include <array>
#include <limits>
#include <vector>

#include <nlohmann/json.hpp>

#include "visproxy/estimator/probabilities.h"
#include "visproxy/render/visibility/visibility.h"
#include "visproxy/render/world/query_costs.h"

namespace visproxy {

/// ProbabilityMode::optimal: eq. 8's optimal probabilities for each form of the rest of the
/// scene (indexed by ProxyKind), from the ray types of 20 000 of the scene's own shadow
/// segments.
std::array<Probabilities, 3> scene_optimal_probabilities(const VisibilityContext& context);

/// ProbabilityMode::learned with the control variate and direct light: per instance, a
/// segment's modelled costs and the proxy's prior, and the exact render's noise per
/// segment; empty when no sample found a lit segment.
struct SceneCorrectionCosts {
  std::vector<CorrectionCosts> costs;
  std::vector<CorrectionPrior> priors;
  std::vector<SegmentQueryCosts> work;  ///< per instance, the averages the costs come from
  double noise = 0;
};
SceneCorrectionCosts scene_correction_costs(const VisibilityContext& context);

/// Whether the learned rule could give any instance's proxy to a pixel at the instance's
/// average costs (context.correction_costs and correction_priors set).
bool any_proxy_can_pay(const VisibilityContext& context);

/// Adaptive eq. 8 with direct light: per instance, the predicted (variance x modelled work)
/// of eq. 8 over exact visibility's for segments from the instance's points, at the
/// instance's costs and ray types from scene_correction_costs(): the variance from eq. 16
/// at the optimal probabilities of those ray types (with the cost heuristic when the
/// options ask for it) added to the exact render's noise, the work with the probe rays
/// (each a proxy query and a mesh query) shared among the point's shadow rays, and only in
/// the probe passes' share of the passes. The render traces exactly from the points of an
/// instance whose ratio is not below kLearnedPaysBelow. The rates of a side the proxy's
/// kind proves right (an outside proxy's misses, an inside proxy's hits) are taken as 0.
/// +infinity where the pairs showed no noise or no exact work to weigh against.
std::vector<double> adaptive_eq8_ratios(const VisibilityContext& context, const SceneCorrectionCosts& costs);
/// One instance's ratio: its proxy's `kind` and rates, its segments' modelled `work`, the
/// exact render's `noise` per segment, the probe rays per shadow ray, and the options'
/// probability floor and cost heuristic.
double eq8_predicted_ratio(ProxyKind kind, const CorrectionPrior& prior, const SegmentQueryCosts& work, double noise,
                           double probes_per_segment, double floor, bool cost_heuristic);

/// ProbabilityMode::learned with the control variate and occluder disks: what the
/// scene-level choice between the control variate and exact visibility weighed.
struct DiskGate {
  bool weighed = false;        ///< the pairs showed noise (T > 0) to weigh A against
  bool trace_exactly = false;  ///< the control variate cannot pay: trace every segment exactly
  int passes = 0;              ///< replayed per pixel
  double noise = 0;            ///< T: the exact render's variance per camera sample
  double added = 0;            ///< A: the variance the corrections add per camera sample
  double variance_ratio = 1;   ///< (T + A) / T
  double work_ratio = 1;       ///< the control variate's modelled work over exact's
  double corrections = 0;      ///< the replayed corrections' mean probability
  nlohmann::json to_json() const;  ///< RenderStats::disk_gate
};
DiskGate scene_disk_gate(const VisibilityContext& context);

/// Adaptive eq. 8 with the VPL integrator: per instance, the predicted (variance x modelled
/// work) of eq. 8 over exact visibility's for the camera samples that find the instance.
/// Before the render, the disk gate's pairs of camera samples are shaded by the render's
/// integrator with every segment traced exactly, and each segment's ray type (its proxy
/// and mesh answers against the rest of the scene), modelled work and contribution are
/// kept, with its point's probabilities as the render would draw them (probe segments
/// included). Per instance, over the samples that found it: T, the exact render's
/// variance (each sample's pair's (x_a - x_b)^2 / 2); A, the variance eq. 8 adds, the sum
/// of contribution^2 x eq. 16's variance for the segment's ray type; exact's work, the
/// camera samples and the segments' meshes; eq. 8's, the camera samples, the proxy queries,
/// the meshes its terms trace (p2 behind a proxy hit, p3 behind a miss) and the probes. A
/// connection that exact visibility traces in a packet costs eq. 8 kSingleRayWork times
/// its modelled work. The render traces exactly from the points of an instance whose
/// (T + A) x work_eq8 / (T x work_exact) is not below kLearnedPaysBelow.
struct Eq8Gate {
  struct Instance {
    std::size_t samples = 0;  ///< camera samples that found the instance
    double noise = 0;         ///< T, summed over those samples
    double added = 0;         ///< A, summed over them
    double work_exact = 0, work_eq8 = 0;
    /// (T + A) x work_eq8 / (T x work_exact); work_eq8 / work_exact where neither adds
    /// variance; +infinity where no sample found the instance, or T = 0 < A.
    double ratio = std::numeric_limits<double>::infinity();
  };
  std::vector<Instance> instances;
  std::vector<double> ratios() const;
  nlohmann::json to_json() const;  ///< RenderStats::eq8_gate
};
Eq8Gate adaptive_eq8_vpl_gate(const VisibilityContext& context);

}  // namespace visproxy
