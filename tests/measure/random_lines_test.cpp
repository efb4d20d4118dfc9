#include "visproxy/measure/random_lines.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "visproxy/measure/proportion.h"
#include "test_meshes.h"
#include "visproxy/trace/ray_scene.h"

namespace visproxy {
namespace {

TEST(BoundingSphere, ContainsEveryVertex) {
  const TriangleMesh cube = testing::unit_cube();
  const Sphere sphere = bounding_sphere(cube);
  for (const Vertex& p : cube.positions) EXPECT_LT((p - sphere.center).norm(), sphere.radius);
  EXPECT_NEAR(sphere.radius, std::sqrt(3.0) / 2, 1e-5);
}

TEST(IsotropicLines, EndPointsLieOnTheSphereAndSeedReproduces) {
  const Sphere sphere{{1, 2, 3}, 5};
  const std::vector<Segment> lines = isotropic_lines(sphere, 1000, 7);
  ASSERT_EQ(lines.size(), 1000u);
  for (const Segment& line : lines) {
    EXPECT_NEAR((line.from - sphere.center).norm(), 5, 1e-12);
    EXPECT_NEAR((line.to - sphere.center).norm(), 5, 1e-12);
  }
  const std::vector<Segment> again = isotropic_lines(sphere, 1000, 7);
  const std::vector<Segment> other = isotropic_lines(sphere, 1000, 8);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    EXPECT_EQ(lines[i].from, again[i].from);
    EXPECT_EQ(lines[i].to, again[i].to);
  }
  EXPECT_NE(lines[0].from, other[0].from);
}

// Cauchy–Crofton: isotropic lines meeting a sphere of radius R hit a convex body inside it
// with probability area / (4 pi R^2). For the unit cube in its bounding sphere that is
// 6 / (3 pi) = 0.6366. 200 000 lines; the 99.9 % Wilson interval must contain it.
TEST(IsotropicLines, HitFractionOfCubeMatchesCauchyCrofton) {
  const TriangleMesh cube = testing::unit_cube();
  const Sphere sphere = bounding_sphere(cube);
  const RayScene scene(cube);
  const std::vector<Segment> lines = isotropic_lines(sphere, 200000, 1);
  Proportion hit;
  for (std::uint8_t blocked : scene.segments_blocked(lines)) hit.successes += blocked;
  hit.trials = lines.size();
  const double expected = 6.0 / (4 * std::numbers::pi * sphere.radius * sphere.radius);
  EXPECT_LE(hit.lower(3.290527), expected);
  EXPECT_GE(hit.upper(3.290527), expected);
}

TEST(Proportion, WilsonIntervalKnownValuesAndEmptyCount) {
  const Proportion half{50, 100};
  EXPECT_DOUBLE_EQ(half.fraction(), 0.5);
  EXPECT_NEAR(half.lower(), 0.4038, 1e-4);  // textbook Wilson interval for 50/100 at 95 %
  EXPECT_NEAR(half.upper(), 0.5962, 1e-4);
  const Proportion none{0, 0};
  EXPECT_EQ(none.fraction(), 0.0);
  EXPECT_EQ(none.lower(), 0.0);
  EXPECT_EQ(none.upper(), 1.0);
  const Proportion all{20, 20};
  EXPECT_EQ(all.upper(), 1.0);
  EXPECT_LT(all.lower(), 1.0);
}

}  // namespace
}  // namespace visproxy
