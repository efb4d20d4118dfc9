#include "trace/ray_scene.h"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace visproxy
