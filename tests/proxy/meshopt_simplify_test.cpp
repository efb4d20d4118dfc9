// simplify_meshopt (meshopt:N): budget, clean output over input vertices, and meshes far
// from the origin, soups and tiny budgets, the ways single precision and topology break it.

#include "visproxy/proxy/meshopt_simplify.h"

#include <gtest/gtest.h>

#include <set>
#include <string>
#include <tuple>

#include "visproxy/core/errors.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/proxy/proxy_spec.h"
#include "visproxy/proxy/quadric_simplify.h"
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

std::set<std::tuple<double, double, double>> coordinates(const TriangleMesh& mesh) {
  std::set<std::tuple<double, double, double>> points;
  for (const Vertex& p : mesh.positions) points.emplace(p.x(), p.y(), p.z());
  return points;
}

double relative_hausdorff(const TriangleMesh& input, const TriangleMesh& proxy) {
  return sampled_hausdorff_distance(input, proxy).hausdorff_world() / bounding_box(input).diagonal();
}

class MeshoptSimplifyRealMeshes : public ::testing::TestWithParam<Budget> {};

// Every output vertex is an input vertex, bit for bit; the budget is met, the mesh clean.
TEST_P(MeshoptSimplifyRealMeshes, StaysWithinBudgetOverInputVertices) {
  const TriangleMesh input = read_mesh(testing::cgal_mesh(GetParam().file));
  const MeshoptSimplifyResult result = simplify_meshopt(input, {.max_triangles = GetParam().max_triangles});
  EXPECT_TRUE(result.reached_target);
  EXPECT_LE(result.mesh.triangles.size(), GetParam().max_triangles);
  EXPECT_GT(result.mesh.triangles.size(), 0u);
  EXPECT_GE(result.error_world, 0.0);
  testing::expect_clean_mesh(result.mesh);
  const auto input_points = coordinates(input);
  for (const Vertex& p : result.mesh.positions)
    EXPECT_TRUE(input_points.count({p.x(), p.y(), p.z()})) << "vertex " << p.transpose() << " is no input vertex";
}

// Watertight, with holes (elephant), non-manifold (pig), open borders (dragon), a knot; and
// budgets the topology-keeping pass cannot reach alone.
INSTANTIATE_TEST_SUITE_P(LibCgalDemo, MeshoptSimplifyRealMeshes,
                         ::testing::Values(Budget{"bunny00.off", 512}, Budget{"armadillo.off", 512},
                                           Budget{"ChineseDragon-10kv.off", 512}, Budget{"elephant-with-holes.off", 512},
                                           Budget{"pig.stl", 512}, Budget{"knot1.off", 512}, Budget{"bunny00.off", 20}),
                         [](const ::testing::TestParamInfo<Budget>& param_info) {
                           return testing::test_name_from(std::string(param_info.param.file) + "_" +
                                                          std::to_string(param_info.param.max_triangles));
                         });

// meshoptimizer decides in single precision. A bunny 10^5 diagonals from the origin
// (float spacing there is ~4 % of the bunny) must decimate as well as at the origin, which
// it does only if the coordinates it sees are relative to the mesh.
TEST(MeshoptSimplify, FarFromTheOriginDecimatesAsAtIt) {
  const TriangleMesh input = read_mesh(testing::cgal_mesh("bunny00.off"));
  const double diagonal = bounding_box(input).diagonal();
  TriangleMesh far = input;
  for (Vertex& p : far.positions) p += Vertex(1e5, -2e5, 3e5) * diagonal;
  const MeshoptSimplifyResult near_result = simplify_meshopt(input, {.max_triangles = 512});
  const MeshoptSimplifyResult far_result = simplify_meshopt(far, {.max_triangles = 512});
  // Rounding differs in the last bits of a few coordinates, so the collapses may differ by
  // a few; the result may not.
  EXPECT_LE(far_result.mesh.triangles.size(), 512u);
  EXPECT_GE(far_result.mesh.triangles.size(), 0.99 * double(near_result.mesh.triangles.size()));
  EXPECT_FALSE(far_result.sloppy_pass);
  const double near_error = relative_hausdorff(input, near_result.mesh);
  const double far_error = relative_hausdorff(far, far_result.mesh);
  EXPECT_LT(near_error, 0.03);
  EXPECT_LT(far_error, 1.25 * near_error) << "at the origin " << near_error;
}

