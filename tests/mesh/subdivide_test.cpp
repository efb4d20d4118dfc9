// subdivide_midpoint: counts, watertightness, orientation and shape.

#include "visproxy/mesh/subdivide.h"

#include <gtest/gtest.h>

#include "visproxy/core/errors.h"
#include "visproxy/mesh/mesh_topology.h"
#include "visproxy/mesh/read_mesh.h"
#include "test_meshes.h"

namespace visproxy {
namespace {

double area(const TriangleMesh& mesh) {
  double sum = 0;
  for (const Triangle& t : mesh.triangles)
    sum += (mesh.positions[t[1]] - mesh.positions[t[0]]).cross(mesh.positions[t[2]] - mesh.positions[t[0]]).norm() / 2;
  return sum;
}

TEST(SubdivideMidpoint, CubeCountsAndTopology) {
  const TriangleMesh cube = testing::unit_cube();
  const TriangleMesh once = subdivide_midpoint(cube, 1);
  EXPECT_EQ(once.triangles.size(), 48u);
  EXPECT_EQ(once.positions.size(), 8u + 18u);  // one vertex per edge
  const TriangleMesh twice = subdivide_midpoint(cube, 2);
  EXPECT_EQ(twice.triangles.size(), 192u);
  EXPECT_EQ(twice.positions.size(), 26u + 72u);
  const MeshTopology topology = analyze_topology(twice);
  EXPECT_TRUE(topology.closed());
  EXPECT_TRUE(topology.manifold());
  EXPECT_TRUE(topology.consistently_oriented());
  EXPECT_EQ(topology.euler_characteristic(twice.triangles.size()), 2);
  EXPECT_NEAR(area(twice), 6.0, 1e-12);
  // The old vertices keep their indices and coordinates.
  for (std::size_t v = 0; v < cube.positions.size(); ++v) EXPECT_EQ(twice.positions[v], cube.positions[v]);
}

TEST(SubdivideMidpoint, KeepsOrientation) {
  const TriangleMesh triangle = [] {
    TriangleMesh mesh;
    mesh.positions = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}};
    mesh.triangles = {{0, 1, 2}};
    return mesh;
  }();
  const TriangleMesh once = subdivide_midpoint(triangle, 1);
  ASSERT_EQ(once.triangles.size(), 4u);
  for (const Triangle& t : once.triangles) {
    const Vertex normal = (once.positions[t[1]] - once.positions[t[0]]).cross(once.positions[t[2]] - once.positions[t[0]]);
    EXPECT_GT(normal.z(), 0.0);
    EXPECT_NEAR(normal.z(), 1.0, 1e-15);  // four triangles of area 1/2
  }
  EXPECT_EQ(once.positions[3], Vertex(1, 0, 0));
}

TEST(SubdivideMidpoint, WatertightBunnyStaysWatertight) {
  const TriangleMesh bunny = read_mesh(testing::cgal_mesh("bunny00.off"));
  const TriangleMesh once = subdivide_midpoint(bunny, 1);
  EXPECT_EQ(once.triangles.size(), 4 * bunny.triangles.size());
  const MeshTopology before = analyze_topology(bunny);
  const MeshTopology after = analyze_topology(once);
  EXPECT_EQ(once.positions.size(), bunny.positions.size() + before.edges);
  EXPECT_TRUE(after.closed());
  EXPECT_TRUE(after.manifold());
  EXPECT_TRUE(after.consistently_oriented());
  EXPECT_EQ(after.euler_characteristic(once.triangles.size()), before.euler_characteristic(bunny.triangles.size()));
  EXPECT_NEAR(area(once), area(bunny), 1e-9 * area(bunny));
}

TEST(SubdivideMidpoint, LevelZeroIsACopyAndRepeatedIndicesGetNoMidpoint) {
  const TriangleMesh cube = testing::unit_cube();
  EXPECT_EQ(subdivide_midpoint(cube, 0), cube);
  TriangleMesh degenerate;
  degenerate.positions = {{0, 0, 0}, {1, 0, 0}};
  degenerate.triangles = {{0, 0, 1}};
  const TriangleMesh once = subdivide_midpoint(degenerate, 1);
  EXPECT_EQ(once.positions.size(), 3u);  // one midpoint, for the edge 0-1 only
  EXPECT_EQ(once.triangles.size(), 4u);
}

TEST(SubdivideMidpoint, RejectsOutOfRangeIndices) {
  TriangleMesh mesh = testing::tetrahedron();
  mesh.triangles.push_back({0, 1, 4});
  EXPECT_THROW(subdivide_midpoint(mesh, 1), InvalidInputError);
}

}  // namespace
}  // namespace visproxy
