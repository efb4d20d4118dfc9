// inner:512 against inside:40 on isotropic lines, on real closed meshes.
// f_hit = (#lines the mesh and the proxy both block) / (#lines the mesh blocks).

#include <gtest/gtest.h>

#include <cstdio>

#include "visproxy/measure/proportion.h"
#include "visproxy/measure/random_lines.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/proxy/inner_hull.h"
#include "visproxy/proxy/inscribed_spheres.h"
#include "test_meshes.h"
#include "test_support.h"
#include "visproxy/trace/ray_scene.h"

namespace visproxy {
namespace {

struct HitFraction {
  Proportion hit;                    // among the lines the mesh blocks, those the proxy blocks
  std::size_t blocked_by_proxy_only = 0;  // lines an inside proxy must never block
};

HitFraction hit_fraction(const std::vector<std::uint8_t>& mesh_blocked, const RayScene& proxy,
                         const std::vector<Segment>& lines) {
  const std::vector<std::uint8_t> proxy_blocked = proxy.segments_blocked(lines);
  HitFraction result;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (!mesh_blocked[i]) {
      result.blocked_by_proxy_only += proxy_blocked[i] ? 1 : 0;
      continue;
    }
    ++result.hit.trials;
    result.hit.successes += proxy_blocked[i] ? 1 : 0;
  }
  return result;
}

struct Case {
  const char* mesh;
  double min_f_hit;  // what the 99.9 % interval of inner:512's f_hit must stay above
};

class InnerHullVisibility : public ::testing::TestWithParam<Case> {};

// 200 000 lines, fixed seed; 99.9 % Wilson intervals (half-width about 0.004). On these
// lines inner:512's f_hit is 0.934 on bunny00 and 0.845 on the armadillo, intervals from
// 0.930 and 0.839; the thresholds refuse the start marked at half a cell from the surface
// instead of 0.3 (0.923 and 0.826, from 0.919 and 0.819) and, below it, every merged vertex
// placed beyond the planes it replaces (progressive hulls alone: 0.913 and 0.807).
// inner:512 must also block more than inside:40 (0.816 and 0.734), interval above
// interval, and no line the mesh lets through.
TEST_P(InnerHullVisibility, Inner512BlocksMoreLinesThanFortyInscribedSpheres) {
  const Case& c = GetParam();
  const TriangleMesh mesh = read_mesh(testing::cgal_mesh(c.mesh));
  const InnerHullResult inner = build_inner_hull(mesh, {.max_triangles = 512});
  ASSERT_TRUE(inner.reached_target);
  const InscribedSpheres spheres = build_inscribed_spheres(mesh, {.count = 40});

  const std::vector<Segment> lines = isotropic_lines(bounding_sphere(mesh), 200000, 20261203);
  const std::vector<std::uint8_t> mesh_blocked = RayScene(mesh).segments_blocked(lines);
  const HitFraction inner_hit = hit_fraction(mesh_blocked, RayScene(inner.mesh), lines);
  const HitFraction spheres_hit = hit_fraction(mesh_blocked, RayScene(spheres.spheres), lines);
  constexpr double z = 3.290527;  // 99.9 %
  std::printf("%s: f_hit of inner:512 %.4f [%.4f, %.4f], of inside:40 %.4f [%.4f, %.4f] (99.9 %% intervals, %zu lines)\n",
              c.mesh, inner_hit.hit.fraction(), inner_hit.hit.lower(z), inner_hit.hit.upper(z),
              spheres_hit.hit.fraction(), spheres_hit.hit.lower(z), spheres_hit.hit.upper(z), lines.size());
  EXPECT_EQ(inner_hit.blocked_by_proxy_only, 0u);
  EXPECT_GE(inner_hit.hit.lower(z), c.min_f_hit) << "f_hit " << inner_hit.hit.fraction();
  EXPECT_GT(inner_hit.hit.lower(z), spheres_hit.hit.upper(z))
      << "inner:512 " << inner_hit.hit.fraction() << ", inside:40 " << spheres_hit.hit.fraction();
}

INSTANTIATE_TEST_SUITE_P(LibCgalDemo, InnerHullVisibility,
                         ::testing::Values(Case{"bunny00.off", 0.925}, Case{"armadillo.off", 0.832}),
                         [](const ::testing::TestParamInfo<Case>& param_info) {
                           return testing::test_name_from(param_info.param.mesh);
                         });

}  // namespace
}  // namespace visproxy
