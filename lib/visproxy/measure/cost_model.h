#pragma once
// The cost of a shadow ray predicted from the work it does, not from its timing alone.
//
// Timings of one ray set move by up to 10 % between runs on a busy machine, and by more
// between machines, so ratios of two timed costs near 1 flip from run to run. The work a
// ray does (BVH nodes visited, triangles and balls tested, counted by CountingBvh on the
// very rays that are timed) does not move. A run times every proxy anyway; from
// those timings it fits one set of per-machine constants
//     ns per ray = c_ray + c_node nodes + c_triangle triangles + c_ball balls
// and predicts each geometry's cost from its counted work. How far the timings lie from
// the fitted model, over every geometry of the run, is the model's error, and an
// interval built on the model carries it.

#include <array>
#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "visproxy/trace/counting_bvh.h"
#include "visproxy/trace/ray_scene.h"

namespace visproxy {

/// The work of one shadow ray, averaged over a ray set.
struct WorkPerRay {
  double nodes = 0;      ///< BVH nodes whose boxes the ray tested
  double triangles = 0;  ///< triangles tested
  double balls = 0;      ///< balls tested
};

/// Counts the work of the first `limit` rays of `rays` against `bvh` (in parallel; the
/// counts do not depend on the number of threads) and averages it per ray; a BVH of balls
/// counts balls, one of triangles triangles.
WorkPerRay count_work(const CountingBvh& bvh, bool balls, std::span<const Segment> rays, std::size_t limit);

/// One timed geometry of a run: its work per ray and its timed nanoseconds per ray.
struct CostObservation {
  WorkPerRay work;
  double ns_per_ray = 0;
};

/// Per-machine constants of one run (nanoseconds), fitted to its observations by least
/// squares on relative errors with every constant non-negative.
struct CostModel {
  double per_ray = 0, per_node = 0, per_triangle = 0, per_ball = 0;
  std::size_t observations = 0;
  /// The least and greatest timed / predicted cost over the observations: how far the
  /// machine's timings lay from the model in this run.
  double residual_low = 1, residual_high = 1;

  double predict(const WorkPerRay& work) const {
    return per_ray + per_node * work.nodes + per_triangle * work.triangles + per_ball * work.balls;
  }
};

/// The fewest observations a model is fitted from: half again its four constants.
inline constexpr std::size_t kCostModelMinimumObservations = 6;

/// The model of `observations` (those with ns_per_ray > 0), or none when fewer than
/// kCostModelMinimumObservations were timed or the fit predicts a non-positive cost for one.
std::optional<CostModel> fit_cost_model(std::span<const CostObservation> observations);

}  // namespace visproxy
