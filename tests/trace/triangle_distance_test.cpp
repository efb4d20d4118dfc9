// TriangleDistance against a scan of every triangle: the BVH's single-precision culling must
// never drop the nearest triangle, near the surface or far from it, at the origin or 10^6
// away, for meshes far larger or far smaller than their distance from the origin.

#include "visproxy/trace/triangle_distance.h"

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <limits>
#include <vector>

#include "visproxy/core/random.h"
#include "visproxy/mesh/read_mesh.h"
#include "test_meshes.h"
#include "trace/placed_meshes.h"

namespace visproxy {
namespace {

double scan(const TriangleMesh& mesh, const Vertex& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const Triangle& t : mesh.triangles)
    best = std::min(best, point_triangle_squared_distance(p, mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]));
  return best;
}

using testing::every_triangle;

TEST(PointTriangleDistance, EveryRegionOfTheTriangle) {
  const Vertex a(0, 0, 0), b(2, 0, 0), c(0, 2, 0);
  EXPECT_DOUBLE_EQ(point_triangle_squared_distance({0.5, 0.5, 3}, a, b, c), 9.0);      // above the inside
  EXPECT_DOUBLE_EQ(point_triangle_squared_distance({-1, -1, 0}, a, b, c), 2.0);        // beyond corner a
  EXPECT_DOUBLE_EQ(point_triangle_squared_distance({3, 0, 1}, a, b, c), 2.0);          // beyond corner b
  EXPECT_DOUBLE_EQ(point_triangle_squared_distance({1, -2, 0}, a, b, c), 4.0);         // beside side ab
  EXPECT_DOUBLE_EQ(point_triangle_squared_distance({-3, 1, 0}, a, b, c), 9.0);         // beside side ac
  EXPECT_NEAR(point_triangle_squared_distance({2, 2, 0}, a, b, c), 2.0, 1e-15);        // beside side bc
  // Collinear corners: the segment they span.
  EXPECT_DOUBLE_EQ(point_triangle_squared_distance({1, 1, 0}, a, b, {4, 0, 0}), 1.0);
  EXPECT_DOUBLE_EQ(point_triangle_squared_distance({6, 0, 0}, a, a, {4, 0, 0}), 4.0);
}

// The nearest point lies on the triangle, at the distance point_triangle_squared_distance
// gives, for points beyond each corner, beside each side and above the inside, and on
// triangles with collinear or equal corners.
TEST(PointTriangleDistance, NearestPointIsOnTheTriangleAtTheDistance) {
  const Vertex a(0, 0, 0), b(2, 0, 0), c(0, 2, 0);
  EXPECT_EQ(point_triangle_nearest_point({0.5, 0.5, 3}, a, b, c), Vertex(0.5, 0.5, 0));
  EXPECT_EQ(point_triangle_nearest_point({-1, -1, 0}, a, b, c), a);
  EXPECT_EQ(point_triangle_nearest_point({3, 0, 1}, a, b, c), b);
  EXPECT_EQ(point_triangle_nearest_point({1, -2, 0}, a, b, c), Vertex(1, 0, 0));
  EXPECT_EQ(point_triangle_nearest_point({-3, 1, 0}, a, b, c), Vertex(0, 1, 0));
  EXPECT_TRUE(point_triangle_nearest_point({2, 2, 0}, a, b, c).isApprox(Vertex(1, 1, 0), 1e-15));
  EXPECT_EQ(point_triangle_nearest_point({1, 1, 0}, a, b, {4, 0, 0}), Vertex(1, 0, 0));  // collinear
  EXPECT_EQ(point_triangle_nearest_point({6, 0, 0}, a, a, {4, 0, 0}), Vertex(4, 0, 0));
  EXPECT_EQ(point_triangle_nearest_point({6, 1, 0}, a, a, a), a);
  Random random(3);
  for (int i = 0; i < 1000; ++i) {
    auto any_point = [&] { return Vertex(random.uniform() - 0.5, random.uniform() - 0.5, random.uniform() - 0.5); };
    const Vertex u = any_point(), v = any_point(), w = any_point(), p = 3 * any_point();
    const Vertex q = point_triangle_nearest_point(p, u, v, w);
    EXPECT_NEAR((p - q).squaredNorm(), point_triangle_squared_distance(p, u, v, w), 1e-12) << i;
    // On the triangle: in its plane, with barycentric coordinates in [0, 1].
    const Vertex n = (v - u).cross(w - u);
    EXPECT_NEAR(n.normalized().dot(q - u), 0.0, 1e-12) << i;
    const double area = n.norm();
    const double alpha = (v - q).cross(w - q).norm() / area, beta = (w - q).cross(u - q).norm() / area,
                 gamma = (u - q).cross(v - q).norm() / area;
    EXPECT_NEAR(alpha + beta + gamma, 1.0, 1e-9) << i;
  }
}

