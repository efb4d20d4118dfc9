#include "visproxy/inspect/exact_checks.h"

#include <gtest/gtest.h>

#include "test_meshes.h"

namespace visproxy {
namespace {

TriangleMesh two_triangles(std::vector<Vertex> positions, Triangle a, Triangle b) {
  TriangleMesh mesh;
  mesh.positions = std::move(positions);
  mesh.triangles = {a, b};
  return mesh;
}

TEST(ExactChecks, ClosedMeshesDoNotSelfIntersect) {
  EXPECT_TRUE(find_self_intersections(testing::unit_cube()).empty());
  EXPECT_TRUE(find_self_intersections(testing::tetrahedron()).empty());
}

TEST(ExactChecks, CrossingTrianglesWithoutSharedVertices) {
  const auto mesh = two_triangles({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5, 0.5, -1}, {0.5, 0.5, 1}, {1.5, 1.5, 1}},
                                  {0, 1, 2}, {3, 4, 5});
  const auto pairs = find_self_intersections(mesh);
  ASSERT_EQ(pairs.size(), 1u);
  EXPECT_EQ(pairs[0], (std::pair<std::uint32_t, std::uint32_t>{0, 1}));
}

TEST(ExactChecks, TouchingAtOneUnsharedPointCounts) {
  // The second triangle's corner lies exactly on the first triangle's interior.
  const auto mesh = two_triangles({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5, 0.5, 0}, {0.5, 0.5, 1}, {1, 0.5, 1}},
                                  {0, 1, 2}, {3, 4, 5});
  EXPECT_EQ(find_self_intersections(mesh).size(), 1u);
}

TEST(ExactChecks, SharedEdgeFoldedOntoItselfCountsHingeDoesNot) {
  const std::vector<Vertex> positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.2, 0.5, 0}, {0.3, -1, 0}, {0.5, 0.5, 1}};
  EXPECT_EQ(find_self_intersections(two_triangles(positions, {0, 1, 2}, {1, 0, 3})).size(), 1u) << "folded";
  EXPECT_TRUE(find_self_intersections(two_triangles(positions, {0, 1, 2}, {1, 0, 4})).empty()) << "flat";
  EXPECT_TRUE(find_self_intersections(two_triangles(positions, {0, 1, 2}, {1, 0, 5})).empty()) << "hinge";
}

TEST(ExactChecks, SharedVertexCases) {
  const std::vector<Vertex> positions = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0},     // triangle in z = 0
                                         {1, 0.5, -1}, {1, 0.5, 1},            // pierces it
                                         {-1, -1, 1}, {-1, -2, 1},             // away from it
                                         {0.5, 0.2, 0}, {0.2, 0.5, 0}};        // inside it, coplanar
  EXPECT_EQ(find_self_intersections(two_triangles(positions, {0, 1, 2}, {0, 3, 4})).size(), 1u) << "piercing";
  EXPECT_TRUE(find_self_intersections(two_triangles(positions, {0, 1, 2}, {0, 5, 6})).empty()) << "apart";
  EXPECT_EQ(find_self_intersections(two_triangles(positions, {0, 1, 2}, {0, 7, 8})).size(), 1u) << "coplanar overlap";
}

TEST(ExactChecks, DuplicateTriangleIntersectsDegenerateIsReportedApart) {
  TriangleMesh mesh = testing::tetrahedron();
  mesh.triangles.push_back(mesh.triangles[0]);
  EXPECT_EQ(find_self_intersections(mesh).size(), 1u);

  TriangleMesh flat = testing::tetrahedron();
  flat.positions.push_back({0.5, 0.5, 0});  // on the segment from (1,0,0) to (0,1,0)
  flat.triangles.push_back({1, 4, 2});
  flat.triangles.push_back({3, 3, 0});
  EXPECT_EQ(find_degenerate_triangles(flat), (std::vector<std::uint32_t>{4, 5}));
  EXPECT_TRUE(find_degenerate_triangles(testing::unit_cube()).empty());
}

}  // namespace
}  // namespace visproxy
