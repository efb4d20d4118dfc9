#include "visproxy/proxy/two_sphere_gssa.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "visproxy/measure/proportion.h"
#include "visproxy/measure/random_lines.h"
#include "visproxy/trace/ray_scene.h"

namespace visproxy {
namespace {

constexpr double kPi = std::numbers::pi;

TEST(TwoSphereGssa, LimitsAreClosedForms) {
  // One ball inside the other (or concentric): the union is the larger ball.
  EXPECT_DOUBLE_EQ(two_sphere_gssa_exact(1, 0.5, 0), 4 * kPi);
  EXPECT_DOUBLE_EQ(two_sphere_gssa_exact(1, 0.5, 0.5), 4 * kPi);
  EXPECT_DOUBLE_EQ(two_sphere_gssa_exact(0.5, 1, 0.2), 4 * kPi);  // either order
  EXPECT_DOUBLE_EQ(two_sphere_gssa_exact(2, 0, 3), 16 * kPi);
  // Far apart, almost no line meets both: the sum, minus the lines through both, which
  // for d >> R + r is about pi^2 R^2 r^2 / d^2 * 4 / pi (mean product of two disc shadows).
  const double far = two_sphere_gssa_exact(1, 0.5, 1000);
  EXPECT_LT(far, two_sphere_area_sum(1, 0.5, 1000));
  EXPECT_NEAR(far, two_sphere_area_sum(1, 0.5, 1000), 1e-5);
  // Equal balls at distance 0 and a tiny distance: continuous.
  EXPECT_NEAR(two_sphere_gssa_exact(1, 1, 1e-9), 4 * kPi, 1e-7);
}

TEST(TwoSphereGssa, ExactIsBelowEveryOverestimateAndAboveTheLargerBall) {
  for (double r : {0.05, 0.2, 0.5, 0.8, 1.0})
    for (double d : {0.01, 0.3, 0.9, 1.0, 1.2, 1.8, 2.0, 2.5, 4.0, 20.0}) {
      SCOPED_TRACE(::testing::Message() << "r " << r << " d " << d);
      const double exact = two_sphere_gssa_exact(1, r, d);
      EXPECT_LE(exact, two_sphere_area_sum(1, r, d) * (1 + 1e-12));
      EXPECT_LE(exact, two_sphere_union_area(1, r, d) * (1 + 1e-12));
      EXPECT_LE(exact, two_sphere_hull_area(1, r, d) * (1 + 1e-12));
      EXPECT_DOUBLE_EQ(two_sphere_gssa_analytic(1, r, d),
                       std::min({two_sphere_area_sum(1, r, d), two_sphere_union_area(1, r, d), two_sphere_hull_area(1, r, d)}));
      EXPECT_GE(exact, 4 * kPi * (1 - 1e-12));
      // Scaling: A(sR, sr, sd) = s^2 A(R, r, d).
      EXPECT_NEAR(two_sphere_gssa_exact(3, 3 * r, 3 * d), 9 * exact, 1e-9 * exact);
    }
  // Touching equal balls: the overestimates all say 8 pi, the exact value is 7.4 pi.
  EXPECT_NEAR(two_sphere_gssa_analytic(1, 1, 2), 8 * kPi, 1e-12);
  EXPECT_NEAR(two_sphere_gssa_exact(1, 1, 2) / kPi, 7.3953, 1e-3);
}

// Monte Carlo against the exact formula over a grid of (r/R, d/R): isotropic lines through
// a sphere holding both balls hit their union with probability GSSA / (4 pi R_s^2). 200 000
// lines per configuration; the exact value must lie in the 99.99 % Wilson interval of every
// count (20 configurations). The analytic minimum is checked to be an overestimate by more
// than the interval where the balls overlap a lot or nearly touch.
TEST(TwoSphereGssa, ExactMatchesMonteCarloLinesOverAGrid) {
  constexpr double z = 3.890592;  // 99.99 %
  int analytic_outside = 0;
  std::uint64_t seed = 100;
  for (double r : {0.25, 0.5, 0.75, 1.0})
    for (double d : {0.5, 1.0, 1.5, 2.0, 3.0}) {
      SCOPED_TRACE(::testing::Message() << "r/R " << r << " d/R " << d);
      const std::vector<Sphere> balls = {{{0, 0, 0}, 1.0}, {{d, 0, 0}, r}};
      const Sphere holder{{d / 2, 0, 0}, d / 2 + 1.0 + 1e-6};
      const RayScene scene(balls);
      const std::vector<Segment> lines = isotropic_lines(holder, 200000, seed++);
      Proportion hit;
      for (const std::uint8_t blocked : scene.segments_blocked(lines)) hit.successes += blocked;
      hit.trials = lines.size();
      const double area = 4 * kPi * holder.radius * holder.radius;
      const double exact = two_sphere_gssa_exact(1, r, d) / area;
      EXPECT_GE(exact, hit.lower(z));
      EXPECT_LE(exact, hit.upper(z));
      if (two_sphere_gssa_analytic(1, r, d) / area > hit.upper(z)) ++analytic_outside;
    }
  EXPECT_GE(analytic_outside, 10);
}

TEST(MergeTwoSpheres, RadiusKeepsTheGssaAndCentreIsWeighted) {
  const Sphere a{{0, 0, 0}, 1.0};
  const Sphere b{{1.5, 0, 0}, 0.5};
  const Sphere merged = merge_two_spheres(a, b);
  EXPECT_NEAR(4 * kPi * merged.radius * merged.radius, two_sphere_gssa_exact(1, 0.5, 1.5), 1e-12);
  const Sphere analytic = merge_two_spheres(a, b, MergeRadius::analytic);
  EXPECT_NEAR(4 * kPi * analytic.radius * analytic.radius, two_sphere_gssa_analytic(1, 0.5, 1.5), 1e-12);
  EXPECT_GT(analytic.radius, merged.radius);
  // cos alpha = 1/3: weights 2 pi (4/3) and 2 pi 0.25 (2/3), centre 1.5 * w_r / (w_R + w_r).
  const double w_large = 2 * kPi * (1 + 1.0 / 3), w_small = 2 * kPi * 0.25 * (1 - 1.0 / 3);
  EXPECT_NEAR(merged.center.x(), 1.5 * w_small / (w_large + w_small), 1e-15);
  EXPECT_EQ(merged.center.y(), 0.0);
  // Symmetric to the bit; equal balls meet in the middle; a held ball changes nothing.
  EXPECT_EQ(merge_two_spheres(b, a), merged);
  EXPECT_EQ(merge_two_spheres({{0, 0, 0}, 1}, {{2, 0, 0}, 1}).center, Vertex(1, 0, 0));
  EXPECT_EQ(merge_two_spheres(a, {{0.25, 0, 0}, 0.5}), a);
}

}  // namespace
}  // namespace visproxy
