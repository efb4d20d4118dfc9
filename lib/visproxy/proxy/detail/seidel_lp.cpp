// Seidel's incremental linear programming (seidel_lp.h).

#include "visproxy/proxy/detail/seidel_lp.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace visproxy::detail {
namespace {

// Minimise objective·y on the line {y : g·y = h}, subject to `constraints`. Objective
// components at most `flat` count as zero: among (nearly) equally good points, the one
// nearest the origin's projection is taken.
std::optional<Eigen::Vector2d> minimise_on_line(const Eigen::Vector2d& objective, const HalfSpace2& line,
                                                std::span<const HalfSpace2> constraints, double flat) {
  const double g2 = line.normal.squaredNorm();
  const Eigen::Vector2d origin = line.normal * (line.offset / g2);
  const Eigen::Vector2d direction = Eigen::Vector2d(-line.normal.y(), line.normal.x()) / std::sqrt(g2);
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  for (const HalfSpace2& c : constraints) {
    const double slope = c.normal.dot(direction);
    const double need = c.offset - c.normal.dot(origin);
    if (std::abs(slope) <= 1e-14 * c.normal.norm()) {
      if (need > kLpTolerance) return std::nullopt;
      continue;
    }
    if (slope > 0)
      lo = std::max(lo, need / slope);
    else
      hi = std::min(hi, need / slope);
  }
  if (lo > hi + kLpTolerance) return std::nullopt;
  const double slope = objective.dot(direction);
  double t = 0;
  if (slope > flat)
    t = lo;
  else if (slope < -flat)
    t = hi;
  else
    t = std::clamp(0.0, std::min(lo, hi), hi);
  if (!std::isfinite(t)) return std::nullopt;  // unbounded: cannot happen with box constraints
  return origin + t * direction;
}

std::optional<Eigen::Vector2d> minimise_2d(const Eigen::Vector2d& objective, std::span<const HalfSpace2> constraints,
                                           double flat) {
  // The first four constraints are the square |y_k| <= half: start from its best corner.
  const double half = -constraints[0].offset;
  Eigen::Vector2d y;
  for (int k = 0; k < 2; ++k) y[k] = objective[k] > flat ? -half : (objective[k] < -flat ? half : 0);
  for (std::size_t i = 4; i < constraints.size(); ++i) {
    if (constraints[i].normal.dot(y) >= constraints[i].offset - kLpTolerance) continue;
    if (constraints[i].normal.squaredNorm() <= 1e-28) return std::nullopt;
    const std::optional<Eigen::Vector2d> on_line = minimise_on_line(objective, constraints[i], constraints.first(i), flat);
    if (!on_line) return std::nullopt;
    y = *on_line;
  }
  return y;
}

}  // namespace

// Minimise objective·x over {|x_k| <= bound} ∩ constraints. Where the objective is flat
// (components below 1e-6 of its length, e.g. on planar parts of the surface) the point
// nearest the origin wins, instead of a far corner that rounding would pick.
std::optional<Eigen::Vector3d> minimise_3d(const Eigen::Vector3d& objective, std::span<const HalfSpace3> constraints,
                                           double bound) {
  const double flat = 1e-6 * objective.norm();
  Eigen::Vector3d x;
  for (int k = 0; k < 3; ++k) x[k] = objective[k] > flat ? -bound : (objective[k] < -flat ? bound : 0);
  std::vector<HalfSpace2> planar;
  for (std::size_t i = 0; i < constraints.size(); ++i) {
    const HalfSpace3& plane = constraints[i];
    if (plane.normal.dot(x) >= plane.offset - kLpTolerance) continue;
    // The optimum moves onto this plane: solve there in 2D, with the box and the earlier planes.
    const Eigen::Vector3d origin = plane.normal * plane.offset;
    const Eigen::Vector3d helper =
        std::abs(plane.normal.x()) < 0.6 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    const Eigen::Vector3d e1 = plane.normal.cross(helper).normalized();
    const Eigen::Vector3d e2 = plane.normal.cross(e1);
    auto project = [&](const Eigen::Vector3d& normal, double offset) {
      return HalfSpace2{{normal.dot(e1), normal.dot(e2)}, offset - normal.dot(origin)};
    };
    const double square = std::sqrt(3.0) * bound * 1.01;  // contains the plane's part of the box
    planar.clear();
    planar.push_back({{-1, 0}, -square});
    planar.push_back({{1, 0}, -square});
    planar.push_back({{0, -1}, -square});
    planar.push_back({{0, 1}, -square});
    for (int k = 0; k < 3; ++k) {
      planar.push_back(project(-Eigen::Vector3d::Unit(k), -bound));
      planar.push_back(project(Eigen::Vector3d::Unit(k), -bound));
    }
    for (std::size_t j = 0; j < i; ++j) planar.push_back(project(constraints[j].normal, constraints[j].offset));
    const std::optional<Eigen::Vector2d> y = minimise_2d({objective.dot(e1), objective.dot(e2)}, planar, flat);
    if (!y) return std::nullopt;
    x = origin + y->x() * e1 + y->y() * e2;
  }
  return x;
}

}  // namespace visproxy::detail
