// cluster_vertices: displacement bound, clean output and grid behaviour.

#include "visproxy/proxy/vertex_clustering.h"

#include <gtest/gtest.h>

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

double largest_extent(const TriangleMesh& mesh) {
  const BoundingBox box = bounding_box(mesh);
  return (box.max - box.min).maxCoeff();
}

// Every output vertex is a cell's representative, inside the cell of the input vertices it
// replaces: so some input vertex lies within one cell diagonal of it (brute force).
void expect_output_vertices_near_input(const TriangleMesh& input, const VertexClusteringResult& result) {
  const double cell_diagonal = std::sqrt(3.0) * result.cell_size_world;
  for (const Vertex& q : result.mesh.positions) {
    double nearest = std::numeric_limits<double>::infinity();
    for (const Vertex& p : input.positions) nearest = std::min(nearest, (p - q).norm());
    EXPECT_LE(nearest, cell_diagonal * (1 + 1e-12));
  }
}

class VertexClusteringRealMeshes : public ::testing::TestWithParam<const char*> {};

TEST_P(VertexClusteringRealMeshes, MovesVerticesAtMostOneCellDiagonal) {
  const TriangleMesh input = read_mesh(testing::cgal_mesh(GetParam()));
  const VertexClusteringResult result = cluster_vertices(input, {.cell_size_relative = 0.03});
  EXPECT_DOUBLE_EQ(result.cell_size_world, 0.03 * largest_extent(input));
  EXPECT_GT(result.max_vertex_displacement_world, 0.0);
  EXPECT_LE(result.max_vertex_displacement_world, std::sqrt(3.0) * result.cell_size_world * (1 + 1e-12));
  EXPECT_FALSE(result.mesh.triangles.empty());
  EXPECT_LT(result.mesh.triangles.size(), input.triangles.size());
  testing::expect_clean_mesh(result.mesh);
  // No two output vertices at one point.
  std::set<std::array<double, 3>> points;
  for (const Vertex& p : result.mesh.positions) EXPECT_TRUE(points.insert({p.x(), p.y(), p.z()}).second);
}

INSTANTIATE_TEST_SUITE_P(LibCgalDemo, VertexClusteringRealMeshes,
                         ::testing::Values("bunny00.off", "armadillo.off", "ChineseDragon-10kv.off",
                                           "elephant-with-holes.off", "pig.stl", "knot1.off"),
                         [](const ::testing::TestParamInfo<const char*>& param_info) { return testing::test_name_from(param_info.param); });

TEST(VertexClustering, OutputVerticesLieNearTheInput) {
  const TriangleMesh input = read_mesh(testing::cgal_mesh("knot1.off"));
  expect_output_vertices_near_input(input, cluster_vertices(input, {.cell_size_relative = 0.05}));
}

// Not a guarantee of the method (thin parts can fold), but what it does on the bunny at the
// paper's 3 %: measured 0.0095 of the diagonal, against a cell diagonal of 0.031.
TEST(VertexClustering, BunnyIsWithinOneCellDiagonal) {
  const TriangleMesh input = read_mesh(testing::cgal_mesh("bunny00.off"));
  const VertexClusteringResult result = cluster_vertices(input, {});
  EXPECT_LT(sampled_hausdorff_distance(input, result.mesh).hausdorff_world(), std::sqrt(3.0) * result.cell_size_world);
}

TEST(VertexClustering, IsDeterministic) {
  const TriangleMesh input = read_mesh(testing::cgal_mesh("armadillo.off"));
  const VertexClusteringResult first = cluster_vertices(input, {.cell_size_relative = 0.02});
  const VertexClusteringResult second = cluster_vertices(input, {.cell_size_relative = 0.02});
  EXPECT_EQ(first.mesh, second.mesh);
  EXPECT_EQ(first.max_vertex_displacement_world, second.max_vertex_displacement_world);
}

// Clusters are made of positions, so a soup with duplicated vertices gives the same result.
TEST(VertexClustering, SoupClustersLikeTheWeldedMesh) {
  const TriangleMesh input = read_mesh(testing::cgal_mesh("knot1.off"));
  EXPECT_EQ(cluster_vertices(testing::unwelded(input), {}).mesh, cluster_vertices(input, {}).mesh);
}

TEST(VertexClustering, SingleTriangleSurvivesSmallCells) {
  const TriangleMesh triangle = testing::single_triangle();
  const VertexClusteringResult result = cluster_vertices(triangle, {.cell_size_relative = 0.1});
  ASSERT_EQ(result.mesh.triangles.size(), 1u);
  for (int c = 0; c < 3; ++c)
    EXPECT_LE((result.mesh.positions[result.mesh.triangles[0][c]] - triangle.positions[triangle.triangles[0][c]]).norm(),
              std::sqrt(3.0) * result.cell_size_world);
}

TEST(VertexClustering, FlatGridStaysInItsPlane) {
  const VertexClusteringResult result = cluster_vertices(testing::flat_grid(30), {.cell_size_relative = 0.1});
  EXPECT_FALSE(result.mesh.triangles.empty());
  testing::expect_clean_mesh(result.mesh);
  for (const Vertex& p : result.mesh.positions) EXPECT_EQ(p.z(), 0.0);
}

TEST(VertexClustering, PartsSmallerThanACellVanish) {
  const TriangleMesh cubes = testing::two_far_apart_cubes();
  EXPECT_TRUE(cluster_vertices(cubes, {.cell_size_relative = 0.03}).mesh.triangles.empty());
  const VertexClusteringResult fine = cluster_vertices(cubes, {.cell_size_relative = 1e-4});
  EXPECT_EQ(fine.mesh.triangles.size(), 24u);
  testing::expect_clean_mesh(fine.mesh);
}

TEST(VertexClustering, OneCellForEverythingGivesAnEmptyMesh) {
  const VertexClusteringResult result = cluster_vertices(testing::unit_cube(), {.cell_size_relative = 2.0});
  EXPECT_TRUE(result.mesh.triangles.empty());
  EXPECT_TRUE(result.mesh.positions.empty());
  EXPECT_LE(result.max_vertex_displacement_world, std::sqrt(3.0) * result.cell_size_world);
}

TEST(VertexClustering, RejectsBadCellSizesAndInput) {
  const TriangleMesh cube = testing::unit_cube();
  for (const double bad : {0.0, -0.5, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(), 1e-12})
    EXPECT_THROW(cluster_vertices(cube, {.cell_size_relative = bad}), InvalidInputError) << bad;
  EXPECT_THROW(cluster_vertices(TriangleMesh{}, {}), InvalidInputError);
  TriangleMesh out_of_range = testing::single_triangle();
  out_of_range.triangles.push_back({0, 1, 9});
  EXPECT_THROW(cluster_vertices(out_of_range, {}), InvalidInputError);
  TriangleMesh not_finite = testing::single_triangle();
  not_finite.positions[0].y() = std::numeric_limits<double>::infinity();
  EXPECT_THROW(cluster_vertices(not_finite, {}), InvalidInputError);
}

}  // namespace
}  // namespace visproxy
