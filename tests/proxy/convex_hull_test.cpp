#include "visproxy/proxy/convex_hull.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
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
#include "visproxy/proxy/detail/hull_facets.h"
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

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;

// The extremes along hull_candidates()'s 26 directions: a cube's corners, its face centres
// pushed out to 1.25 and its edges' middles to 1.125 (dyadic, so that points on the faces
// of their hull can be exact).
std::vector<Vertex> cube_extremes() {
  std::vector<Vertex> extremes;
  for (int x = -1; x <= 1; ++x)
    for (int y = -1; y <= 1; ++y)
      for (int z = -1; z <= 1; ++z) {
        const int nonzero = (x != 0) + (y != 0) + (z != 0);
        if (nonzero > 0) extremes.push_back((nonzero == 1 ? 1.25 : nonzero == 2 ? 1.125 : 1.0) * Vertex(x, y, z));
      }
  return extremes;
}

// The outward triangles of CGAL's convex hull of `points`.
std::vector<std::array<Kernel::Point_3, 3>> hull_faces(const std::vector<Kernel::Point_3>& points) {
  CGAL::Surface_mesh<Kernel::Point_3> hull;
  CGAL::convex_hull_3(points.begin(), points.end(), hull);
  std::vector<std::array<Kernel::Point_3, 3>> faces;
  for (const auto face : hull.faces()) {
    std::array<Kernel::Point_3, 3> corners;
    int k = 0;
    for (const auto v : CGAL::vertices_around_face(hull.halfedge(face), hull)) corners[static_cast<std::size_t>(k++)] = hull.point(v);
    faces.push_back(corners);
  }
  return faces;
}

std::vector<Kernel::Point_3> cgal_points(const std::vector<Vertex>& points) {
  std::vector<Kernel::Point_3> out;
  for (const Vertex& p : points) out.emplace_back(p.x(), p.y(), p.z());
  return out;
}

// hull_faces() of `points`, with Vertex corners.
std::vector<std::array<Vertex, 3>> hull_faces(const std::vector<Vertex>& points) {
  std::vector<std::array<Vertex, 3>> faces;
  for (const auto& f : hull_faces(cgal_points(points))) {
    std::array<Vertex, 3> corners;
    for (std::size_t k = 0; k < 3; ++k) corners[k] = Vertex(f[k].x(), f[k].y(), f[k].z());
    faces.push_back(corners);
  }
  return faces;
}

