#include "proxy/convex_hull.h"

#include <gtest/gtest.h>

#include "core/errors.h"
#include "mesh/read_mesh.h"
#include "proxy/hull_test_support.h"
#include "test_meshes.h"

namespace visproxy {
namespace {

TEST(ConvexHull, Cube) {
  const ConvexHullResult hull = build_convex_hull(testing::unit_cube());
  EXPECT_EQ(hull.faces, 6u);
  EXPECT_EQ(hull.volume, 1.0);
  EXPECT_EQ(hull.mesh.positions.size(), 8u);
  EXPECT_TRUE(testing::is_closed_polytope_surface(hull.mesh));
  EXPECT_TRUE(testing::contains_every_vertex(hull.mesh, testing::unit_cube()));
}

}  // namespace
}  // namespace visproxy
