#pragma once
// Private to lib/visproxy/proxy/detail: Seidel's incremental linear programming in 3, 2
// and 1 dimensions (R. Seidel, "Small-dimensional linear programming and convex hulls made
// easy", Discrete & Computational Geometry 6, 1991): minimise c.x subject to n_i.x >= b_i
// and the box |x_k| <= bound. The progressive hull's vertex that adds the least volume
// (conservative_decimation.cpp).

#include <Eigen/Core>

#include <optional>
#include <span>

namespace visproxy::detail {

struct HalfSpace3 {
  Eigen::Vector3d normal;  // unit length
  double offset;
};

struct HalfSpace2 {
  Eigen::Vector2d normal;
  double offset;
};

/// Constraints count as met within this much.
constexpr double kLpTolerance = 1e-10;

/// Minimise objective.x over {|x_k| <= bound} and the constraints (in their order, each one
/// that the current optimum breaks solved for on its plane). Where the objective is flat
/// (components below 1e-6 of its length) the point nearest the origin wins, instead of a far
/// corner that rounding would pick. nullopt when the constraints leave nothing.
std::optional<Eigen::Vector3d> minimise_3d(const Eigen::Vector3d& objective, std::span<const HalfSpace3> constraints, double bound);

}  // namespace visproxy::detail