// Over 200 000 points, the points certainly inside the hull of those extreme along 26
// directions are dropped first. Thousands of points lie on that inner hull's faces and
// near them on both sides, about the origin and 10^6 away (where rounding moves them by
// more than that): within 1e-16 to 1e-15, where the double-precision test errs and those
// outside are corners of the whole, or within 1e-13 to 1e-9. The corners must still be
// CGAL's, for every point.
TEST(ConvexHull, PointsAtTheInnerHullsFacesKeepTheCornersOfAll) {
  const std::vector<Vertex> extremes = cube_extremes();
  const std::vector<std::array<Vertex, 3>> faces = hull_faces(extremes);
  ASSERT_GE(faces.size(), 24u);
  for (const Vertex& offset : {Vertex(0, 0, 0), Vertex(1e6, -2e6, 3e6)})
  for (const std::vector<double>& distances : {std::vector<double>{0.0}, std::vector<double>{-1e-9, -1e-13, 0.0, 1e-13, 1e-9}}) {
    Random random(17);
    std::vector<Vertex> points;
    for (int i = 0; i < 210000; ++i)
      points.push_back(offset + Vertex(random.uniform() - 0.5, random.uniform() - 0.5, random.uniform() - 0.5));
    for (const Vertex& p : extremes) points.push_back(offset + p);
    std::size_t near = 0;
    for (int i = 0; i < 3000; ++i) {
      const std::array<Vertex, 3>& f = faces[static_cast<std::size_t>(random.uniform() * static_cast<double>(faces.size())) % faces.size()];
      // Weights in 1/1024ths: the point lies exactly on the face.
      double a = std::floor(1024 * random.uniform()) / 1024, b = std::floor(1024 * random.uniform()) / 1024;
      if (a + b > 1) a = 1 - a, b = 1 - b;
      const Vertex on = offset + f[0] + a * (f[1] - f[0]) + b * (f[2] - f[0]);
      const Vertex normal = (f[1] - f[0]).cross(f[2] - f[0]).normalized();
      for (const double d : distances) {
        if (d != 0) {
          points.push_back(on + d * normal), ++near;
          continue;
        }
        // On the face, and one unit in the last place off it on either side along each
        // axis the face's normal leans on: where the double-precision test errs.
        points.push_back(on), ++near;
        for (int axis = 0; axis < 3; ++axis) {
          if (std::abs(normal[axis]) < 0.1) continue;
          for (const double towards : {-1e300, 1e300}) {
            Vertex nudged = on;
            nudged[axis] = std::nextafter(on[axis], towards);
            points.push_back(nudged);
          }
        }
      }
    }
    const ConvexHullResult hull = build_convex_hull(fan_over(points));
    const std::vector<Kernel::Point_3> all = cgal_points(points);
    std::vector<Kernel::Point_3> extreme;
    CGAL::extreme_points_3(all, std::back_inserter(extreme));
    std::vector<std::array<double, 3>> expected, got;
    for (const Kernel::Point_3& p : extreme) expected.push_back({p.x(), p.y(), p.z()});
    for (const Vertex& p : hull.mesh.positions) got.push_back({p.x(), p.y(), p.z()});
    std::sort(expected.begin(), expected.end());
    std::sort(got.begin(), got.end());
    const std::string label = "offset " + std::to_string(offset.x()) + (distances.size() == 1 ? ", within an ulp" : ", within 1e-9");
    EXPECT_EQ(got, expected) << label;
    // The near points made corners of their own: the hull has more than the extremes.
    EXPECT_GT(got.size(), 2 * extremes.size()) << label << ": " << got.size() << " corners";
    EXPECT_EQ(near, 3000 * distances.size());
  }
}

// The claim itself: every point hull_candidates() drops is strictly inside the hull of
// those it keeps (exact orientations). Points on the faces of the extreme points' hull,
// exactly (dyadic weights of dyadic corners) or within rounding (any weights), lie on or
// outside the hull of the others. Coordinates of 10^-110 and 10^-300, where the planes'
// products underflow, must drop nothing.
TEST(ConvexHull, CandidatesDropOnlyPointsStrictlyInside) {
  const std::vector<Vertex> extremes = cube_extremes();
  const std::vector<std::array<Vertex, 3>> faces = hull_faces(extremes);
  for (const double scale : {1.0, 1e-110, 1e-300})
    for (const Vertex& offset : {Vertex(0, 0, 0), Vertex(1e6, -2e6, 3e6)}) {
      if (scale != 1.0 && offset.x() != 0) continue;
      Random random(23);
      std::vector<Vertex> points;
      for (const Vertex& p : extremes) points.push_back(offset + scale * p);
      for (int i = 0; i < 20000; ++i) {
        const std::array<Vertex, 3>& f = faces[static_cast<std::size_t>(random.uniform() * static_cast<double>(faces.size())) % faces.size()];
        double a = random.uniform(), b = random.uniform();
        if (i % 2 == 0) a = std::floor(1024 * a) / 1024, b = std::floor(1024 * b) / 1024;
        if (a + b > 1) a = 1 - a, b = 1 - b;
        points.push_back(offset + scale * f[0] + scale * a * (f[1] - f[0]) + scale * b * (f[2] - f[0]));
        points.push_back(offset + scale * Vertex(random.uniform() - 0.5, random.uniform() - 0.5, random.uniform() - 0.5));
      }
      const std::vector<std::size_t> kept = hull_detail::hull_candidates(points);
      std::vector<Vertex> kept_points;
      for (const std::size_t i : kept) kept_points.push_back(points[i]);
      const std::vector<std::array<Kernel::Point_3, 3>> planes = hull_faces(cgal_points(kept_points));
      std::size_t dropped = 0, outside = 0;
      for (std::size_t i = 0, next = 0; i < points.size(); ++i) {
        if (next < kept.size() && kept[next] == i) {
          ++next;
          continue;
        }
        ++dropped;
        const Kernel::Point_3 p(points[i].x(), points[i].y(), points[i].z());
        for (const auto& c : planes)
          if (CGAL::orientation(c[0], c[1], c[2], p) != CGAL::NEGATIVE) {  // outward faces: inside is negative
            ++outside;
            break;
          }
      }
      const std::string label = "scale " + std::to_string(scale) + " offset " + std::to_string(offset.x());
      EXPECT_EQ(outside, 0u) << label << ": " << dropped << " dropped";
      if (scale == 1.0) {
        EXPECT_GT(dropped, 19000u) << label;  // the cube's inside
      } else {
        EXPECT_EQ(dropped, 0u) << label;  // planes that underflow drop nothing
      }
    }
}

