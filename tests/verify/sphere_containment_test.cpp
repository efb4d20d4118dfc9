#include "visproxy/verify/sphere_containment.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Simple_cartesian.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "visproxy/core/errors.h"
#include "visproxy/core/random.h"
#include "visproxy/mesh/read_mesh.h"
#include "test_meshes.h"
#include "visproxy/verify/containment.h"

namespace visproxy {
namespace {

double up(double x, int ulps = 1) {
  for (int i = 0; i < ulps; ++i) x = std::nextafter(x, std::numeric_limits<double>::infinity());
  return x;
}
double down(double x, int ulps = 1) {
  for (int i = 0; i < ulps; ++i) x = std::nextafter(x, 0.0);
  return x;
}

bool inside(const TriangleMesh& mesh, const Sphere& sphere) {
  const Sphere one[1] = {sphere};
  return check_spheres_inside(mesh, one).contained();
}

TEST(CheckSpheresInside, CubeTangentSpheresPassAndOneUlpMoreFails) {
  const TriangleMesh cube = testing::unit_cube();
  EXPECT_TRUE(inside(cube, {{0.5, 0.5, 0.5}, 0.5}));  // touches all six faces
  EXPECT_FALSE(inside(cube, {{0.5, 0.5, 0.5}, up(0.5)}));
  EXPECT_TRUE(inside(cube, {{0.1, 0.5, 0.5}, 0.1}));  // distance to x = 0 is the double 0.1 itself
  EXPECT_FALSE(inside(cube, {{0.1, 0.5, 0.5}, up(0.1)}));
  EXPECT_TRUE(inside(cube, {{0.5, 0.5, 0.5}, 0.0}));  // a point strictly inside
  EXPECT_TRUE(inside(cube, {{0.3, 0.6, 0.7}, 0.25}));
}

TEST(CheckSpheresInside, CentreOutsideOnTheSurfaceOrNotFiniteFails) {
  const TriangleMesh cube = testing::unit_cube();
  EXPECT_FALSE(inside(cube, {{1.5, 0.5, 0.5}, 0.1}));  // wholly outside
  EXPECT_FALSE(inside(cube, {{1.0, 0.5, 0.5}, 0.0}));  // on a face: not strictly inside
  EXPECT_FALSE(inside(cube, {{0.5, 0.5, 0.5}, -0.1}));
  EXPECT_FALSE(inside(cube, {{0.5, 0.5, 0.5}, std::numeric_limits<double>::quiet_NaN()}));
  EXPECT_FALSE(inside(cube, {{std::numeric_limits<double>::infinity(), 0.5, 0.5}, 0.1}));
}

// The binding face is slanted (x + y + z = 1 of the unit tetrahedron), so the exact
// distance is irrational and the double radius closest to it may be a hair too large or
// small: the verdict must match exact rational arithmetic for every nearby radius.
TEST(CheckSpheresInside, DecidesExactlyAtTheThresholdOfASlantedFace) {
  using Exact = CGAL::Exact_predicates_exact_constructions_kernel;
  const TriangleMesh tetrahedron = testing::tetrahedron();
  const double c = 0.3;
  const Exact::FT one_minus = Exact::FT(1) - Exact::FT(c) * 3;
  const Exact::FT squared_distance = one_minus * one_minus / 3;  // < c^2, so this face binds
  const double rounded = std::sqrt(CGAL::to_double(squared_distance));
  int passed = 0, failed = 0;
  for (int step = -3; step <= 3; ++step) {
    const double radius = step < 0 ? down(rounded, -step) : up(rounded, step);
    const bool exact = Exact::FT(radius) * Exact::FT(radius) <= squared_distance;
    EXPECT_EQ(inside(tetrahedron, {{c, c, c}, radius}), exact) << "step " << step;
    (exact ? passed : failed) += 1;
  }
  EXPECT_GT(passed, 0);
  EXPECT_GT(failed, 0);
}

TEST(CheckSpheresInside, CountsFirstFailureAndMargin) {
  const TriangleMesh cube = testing::unit_cube();
  const std::vector<Sphere> spheres = {
      {{0.5, 0.5, 0.5}, 0.25}, {{0.5, 0.5, 0.5}, 0.75}, {{0.2, 0.2, 0.2}, 0.1}, {{2, 2, 2}, 0.1}};
  const SphereContainment result = check_spheres_inside(cube, spheres);
  EXPECT_EQ(result.spheres_checked, 4u);
  EXPECT_EQ(result.spheres_outside, 2u);
  ASSERT_TRUE(result.first_outside.has_value());
  EXPECT_EQ(*result.first_outside, 1u);
  EXPECT_FALSE(result.contained());
  // The outside centre (2, 2, 2) is sqrt(3) from the corner: margin -sqrt(3) - 0.1.
  EXPECT_NEAR(result.min_margin_world, -std::sqrt(3.0) - 0.1, 1e-12);

  const std::vector<Sphere> good = {spheres[0], spheres[2]};
  const SphereContainment ok = check_spheres_inside(cube, good);
  EXPECT_TRUE(ok.contained());
  EXPECT_FALSE(ok.first_outside.has_value());
  EXPECT_NEAR(ok.min_margin_world, 0.1, 1e-12);  // (0.2 - 0.1) for the second sphere
  EXPECT_EQ(check_spheres_inside(cube, {}).spheres_checked, 0u);
}

TEST(CheckSpheresInside, OpenOrEmptyMeshIsRejected) {
  TriangleMesh open = testing::unit_cube();
  open.triangles.pop_back();
  const Sphere sphere{{0.5, 0.5, 0.5}, 0.1};
  EXPECT_THROW(check_spheres_inside(open, {&sphere, 1}), InvalidInputError);
  TriangleMesh flipped = testing::unit_cube();
  std::swap(flipped.triangles[0][0], flipped.triangles[0][1]);  // one triangle against its neighbours
  EXPECT_THROW(check_spheres_inside(flipped, {&sphere, 1}), InvalidInputError);
  EXPECT_THROW(check_spheres_inside(TriangleMesh{}, {&sphere, 1}), InvalidInputError);
}

// A ball that holds whole triangles without touching any: radius 0.9 about the cube's
// centre holds the whole cube (its corners are 0.87 away), and its sphere meets no
// triangle. Candidates found by the sphere alone would miss every one of them.
TEST(CheckSpheresInside, BallHoldingWholeTrianglesFails) {
  const TriangleMesh cube = testing::unit_cube();
  EXPECT_FALSE(inside(cube, {{0.5, 0.5, 0.5}, 0.9}));
  EXPECT_FALSE(inside(cube, {{0.5, 0.5, 0.5}, 0.6}));  // pokes through every face
  // A cavity: a small inverted tetrahedron (a second component) inside the cube. A ball
  // whose centre is in the solid and that swallows the cavity holds points of winding
  // number 0, though its sphere meets no triangle; one beside the cavity is fine.
  TriangleMesh hollow = testing::unit_cube();
  TriangleMesh cavity = testing::tetrahedron();
  for (Vertex& p : cavity.positions) p = 0.06 * p + Vertex(0.5, 0.5, 0.5);
  for (Triangle& t : cavity.triangles) std::swap(t[1], t[2]);
  append_mesh(hollow, cavity);
  const std::vector<Vertex> centre = {{0.42, 0.42, 0.42}};
  ASSERT_EQ(locate_points(hollow, centre)[0], PointLocation::inside);
  EXPECT_FALSE(inside(hollow, {centre[0], 0.3}));
  EXPECT_TRUE(inside(hollow, {{0.2, 0.2, 0.2}, 0.15}));
  EXPECT_TRUE(inside(cube, {centre[0], 0.3}));
}

// Closed but self-intersecting: two overlapping cubes as one mesh. The solid is where the
// winding number is not zero (1 in each cube, 2 in the overlap): balls inside it pass, a
// ball through an inner surface fails (conservative: it crosses a triangle).
TEST(CheckSpheresInside, SelfIntersectingClosedMeshByWindingNumber) {
  TriangleMesh two = testing::unit_cube();
  TriangleMesh shifted = testing::unit_cube();
  for (Vertex& p : shifted.positions) p += Vertex(0.5, 0.5, 0.5);
  append_mesh(two, shifted);
  EXPECT_TRUE(inside(two, {{0.75, 0.75, 0.75}, 0.2}));  // in the overlap
  EXPECT_TRUE(inside(two, {{1.25, 1.25, 1.25}, 0.2}));  // in the second cube only
  EXPECT_FALSE(inside(two, {{0.75, 0.75, 0.75}, 0.3}));  // crosses inner faces
  EXPECT_FALSE(inside(two, {{1.7, 0.3, 0.3}, 0.1}));     // outside both
  // Degenerate triangles (zero area) bound nothing: a sliver through the ball does not fail it.
  TriangleMesh with_sliver = testing::unit_cube();
  with_sliver.positions.push_back({0.5, 0.5, 0.5});
  with_sliver.triangles.push_back({8, 8, 8});
  EXPECT_TRUE(inside(with_sliver, {{0.5, 0.5, 0.5}, 0.4}));
}

// On a real mesh: balls at random inside points with radius just below / above the
// closest distance (CGAL's AABB tree, independent of the check's own distance filter).
TEST(CheckSpheresInside, KnotBallsBelowAndAboveTheClosestDistance) {
  using Kernel = CGAL::Simple_cartesian<double>;
  using Triangles = std::vector<Kernel::Triangle_3>;
  using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, CGAL::AABB_triangle_primitive<Kernel, Triangles::const_iterator>>>;
  const TriangleMesh knot = read_mesh(testing::cgal_mesh("knot1.off"));
  Triangles triangles;
  for (const Triangle& t : knot.triangles) {
    auto p = [&](VertexIndex v) { return Kernel::Point_3(knot.positions[v].x(), knot.positions[v].y(), knot.positions[v].z()); };
    triangles.emplace_back(p(t[0]), p(t[1]), p(t[2]));
  }
  Tree tree(triangles.begin(), triangles.end());
  tree.accelerate_distance_queries();

  const BoundingBox box = bounding_box(knot);
  Random random(5);
  std::vector<Vertex> points;
  for (int i = 0; i < 3000; ++i)
    points.push_back(box.min + Vertex(random.uniform(), random.uniform(), random.uniform()).cwiseProduct(box.max - box.min));
  const std::vector<PointLocation> locations = locate_points(knot, points);
  std::vector<Sphere> smaller, larger;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (locations[i] != PointLocation::inside) continue;
    const double distance = std::sqrt(tree.squared_distance(Kernel::Point_3(points[i].x(), points[i].y(), points[i].z())));
    smaller.push_back({points[i], distance * (1 - 1e-9)});
    larger.push_back({points[i], distance * (1 + 1e-9)});
  }
  ASSERT_GT(smaller.size(), 20u);
  const SphereContainment below = check_spheres_inside(knot, smaller);
  EXPECT_TRUE(below.contained()) << below.spheres_outside;
  EXPECT_GE(below.min_margin_world, 0.0);
  const SphereContainment above = check_spheres_inside(knot, larger);
  EXPECT_EQ(above.spheres_outside, larger.size());
  EXPECT_LT(above.min_margin_world, 0.0);
}

}  // namespace
}  // namespace visproxy
