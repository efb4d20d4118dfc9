#include "proxy/bounded_hull.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>

#include "core/errors.h"
#include "mesh/read_mesh.h"
#include "proxy/convex_hull.h"
#include "proxy/hull_test_support.h"
#include "test_meshes.h"

namespace visproxy {
namespace {

TEST(BoundedHull, Smoke) {
  const TriangleMesh mesh = read_mesh(testing::cgal_mesh("bunny00.off"));
  for (std::size_t n : {64, 32, 18, 6}) {
    const auto start = std::chrono::steady_clock::now();
    const BoundedHullResult result = build_bounded_hull(mesh, {.max_faces = n});
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("N=%zu faces=%zu added=%.4f time=%.3f s\n", n, result.faces, result.added_volume_fraction(), seconds);
    EXPECT_LE(result.faces, n);
    EXPECT_TRUE(testing::is_closed_polytope_surface(result.mesh));
    EXPECT_TRUE(testing::contains_every_vertex(result.mesh, mesh));
  }
}

}  // namespace
}  // namespace visproxy
