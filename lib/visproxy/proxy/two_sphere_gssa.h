#pragma once
// The generalised shadowing surface area (GSSA) of the union of two balls, and the one
// ball that replaces them when a sphere set is simplified (occluding-spheres paper, 3.3-3.4).
//
// GSSA(K) is defined by isotropic lines: a line meeting a ball S of radius R_s that holds K
// hits K with probability GSSA(K) / (4 pi R_s^2); for convex K it is the surface area.
// Every function takes the larger radius R, the smaller r (0 <= r <= R) and the distance d
// between the centres (d >= 0), in any one length unit; areas come back in its square.

#include "visproxy/mesh/sphere_set.h"

namespace visproxy {

/// 4 pi R^2 + 4 pi r^2: exact for lines when the balls are far apart, otherwise it counts
/// lines through both twice (an overestimate).
double two_sphere_area_sum(double R, double r, double d);

/// The surface area of the union (SPEC, errata): the sum when the balls are apart, 4 pi R^2
/// when the larger holds the smaller, otherwise the two outer caps. An overestimate.
double two_sphere_union_area(double R, double r, double d);

/// The surface area of the convex hull of the two balls (two caps and a cone frustum);
/// 4 pi R^2 when the larger holds the smaller. An overestimate.
double two_sphere_hull_area(double R, double r, double d);

/// The minimum of the three overestimates above (SPEC's rule).
double two_sphere_gssa_analytic(double R, double r, double d);

/// The exact GSSA of the union, from Cauchy's projection formula: a line in direction u hits
/// the union when it meets the union's shadow on a plane normal to u, which is two discs of
/// radii R and r at centre distance d sin(theta). Averaged over directions,
///   GSSA = 4 pi (R^2 + r^2) - 4 * integral_0^1 lens(R, r, d sqrt(1 - t^2)) dt,
/// with lens the area where the two discs overlap. The integral is taken by Gauss-Legendre
/// quadrature after a change of variable that smooths the lens's 3/2-power ends; relative
/// error below 1e-9 (tests check it against the closed forms at the limits and against
/// Monte Carlo lines over a grid of r/R and d/R).
double two_sphere_gssa_exact(double R, double r, double d);

/// Which GSSA a merge preserves.
enum class MergeRadius {
  exact,     ///< two_sphere_gssa_exact: the merged ball is hit exactly as often as the pair
  analytic,  ///< two_sphere_gssa_analytic: the paper's overestimates (merged balls grow)
};

/// The ball that replaces `a` and `b` (occluding-spheres, 3.3-3.4): radius sqrt(A / 4 pi)
/// for the GSSA A of their union (by `rule`), centre the average of the two centres weighted
/// by the convex-hull cap areas S_R = 2 pi R^2 (1 + cos alpha) and S_r = 2 pi r^2 (1 - cos
/// alpha), cos alpha = (R - r) / d. When one ball holds the other the result is the larger
/// ball itself. Symmetric in a and b.
Sphere merge_two_spheres(const Sphere& a, const Sphere& b, MergeRadius rule = MergeRadius::exact);

}  // namespace visproxy
