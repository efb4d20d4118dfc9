#include "visproxy/measure/cost_model.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

namespace visproxy {

WorkPerRay count_work(const CountingBvh& bvh, bool balls, std::span<const Segment> rays, std::size_t limit) {
  const std::size_t n = std::min(rays.size(), limit);
  if (n == 0) return {};
  const TraversalCounts total = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, n, 1024), TraversalCounts{},
      [&](const tbb::blocked_range<std::size_t>& range, TraversalCounts counts) {
        for (std::size_t i = range.begin(); i < range.end(); ++i) bvh.segment_blocked(rays[i].from, rays[i].to, counts);
        return counts;
      },
      [](TraversalCounts a, const TraversalCounts& b) {
        a.nodes += b.nodes, a.primitives += b.primitives;
        return a;
      });
  const double count = static_cast<double>(n);
  WorkPerRay work;
  work.nodes = static_cast<double>(total.nodes) / count;
  (balls ? work.balls : work.triangles) = static_cast<double>(total.primitives) / count;
  return work;
}

std::optional<CostModel> fit_cost_model(std::span<const CostObservation> observations) {
  std::vector<CostObservation> timed;
  for (const CostObservation& o : observations)
    if (o.ns_per_ray > 0 && std::isfinite(o.ns_per_ray)) timed.push_back(o);
  if (timed.size() < kCostModelMinimumObservations) return std::nullopt;

  // Relative errors: each row divided by its timing, so that a one-box proxy's 20 ns
  // weighs as much as the mesh's 2000.
  const Eigen::Index rows = static_cast<Eigen::Index>(timed.size());
  Eigen::MatrixXd a(rows, 4);
  Eigen::VectorXd b = Eigen::VectorXd::Ones(rows);
  for (Eigen::Index i = 0; i < rows; ++i) {
    const CostObservation& o = timed[static_cast<std::size_t>(i)];
    a.row(i) << 1.0, o.work.nodes, o.work.triangles, o.work.balls;
    a.row(i) /= o.ns_per_ray;
  }
  // Non-negative least squares over four unknowns: the best of the unconstrained fits on
  // every subset of free constants (the others held at 0) whose solution is non-negative;
  // the optimum is one of them (its free set is exactly its positive constants).
  Eigen::Vector4d best = Eigen::Vector4d::Zero();
  double best_error = std::numeric_limits<double>::infinity();
  for (unsigned subset = 1; subset < 16; ++subset) {
    std::vector<Eigen::Index> free;
    for (Eigen::Index k = 0; k < 4; ++k)
      if (subset & (1u << k)) free.push_back(k);
    Eigen::MatrixXd columns(rows, static_cast<Eigen::Index>(free.size()));
    for (std::size_t k = 0; k < free.size(); ++k) columns.col(static_cast<Eigen::Index>(k)) = a.col(free[k]);
    const Eigen::VectorXd x = columns.colPivHouseholderQr().solve(b);
    if (!x.allFinite() || (x.array() < 0).any()) continue;
    Eigen::Vector4d candidate = Eigen::Vector4d::Zero();
    for (std::size_t k = 0; k < free.size(); ++k) candidate[free[k]] = x[static_cast<Eigen::Index>(k)];
    const double error = (a * candidate - b).squaredNorm();
    if (error < best_error) best_error = error, best = candidate;
  }
  if (!std::isfinite(best_error)) return std::nullopt;

  CostModel model;
  model.per_ray = best[0], model.per_node = best[1], model.per_triangle = best[2], model.per_ball = best[3];
  model.observations = timed.size();
  model.residual_low = std::numeric_limits<double>::infinity(), model.residual_high = 0;
  for (const CostObservation& o : timed) {
    const double predicted = model.predict(o.work);
    if (!(predicted > 0)) return std::nullopt;
    model.residual_low = std::min(model.residual_low, o.ns_per_ray / predicted);
    model.residual_high = std::max(model.residual_high, o.ns_per_ray / predicted);
  }
  return model;
}

}  // namespace visproxy
