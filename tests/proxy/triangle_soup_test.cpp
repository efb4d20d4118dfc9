#include "visproxy/proxy/detail/triangle_soup.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "test_meshes.h"

namespace visproxy {
namespace {

TEST(SoupPrimitives, SortsProperCollinearAndPointTriangles) {
  TriangleMesh mesh = testing::tetrahedron();
  const auto first = static_cast<VertexIndex>(mesh.positions.size());
  mesh.positions.emplace_back(2, 2, 2);
  mesh.positions.emplace_back(3, 3, 3);
  mesh.positions.emplace_back(5, 5, 5);
  mesh.triangles.push_back({first + 2, first, first + 1});      // collinear, extremes first + 2 and first
  mesh.triangles.push_back({first + 1, first + 1, first + 1});  // a point
  mesh.triangles.push_back({first, first, first + 1});          // repeated corner: a segment
  const SoupPrimitives primitives = soup_primitives(mesh);
  EXPECT_EQ(primitives.triangle_indices, (std::vector<std::uint32_t>{0, 1, 2, 3}));  // the tetrahedron's
  ASSERT_EQ(primitives.segments.size(), 2u);
  EXPECT_EQ(primitives.segments[0].first, Vertex(5, 5, 5));
  EXPECT_EQ(primitives.segments[0].second, Vertex(2, 2, 2));
  EXPECT_EQ(primitives.segments[1].first, Vertex(2, 2, 2));
  EXPECT_EQ(primitives.segments[1].second, Vertex(3, 3, 3));
  ASSERT_EQ(primitives.points.size(), 1u);
  EXPECT_EQ(primitives.points[0], Vertex(3, 3, 3));
}

// Corners one rounding step apart: comparing rounded lengths could pick the wrong
// extremes; the exact order along the line does not.
TEST(SoupPrimitives, ExtremeCornersAreExactForNearlyEqualCorners) {
  TriangleMesh mesh;
  const double next = std::nextafter(1.0, 2.0);
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {next, 0, 0}};
  for (const Triangle& t : {Triangle{0, 1, 2}, Triangle{1, 2, 0}, Triangle{2, 0, 1}, Triangle{1, 0, 2}}) {
    mesh.triangles = {t};
    const SoupPrimitives primitives = soup_primitives(mesh);
    ASSERT_EQ(primitives.segments.size(), 1u);
    const auto& [a, b] = primitives.segments[0];
    EXPECT_EQ(std::min(a.x(), b.x()), 0.0);
    EXPECT_EQ(std::max(a.x(), b.x()), next);
  }
}

}  // namespace
}  // namespace visproxy