// Points near the surface (jittered vertices), inside, and far outside, on bunny00 where it
// lies and moved 10^6 away, and on a copy shrunk to 10^-6 of its size 10^3 from the origin.
TEST(TriangleDistance, FindsTheNearestTriangleOfAScanAnywhere) {
  const TriangleMesh bunny = read_mesh(testing::cgal_mesh("bunny00.off"));
  for (const testing::Placement& placement : testing::kPlacements) {
    SCOPED_TRACE(placement.name);
    const TriangleMesh mesh = testing::placed(bunny, placement);
    const BoundingBox box = bounding_box(mesh);
    const double size = box.diagonal();
    const TriangleDistance distance(mesh, every_triangle(mesh));
    ASSERT_EQ(distance.size(), mesh.triangles.size());
    Random random(11);
    std::vector<Vertex> points;
    for (int i = 0; i < 300; ++i) {
      const Vertex& v = mesh.positions[random.below(mesh.positions.size())];
      const Vertex jitter(random.uniform() - 0.5, random.uniform() - 0.5, random.uniform() - 0.5);
      points.push_back(v + 1e-3 * size * jitter);
      points.push_back(box.min + Vertex(random.uniform(), random.uniform(), random.uniform()).cwiseProduct(box.max - box.min));
      points.push_back(box.min + 3 * size * Vertex(random.uniform(), random.uniform(), random.uniform()) - Vertex::Constant(size));
    }
    std::vector<double> found(points.size()), scanned(points.size());
    tbb::parallel_for(std::size_t{0}, points.size(), [&](std::size_t i) {
      found[i] = distance.squared_distance(points[i]);
      scanned[i] = scan(mesh, points[i]);
    });
    for (std::size_t i = 0; i < points.size(); ++i) {
      EXPECT_EQ(found[i], scanned[i]) << "point " << i;
      // within() agrees just above and just below the nearest distance.
      EXPECT_TRUE(distance.within(points[i], scanned[i] * (1 + 1e-9) + 1e-300)) << "point " << i;
      EXPECT_FALSE(distance.within(points[i], scanned[i])) << "point " << i;
    }
  }
}

// Pairs of triangles on either side of a point, 1 and 1 - 10^-9 away, spread over 2000
// units about a point 10^6 from the origin: single precision cannot tell the two apart, so
// a search radius without its slack culls the nearer one whenever the farther is found
// first.
TEST(TriangleDistance, TellsApartTrianglesNearerThanSinglePrecisionResolves) {
  Random random(5);
  TriangleMesh mesh;
  std::vector<Vertex> points;
  const Vertex far(1e6, 1e6, -1e6);
  for (int i = 0; i < 400; ++i) {
    const Vertex p = far + 1000 * Vertex(random.uniform() - 0.5, random.uniform() - 0.5, random.uniform() - 0.5) * 2;
    points.push_back(p);
    for (const double x : {1.0, -(1.0 - 1e-9)}) {
      const auto base = static_cast<VertexIndex>(mesh.positions.size());
      mesh.positions.push_back(p + Vertex(x, -0.1, -0.1));
      mesh.positions.push_back(p + Vertex(x, 0.1, -0.1));
      mesh.positions.push_back(p + Vertex(x, 0, 0.1));
      mesh.triangles.push_back({base, base + 1, base + 2});
    }
  }
  const TriangleDistance distance(mesh, every_triangle(mesh));
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double scanned = scan(mesh, points[i]);
    ASSERT_LT(scanned, 1.0);
    EXPECT_EQ(distance.squared_distance(points[i]), scanned) << "point " << i;
    EXPECT_TRUE(distance.within(points[i], 1.0)) << "point " << i;
  }
}

// The worst case of single precision: the nearer triangle's plane x = 511 is a float, so
// its box does not grow, and the query point x = 512.000035 rounds up to 512.000061, away
// from it, while the farther triangle (1e-9 farther) is found first. Without the search
// radius's slack the nearer one is culled (a box 1.000061 away against a radius of
// 1.000035). Triangles at +-1024 keep the BVH's centre at the origin.
TEST(TriangleDistance, APointRoundedAwayFromTheNearestTriangleStillFindsIt) {
  TriangleMesh mesh;
  auto add = [&](double x, double half) {
    const auto base = static_cast<VertexIndex>(mesh.positions.size());
    mesh.positions.push_back(Vertex(x, -half, -half));
    mesh.positions.push_back(Vertex(x, half, -half));
    mesh.positions.push_back(Vertex(x, 0, half));
    mesh.triangles.push_back({base, base + 1, base + 2});
  };
  add(-1024, 1024);
  add(1024, 1024);
  const double p_x = 512.000035;
  const double near_x = 511;                          // 1.000035 from the point
  const double far_x = p_x + (p_x - near_x) + 1e-9;  // 1e-9 farther on the other side
  add(near_x, 0.1);
  add(far_x, 0.1);
  const Vertex p(p_x, 0, 0);
  ASSERT_GT(static_cast<double>(static_cast<float>(p_x)), p_x + 2e-5);  // rounded away from x = 511
  const TriangleDistance distance(mesh, every_triangle(mesh));
  EXPECT_EQ(distance.squared_distance(p), scan(mesh, p));
  EXPECT_EQ(distance.squared_distance(p), (p_x - near_x) * (p_x - near_x));
  EXPECT_TRUE(distance.within(p, (p_x - near_x) * (p_x - near_x) * (1 + 1e-12)));
}

TEST(TriangleDistance, NoTrianglesIsInfinitelyFar) {
  const TriangleMesh cube = testing::unit_cube();
  const TriangleDistance none(cube, {});
  EXPECT_EQ(none.squared_distance(Vertex(0.5, 0.5, 0.5)), std::numeric_limits<double>::infinity());
  EXPECT_FALSE(none.within(Vertex(0.5, 0.5, 0.5), 1e9));
  const TriangleDistance top(cube, {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11});
  EXPECT_NEAR(top.squared_distance(Vertex(0.5, 0.5, 0.25)), 0.0625, 1e-15);
}

}  // namespace
}  // namespace visproxy
