// displace_along_normals: bounded, seeded, translation-invariant bumps that make a flat
// subdivided face bumpy and keep the mesh closed.

#include "visproxy/mesh/displace.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "test_meshes.h"
#include "visproxy/mesh/mesh_topology.h"
#include "visproxy/mesh/subdivide.h"

namespace visproxy {
namespace {

TEST(Displace, MovesEveryVertexAlongItsNormalWithinTheAmplitude) {
  const TriangleMesh cube = subdivide_midpoint(testing::unit_cube(), 4);  // 3072 triangles
  const double edge = mean_edge_length(cube);
  const TriangleMesh bumpy = displace_along_normals(cube, {.amplitude_relative = 0.3, .seed = 5});
  ASSERT_EQ(bumpy.triangles, cube.triangles);
  EXPECT_TRUE(analyze_topology(bumpy).closed());
  double largest = 0;
  std::size_t moved = 0, off_axis = 0;
  for (std::size_t v = 0; v < cube.positions.size(); ++v) {
    const Vertex d = bumpy.positions[v] - cube.positions[v];
    largest = std::max(largest, d.norm());
    moved += d.norm() > 1e-3 * edge;
    // A vertex inside a face moves along the face normal only.
    const Vertex& p = cube.positions[v];
    const bool inside_face_z = p.z() == 0 && p.x() > 0 && p.x() < 1 && p.y() > 0 && p.y() < 1;
    if (inside_face_z) off_axis += std::abs(d.x()) + std::abs(d.y()) > 1e-15;
  }
  EXPECT_LE(largest, 0.3 * edge * (1 + 1e-12));
  EXPECT_GT(largest, 0.1 * edge);
  EXPECT_GT(moved, cube.positions.size() * 3 / 4);
  EXPECT_EQ(off_axis, 0u);
  // The face z = 0 is no longer flat.
  std::size_t bumped = 0;
  for (std::size_t v = 0; v < cube.positions.size(); ++v)
    if (cube.positions[v].z() == 0 && std::abs(bumpy.positions[v].z()) > 0.05 * edge) ++bumped;
  EXPECT_GT(bumped, 100u);
}

TEST(Displace, IsSeededAndTheSameForATranslatedMesh) {
  const TriangleMesh cube = subdivide_midpoint(testing::unit_cube(), 3);
  const TriangleMesh a = displace_along_normals(cube, {.seed = 1});
  EXPECT_EQ(a.positions, displace_along_normals(cube, {.seed = 1}).positions);
  EXPECT_NE(a.positions, displace_along_normals(cube, {.seed = 2}).positions);
  // Far from the origin the bumps are the same, relative to the coordinates' rounding.
  const Vertex offset(3e6, -1e6, 2e6);
  TriangleMesh far = cube;
  for (Vertex& p : far.positions) p += offset;
  const TriangleMesh b = displace_along_normals(far, {.seed = 1});
  for (std::size_t v = 0; v < cube.positions.size(); ++v)
    EXPECT_NEAR((b.positions[v] - offset - a.positions[v]).norm(), 0.0, 1e-8) << v;
}

TEST(Displace, AMeshWithoutTrianglesIsKept) {
  TriangleMesh points;
  points.positions = {{0, 0, 0}, {1, 0, 0}};
  EXPECT_EQ(displace_along_normals(points).positions, points.positions);
  EXPECT_EQ(mean_edge_length(points), 0.0);
}

}  // namespace
}  // namespace visproxy
