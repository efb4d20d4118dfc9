#include "visproxy/proxy/alpha_wrap.h"

#include <gtest/gtest.h>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>

#include <tbb/task_arena.h>

#include <cmath>
#include <limits>

#include "visproxy/core/errors.h"
#include "visproxy/mesh/read_mesh.h"
#include "proxy/awkward_meshes.h"
#include "proxy/outside_proxy_checks.h"
#include "test_meshes.h"
#include "test_support.h"

namespace visproxy {
namespace {

using testing::expect_conservative_outside_proxy;

// The independent check itself must catch proxies that are not conservative.
TEST(OutsideProxyCheck, CatchesProxiesThatAreNotConservative) {
  const TriangleMesh cube = testing::unit_cube();
  const testing::OutsideProxyFindings itself = testing::check_outside_proxy(cube, cube);
  EXPECT_EQ(itself.input_triangles_touching, cube.triangles.size());
  EXPECT_EQ(itself.input_vertices_not_inside, 8u);

  TriangleMesh shrunk = cube;
  for (Vertex& p : shrunk.positions) p = Vertex::Constant(0.5) + 0.9 * (p - Vertex::Constant(0.5));
  const testing::OutsideProxyFindings inner = testing::check_outside_proxy(cube, shrunk);
  EXPECT_EQ(inner.input_triangles_touching, 0u);
  EXPECT_EQ(inner.input_vertices_not_inside, 8u);

  TriangleMesh inverted = cube;
  for (Triangle& t : inverted.triangles) std::swap(t[1], t[2]);
  EXPECT_LT(testing::check_outside_proxy(cube, inverted).signed_volume, 0.0);
}

TEST(AlphaWrap, ParametersAreRelativeToTheDiagonal) {
  const TriangleMesh cube = testing::unit_cube();
  const AlphaWrapResult wrap = build_alpha_wrap(cube, {});
  EXPECT_DOUBLE_EQ(wrap.alpha_world, std::sqrt(3.0) / 20);
  EXPECT_DOUBLE_EQ(wrap.offset_world, std::sqrt(3.0) / 600);
  expect_conservative_outside_proxy(cube, wrap.mesh);
}

// CGAL puts the wrap's vertices on the offset surface: each is about offset_world from the input.
TEST(AlphaWrap, VerticesLieAtTheOffsetFromTheInput) {
  const TriangleMesh tetrahedron = testing::tetrahedron();
  const AlphaWrapResult wrap = build_alpha_wrap(tetrahedron, {.alpha_relative = 0.1, .offset_relative = 0.02});
  using Kernel = testing::CheckKernel;
  std::vector<Kernel::Triangle_3> triangles;
  for (const Triangle& t : tetrahedron.triangles) {
    const auto point = [&](VertexIndex v) {
      const Vertex& p = tetrahedron.positions[v];
      return Kernel::Point_3(p.x(), p.y(), p.z());
    };
    triangles.emplace_back(point(t[0]), point(t[1]), point(t[2]));
  }
  using Primitive = CGAL::AABB_triangle_primitive<Kernel, std::vector<Kernel::Triangle_3>::const_iterator>;
  CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>> tree(triangles.begin(), triangles.end());
  for (const Vertex& p : wrap.mesh.positions) {
    const double distance = std::sqrt(tree.squared_distance(Kernel::Point_3(p.x(), p.y(), p.z())));
    EXPECT_NEAR(distance, wrap.offset_world, 0.01 * wrap.offset_world);
  }
  expect_conservative_outside_proxy(tetrahedron, wrap.mesh);
}

TEST(AlphaWrap, SingleTriangle) {
  const TriangleMesh triangle = testing::single_triangle();
  expect_conservative_outside_proxy(triangle, build_alpha_wrap(triangle, {}).mesh);
}

TEST(AlphaWrap, FlatMesh) {
  const TriangleMesh flat = testing::flat_grid(8);
  expect_conservative_outside_proxy(flat, build_alpha_wrap(flat, {}).mesh);
}

TEST(AlphaWrap, TwoFarApartComponentsGetOneWrapEach) {
  const TriangleMesh cubes = testing::two_far_cubes();
  const AlphaWrapResult wrap = build_alpha_wrap(cubes, {});
  expect_conservative_outside_proxy(cubes, wrap.mesh);
  EXPECT_EQ(analyze_topology(wrap.mesh).components, 2u);
}

TEST(AlphaWrap, DuplicatedVertices) {
  const TriangleMesh soup = testing::unwelded(testing::unit_cube());
  const AlphaWrapResult wrap = build_alpha_wrap(soup, {});
  expect_conservative_outside_proxy(soup, wrap.mesh);
  EXPECT_EQ(wrap.mesh, build_alpha_wrap(testing::unit_cube(), {}).mesh) << "the wrap sees geometry, not indices";
}

TEST(AlphaWrap, EnclosesTrianglesWithCollinearOrEqualCorners) {
  const TriangleMesh mesh = testing::cube_with_degenerate_triangles();
  expect_conservative_outside_proxy(mesh, build_alpha_wrap(mesh, {}).mesh);
}

class AlphaWrapOfRealMesh : public ::testing::TestWithParam<const char*> {};

// Coarse wraps keep the default test run fast; containment does not depend on alpha.
TEST_P(AlphaWrapOfRealMesh, IsAConservativeOutsideProxy) {
  const TriangleMesh mesh = read_mesh(testing::cgal_mesh(GetParam()));
  const AlphaWrapResult wrap = build_alpha_wrap(mesh, {.alpha_relative = 1.0 / 10, .offset_relative = 1.0 / 100});
  expect_conservative_outside_proxy(mesh, wrap.mesh);
}

INSTANTIATE_TEST_SUITE_P(LibCgalDemo, AlphaWrapOfRealMesh,
                         ::testing::Values("knot1.off", "ChineseDragon-10kv.off", "elephant-with-holes.off",
                                           "pig.stl"),
                         [](const ::testing::TestParamInfo<const char*>& param_info) { return testing::test_name_from(param_info.param); });

TEST(AlphaWrap, IsDeterministic) {
  const TriangleMesh mesh = read_mesh(testing::cgal_mesh("elephant-with-holes.off"));
  const AlphaWrapOptions options{.alpha_relative = 1.0 / 15, .offset_relative = 1.0 / 200};
  EXPECT_EQ(build_alpha_wrap(mesh, options).mesh, build_alpha_wrap(mesh, options).mesh);
}

// The input's BVH is built in parallel, so its shape may follow the threads; the answers
// the wrap asks of it (exact intersections, nearest points with a tie rule) must not.
TEST(AlphaWrap, DoesNotDependOnTheNumberOfThreads) {
  const TriangleMesh mesh = read_mesh(testing::cgal_mesh("knot1.off"));
  const AlphaWrapOptions options{.alpha_relative = 1.0 / 15, .offset_relative = 1.0 / 200};
  AlphaWrapResult one, three;
  tbb::task_arena(1).execute([&] { one = build_alpha_wrap(mesh, options); });
  tbb::task_arena(3).execute([&] { three = build_alpha_wrap(mesh, options); });
  EXPECT_EQ(one.mesh, three.mesh);
}

// 10^6 from the origin the input's coordinates need double precision: the BVH's boxes,
// held in single precision about the input's centre, must still hold every triangle.
TEST(AlphaWrap, FarFromTheOriginIsConservative) {
  TriangleMesh mesh = read_mesh(testing::cgal_mesh("knot1.off"));
  for (Vertex& p : mesh.positions) p += Vertex(1e6, -2e6, 5e5);
  expect_conservative_outside_proxy(mesh, build_alpha_wrap(mesh, {.alpha_relative = 1.0 / 10, .offset_relative = 1.0 / 100}).mesh);
}

TEST(AlphaWrap, RejectsOptionsThatAreNotPositiveFiniteNumbers) {
  const TriangleMesh cube = testing::unit_cube();
  for (const double bad : {0.0, -0.05, std::numeric_limits<double>::quiet_NaN(),
                           std::numeric_limits<double>::infinity()}) {
    EXPECT_THROW(build_alpha_wrap(cube, {.alpha_relative = bad}), InvalidInputError) << bad;
    EXPECT_THROW(build_alpha_wrap(cube, {.offset_relative = bad}), InvalidInputError) << bad;
  }
}

TEST(AlphaWrap, RejectsMeshesWithoutExtent) {
  EXPECT_THROW(build_alpha_wrap(TriangleMesh{}, {}), InvalidInputError);
  TriangleMesh point;
  point.positions = {{1, 2, 3}};
  point.triangles = {{0, 0, 0}};
  EXPECT_THROW(build_alpha_wrap(point, {}), InvalidInputError);
  TriangleMesh out_of_range = testing::tetrahedron();
  out_of_range.triangles.push_back({0, 1, 7});
  EXPECT_THROW(build_alpha_wrap(out_of_range, {}), InvalidInputError);
  TriangleMesh not_finite = testing::tetrahedron();
  not_finite.positions[2].y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(build_alpha_wrap(not_finite, {}), InvalidInputError);
}

}  // namespace
}  // namespace visproxy