// Its error stays within reach of quadric:N's on the same budget (meshoptimizer's
// simplifier is the fast one; quadric:N is the accurate one).
TEST(MeshoptSimplify, BunnyTo512IsCloseToTheInput) {
  const TriangleMesh input = read_mesh(testing::cgal_mesh("bunny00.off"));
  const MeshoptSimplifyResult result = simplify_meshopt(input, {.max_triangles = 512});
  const double error = relative_hausdorff(input, result.mesh);
  const double quadric = relative_hausdorff(input, simplify_quadric(input, {.max_triangles = 512}).mesh);
  EXPECT_GT(result.mesh.triangles.size(), 400u);
  EXPECT_LT(error, 2.5 * quadric) << "quadric:512 " << quadric;
  EXPECT_GT(result.error_world, 0.0);
}

// Corners at equal coordinates are one vertex: a soup (every triangle its own three
// vertices) decimates without the sloppy pass, to the welded mesh's error.
TEST(MeshoptSimplify, SoupDecimatesLikeTheWeldedMesh) {
  const TriangleMesh input = read_mesh(testing::cgal_mesh("knot1.off"));
  const MeshoptSimplifyResult welded = simplify_meshopt(input, {.max_triangles = 400});
  const MeshoptSimplifyResult soup = simplify_meshopt(testing::unwelded(input), {.max_triangles = 400});
  EXPECT_FALSE(soup.sloppy_pass);
  EXPECT_EQ(soup.mesh.triangles.size(), welded.mesh.triangles.size());
  EXPECT_LT(relative_hausdorff(input, soup.mesh), 1.1 * relative_hausdorff(input, welded.mesh));
}

TEST(MeshoptSimplify, IsDeterministic) {
  const TriangleMesh input = read_mesh(testing::cgal_mesh("armadillo.off"));
  const MeshoptSimplifyResult first = simplify_meshopt(input, {.max_triangles = 300});
  const MeshoptSimplifyResult second = simplify_meshopt(input, {.max_triangles = 300});
  EXPECT_EQ(first.mesh, second.mesh);
  EXPECT_EQ(first.error_world, second.error_world);
}

// Budgets below what keeping the topology allows: the sloppy pass takes over and says so,
// and leaves a mesh (it merges everything away at the budget itself).
TEST(MeshoptSimplify, TinyBudgetsTakeTheSloppyPass) {
  const TriangleMesh input = read_mesh(testing::cgal_mesh("elephant-with-holes.off"));
  const MeshoptSimplifyResult result = simplify_meshopt(input, {.max_triangles = 8});
  EXPECT_TRUE(result.sloppy_pass);
  EXPECT_GT(result.mesh.triangles.size(), 0u);
  EXPECT_EQ(result.reached_target, result.mesh.triangles.size() <= 8);
  EXPECT_LT(result.mesh.triangles.size(), 100u);
  testing::expect_clean_mesh(result.mesh);
  const MeshoptSimplifyResult cubes = simplify_meshopt(testing::two_far_apart_cubes(), {.max_triangles = 6});
  EXPECT_TRUE(cubes.reached_target);
  EXPECT_LE(cubes.mesh.triangles.size(), 6u);
  testing::expect_clean_mesh(cubes.mesh);
}

TEST(MeshoptSimplify, RefusesAZeroBudgetAndAnEmptyMesh) {
  EXPECT_THROW(simplify_meshopt(testing::unit_cube(), {.max_triangles = 0}), InvalidInputError);
  EXPECT_THROW(simplify_meshopt(TriangleMesh{}, {.max_triangles = 10}), InvalidInputError);
}

TEST(MeshoptSimplify, IsAGeneralMethodOfItsOwn) {
  const ProxySpec spec = parse_proxy_spec("meshopt:64");
  EXPECT_TRUE(spec.is("meshopt"));
  EXPECT_EQ(spec.kind(), ProxyKind::general);
  EXPECT_EQ(spec.count, 64u);
  EXPECT_EQ(spec.name(), "meshopt-64");
  EXPECT_THROW(parse_proxy_spec("meshopt"), Error);
  EXPECT_THROW(parse_proxy_spec("meshopt:0"), Error);
  EXPECT_THROW(parse_proxy_spec("meshopt:many"), Error);
}

}  // namespace
}  // namespace visproxy
