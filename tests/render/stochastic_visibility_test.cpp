// The stochastic visibility estimator is unbiased: for fixed segments, the mean of many
// draws equals the exact visibility, for outside, inside and general proxies, with equal
// and optimal probabilities and with the cost heuristic, with and without splitting.

#include <gtest/gtest.h>

#include <cmath>

#include "core/random.h"
#include "mesh/sphere_set.h"
#include "render/renderer.h"
#include "trace/ray_scene.h"

namespace visproxy {
namespace {

TriangleMesh quad(const Vertex& corner, const Vertex& u, const Vertex& v) {
  TriangleMesh mesh;
  mesh.positions = {corner, corner + u, corner + u + v, corner + v};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  return mesh;
}

TriangleMesh box(const Vertex& min, const Vertex& max) {
  TriangleMesh mesh;
  for (int c = 0; c < 8; ++c) mesh.positions.emplace_back(c & 1 ? max.x() : min.x(), c & 2 ? max.y() : min.y(), c & 4 ? max.z() : min.z());
  mesh.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                    {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  return mesh;
}

// A floor (instance 0) and a ball of radius 1 at (0, 0, 2) (instance 1) whose proxy is
// `proxy`; the floor has none.
struct TwoInstances {
  Scene scene;
  std::vector<MeshProxies> proxies;
};

TwoInstances scene_with(const InstanceProxy& proxy) {
  TwoInstances s;
  s.scene.meshes.push_back({"floor", {}, quad({-4, -4, 0}, {8, 0, 0}, {0, 8, 0}), {}});
  s.scene.meshes.push_back({"ball", {}, sphere_set_mesh({{{0, 0, 2}, 1.0}}, 3), {}});
  s.scene.instances.push_back({"floor", Eigen::Affine3d::Identity(), Color::Constant(0.5), {}});
  s.scene.instances.push_back({"ball", Eigen::Affine3d::Identity(), Color::Constant(0.5), {}});
  AreaLight light;
  light.triangles = {{Vertex(-1, -1, 5), Vertex(-1, 1, 5), Vertex(1, 1, 5)}};
  s.scene.lights.push_back(light);
  s.proxies.resize(2);  // per instance: the floor has none
  s.proxies[1].stochastic = proxy;
  return s;
}

// Segments from the floor upwards: through the ball's centre (blocked by every proxy),
// beside everything (free), through the gap between the ball and its box (free, but the
// outside proxy is hit), through the ball's rim outside the inner sphere (blocked, but the
// inside proxy is missed), and one that leaves the general proxy's reach.
const std::vector<Segment> kSegments = {
    {{0, 0, 0.001}, {0, 0, 5}},      {{3, 3, 0.001}, {3.5, 3.5, 5}}, {{0.95, 0.95, 0.001}, {0.95, 0.95, 5}},
    {{0.93, 0, 0.001}, {0.93, 0, 5}}, {{0, 1.02, 0.001}, {0, 1.02, 5}}, {{-0.5, 0.3, 0.001}, {2, -1, 5}}};

void expect_unbiased(const TwoInstances& s, ProxyKind kind, const std::string& label) {
  const RenderWorld world(s.scene, s.proxies);
  Random random(4242);
  for (bool split : {true, false})
    for (int variant = 0; variant < 3; ++variant)
      for (const Segment& segment : kSegments) {
        const double exact = world.mesh_blocks(segment.from, segment.to) ? 0.0 : 1.0;
        // Probabilities: equal; optimal for skewed fractions; the cost heuristic on them.
        RayTypeFractions fractions;
        fractions.f = {0.5, 0.05, 0.1, 0.35};
        Probabilities p = equal_probabilities(kind);
        if (variant >= 1) p = optimal_probabilities(kind, fractions, {.floor = 0.05});
        if (variant == 2) p = apply_cost_heuristic(kind, p, fractions, 0.05);
        RenderStats stats;
        constexpr int draws = 40000;
        double sum = 0, square = 0;
        for (int i = 0; i < draws; ++i) {
          const double v = stochastic_visibility(world, segment.from, segment.to, 0, p, random.uniform(), split, stats);
          sum += v;
          square += v * v;
        }
        const double mean = sum / draws;
        const double variance = std::max(0.0, square / draws - mean * mean);
        // 4.9 standard errors: two-sided 1e-6 per check, so the 216 checks of this file
        // fail together by chance with probability below 3e-4 (fixed seed: reproducible).
        const double tolerance = 4.9 * std::sqrt(variance / draws) + 1e-12;
        EXPECT_NEAR(mean, exact, tolerance) << label << " split " << split << " variant " << variant << " segment "
                                            << segment.from.transpose() << " -> " << segment.to.transpose();
        EXPECT_TRUE(std::isfinite(mean));
      }
}

TEST(StochasticVisibility, UnbiasedWithAnOutsideProxy) {
  InstanceProxy proxy{ProxyKind::outside, "aabb", box({-1, -1, 1}, {1, 1, 3}), {}};
  expect_unbiased(scene_with(proxy), ProxyKind::outside, "outside");
}

TEST(StochasticVisibility, UnbiasedWithAnInsideProxy) {
  InstanceProxy proxy{ProxyKind::inside, "inside:1", {}, {{{0, 0, 2}, 0.9}}};
  expect_unbiased(scene_with(proxy), ProxyKind::inside, "inside");
}

TEST(StochasticVisibility, UnbiasedWithAGeneralProxy) {
  // A smaller ball moved sideways: it covers part of the ball and sticks out elsewhere.
  InstanceProxy proxy{ProxyKind::general, "general", sphere_set_mesh({{{0.3, 0, 2}, 0.8}}, 2), {}};
  expect_unbiased(scene_with(proxy), ProxyKind::general, "general");
}

// The world's proxy queries see what they should: the segments above classify as designed.
TEST(StochasticVisibility, ProxiesAndMeshesAnswerAsDesigned) {
  InstanceProxy outside{ProxyKind::outside, "aabb", box({-1, -1, 1}, {1, 1, 3}), {}};
  const TwoInstances s = scene_with(outside);
  const RenderWorld world(s.scene, s.proxies);
  EXPECT_TRUE(world.mesh_blocks(kSegments[0].from, kSegments[0].to));
  EXPECT_FALSE(world.mesh_blocks(kSegments[1].from, kSegments[1].to));
  EXPECT_FALSE(world.mesh_blocks(kSegments[2].from, kSegments[2].to));
  EXPECT_TRUE(world.proxy_blocks(kSegments[2].from, kSegments[2].to));  // type 3
  EXPECT_TRUE(world.mesh_blocks(kSegments[3].from, kSegments[3].to));
  // Filters: only the floor (nothing above it blocks), or everything but the ball.
  EXPECT_FALSE(world.mesh_blocks(kSegments[0].from, kSegments[0].to, {.skip = 1, .only = -1}));
  EXPECT_FALSE(world.mesh_blocks(kSegments[0].from, kSegments[0].to, {.skip = -1, .only = 0}));
  EXPECT_TRUE(world.mesh_blocks(kSegments[0].from, kSegments[0].to, {.skip = 0, .only = -1}));
  EXPECT_EQ(world.stochastic_kind(0), ProxyKind::outside);

  InstanceProxy inside{ProxyKind::inside, "inside:1", {}, {{{0, 0, 2}, 0.9}}};
  const TwoInstances t = scene_with(inside);
  const RenderWorld inner(t.scene, t.proxies);
  EXPECT_TRUE(inner.proxy_blocks(kSegments[0].from, kSegments[0].to));
  EXPECT_FALSE(inner.proxy_blocks(kSegments[3].from, kSegments[3].to));  // type 2
  EXPECT_FALSE(inner.proxy_blocks(kSegments[0].from, kSegments[0].to, {.skip = 1, .only = -1}));  // spheres filtered too
}

}  // namespace
}  // namespace visproxy
