// outer:512 against the convex hull on isotropic lines (slow: default wraps of real meshes).
// f_miss = (#lines missing the mesh and the proxy) / (#lines missing the mesh).

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <gtest/gtest.h>

#include "visproxy/measure/proportion.h"
#include "visproxy/measure/random_lines.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/proxy/outer_hull.h"
#include "proxy/outside_proxy_checks.h"
#include "cgal_hull.h"
#include "test_meshes.h"
#include "test_support.h"
#include "visproxy/trace/ray_scene.h"

namespace visproxy {
namespace {

using testing::cgal_convex_hull;

Proportion miss_fraction(const std::vector<std::uint8_t>& mesh_blocked, const TriangleMesh& proxy,
                         const std::vector<Segment>& lines) {
  const std::vector<std::uint8_t> proxy_blocked = RayScene(proxy).segments_blocked(lines);
  Proportion miss;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (mesh_blocked[i]) continue;
    ++miss.trials;
    miss.successes += proxy_blocked[i] ? 0 : 1;
  }
  return miss;
}

class OuterHullVisibility : public ::testing::TestWithParam<const char*> {};

// 100 000 lines, fixed seed; the 99.9 % Wilson interval of outer:512's f_miss must lie
// above 0.95 and entirely above the convex hull's.
TEST_P(OuterHullVisibility, Outer512MissesFarMoreLinesThanTheConvexHull) {
  const TriangleMesh mesh = read_mesh(testing::cgal_mesh(GetParam()));
  const OuterHullOptions options{.max_triangles = 512};
  const OuterHullResult outer = build_outer_hull(mesh, options);
  ASSERT_TRUE(outer.reached_target);
  testing::expect_conservative_outside_proxy(mesh, outer.mesh);

  const std::vector<Segment> lines = isotropic_lines(bounding_sphere(mesh), 100000, 20240601);
  const std::vector<std::uint8_t> mesh_blocked = RayScene(mesh).segments_blocked(lines);
  const Proportion outer_miss = miss_fraction(mesh_blocked, outer.mesh, lines);
  const Proportion hull_miss = miss_fraction(mesh_blocked, cgal_convex_hull(mesh), lines);
  constexpr double z = 3.290527;  // 99.9 %
  EXPECT_GE(outer_miss.lower(z), 0.95) << "f_miss " << outer_miss.fraction();
  EXPECT_GT(outer_miss.lower(z), hull_miss.upper(z))
      << "outer " << outer_miss.fraction() << ", convex hull " << hull_miss.fraction();
}

INSTANTIATE_TEST_SUITE_P(LibCgalDemo, OuterHullVisibility, ::testing::Values("armadillo.off", "bunny00.off"),
                         [](const ::testing::TestParamInfo<const char*>& param_info) {
                           return testing::test_name_from(param_info.param);
                         });

}  // namespace
}  // namespace visproxy
