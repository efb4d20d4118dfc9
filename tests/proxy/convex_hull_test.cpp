#include "visproxy/proxy/convex_hull.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/convex_hull_3.h>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <cmath>

#include <string>

#include "visproxy/core/errors.h"
#include "visproxy/core/random.h"
#include "visproxy/mesh/read_mesh.h"
#include "proxy/hull_test_support.h"
#include "test_meshes.h"
#include "test_support.h"

namespace visproxy {
namespace {

using testing::contains_every_vertex;
using testing::is_closed_polytope_surface;

// A mesh whose triangles are fans over the given points (enough to reference them all).
TriangleMesh fan_over(const std::vector<Vertex>& points) {
  TriangleMesh mesh;
  mesh.positions = points;
  for (VertexIndex i = 1; i + 1 < points.size(); ++i) mesh.triangles.push_back({0, i, i + 1});
  return mesh;
}

// The unit cube with every face split into a 3 x 3 grid of quads: points inside faces and
// on edges, all coplanar with the cube's faces.
TriangleMesh subdivided_cube() {
  std::vector<Vertex> points;
  for (int x = 0; x <= 3; ++x)
    for (int y = 0; y <= 3; ++y)
      for (int z = 0; z <= 3; ++z)
        if (x == 0 || x == 3 || y == 0 || y == 3 || z == 0 || z == 3) points.emplace_back(x / 3.0, y / 3.0, z / 3.0);
  return fan_over(points);
}

void expect_throws_saying(const TriangleMesh& mesh, const std::string& words) {
  try {
    build_convex_hull(mesh);
    ADD_FAILURE() << "no InvalidInputError";
  } catch (const InvalidInputError& error) {
    EXPECT_NE(std::string(error.what()).find(words), std::string::npos) << error.what();
  }
}

TEST(ConvexHull, CubeHasSixFacesAndVolumeOne) {
  const ConvexHullResult hull = build_convex_hull(testing::unit_cube());
  EXPECT_EQ(hull.faces, 6u);
  EXPECT_EQ(hull.volume, 1.0);
  EXPECT_EQ(hull.mesh.positions.size(), 8u);
  EXPECT_EQ(hull.mesh.triangles.size(), 12u);
  EXPECT_TRUE(is_closed_polytope_surface(hull.mesh));
  EXPECT_TRUE(contains_every_vertex(hull.mesh, testing::unit_cube()));
}

TEST(ConvexHull, TetrahedronHasFourFacesAndVolumeOneSixth) {
  const ConvexHullResult hull = build_convex_hull(testing::tetrahedron());
  EXPECT_EQ(hull.faces, 4u);
  EXPECT_EQ(hull.volume, 1.0 / 6.0);
  EXPECT_TRUE(is_closed_polytope_surface(hull.mesh));
}

TEST(ConvexHull, PointsOnFacesAndEdgesDoNotAddFaces) {
  const TriangleMesh cube = subdivided_cube();
  const ConvexHullResult hull = build_convex_hull(cube);
  EXPECT_EQ(hull.faces, 6u);
  EXPECT_DOUBLE_EQ(hull.volume, 1.0);
  EXPECT_TRUE(is_closed_polytope_surface(hull.mesh));
  EXPECT_TRUE(contains_every_vertex(hull.mesh, cube));
}

TEST(ConvexHull, DuplicatedAndUnreferencedVerticesAreHarmless) {
  // The cube as a triangle soup (every triangle its own three vertices) plus a far
  // vertex that no triangle uses.
  const TriangleMesh cube = testing::unit_cube();
  TriangleMesh soup;
  for (const Triangle& t : cube.triangles) {
    const auto base = static_cast<VertexIndex>(soup.positions.size());
    for (const VertexIndex v : t) soup.positions.push_back(cube.positions[v]);
    soup.triangles.push_back({base, base + 1, base + 2});
  }
  soup.positions.emplace_back(100.0, 100.0, 100.0);
  const ConvexHullResult hull = build_convex_hull(soup);
  EXPECT_EQ(hull.faces, 6u);
  EXPECT_EQ(hull.volume, 1.0);
  EXPECT_EQ(hull.mesh.positions.size(), 8u);
  EXPECT_TRUE(is_closed_polytope_surface(hull.mesh));
}

TEST(ConvexHull, SingleTriangleIsAClosedTwoSidedTriangle) {
  TriangleMesh triangle;
  triangle.positions = {{0.1, 0.2, 0.3}, {1.7, -0.4, 0.9}, {0.5, 2.5, -1.1}};
  triangle.triangles = {{0, 1, 2}};
  const ConvexHullResult hull = build_convex_hull(triangle);
  EXPECT_EQ(hull.faces, 2u);
  EXPECT_EQ(hull.volume, 0.0);
  EXPECT_EQ(hull.mesh.positions.size(), 3u);
  EXPECT_EQ(hull.mesh.triangles.size(), 2u);
  EXPECT_TRUE(is_closed_polytope_surface(hull.mesh));
  EXPECT_TRUE(contains_every_vertex(hull.mesh, triangle));
}

TEST(ConvexHull, FlatMeshIsItsConvexPolygonOnBothSides) {
  // A 5 x 5 grid in the tilted plane x + 2y - z = 0 (exact in double), corners at the four
  // grid corners; the inner points and the points on the sides are not corners.
  std::vector<Vertex> points;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j) points.emplace_back(i, j, i + 2 * j);
  const TriangleMesh flat = fan_over(points);
  const ConvexHullResult hull = build_convex_hull(flat);
  EXPECT_EQ(hull.faces, 2u);
  EXPECT_EQ(hull.volume, 0.0);
  EXPECT_EQ(hull.mesh.positions.size(), 4u);
  EXPECT_EQ(hull.mesh.triangles.size(), 4u);
  EXPECT_TRUE(is_closed_polytope_surface(hull.mesh));
  EXPECT_TRUE(contains_every_vertex(hull.mesh, flat));
}

TEST(ConvexHull, TwoFarApartComponents) {
  TriangleMesh two = testing::tetrahedron();
  const TriangleMesh far = testing::tetrahedron();
  for (const Vertex& p : far.positions) two.positions.push_back(p + Vertex(1000.0, 0.0, 0.0));
  for (const Triangle& t : far.triangles) two.triangles.push_back({t[0] + 4, t[1] + 4, t[2] + 4});
  const ConvexHullResult hull = build_convex_hull(two);
  EXPECT_TRUE(is_closed_polytope_surface(hull.mesh));
  EXPECT_TRUE(contains_every_vertex(hull.mesh, two));
  // (1, 0, 0) and (1000, 0, 0) lie on the edges from (0, 0, 0) to (1000, 0, 0) and from
  // (1, 0, 0) to (1001, 0, 0): not corners.
  EXPECT_EQ(hull.mesh.positions.size(), 6u);
  // The hull of a convex body and its translate by s is their Minkowski sum with the
  // segment [0, s]: volume 1/6 + 1000 * (area of the tetrahedron's shadow on x = 0, 1/2).
  EXPECT_NEAR(hull.volume, 500.0 + 1.0 / 6.0, 1e-9);
}

TEST(ConvexHull, NothingToHullIsAnError) {
  expect_throws_saying(TriangleMesh{}, "no triangles");
  TriangleMesh no_triangles;
  no_triangles.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  expect_throws_saying(no_triangles, "no triangles");
  TriangleMesh point;
  point.positions = {{1, 2, 3}, {1, 2, 3}};
  point.triangles = {{0, 1, 0}};
  expect_throws_saying(point, "one point");
  TriangleMesh collinear;
  collinear.positions = {{0, 0, 0}, {1, 1, 1}, {3, 3, 3}, {-2, -2, -2}};
  collinear.triangles = {{0, 1, 2}, {0, 2, 3}};
  expect_throws_saying(collinear, "one line");
  TriangleMesh dangling = testing::tetrahedron();
  dangling.triangles.push_back({0, 1, 4});
  expect_throws_saying(dangling, "does not have");
  TriangleMesh infinite = testing::tetrahedron();
  infinite.positions[2].y() = std::numeric_limits<double>::infinity();
  expect_throws_saying(infinite, "non-finite");
}

TEST(ConvexHull, EmptyRealMeshIsAnError) {
  // b9.ply has vertices and no faces.
  EXPECT_THROW(build_convex_hull(read_mesh(testing::cgal_mesh("b9.ply"))), InvalidInputError);
}

TEST(ConvexHull, IsDeterministic) {
  const TriangleMesh mesh = read_mesh(testing::cgal_mesh("knot1.off"));
  const ConvexHullResult first = build_convex_hull(mesh);
  const ConvexHullResult second = build_convex_hull(mesh);
  EXPECT_EQ(first.mesh, second.mesh);
  EXPECT_EQ(first.faces, second.faces);
  EXPECT_EQ(first.volume, second.volume);
}

// Over 200 000 points the corners are first found slice by slice in parallel. The hull
// must be that of all the points: the same corners as CGAL's hull of every point, each the
// first input vertex at its position (duplicates across slices included), whatever the
// number of threads. A cube's corners in the last slice only, duplicated in the first, and a
// dense ball of points with a flat slice of coplanar points among them.
TEST(ConvexHull, ManyPointsGiveTheHullOfAll) {
  Random random(3);
  std::vector<Vertex> points;
  for (int i = 0; i < 40000; ++i) points.push_back({random.uniform(), random.uniform(), 0.5});  // a flat slice
  for (int i = 0; i < 200000; ++i) {
    const Vertex d = random.unit_vector();
    points.push_back(0.49 * std::cbrt(random.uniform()) * d + Vertex::Constant(0.5));
  }
  const Vertex corner(1, 1, 1);
  points.insert(points.begin() + 5, corner);  // first slice: the duplicate that counts
  for (int c = 0; c < 8; ++c) points.push_back(Vertex(c & 1, (c >> 1) & 1, (c >> 2) & 1));
  const TriangleMesh mesh = fan_over(points);
  ConvexHullResult one, many;
  {
    tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    one = build_convex_hull(mesh);
  }
  many = build_convex_hull(mesh);
  EXPECT_EQ(one.mesh, many.mesh);
  EXPECT_EQ(many.mesh.positions.size(), 8u);
  EXPECT_EQ(many.faces, 6u);
  EXPECT_DOUBLE_EQ(many.volume, 1.0);
  EXPECT_TRUE(is_closed_polytope_surface(many.mesh));
  EXPECT_TRUE(contains_every_vertex(many.mesh, mesh));
  // Corners keep the input order: (1, 1, 1) first, from its early duplicate.
  EXPECT_EQ(many.mesh.positions.front(), corner);
  // A round point set: the corners are CGAL's hull's, for every point.
  std::vector<Vertex> ball;
  for (int i = 0; i < 210000; ++i) ball.push_back(random.unit_vector() * std::cbrt(random.uniform()));
  const ConvexHullResult round = build_convex_hull(fan_over(ball));
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  std::vector<Kernel::Point_3> all;
  for (const Vertex& p : ball) all.emplace_back(p.x(), p.y(), p.z());
  std::vector<Kernel::Point_3> extreme;
  CGAL::extreme_points_3(all, std::back_inserter(extreme));
  std::vector<std::array<double, 3>> expected, got;
  for (const Kernel::Point_3& p : extreme) expected.push_back({p.x(), p.y(), p.z()});
  for (const Vertex& p : round.mesh.positions) got.push_back({p.x(), p.y(), p.z()});
  std::sort(expected.begin(), expected.end());
  std::sort(got.begin(), got.end());
  EXPECT_EQ(got, expected);
  EXPECT_TRUE(contains_every_vertex(round.mesh, fan_over(ball)));
}

class ConvexHullOfRealMesh : public ::testing::TestWithParam<std::string> {};

TEST_P(ConvexHullOfRealMesh, ContainsEveryVertexAndIsAClosedConvexSurface) {
  const TriangleMesh mesh = read_mesh(testing::cgal_mesh(GetParam()));
  const ConvexHullResult hull = build_convex_hull(mesh);
  EXPECT_TRUE(is_closed_polytope_surface(hull.mesh));
  EXPECT_TRUE(contains_every_vertex(hull.mesh, mesh));
  // Convex: every hull corner is inside or on every hull triangle's plane.
  EXPECT_TRUE(contains_every_vertex(hull.mesh, hull.mesh));
  EXPECT_GT(hull.volume, 0.0);
  EXPECT_GE(hull.faces, 4u);
  EXPECT_LE(hull.faces, hull.mesh.triangles.size());
  std::printf("%-26s %6zu vertices -> hull %5zu corners, %5zu triangles, %5zu planar faces, volume %.6g\n",
              GetParam().c_str(), mesh.positions.size(), hull.mesh.positions.size(), hull.mesh.triangles.size(),
              hull.faces, hull.volume);
}

INSTANTIATE_TEST_SUITE_P(CgalDemo, ConvexHullOfRealMesh,
                         ::testing::Values("bunny00.off", "armadillo.off", "knot1.off", "knot2.off",
                                           "ChineseDragon-10kv.off", "elephant-with-holes.off", "sphere.ply",
                                           "pig.stl"),
                         [](const auto& test) { return testing::test_name_from(test.param); });

}  // namespace
}  // namespace visproxy
