// sampled_hausdorff_distance against distances known exactly.

#include "visproxy/proxy/surface_distance.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include <tbb/task_arena.h>

#include "visproxy/core/errors.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/proxy/convex_hull.h"
#include "proxy_test_support.h"
#include "test_meshes.h"

namespace visproxy {
namespace {

TriangleMesh transformed(TriangleMesh mesh, double scale, const Vertex& centre, const Vertex& offset) {
  for (Vertex& p : mesh.positions) p = centre + scale * (p - centre) + offset;
  return mesh;
}

// Every point of a triangle lies straight above the same point of its copy moved along the
// normal: both one-sided distances are the offset.
TEST(SurfaceDistance, ParallelOffsetTriangle) {
  const TriangleMesh a = testing::single_triangle();
  const TriangleMesh b = transformed(a, 1.0, Vertex::Zero(), Vertex(0, 0, 0.375));
  const SurfaceDistance distance = sampled_hausdorff_distance(a, b);
  EXPECT_NEAR(distance.a_to_b_world, 0.375, 1e-12);
  EXPECT_NEAR(distance.b_to_a_world, 0.375, 1e-12);
  EXPECT_NEAR(distance.hausdorff_world(), 0.375, 1e-12);
}

// Cube [0,1]^3 inside the cube [-1/2, 3/2]^3: from the inner surface the outer one is at
// most 1/2 away (every point of a face is 1/2 below the parallel face); from the outer
// surface, its corners are farthest, sqrt(3)/2 from the inner corners.
TEST(SurfaceDistance, CubeInsideADoubledCube) {
  const TriangleMesh inner = testing::unit_cube();
  const TriangleMesh outer = transformed(inner, 2.0, Vertex(0.5, 0.5, 0.5), Vertex::Zero());
  const SurfaceDistance distance = sampled_hausdorff_distance(inner, outer);
  EXPECT_NEAR(distance.a_to_b_world, 0.5, 1e-12);
  EXPECT_NEAR(distance.b_to_a_world, std::sqrt(3.0) / 2, 1e-12);
}

// Unit cube against itself moved by 1/4 along x: the face x = 0 is 1/4 from the moved cube,
// and nothing is farther, both ways.
TEST(SurfaceDistance, TranslatedCube) {
  const TriangleMesh a = testing::unit_cube();
  const TriangleMesh b = transformed(a, 1.0, Vertex::Zero(), Vertex(0.25, 0, 0));
  const SurfaceDistance distance = sampled_hausdorff_distance(a, b);
  EXPECT_NEAR(distance.a_to_b_world, 0.25, 1e-12);
  EXPECT_NEAR(distance.b_to_a_world, 0.25, 1e-12);
}

TEST(SurfaceDistance, SameSurfaceDifferentTriangulationIsZero) {
  const TriangleMesh grid = testing::flat_grid(4);
  TriangleMesh square;
  square.positions = {{0, 0, 0}, {4, 0, 0}, {4, 4, 0}, {0, 4, 0}};
  square.triangles = {{0, 1, 2}, {0, 2, 3}};
  const SurfaceDistance distance = sampled_hausdorff_distance(grid, square);
  EXPECT_NEAR(distance.hausdorff_world(), 0.0, 1e-12);
}

// Every point of a surface is within t of its copy moved by t, so the true distance is at
// most t, and a sampled one never exceeds the true one; where the surface faces the move,
// points are nearly t away.
TEST(SurfaceDistance, BunnyAgainstItsTranslateIsTheTranslation) {
  const TriangleMesh bunny = read_mesh(testing::cgal_mesh("bunny00.off"));
  const double diagonal = bounding_box(bunny).diagonal();
  const TriangleMesh moved = transformed(bunny, 1.0, Vertex::Zero(), Vertex(0.001 * diagonal, 0, 0));
  const SurfaceDistance distance = sampled_hausdorff_distance(bunny, moved, {.samples_per_mesh = 2000});
  EXPECT_LE(distance.hausdorff_world(), 0.001 * diagonal * (1 + 1e-9));
  EXPECT_GT(distance.hausdorff_world(), 0.0005 * diagonal);
}

TEST(SurfaceDistance, IsDeterministicForASeed) {
  const TriangleMesh a = read_mesh(testing::cgal_mesh("knot1.off"));
  const TriangleMesh b = testing::unit_cube();
  const SurfaceDistance first = sampled_hausdorff_distance(a, b, {.samples_per_mesh = 500, .seed = 7});
  const SurfaceDistance second = sampled_hausdorff_distance(a, b, {.samples_per_mesh = 500, .seed = 7});
  EXPECT_EQ(first.a_to_b_world, second.a_to_b_world);
  EXPECT_EQ(first.b_to_a_world, second.b_to_a_world);
}

// Degenerate triangles are skipped, their vertices still count.
TEST(SurfaceDistance, DegenerateTrianglesAreNotMeasuredTo) {
  TriangleMesh a = testing::single_triangle();
  a.positions.emplace_back(3, 0, 0);
  a.triangles.push_back({0, 1, 3});  // collinear: adds the sample point (3, 0, 0) only
  const SurfaceDistance distance = sampled_hausdorff_distance(a, testing::single_triangle());
  EXPECT_NEAR(distance.a_to_b_world, 2.0, 1e-12);
  EXPECT_NEAR(distance.b_to_a_world, 0.0, 1e-12);
}

// Pruning skips the exact distance of points a nearer triangle rules out: the result must
// be that of measuring every point, bit for bit, on one thread or many. The pairs include
// two copies of one surface far from the origin, where every distance is rounding noise
// and a margin too small for it would let the order of the threads decide the maximum.
TEST(SurfaceDistance, PruningGivesTheDistanceOfMeasuringEveryPoint) {
  const TriangleMesh bunny = read_mesh(testing::cgal_mesh("bunny00.off"));
  const TriangleMesh knot = read_mesh(testing::cgal_mesh("knot1.off"));
  const Vertex far(3.0e5, -1.0e5, 7.0e4);
  struct Pair {
    const char* name;
    TriangleMesh a, b;
  };
  const std::vector<Pair> pairs = {
      {"bunny, its hull", bunny, build_convex_hull(bunny).mesh},
      {"bunny, its copy far from the origin", transformed(bunny, 1.0, Vertex::Zero(), far),
       transformed(bunny, 1.0, Vertex::Zero(), far)},
      {"bunny, shrunk far from the origin", transformed(bunny, 1.0, Vertex::Zero(), far),
       transformed(bunny, 0.97, Vertex(0, 0.1, 0), far)},
      {"knot, a cube", knot, testing::unit_cube()},
  };
  for (const Pair& pair : pairs) {
    SCOPED_TRACE(pair.name);
    const SurfaceDistanceOptions every{.samples_per_mesh = 5000, .seed = 3, .prune = false};
    const SurfaceDistanceOptions pruned{.samples_per_mesh = 5000, .seed = 3, .prune = true};
    const SurfaceDistance reference = sampled_hausdorff_distance(pair.a, pair.b, every);
    for (const int threads : {1, 2, 5}) {
      SCOPED_TRACE(threads);
      tbb::task_arena arena(threads);
      const SurfaceDistance distance = arena.execute([&] { return sampled_hausdorff_distance(pair.a, pair.b, pruned); });
      EXPECT_EQ(distance.a_to_b_world, reference.a_to_b_world);
      EXPECT_EQ(distance.b_to_a_world, reference.b_to_a_world);
    }
  }
}

// distance_to: the exact distance to the nearest triangle, far from the origin too; a
// triangle with collinear corners (left out of the tree) still counts, through its sides.
TEST(SurfaceDistance, DistanceToAPointCountsEveryTriangle) {
  const Vertex far(2.0e6, -3.0e5, 1.0e5);
  TriangleMesh mesh = transformed(testing::unit_cube(), 1.0, Vertex::Zero(), far);
  const auto base = static_cast<VertexIndex>(mesh.positions.size());
  mesh.positions.push_back(far + Vertex(5, 0, 0));
  mesh.positions.push_back(far + Vertex(6, 0, 0));
  mesh.positions.push_back(far + Vertex(8, 0, 0));
  mesh.triangles.push_back({base, base + 1, base + 2});
  const MeasuredSurface surface(mesh);
  EXPECT_NEAR(surface.distance_to(far + Vertex(0.5, 0.5, 3)), 2.0, 1e-9);    // above the top face
  EXPECT_NEAR(surface.distance_to(far + Vertex(0.5, 0.5, 0.25)), 0.25, 1e-9);  // inside, nearest the bottom
  EXPECT_NEAR(surface.distance_to(far + Vertex(7, 0.75, 0)), 0.75, 1e-9);      // beside the collinear triangle
  EXPECT_NEAR(surface.distance_to(far + Vertex(9, 0, 0)), 1.0, 1e-9);          // past its far corner
}

TEST(SurfaceDistance, RejectsMeshesWithoutArea) {
  EXPECT_THROW(sampled_hausdorff_distance(TriangleMesh{}, testing::unit_cube()), InvalidInputError);
  TriangleMesh flat;
  flat.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  flat.triangles = {{0, 1, 2}};
  EXPECT_THROW(sampled_hausdorff_distance(testing::unit_cube(), flat), InvalidInputError);
}

}  // namespace
}  // namespace visproxy
