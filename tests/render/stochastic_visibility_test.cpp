// The stochastic visibility estimator is unbiased: for fixed segments, the mean of many
// draws equals the exact visibility, for outside, inside and general proxies, with equal
// and optimal probabilities and with the cost heuristic, with and without splitting.

#include <gtest/gtest.h>

#include <cmath>

#include "core/random.h"
#include "mesh/sphere_set.h"
#include "render/renderer.h"
#include "render/render_test_scenes.h"
#include "test_support.h"
#include "trace/ray_scene.h"

namespace visproxy {
namespace {

using testing::box;
using testing::quad;

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

// The same for the control-variate estimator: equal probabilities, the probabilities probe
// counts give, and the floor alone on each side the kind needs.
void expect_control_variate_unbiased(const TwoInstances& s, ProxyKind kind, const std::string& label) {
  const RenderWorld world(s.scene, s.proxies);
  Random random(4343);
  RayTypeCounts probes;
  probes.counts = {50, 5, 10, 35};
  const CorrectionEvidence evidence = CorrectionEvidence::from(probes);
  const std::vector<CorrectionProbabilities> variants = {equal_correction_probabilities(kind),
                                                         correction_probabilities(kind, evidence, {.scale = 1, .floor = 0.05}),
                                                         correction_probabilities(kind, CorrectionEvidence{}, {.scale = 0.01, .floor = 0.05})};
  for (bool split : {true, false})
    for (std::size_t variant = 0; variant < variants.size(); ++variant)
      for (const Segment& segment : kSegments) {
        const double exact = world.mesh_blocks(segment.from, segment.to) ? 0.0 : 1.0;
        RenderStats stats;
        constexpr int draws = 40000;
        double sum = 0, square = 0;
        for (int i = 0; i < draws; ++i) {
          const double v = control_variate_visibility(world, segment.from, segment.to, 0, variants[variant], random.uniform(), split, stats).visibility;
          sum += v;
          square += v * v;
        }
        const double mean = sum / draws;
        const double variance = std::max(0.0, square / draws - mean * mean);
        // 4.9 standard errors, as above (216 checks over the three kinds).
        EXPECT_NEAR(mean, exact, 4.9 * std::sqrt(variance / draws) + 1e-12)
            << label << " split " << split << " variant " << variant << " segment " << segment.from.transpose() << " -> "
            << segment.to.transpose();
      }
}

TEST(StochasticVisibility, UnbiasedWithAnOutsideProxy) {
  InstanceProxy proxy{ProxyKind::outside, "aabb", box({-1, -1, 1}, {1, 1, 3}), {}};
  expect_unbiased(scene_with(proxy), ProxyKind::outside, "outside");
  expect_control_variate_unbiased(scene_with(proxy), ProxyKind::outside, "outside");
}

TEST(StochasticVisibility, UnbiasedWithAnInsideProxy) {
  InstanceProxy proxy{ProxyKind::inside, "inside:1", {}, {{{0, 0, 2}, 0.9}}};
  expect_unbiased(scene_with(proxy), ProxyKind::inside, "inside");
  expect_control_variate_unbiased(scene_with(proxy), ProxyKind::inside, "inside");
}

TEST(StochasticVisibility, UnbiasedWithAGeneralProxy) {
  // A smaller ball moved sideways: it covers part of the ball and sticks out elsewhere.
  InstanceProxy proxy{ProxyKind::general, "general", sphere_set_mesh({{{0.3, 0, 2}, 0.8}}, 2), {}};
  expect_unbiased(scene_with(proxy), ProxyKind::general, "general");
  expect_control_variate_unbiased(scene_with(proxy), ProxyKind::general, "general");
}

// The box proxy above is closed and convex, so the world clips segments against it as a
// solid instead of asking Embree (a segment inside it meets it); an open mesh goes to
// Embree, whose triangles let such a segment through.
TEST(StochasticVisibility, ConvexProxiesAreClippedAsSolids) {
  InstanceProxy box_proxy{ProxyKind::outside, "aabb", box({-1, -1, 1}, {1, 1, 3}), {}};
  TwoInstances s = scene_with(box_proxy);
  s.proxies[1].outside = box_proxy;
  const RenderWorld world(s.scene, s.proxies);
  InstanceProxy open_proxy = box_proxy;  // not closed: traced by Embree as triangles
  open_proxy.mesh.triangles.pop_back();
  TwoInstances t = scene_with(open_proxy);
  t.proxies[1].outside = open_proxy;
  // Against the slab test of the box [-1, 1] x [-1, 1] x [1, 3].
  auto meets_box = [](const Vertex& from, const Vertex& to) {
    return testing::segment_meets_box(from, to, Vertex(-1, -1, 1), Vertex(1, 1, 3));
  };
  Random random(99);
  int blocked = 0;
  for (int i = 0; i < 4000; ++i) {
    const Vertex from(4 * random.uniform() - 2, 4 * random.uniform() - 2, 0.001), to(4 * random.uniform() - 2, 4 * random.uniform() - 2, 5);
    const bool clipped = world.proxy_blocks(from, to, {.skip = 0, .only = -1});
    EXPECT_EQ(clipped, meets_box(from, to)) << from.transpose() << " -> " << to.transpose();
    blocked += clipped ? 1 : 0;
  }
  EXPECT_GT(blocked, 400);
  EXPECT_LT(blocked, 3600);
  // A segment inside the solid meets it (Embree's triangles would let it through), for the
  // stochastic proxy and for bounds' outside proxy alike.
  EXPECT_TRUE(world.proxy_blocks({0.5, 0.5, 1.5}, {-0.5, 0.2, 2.5}, {.skip = 0, .only = -1}));
  EXPECT_TRUE(world.outside_blocks({0.5, 0.5, 1.5}, {-0.5, 0.2, 2.5}, {.skip = 0, .only = -1}));
  EXPECT_FALSE(RenderWorld(t.scene, t.proxies).outside_blocks({0.5, 0.5, 1.5}, {-0.5, 0.2, 2.5}, {.skip = 0, .only = -1}));
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

// Whole renders: per pixel, the mean of stochastic renders over many seeds equals the mean
// of exact renders over as many other seeds (two-sample z-test, 4.5 standard errors per
// pixel: 1 in 147 000 by chance, 960 pixels tested in all: 3 proxies x 5 estimator and
// probability variants x 64 pixels, so 0.7 % that one fails by chance; seeds fixed).
TEST(StochasticVisibility, PixelMeansOverSeedsConvergeToTheExactImage) {
  const std::vector<InstanceProxy> proxies = {
      {ProxyKind::outside, "aabb", box({-1, -1, 1}, {1, 1, 3}), {}},
      {ProxyKind::inside, "inside:1", {}, {{{0, 0, 2}, 0.9}}},
      {ProxyKind::general, "general", sphere_set_mesh({{{0.3, 0, 2}, 0.8}}, 2), {}}};
  for (const InstanceProxy& proxy : proxies) {
    TwoInstances s = scene_with(proxy);
    s.scene.camera.from = {0, -3.2, 0.6};
    s.scene.camera.at = {0, 0, 0};
    s.scene.camera.up = {0, 0, 1};
    s.scene.camera.fov_degrees = 70;
    s.scene.camera.width = s.scene.camera.height = 8;
    const RenderWorld world(s.scene, s.proxies);
    struct Variant {
      StochasticEstimator estimator;
      ProbabilityMode probabilities;
    };
    for (const Variant variant : {Variant{StochasticEstimator::term_choice, ProbabilityMode::equal},
                                  Variant{StochasticEstimator::term_choice, ProbabilityMode::adaptive},
                                  Variant{StochasticEstimator::control_variate, ProbabilityMode::equal},
                                  Variant{StochasticEstimator::control_variate, ProbabilityMode::adaptive},
                                  Variant{StochasticEstimator::control_variate, ProbabilityMode::learned}}) {
      const ProbabilityMode probabilities = variant.probabilities;
      constexpr int seeds = 48;
      const std::size_t n = 64;
      std::vector<double> exact_sum(n, 0), exact_square(n, 0), stochastic_sum(n, 0), stochastic_square(n, 0);
      for (int seed = 0; seed < seeds; ++seed) {
        RenderOptions exact{.spp = 8, .shadow_rays = 2, .seed = 1000u + static_cast<unsigned>(seed)};
        RenderOptions stochastic = exact;
        stochastic.visibility = VisibilityMode::stochastic;
        stochastic.probabilities = probabilities;
        stochastic.estimator = variant.estimator;
        stochastic.cost_heuristic = probabilities == ProbabilityMode::adaptive && variant.estimator == StochasticEstimator::term_choice;
        stochastic.probe_rays = 4;
        stochastic.probe_passes = variant.estimator == StochasticEstimator::control_variate ? 2 : 0;
        stochastic.correction_scale = 0.5;  // aggressive: most corrections skipped
        stochastic.seed = 5000u + static_cast<unsigned>(seed);
        const Image a = render(s.scene, world, exact).image, b = render(s.scene, world, stochastic).image;
        ASSERT_TRUE(all_finite(b));
        for (std::size_t i = 0; i < n; ++i) {
          exact_sum[i] += a.pixels[i].x(), exact_square[i] += a.pixels[i].x() * a.pixels[i].x();
          stochastic_sum[i] += b.pixels[i].x(), stochastic_square[i] += b.pixels[i].x() * b.pixels[i].x();
        }
      }
      int noisier_pixels = 0;
      for (std::size_t i = 0; i < n; ++i) {
        const double ma = exact_sum[i] / seeds, mb = stochastic_sum[i] / seeds;
        const double va = std::max(0.0, exact_square[i] / seeds - ma * ma), vb = std::max(0.0, stochastic_square[i] / seeds - mb * mb);
        const double standard_error = std::sqrt((va + vb) / (seeds - 1));
        EXPECT_LE(std::abs(ma - mb), 4.5 * standard_error + 1e-12) << proxy.spec << " pixel " << i;
        noisier_pixels += vb > 1.2 * va ? 1 : 0;
      }
      // The estimator did work here: where proxy and ball disagree it adds noise.
      EXPECT_GT(noisier_pixels, 0) << proxy.spec;
    }
  }
}

}  // namespace
}  // namespace visproxy
