#include "visproxy/trace/ray_scene.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "visproxy/core/random.h"
#include "test_meshes.h"

namespace visproxy {
namespace {

TEST(RayScene, SegmentThroughCubeIsBlockedFromEitherSide) {
  const RayScene cube(testing::unit_cube());
  EXPECT_TRUE(cube.segment_blocked({{-1, 0.5, 0.5}, {2, 0.5, 0.5}}));
  EXPECT_TRUE(cube.segment_blocked({{2, 0.3, 0.7}, {-1, 0.3, 0.7}}));
  // From inside: the segment leaves through a face.
  EXPECT_TRUE(cube.segment_blocked({{0.5, 0.5, 0.5}, {0.5, 0.5, 3}}));
}

TEST(RayScene, SegmentBesideOrShortOfTheCubeIsNotBlocked) {
  const RayScene cube(testing::unit_cube());
  EXPECT_FALSE(cube.segment_blocked({{-1, 1.5, 0.5}, {2, 1.5, 0.5}}));
  EXPECT_FALSE(cube.segment_blocked({{-1, 0.5, 0.5}, {-0.1, 0.5, 0.5}}));
  EXPECT_FALSE(cube.segment_blocked({{0.2, 0.2, 0.2}, {0.8, 0.8, 0.8}}));  // inside, no face crossed
}

TEST(RayScene, EmptyMeshBlocksNothing) {
  const RayScene empty(TriangleMesh{});
  EXPECT_FALSE(empty.segment_blocked({{-1, 0, 0}, {1, 0, 0}}));
}

TEST(RayScene, BatchAgreesWithSingleQueries) {
  const RayScene tetrahedron(testing::tetrahedron());
  std::vector<Segment> segments;
  for (int i = 0; i < 200; ++i) {
    const double t = i / 200.0;
    segments.push_back({{t, 0.2, -1}, {0.1, t, 2}});
  }
  const std::vector<std::uint8_t> blocked = tetrahedron.segments_blocked(segments);
  ASSERT_EQ(blocked.size(), segments.size());
  std::size_t hits = 0;
  for (std::size_t i = 0; i < segments.size(); ++i) {
    EXPECT_EQ(blocked[i] != 0, tetrahedron.segment_blocked(segments[i])) << i;
    hits += blocked[i];
  }
  EXPECT_GT(hits, 0u);
  EXPECT_LT(hits, segments.size());
}

TEST(RaySceneSpheres, BallsAreSolid) {
  const std::vector<Sphere> balls = {{{0, 0, 0}, 1.0}, {{5, 0, 0}, 0.5}};
  const RayScene scene(balls);
  EXPECT_TRUE(scene.segment_blocked({{-3, 0.9, 0}, {3, 0.9, 0}}));
  EXPECT_FALSE(scene.segment_blocked({{-3, 1.1, 0}, {3, 1.1, 0}}));
  EXPECT_TRUE(scene.segment_blocked({{0.1, 0, 0}, {0.2, 0, 0}}));  // wholly inside a ball
  EXPECT_TRUE(scene.segment_blocked({{0, 0, 0}, {0, 0, 9}}));      // starts inside
  EXPECT_TRUE(scene.segment_blocked({{0, 0, 9}, {0, 0, 0.5}}));    // ends inside
  EXPECT_FALSE(scene.segment_blocked({{-3, 0, 0}, {-1.5, 0, 0}}));  // stops short
  EXPECT_FALSE(scene.segment_blocked({{1.5, 0, 0}, {4.4, 0, 0}}));  // between the balls
  EXPECT_TRUE(scene.segment_blocked({{1.5, 0, 0}, {4.6, 0, 0}}));
  EXPECT_FALSE(RayScene(std::vector<Sphere>{}).segment_blocked({{-1, 0, 0}, {1, 0, 0}}));
}

// Against a brute-force double-precision test of every ball, on many random segments
// around a cluster of overlapping balls of very different sizes.
TEST(RaySceneSpheres, AgreesWithBruteForce) {
  Random random(7);
  std::vector<Sphere> balls;
  for (int i = 0; i < 300; ++i)
    balls.push_back({Vertex(random.uniform(), random.uniform(), random.uniform()) * 10.0,
                     0.01 + random.uniform() * random.uniform() * 2.0});
  const RayScene scene(balls);
  std::vector<Segment> segments;
  for (int i = 0; i < 20000; ++i) {
    const Vertex a = Vertex(random.uniform(), random.uniform(), random.uniform()) * 14.0 - Vertex::Constant(2.0);
    const Vertex b = Vertex(random.uniform(), random.uniform(), random.uniform()) * 14.0 - Vertex::Constant(2.0);
    segments.push_back({a, b});
  }
  const std::vector<std::uint8_t> blocked = scene.segments_blocked(segments);
  std::size_t disagreements = 0, hits = 0;
  for (std::size_t i = 0; i < segments.size(); ++i) {
    // Closest point of the closed segment to each centre.
    const Vertex& a = segments[i].from;
    const Vertex d = segments[i].to - a;
    bool expected = false;
    for (const Sphere& ball : balls) {
      const double t = std::clamp((ball.center - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
      if ((a + t * d - ball.center).norm() <= ball.radius) expected = true;
    }
    disagreements += expected != (blocked[i] != 0);
    hits += expected;
  }
  // Only segments that graze a ball within float rounding of the ray may differ.
  EXPECT_LE(disagreements, 2u);
  EXPECT_GT(hits, 1000u);
  EXPECT_LT(hits, 19000u);
}

}  // namespace
}  // namespace visproxy
