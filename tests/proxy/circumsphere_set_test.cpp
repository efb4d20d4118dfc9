#include "visproxy/proxy/circumsphere_set.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "visproxy/core/errors.h"
#include "visproxy/mesh/read_mesh.h"
#include "proxy/awkward_meshes.h"
#include "visproxy/proxy/detail/delaunay_cells.h"
#include "test_meshes.h"
#include "visproxy/verify/containment.h"

namespace visproxy {
namespace {

std::string error_of(const TriangleMesh& mesh, const CircumsphereOptions& options) {
  try {
    build_circumsphere_set(mesh, options);
  } catch (const InvalidInputError& error) {
    return error.problem();
  }
  return "";
}

TEST(CircumsphereSet, NormalsKeepTetrahedraWhoseCentresAreInsideTheKnot) {
  const TriangleMesh knot = read_mesh(testing::cgal_mesh("knot1.off"));
  const CircumsphereSet set = build_circumsphere_set(knot, {.samples = 3000});
  EXPECT_GT(set.spheres.size(), 5000u);
  EXPECT_LT(set.spheres.size(), set.tetrahedra);
  std::vector<Vertex> centers;
  for (const Sphere& s : set.spheres) {
    ASSERT_TRUE(s.center.allFinite());
    ASSERT_GT(s.radius, 0);
    centers.push_back(s.center);
  }
  std::size_t inside = 0;
  for (const PointLocation location : locate_points(knot, centers)) inside += location == PointLocation::inside;
  EXPECT_GT(static_cast<double>(inside), 0.99 * static_cast<double>(centers.size()));
  // Same seed, same set. An inside-out copy is flipped back (its samples differ, since
  // corners are listed in another order, so only the size is compared).
  EXPECT_EQ(build_circumsphere_set(knot, {.samples = 3000}).spheres, set.spheres);
  TriangleMesh inverted = knot;
  for (Triangle& t : inverted.triangles) std::swap(t[1], t[2]);
  EXPECT_NEAR(static_cast<double>(build_circumsphere_set(inverted, {.samples = 3000}).spheres.size()),
              static_cast<double>(set.spheres.size()), 0.02 * static_cast<double>(set.spheres.size()));
}

TEST(CircumsphereSet, TetgenFillsTheCubeWithItsCircumsphere) {
  const CircumsphereSet set =
      build_circumsphere_set(testing::unit_cube(), {.tetrahedra = InnerTetrahedra::tetgen});
  ASSERT_GE(set.spheres.size(), 5u);
  for (const Sphere& s : set.spheres) {
    EXPECT_NEAR(s.radius, std::sqrt(3.0) / 2, 1e-12);
    EXPECT_NEAR((s.center - Vertex(0.5, 0.5, 0.5)).norm(), 0, 1e-12);
  }
}

TEST(CircumsphereSet, TetgenOnTheKnotGivesOnlyInsideTetrahedra) {
  const TriangleMesh knot = read_mesh(testing::cgal_mesh("knot1.off"));
  const CircumsphereSet set = build_circumsphere_set(knot, {.tetrahedra = InnerTetrahedra::tetgen});
  EXPECT_EQ(set.spheres.size(), set.tetrahedra);
  EXPECT_GT(set.spheres.size(), knot.triangles.size());
}

TEST(SmallestEnclosingBall, CircumsphereWhenItsCentreIsInsideElseFewerSupportPoints) {
  // Regular tetrahedron: its circumsphere.
  const Vertex a(1, 1, 1), b(1, -1, -1), c(-1, 1, -1), d(-1, -1, 1);
  const Sphere regular = smallest_enclosing_ball(a, b, c, d);
  EXPECT_NEAR(regular.radius, std::sqrt(3.0), 1e-9);
  EXPECT_NEAR(regular.center.norm(), 0, 1e-12);
  // A flat tetrahedron (a right triangle and a point just above its inside): the
  // circumsphere is huge (radius about 240), the smallest ball is on the hypotenuse.
  const Vertex p(0, 0, 0), q(1, 0, 0), r(0, 1, 0), t(0.4, 0.4, 1e-3);
  EXPECT_GT(tetrahedron_circumsphere(p, q, r, t).radius, 10.0);
  const Sphere flat = smallest_enclosing_ball(p, q, r, t);
  EXPECT_NEAR(flat.radius, std::sqrt(0.5), 1e-3);
  for (const Vertex& corner : {p, q, r, t}) EXPECT_LE((corner - flat.center).norm(), flat.radius);
  // A needle: the ball on its longest edge.
  const Sphere needle = smallest_enclosing_ball({0, 0, 0}, {10, 0, 0}, {5, 0.1, 0}, {5, 0, 0.1});
  EXPECT_NEAR(needle.radius, 5, 1e-9);
}

TEST(CircumsphereSet, BadInputsFailClearly) {
  EXPECT_NE(error_of(testing::flat_grid(4), {}).find("flat"), std::string::npos);
  EXPECT_NE(error_of(testing::single_triangle(), {}).find("flat"), std::string::npos);
  EXPECT_NE(error_of(TriangleMesh{}, {}).find("no triangle"), std::string::npos);
  const TriangleMesh elephant = read_mesh(testing::cgal_mesh("elephant-with-holes.off"));
  const std::string holes = error_of(elephant, {.tetrahedra = InnerTetrahedra::tetgen});
  EXPECT_NE(holes.find("boundary edges"), std::string::npos) << holes;
  EXPECT_NE(holes.find("--tets normals"), std::string::npos) << holes;
  // The normal criterion works on any input, open ones included.
  EXPECT_GT(build_circumsphere_set(elephant, {.samples = 2000}).spheres.size(), 100u);
  const TriangleMesh pig = read_mesh(testing::cgal_mesh("pig.stl"));
  EXPECT_NE(error_of(pig, {.tetrahedra = InnerTetrahedra::tetgen}).find("non-manifold"), std::string::npos);
}

TEST(CircumsphereSet, TwoFarApartCubesBothGetSpheres) {
  const TriangleMesh two = testing::two_far_cubes();
  for (const InnerTetrahedra method : {InnerTetrahedra::normals, InnerTetrahedra::tetgen}) {
    const CircumsphereSet set = build_circumsphere_set(two, {.tetrahedra = method, .samples = 2000});
    std::size_t near = 0, far = 0;
    for (const Sphere& s : set.spheres) (s.center.x() < 25 ? near : far) += 1;
    EXPECT_GT(near, 0u) << name_of(method);
    EXPECT_GT(far, 0u) << name_of(method);
  }
}

}  // namespace
}  // namespace visproxy
