#include "visproxy/proxy/inscribed_spheres.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "visproxy/core/errors.h"
#include "visproxy/mesh/read_mesh.h"
#include "proxy/awkward_meshes.h"
#include "test_meshes.h"
#include "test_support.h"
#include "visproxy/mesh/mesh_topology.h"
#include "visproxy/verify/containment.h"
#include "visproxy/verify/sphere_containment.h"

namespace visproxy {
namespace {

std::string error_of(const TriangleMesh& mesh, const InscribedSpheresOptions& options = {}) {
  try {
    build_inscribed_spheres(mesh, options);
  } catch (const InvalidInputError& error) {
    return error.problem();
  }
  return "";
}

TriangleMesh box(const Vertex& size) {
  TriangleMesh mesh = testing::unit_cube();
  for (Vertex& p : mesh.positions) p = p.cwiseProduct(size);
  return mesh;
}

class InscribedOnRealMesh : public ::testing::TestWithParam<const char*> {};

// Every sphere passes the independent exact check; the check fails when a sphere grows by
// a hair (1e-5 of the diagonal, ten times the margin) or its centre moves outside.
TEST_P(InscribedOnRealMesh, FortySpheresProvedInsideAndTheCheckCatchesTampering) {
  const TriangleMesh mesh = read_mesh(testing::cgal_mesh(GetParam()));
  const InscribedSpheres result = build_inscribed_spheres(mesh, {.count = 40});
  ASSERT_EQ(result.spheres.size(), 40u);
  const SphereContainment check = check_spheres_inside(mesh, result.spheres);
  EXPECT_TRUE(check.contained()) << check.spheres_outside << " outside, first " << check.first_outside.value_or(0);
  EXPECT_GE(check.min_margin_world, 0.0);
  EXPECT_EQ(result.min_margin_world, check.min_margin_world);
  EXPECT_GE(result.candidates, 40u);
  EXPECT_GT(result.covered_volume_fraction, 0.5);
  EXPECT_LE(result.covered_volume_lower, result.covered_volume_fraction);
  EXPECT_GE(result.covered_volume_upper, result.covered_volume_fraction);
  EXPECT_LT(result.covered_volume_upper, 1.0);

  const double diagonal = bounding_box(mesh).diagonal();
  for (const std::size_t i : {std::size_t{0}, std::size_t{17}, std::size_t{39}}) {
    std::vector<Sphere> grown = result.spheres;
    grown[i].radius += 1e-5 * diagonal;
    const SphereContainment bad = check_spheres_inside(mesh, grown);
    EXPECT_EQ(bad.spheres_outside, 1u);
    EXPECT_EQ(bad.first_outside, i);
    std::vector<Sphere> moved = result.spheres;
    moved[i].center = bounding_box(mesh).max + Vertex::Constant(0.01 * diagonal);
    EXPECT_EQ(check_spheres_inside(mesh, moved).first_outside, i);
  }
}

INSTANTIATE_TEST_SUITE_P(LibcgalDemo, InscribedOnRealMesh, ::testing::Values("knot1.off", "bunny00.off", "armadillo.off"),
                         [](const auto& test) { return testing::test_name_from(test.param); });

TEST(InscribedSpheres, SmallMeshesWorkAndTheBallInAnIcosphereFillsIt) {
  // The cube (12 triangles): the largest inscribed ball is the central one, radius 1/2.
  const InscribedSpheres cube = build_inscribed_spheres(testing::unit_cube(), {.count = 8});
  ASSERT_EQ(cube.spheres.size(), 8u);
  EXPECT_TRUE(check_spheres_inside(testing::unit_cube(), cube.spheres).contained());
  EXPECT_NEAR(cube.spheres[0].radius, 0.5, 0.02);
  // A 320-triangle icosphere of radius 1: one ball, radius the distance to its flat faces.
  const TriangleMesh ball = sphere_set_mesh({{{1, 2, 3}, 1.0}}, 2);
  const InscribedSpheres one = build_inscribed_spheres(ball, {.count = 1});
  ASSERT_EQ(one.spheres.size(), 1u);
  EXPECT_TRUE(check_spheres_inside(ball, one.spheres).contained());
  EXPECT_GT(one.spheres[0].radius, 0.97);
  EXPECT_GT(one.covered_volume_fraction, 0.9);
}

TEST(InscribedSpheres, ThinSlabAndTwoFarCubes) {
  const TriangleMesh slab = box({1, 1, 0.01});
  const InscribedSpheres thin = build_inscribed_spheres(slab, {.count = 20});
  ASSERT_EQ(thin.spheres.size(), 20u);
  EXPECT_TRUE(check_spheres_inside(slab, thin.spheres).contained());
  for (const Sphere& s : thin.spheres) EXPECT_LE(s.radius, 0.005);
  const TriangleMesh two = testing::two_far_cubes();
  const InscribedSpheres both = build_inscribed_spheres(two, {.count = 2});
  ASSERT_EQ(both.spheres.size(), 2u);
  EXPECT_NEAR(std::abs(both.spheres[0].center.x() - both.spheres[1].center.x()), 50, 0.1);  // one per cube
}

// Radii equal to the rounded distance to the surface are sometimes a hair too large: those
// spheres are shrunk by ulps until the exact check passes (on knot1, 5 of 10).
TEST(InscribedSpheres, ZeroMarginStillPassesTheExactCheck) {
  const TriangleMesh knot = read_mesh(testing::cgal_mesh("knot1.off"));
  const InscribedSpheres touching = build_inscribed_spheres(knot, {.count = 10, .margin_relative = 0});
  EXPECT_TRUE(check_spheres_inside(knot, touching.spheres).contained());
  EXPECT_GT(touching.spheres_shrunk, 0u);
  EXPECT_LT(touching.min_margin_world, 1e-12 * bounding_box(knot).diagonal());
  EXPECT_EQ(build_inscribed_spheres(knot, {.count = 10, .margin_relative = 0}).spheres, touching.spheres);
}

// Closed meshes that self-intersect (CGAL's camel: 20 pairs, cow: 101) bound a solid all
// the same: {winding number != 0}. Every sphere is proved inside it by that definition.
class InscribedInSelfIntersectingMesh : public ::testing::TestWithParam<const char*> {};

TEST_P(InscribedInSelfIntersectingMesh, FortySpheresProvedInsideByWindingNumber) {
  const TriangleMesh mesh = read_mesh(testing::cgal_mesh(GetParam()));
  ASSERT_TRUE(check_edge_balance(mesh).balanced());
  const InscribedSpheres result = build_inscribed_spheres(mesh, {.count = 40});
  ASSERT_EQ(result.spheres.size(), 40u);
  EXPECT_TRUE(check_spheres_inside(mesh, result.spheres).contained());
  // Every centre has a non-zero winding number, and no sphere crosses a triangle.
  std::vector<Vertex> centres;
  for (const Sphere& s : result.spheres) centres.push_back(s.center);
  for (const PointLocation location : locate_points(mesh, centres)) EXPECT_EQ(location, PointLocation::inside);
  EXPECT_GE(result.min_margin_world, 0.0);
  EXPECT_GT(result.covered_volume_fraction, 0.3);
}

INSTANTIATE_TEST_SUITE_P(LibcgalDemo, InscribedInSelfIntersectingMesh, ::testing::Values("camel.off", "cow.off"),
                         [](const auto& test) { return testing::test_name_from(test.param); });

TEST(InscribedSpheres, OverlappingClosedPartsAreOneSolid) {
  TriangleMesh overlapping = testing::unit_cube();
  append_mesh(overlapping, box({1.5, 0.5, 0.5}));
  const InscribedSpheres result = build_inscribed_spheres(overlapping, {.count = 4});
  ASSERT_EQ(result.spheres.size(), 4u);
  EXPECT_TRUE(check_spheres_inside(overlapping, result.spheres).contained());
  // The second box's faces pass through the cube: no ball crosses them (y, z = 0.5), so
  // the largest lies in the cube beside them, radius about 0.29, not the central 0.5.
  EXPECT_GT(result.spheres[0].radius, 0.25);
  EXPECT_LT(result.spheres[0].radius, 0.3);
}

TEST(InscribedSpheres, InputsWithoutAnInsideAreRejectedNamingTheDefect) {
  const std::string holes = error_of(read_mesh(testing::cgal_mesh("elephant-with-holes.off")));
  EXPECT_NE(holes.find("boundary edges"), std::string::npos) << holes;
  EXPECT_NE(holes.find("inside proxy"), std::string::npos) << holes;
  EXPECT_NE(holes.find("not closed"), std::string::npos) << holes;
  TriangleMesh flipped = testing::unit_cube();
  std::swap(flipped.triangles[3][0], flipped.triangles[3][1]);
  EXPECT_NE(error_of(flipped).find("inconsistent orientation"), std::string::npos);
  // Three triangles on one edge, two of them the same way: unbalanced though not a boundary.
  TriangleMesh fin = testing::unit_cube();
  fin.positions.push_back({0.5, 0.5, 2});
  fin.triangles.push_back({4, 5, 8});
  fin.triangles.push_back({5, 4, 8});
  fin.triangles.push_back({4, 5, 8});
  EXPECT_NE(error_of(fin).find("not closed"), std::string::npos) << error_of(fin);
  EXPECT_NE(error_of(testing::single_triangle()).find("boundary"), std::string::npos);
  EXPECT_NE(error_of(TriangleMesh{}).find("no triangles"), std::string::npos);
  EXPECT_NE(error_of(testing::unit_cube(), {.count = 0}).find("at least one"), std::string::npos);
  const std::string many = error_of(testing::unit_cube(), {.count = 1000, .surface_samples = 200});
  EXPECT_NE(many.find("ask for at most"), std::string::npos) << many;
}

}  // namespace
}  // namespace visproxy
