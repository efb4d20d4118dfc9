#pragma once
// What a render did: counts of its camera samples, segments and queries, each strategy's
// and integrator's own, merged across threads with one operator.

#include <cstdint>
#include <nlohmann/json.hpp>

namespace visproxy {

/// Counts over a render, summed over threads with +=: the loop's own, then each visibility
/// strategy's in its own group (only the strategy in use counts into its group), and what
/// the integrator reports.
struct RenderStats {
  double seconds = 0;
  int passes = 0;  ///< camera samples per pixel reached
  std::uint64_t camera_samples = 0, shading_points = 0, shadow_rays = 0;
  std::uint64_t vpl_connections = 0;  ///< vpl: segments from shading points to VPLs (not in shadow_rays)
  std::uint64_t exact_tests = 0;      ///< segment queries against exact meshes
  std::uint64_t proxy_tests = 0;      ///< segment queries against proxies
  std::uint64_t probe_rays = 0;       ///< adaptive probe segments (each tests proxy and mesh)
  struct TermChoice {
    std::uint64_t terms[3] = {0, 0, 0};  ///< times terms (a), (b), (c) were chosen
    /// adaptive, direct light: segments traced exactly because eq. 8 cannot pay from the
    /// points of their instance (the gate before the render)
    std::uint64_t traced_exactly = 0;
  } eq8;                                 ///< stochastic, eq. 8
  struct ControlVariate {
    std::uint64_t after_miss = 0, after_hit = 0;  ///< exact corrections traced after the proxy missed / was hit
    /// learned, direct light: segments traced exactly because the pixel's evidence said the
    /// proxy would not pay there, and of those, the ones that also traced the proxy to keep learning
    std::uint64_t traced_exactly = 0, explored = 0;
  } control_variate;                              ///< stochastic, the control variate
  struct Bounds {
    std::uint64_t unoccluded = 0, occluded = 0, traced = 0;
    /// shading points that traced a second segment to a light, and whose light shaft (found then)
    /// missed every other instance
    std::uint64_t shafts_culled = 0;
  } bounds;
  struct Disks {
    std::uint64_t tests = 0;  ///< sphere disks compared with a segment
    /// from RenderOptions::disk_lazy_from instances with sphere sets: clusters of balls the
    /// tree over them gave a segment (each tested by its bound's cone)
    std::uint64_t clusters = 0;
  } disks;                            ///< occluder disks (spheres, and the control variate's V' with VPLs)
  nlohmann::json integrator;          ///< what the integrator reports (vpl: the VPLs, the clamp, the energy it dropped)
  /// ProbabilityMode::optimal: the probabilities used per form of the rest of the scene
  /// ({"outside": [p1, p2, p3], "inside": ..., "general": ...}); null otherwise.
  nlohmann::json optimal_probabilities;
  /// ProbabilityMode::learned with the control variate and direct light: what the learned
  /// choice weighed, modelled before the render (render/world/query_costs.h): the exact
  /// render's noise per segment and, per instance, a segment's modelled work; null otherwise.
  nlohmann::json learned_costs;
  /// ProbabilityMode::learned with the control variate and occluder disks (the VPL
  /// integrator with sphere sets): what the scene-level choice between the control variate
  /// and exact visibility weighed before the render; null otherwise.
  nlohmann::json disk_gate;
  /// Adaptive eq. 8 with the VPL integrator: per instance, what the choice between eq. 8
  /// and exact visibility for its points weighed before the render (Eq8Gate); null otherwise.
  nlohmann::json eq8_gate;
  bool counted = false;               ///< the world was a counting one: the two below are set
  std::uint64_t traversal_steps = 0;  ///< BVH nodes visited by shadow queries (and probes)
  std::uint64_t primitive_tests = 0;  ///< triangles and balls tested by shadow queries

  /// Adds `other`'s counts (not its seconds, passes, integrator report or counted flag).
  RenderStats& operator+=(const RenderStats& other);
  nlohmann::json to_json() const;
};

}  // namespace visproxy
