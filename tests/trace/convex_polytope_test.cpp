#include "visproxy/trace/convex_polytope.h"

#include <gtest/gtest.h>

#include <numbers>

#include "visproxy/core/random.h"
#include "visproxy/mesh/sphere_set.h"
#include "test_support.h"

namespace visproxy {
namespace {

TriangleMesh unit_cube() {
  TriangleMesh mesh;
  for (int c = 0; c < 8; ++c) mesh.positions.emplace_back(c & 1 ? 1.0 : 0.0, c & 2 ? 1.0 : 0.0, c & 4 ? 1.0 : 0.0);
  mesh.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                    {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  return mesh;
}

TEST(ConvexPolytope, CubeHasSixPlanesAndAcceptsOnlyClosedConvexOutwardMeshes) {
  const auto cube = ConvexPolytope::from_mesh(unit_cube());
  ASSERT_TRUE(cube.has_value());
  EXPECT_EQ(cube->planes().size(), 6u);  // coplanar triangle pairs share a plane
  TriangleMesh inverted = unit_cube();
  for (Triangle& t : inverted.triangles) std::swap(t[1], t[2]);
  EXPECT_FALSE(ConvexPolytope::from_mesh(inverted).has_value());
  TriangleMesh open = unit_cube();
  open.triangles.pop_back();
  EXPECT_FALSE(ConvexPolytope::from_mesh(open).has_value());
  TriangleMesh dented = unit_cube();
  dented.positions[7] = {0.6, 0.6, 0.6};  // a corner pushed in: not convex
  EXPECT_FALSE(ConvexPolytope::from_mesh(dented).has_value());
  // A finely tessellated ball has more planes than allowed.
  EXPECT_FALSE(ConvexPolytope::from_mesh(sphere_set_mesh({{{0, 0, 0}, 1.0}}, 3)).has_value());
  EXPECT_TRUE(ConvexPolytope::from_mesh(sphere_set_mesh({{{0, 0, 0}, 1.0}}, 3), 4096).has_value());
}

// Random segments against a rotated, scaled, moved cube: the same answers as a slab test
// in the cube's own frame.
TEST(ConvexPolytope, TransformedSolidMatchesTheSlabTestInItsOwnFrame) {
  Eigen::Affine3d transform = Eigen::Affine3d::Identity();
  transform.translate(Vertex(0.3, -2, 1))
      .rotate(Eigen::AngleAxisd(0.7, Vertex(1, 2, 3).normalized()))
      .scale(Vertex(2, 0.5, 1.5));
  const ConvexPolytope solid = ConvexPolytope::from_mesh(unit_cube())->transformed(transform);
  const Eigen::Affine3d inverse = transform.inverse();
  auto in_unit_cube = [&](const Vertex& a, const Vertex& b) {
    return testing::segment_meets_box(Vertex(inverse * a), Vertex(inverse * b), Vertex(0, 0, 0), Vertex(1, 1, 1));
  };
  Random random(5);
  int met = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vertex a = transform * Vertex(3 * random.uniform() - 1, 3 * random.uniform() - 1, 3 * random.uniform() - 1);
    const Vertex b = transform * Vertex(3 * random.uniform() - 1, 3 * random.uniform() - 1, 3 * random.uniform() - 1);
    const bool expected = in_unit_cube(a, b);
    EXPECT_EQ(solid.meets_segment(a, b), expected) << a.transpose() << " -> " << b.transpose();
    met += expected ? 1 : 0;
  }
  EXPECT_GT(met, 2000);
  EXPECT_LT(met, 18000);
}

// Pushed out for rounding bounds: the grown solid holds points within the distance, and its
// inner distance from the centre grows by it.
TEST(ConvexPolytope, GrownSolidHoldsItsNeighbourhood) {
  const ConvexPolytope cube = *ConvexPolytope::from_mesh(unit_cube());
  const ConvexPolytope grown = cube.grown(0.1);
  EXPECT_FALSE(cube.meets_segment({1.05, 0.5, 0.5}, {1.08, 0.5, 0.5}));
  EXPECT_TRUE(grown.meets_segment({1.05, 0.5, 0.5}, {1.08, 0.5, 0.5}));
  EXPECT_FALSE(grown.meets_segment({1.11, 0.5, 0.5}, {1.2, 0.5, 0.5}));
  EXPECT_NEAR(cube.inner_distance({0.5, 0.5, 0.5}), 0.5, 1e-8);
  EXPECT_NEAR(grown.inner_distance({0.5, 0.5, 0.5}), 0.6, 1e-8);
  EXPECT_LT(cube.inner_distance({2, 0.5, 0.5}), 0.0);
}

// A cube with its top dented inwards is closed, manifold and oriented, but not convex at
// the dent's edges: rejected before any plane is collected.
TEST(ConvexPolytope, DentedCubeIsNotConvex) {
  TriangleMesh dented = unit_cube();
  const BoundingBox box = bounding_box(dented);
  ASSERT_EQ(box.max.z(), 1.0);
  // Split every top triangle at its centroid and push the new vertices down.
  const std::size_t count = dented.triangles.size();
  for (std::size_t t = 0; t < count; ++t) {
    const Triangle triangle = dented.triangles[t];
    bool top = true;
    for (const VertexIndex v : triangle) top = top && dented.positions[v].z() == 1.0;
    if (!top) continue;
    const auto centre = static_cast<VertexIndex>(dented.positions.size());
    dented.positions.push_back((dented.positions[triangle[0]] + dented.positions[triangle[1]] + dented.positions[triangle[2]]) / 3 -
                               Vertex(0, 0, 0.3));
    dented.triangles[t] = {triangle[0], triangle[1], centre};
    dented.triangles.push_back({triangle[1], triangle[2], centre});
    dented.triangles.push_back({triangle[2], triangle[0], centre});
  }
  EXPECT_FALSE(ConvexPolytope::from_mesh(dented, 64).has_value());
  EXPECT_FALSE(ConvexPolytope::from_mesh(dented, dented.triangles.size()).has_value());
}

}  // namespace
}  // namespace visproxy
