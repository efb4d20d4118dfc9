// simplify_quadric: budget, clean output and error on real and awkward meshes.

#include "visproxy/proxy/quadric_simplify.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <limits>
#include <string>

#include "visproxy/core/errors.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/proxy/surface_distance.h"
#include "proxy_test_support.h"
#include "test_meshes.h"
#include "test_support.h"

namespace visproxy {
namespace {

struct Budget {
  const char* file;
  std::size_t max_triangles;
};

void PrintTo(const Budget& budget, std::ostream* out) { *out << budget.file << " to " << budget.max_triangles; }

class QuadricSimplifyRealMeshes : public ::testing::TestWithParam<Budget> {};

TEST_P(QuadricSimplifyRealMeshes, StaysWithinBudgetAndClean) {
  const TriangleMesh input = read_mesh(testing::cgal_mesh(GetParam().file));
  const QuadricSimplifyResult result = simplify_quadric(input, {.max_triangles = GetParam().max_triangles});
  EXPECT_LE(result.mesh.triangles.size(), GetParam().max_triangles);
  EXPECT_GT(result.mesh.triangles.size(), GetParam().max_triangles / 2);
  EXPECT_GT(result.collapses, 0u);
  EXPECT_TRUE(std::isfinite(result.max_quadric_error_relative));
  EXPECT_GE(result.max_quadric_error_relative, 0.0);
  testing::expect_clean_mesh(result.mesh);
}

// Watertight, with holes (elephant), non-manifold (pig), open borders (dragon), a knot.
INSTANTIATE_TEST_SUITE_P(LibCgalDemo, QuadricSimplifyRealMeshes,
                         ::testing::Values(Budget{"bunny00.off", 512}, Budget{"armadillo.off", 512},
                                           Budget{"ChineseDragon-10kv.off", 512}, Budget{"elephant-with-holes.off", 512},
                                           Budget{"pig.stl", 512}, Budget{"knot1.off", 512}, Budget{"bunny00.off", 20},
                                           Budget{"elephant-with-holes.off", 8}),
                         [](const ::testing::TestParamInfo<Budget>& param_info) {
                           return testing::test_name_from(std::string(param_info.param.file) + "_" +
                                                          std::to_string(param_info.param.max_triangles));
                         });

// The bound is the measured error (0.0100 of the diagonal with the default sampling) with
// margin; meshoptimizer's meshopt_simplify reaches 0.0174 on the same input and budget.
TEST(QuadricSimplify, BunnyTo512IsCloseToTheInput) {
  const TriangleMesh input = read_mesh(testing::cgal_mesh("bunny00.off"));
  const QuadricSimplifyResult result = simplify_quadric(input, {.max_triangles = 512});
  const double diagonal = bounding_box(input).diagonal();
  const SurfaceDistance distance = sampled_hausdorff_distance(input, result.mesh);
  EXPECT_LT(distance.hausdorff_world() / diagonal, 0.013);
  EXPECT_GT(result.max_quadric_error_relative, 0.0);
  EXPECT_LT(result.max_quadric_error_relative, distance.hausdorff_world() / diagonal);
}

// Holes keep their rims thanks to the border quadrics: measured 0.033 of the diagonal
// (meshopt_simplify: 0.057, stopping at 515 triangles).
TEST(QuadricSimplify, ElephantWithHolesKeepsItsShape) {
  const TriangleMesh input = read_mesh(testing::cgal_mesh("elephant-with-holes.off"));
  const QuadricSimplifyResult result = simplify_quadric(input, {.max_triangles = 512});
  const double diagonal = bounding_box(input).diagonal();
  EXPECT_LT(sampled_hausdorff_distance(input, result.mesh).hausdorff_world() / diagonal, 0.045);
}

TEST(QuadricSimplify, IsDeterministic) {
  const TriangleMesh input = read_mesh(testing::cgal_mesh("armadillo.off"));
  const QuadricSimplifyResult first = simplify_quadric(input, {.max_triangles = 300});
  const QuadricSimplifyResult second = simplify_quadric(input, {.max_triangles = 300});
  EXPECT_EQ(first.mesh, second.mesh);
  EXPECT_EQ(first.max_quadric_error_relative, second.max_quadric_error_relative);
  EXPECT_EQ(first.collapses, second.collapses);
}

// Edges are rated in parallel; the result must not depend on how many threads rate them.
TEST(QuadricSimplify, IsTheSameOnOneThreadAsOnAll) {
  const TriangleMesh input = read_mesh(testing::cgal_mesh("bunny00.off"));
  const QuadricSimplifyResult all = simplify_quadric(input, {.max_triangles = 512});
  QuadricSimplifyResult one;
  {
    tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    one = simplify_quadric(input, {.max_triangles = 512});
  }
  EXPECT_EQ(all.mesh, one.mesh);
  EXPECT_EQ(all.max_quadric_error_relative, one.max_quadric_error_relative);
  EXPECT_EQ(all.collapses, one.collapses);
}

// Vertices with equal coordinates are one vertex: a soup simplifies exactly like the
// welded mesh.
TEST(QuadricSimplify, SoupSimplifiesLikeTheWeldedMesh) {
  const TriangleMesh input = read_mesh(testing::cgal_mesh("knot1.off"));
  const QuadricSimplifyResult welded = simplify_quadric(input, {.max_triangles = 400});
  const QuadricSimplifyResult soup = simplify_quadric(testing::unwelded(input), {.max_triangles = 400});
  EXPECT_EQ(soup.mesh, welded.mesh);
}

TEST(QuadricSimplify, MeshWithinBudgetComesBackUnchanged) {
  const TriangleMesh cube = testing::unit_cube();
  const QuadricSimplifyResult result = simplify_quadric(cube, {.max_triangles = 12});
  EXPECT_EQ(result.collapses, 0u);
  EXPECT_EQ(result.max_quadric_error_relative, 0.0);
  EXPECT_EQ(testing::triangle_shapes(result.mesh), testing::triangle_shapes(cube));
}

TEST(QuadricSimplify, SingleTriangle) {
  const TriangleMesh triangle = testing::single_triangle();
  const QuadricSimplifyResult result = simplify_quadric(triangle, {.max_triangles = 1});
  EXPECT_EQ(result.mesh, triangle);
}

// A flat grid stays exactly in its plane and within its outline (up to the rounding of
// mapping moved vertices back from the unit frame).
TEST(QuadricSimplify, FlatGridStaysFlat) {
  const TriangleMesh grid = testing::flat_grid(20);
  const QuadricSimplifyResult result = simplify_quadric(grid, {.max_triangles = 10});
  EXPECT_LE(result.mesh.triangles.size(), 10u);
  EXPECT_GE(result.mesh.triangles.size(), 2u);
  testing::expect_clean_mesh(result.mesh);
  for (const Vertex& p : result.mesh.positions) {
    EXPECT_EQ(p.z(), 0.0);
    EXPECT_GE(p.x(), -1e-12);
    EXPECT_LE(p.x(), 20 + 1e-12);
    EXPECT_GE(p.y(), -1e-12);
    EXPECT_LE(p.y(), 20 + 1e-12);
  }
}

// Budgets below what the rules allow (a cube cannot lose a triangle without a flip or a
// fold at 2 per component) are still met.
TEST(QuadricSimplify, TinyBudgetsAreMetOnFarApartComponents) {
  const TriangleMesh cubes = testing::two_far_apart_cubes();
  for (const std::size_t budget : {12u, 4u, 2u, 1u}) {
    const QuadricSimplifyResult result = simplify_quadric(cubes, {.max_triangles = budget});
    EXPECT_LE(result.mesh.triangles.size(), budget);
    EXPECT_GE(result.mesh.triangles.size(), 1u) << budget;
    testing::expect_clean_mesh(result.mesh);
  }
}

TEST(QuadricSimplify, TetrahedronToOneTriangle) {
  const QuadricSimplifyResult result = simplify_quadric(testing::tetrahedron(), {.max_triangles = 1});
  EXPECT_EQ(result.mesh.triangles.size(), 1u);
  testing::expect_clean_mesh(result.mesh);
}

TEST(QuadricSimplify, OnlyDegenerateTrianglesGiveAnEmptyResult) {
  TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {1, 0, 0}};
  mesh.triangles = {{0, 1, 1}, {0, 1, 2}};  // a repeated index; then equal coordinates
  const QuadricSimplifyResult result = simplify_quadric(mesh, {.max_triangles = 4});
  EXPECT_TRUE(result.mesh.triangles.empty());
  EXPECT_TRUE(result.mesh.positions.empty());
}

// Collinear input triangles (zero area, distinct corners) never reach the output.
TEST(QuadricSimplify, CollinearInputTrianglesAreDropped) {
  TriangleMesh mesh = testing::single_triangle();
  mesh.positions.emplace_back(0.5, 0, 0);  // on the edge 0-1
  mesh.triangles.push_back({0, 3, 1});
  const QuadricSimplifyResult result = simplify_quadric(mesh, {.max_triangles = 2});
  EXPECT_EQ(result.mesh.triangles.size(), 1u);
  testing::expect_clean_mesh(result.mesh);
}

TEST(QuadricSimplify, RejectsBadInput) {
  EXPECT_THROW(simplify_quadric(testing::unit_cube(), {.max_triangles = 0}), InvalidInputError);
  EXPECT_THROW(simplify_quadric(TriangleMesh{}, {.max_triangles = 10}), InvalidInputError);
  TriangleMesh out_of_range = testing::single_triangle();
  out_of_range.triangles.push_back({0, 1, 7});
  EXPECT_THROW(simplify_quadric(out_of_range, {}), InvalidInputError);
  TriangleMesh not_finite = testing::single_triangle();
  not_finite.positions[2].x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(simplify_quadric(not_finite, {}), InvalidInputError);
  // A non-finite vertex that no triangle uses is ignored.
  TriangleMesh unused_nan = testing::single_triangle();
  unused_nan.positions.emplace_back(std::numeric_limits<double>::infinity(), 0, 0);
  EXPECT_EQ(simplify_quadric(unused_nan, {.max_triangles = 1}).mesh, testing::single_triangle());
}

}  // namespace
}  // namespace visproxy