// The plane test the candidates are dropped by: "certainly below" must be strictly below
// by exact orientation, for points within rounding of fat and sliver triangles (any
// mantissa), about the origin and 10^6 away, at scales from 10^-90 to 10^90 (at 10^+-150
// the slack's products leave the normal numbers and there is no plane). It must also say
// so for most points clearly below, or it proves nothing.
TEST(ConvexHull, CertainPlaneCallsBelowOnlyWhatIsStrictlyBelow) {
  Random random(29);
  std::size_t near_below = 0, clearly_below = 0, clearly = 0, refused = 0, wrong = 0;
  std::string first_wrong;
  for (const double scale : {1.0, 1e-90, 1e90})
    for (const Vertex& offset : {Vertex(0, 0, 0), Vertex(1e6, -2e6, 3e6)})
      for (int triangle = 0; triangle < 200; ++triangle) {
        const Vertex a = offset * scale + scale * (Vertex(random.uniform(), random.uniform(), random.uniform()) - Vertex::Constant(0.5));
        const Vertex b = a + scale * (Vertex(random.uniform(), random.uniform(), random.uniform()) - Vertex::Constant(0.5));
        Vertex c = a + scale * (Vertex(random.uniform(), random.uniform(), random.uniform()) - Vertex::Constant(0.5));
        if (triangle % 2 == 1) c = a + 0.3 * (b - a) + 1e-9 * scale * Vertex(random.uniform(), random.uniform(), random.uniform());  // a sliver
        const std::optional<hull_detail::CertainPlane> plane = hull_detail::CertainPlane::through(a, b, c, 4 * scale);
        if (!plane) {
          ++refused;
          continue;
        }
        const Kernel::Point_3 pa(a.x(), a.y(), a.z()), pb(b.x(), b.y(), b.z()), pc(c.x(), c.y(), c.z());
        const Vertex unit = (plane->normal / plane->normal.cwiseAbs().maxCoeff()).normalized();  // no squares that overflow
        for (int i = 0; i < 50; ++i) {
          const double s = 2 * random.uniform() - 0.5, t = 2 * random.uniform() - 0.5;
          const Vertex on = a + s * (b - a) + t * (c - a);
          for (const double d : {0.0, -1e-17, -1e-16, -1e-15, -1e-3}) {
            const Vertex p = on + d * scale * unit;
            const bool below = plane->certainly_below(p);
            const CGAL::Orientation exact = CGAL::orientation(pa, pb, pc, Kernel::Point_3(p.x(), p.y(), p.z()));
            if (below && exact != CGAL::NEGATIVE && wrong++ == 0)
              first_wrong = "scale " + std::to_string(scale) + " offset " + std::to_string(offset.x()) + " triangle " +
                            std::to_string(triangle) + " distance " + std::to_string(d);
            if (d > -1e-3) near_below += below ? 1 : 0;
            if (d == -1e-3 && triangle % 2 == 0 && offset.x() == 0) ++clearly, clearly_below += below ? 1 : 0;
          }
        }
      }
  EXPECT_EQ(wrong, 0u) << "first: " << first_wrong;
  EXPECT_EQ(refused, 0u);
  for (const double scale : {1e-150, 1e150, 1e101})  // at 1e101 the products could reach 1e303
    EXPECT_FALSE(hull_detail::CertainPlane::through(Vertex::Zero(), scale * Vertex(1, 0, 0), scale * Vertex(0, 1, 0), scale));
  EXPECT_GT(clearly_below, clearly * 9 / 10);  // the slack is small beside real distances
  std::printf("points within 1e-15 of the plane called below: %zu; clearly below: %zu of %zu\n", near_below, clearly_below, clearly);
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
