// The stochastic visibility estimator is unbiased: for fixed segments, the mean of many
// draws equals the exact visibility, for outside, inside and general proxies, with equal
// and optimal probabilities and with the cost heuristic, with and without splitting.

#include <array>
#include <map>
#include <optional>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstdio>

#include "visproxy/core/random.h"
#include "visproxy/mesh/sphere_set.h"
#include "visproxy/render/renderer.h"
#include "visproxy/render/scene_learning.h"
#include "visproxy/render/world/sampling.h"
#include "visproxy/render/visibility/visibility.h"
#include "render/render_test_scenes.h"
#include "test_support.h"
#include "visproxy/trace/ray_scene.h"

namespace visproxy {
namespace {

using testing::box;
using testing::quad;

// A floor (instance 0) and a ball of radius 1 at (0, 0, 2) (instance 1, an icosphere of
// `ball_levels` subdivisions: 1280 triangles at 3) whose proxy is `proxy`; the floor has none.
struct TwoInstances {
  Scene scene;
  std::vector<MeshProxies> proxies;
};

TwoInstances scene_with(const InstanceProxy& proxy, int ball_levels = 3) {
  TwoInstances s;
  s.scene.meshes.push_back({"floor", {}, quad({-4, -4, 0}, {8, 0, 0}, {0, 8, 0}), {}});
  s.scene.meshes.push_back({"ball", {}, sphere_set_mesh({{{0, 0, 2}, 1.0}}, ball_levels), {}});
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
// inside proxy is missed), one that leaves the general proxy's reach, one through the
// general proxy where it sticks out of the ball (type 3) and one through the ball beside
// the general proxy (type 2).
const std::vector<Segment> kSegments = {
    {{0, 0, 0.001}, {0, 0, 5}},      {{3, 3, 0.001}, {3.5, 3.5, 5}}, {{0.95, 0.95, 0.001}, {0.95, 0.95, 5}},
    {{0.93, 0, 0.001}, {0.93, 0, 5}}, {{0, 1.02, 0.001}, {0, 1.02, 5}}, {{-0.5, 0.3, 0.001}, {2, -1, 5}},
    {{1.05, 0, 0.001}, {1.05, 0, 5}}, {{-0.7, 0, 0.001}, {-0.7, 0, 5}}};

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
        // 4.9 standard errors: two-sided 1e-6 per check, so the 288 checks of this file
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
        // 4.9 standard errors, as above (288 checks over the three kinds).
        EXPECT_NEAR(mean, exact, 4.9 * std::sqrt(variance / draws) + 1e-12)
            << label << " split " << split << " variant " << variant << " segment " << segment.from.transpose() << " -> "
            << segment.to.transpose();
      }
}

TEST(StochasticVisibility, UnbiasedWithAnOutsideProxy) {
  InstanceProxy proxy{ProxyKind::outside, "aabb", box({-1, -1, 1}, {1, 1, 3}), {}, true};
  expect_unbiased(scene_with(proxy), ProxyKind::outside, "outside");
  expect_control_variate_unbiased(scene_with(proxy), ProxyKind::outside, "outside");
}

TEST(StochasticVisibility, UnbiasedWithAnInsideProxy) {
  InstanceProxy proxy{ProxyKind::inside, "inside:1", {}, {{{0, 0, 2}, 0.9}}, true};
  expect_unbiased(scene_with(proxy), ProxyKind::inside, "inside");
  expect_control_variate_unbiased(scene_with(proxy), ProxyKind::inside, "inside");
}

TEST(StochasticVisibility, UnbiasedWithAGeneralProxy) {
  // A smaller ball moved sideways: it covers part of the ball and sticks out elsewhere.
  InstanceProxy proxy{ProxyKind::general, "general", sphere_set_mesh({{{0.3, 0, 2}, 0.8}}, 2), {}};
  {
    // The segments hold rays of types 2 (mesh blocks, proxy lets through) and 3 (the other
    // way round), the ones only a general estimator must weigh both ways.
    const TwoInstances s = scene_with(proxy);
    const RenderWorld world(s.scene, s.proxies);
    RayTypeCounts types;
    for (const Segment& segment : kSegments)
      types.add(world.mesh_blocks(segment.from, segment.to, {.skip = 0, .only = -1}),
                world.proxy_blocks(segment.from, segment.to, {.skip = 0, .only = -1}));
    EXPECT_GT(types.counts[1], 0u);
    EXPECT_GT(types.counts[2], 0u);
  }
  expect_unbiased(scene_with(proxy), ProxyKind::general, "general");
  expect_control_variate_unbiased(scene_with(proxy), ProxyKind::general, "general");
}

// The box proxy above is closed and convex, so the world clips segments against it as a
// solid instead of asking Embree (a segment inside it meets it); an open mesh goes to
// Embree, whose triangles let such a segment through.
TEST(StochasticVisibility, ConvexProxiesAreClippedAsSolids) {
  InstanceProxy box_proxy{ProxyKind::outside, "aabb", box({-1, -1, 1}, {1, 1, 3}), {}, true};
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
  InstanceProxy outside{ProxyKind::outside, "aabb", box({-1, -1, 1}, {1, 1, 3}), {}, true};
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

  InstanceProxy inside{ProxyKind::inside, "inside:1", {}, {{{0, 0, 2}, 0.9}}, true};
  const TwoInstances t = scene_with(inside);
  const RenderWorld inner(t.scene, t.proxies);
  EXPECT_TRUE(inner.proxy_blocks(kSegments[0].from, kSegments[0].to));
  EXPECT_FALSE(inner.proxy_blocks(kSegments[3].from, kSegments[3].to));  // type 2
  EXPECT_FALSE(inner.proxy_blocks(kSegments[0].from, kSegments[0].to, {.skip = 1, .only = -1}));  // spheres filtered too
}

// The scene of scene_with(proxy) seen from low beside the ball, 8 x 8 pixels, so that
// most pixels show the floor in the ball's penumbra.
TwoInstances penumbra_view(const InstanceProxy& proxy, int ball_levels = 3) {
  TwoInstances s = scene_with(proxy, ball_levels);
  s.scene.camera.from = {0, -3.2, 0.6};
  s.scene.camera.at = {0, 0, 0};
  s.scene.camera.up = {0, 0, 1};
  s.scene.camera.fov_degrees = 70;
  s.scene.camera.width = s.scene.camera.height = 8;
  return s;
}

// eq. 8 with the scene's optimal probabilities (ProbabilityMode::optimal): one set for the
// image (the p1 map is one value wherever the shading point's form is the same), not the
// equal ones, and less noise than with those at the same samples: the paired difference to
// exact (same seed, same light samples) varies less over 48 seeds, summed over the pixels.
// With a general proxy the equal probabilities are 1/3 each; the scene's optimum is far
// from them (the proxy sticks out of the ball and misses its rim).
TEST(StochasticVisibility, OptimalProbabilitiesAreOneSetAndLowerEq8sNoise) {
  const TwoInstances s = penumbra_view({ProxyKind::general, "general", sphere_set_mesh({{{0.3, 0, 2}, 0.8}}, 2), {}});
  const RenderWorld world(s.scene, s.proxies);
  constexpr int seeds = 48;
  const std::size_t n = 64;
  std::array<double, 2> spread{};  // equal, optimal: sum over pixels of the variance of the paired difference
  for (const ProbabilityMode mode : {ProbabilityMode::equal, ProbabilityMode::optimal}) {
    std::vector<double> sum(n, 0), square(n, 0);
    for (int seed = 0; seed < seeds; ++seed) {
      const RenderOptions exact_options{.spp = 8, .shadow_rays = 4, .seed = 500u + static_cast<unsigned>(seed)};
      RenderOptions stochastic = exact_options;
      stochastic.visibility = VisibilityMode::stochastic;
      stochastic.probabilities = mode;
      const RenderResult a = render(s.scene, world, exact_options), b = render(s.scene, world, stochastic);
      for (std::size_t i = 0; i < n; ++i) {
        const double d = b.image.pixels[i].x() - a.image.pixels[i].x();
        sum[i] += d, square[i] += d * d;
      }
      if (mode == ProbabilityMode::optimal && seed == 0) {
        // The floor's points see the ball through the general form: one p1 for all of them
        // (the ball's own points see only the floor, another form; pixels that hold both mix).
        std::map<double, int> p1;
        for (const Color& c : b.p1_map.pixels) ++p1[c.x()];
        const auto most = std::max_element(p1.begin(), p1.end(), [](const auto& x, const auto& y) { return x.second < y.second; });
        EXPECT_GE(most->second, static_cast<int>(n / 2)) << "the floor's pixels share one p1";
        EXPECT_GT(std::abs(most->first - 1.0 / 3), 0.05) << "p1 " << most->first;
        // The stats say which probabilities were used: the floor's are the general form's.
        ASSERT_TRUE(b.stats.optimal_probabilities.contains("general")) << b.stats.optimal_probabilities.dump();
        EXPECT_NEAR(b.stats.optimal_probabilities["general"][0].get<double>(), most->first, 1e-12);
        EXPECT_TRUE(a.stats.optimal_probabilities.is_null());
      }
    }
    for (std::size_t i = 0; i < n; ++i) spread[mode == ProbabilityMode::optimal] += square[i] / seeds - (sum[i] / seeds) * (sum[i] / seeds);
  }
  std::printf("eq8 paired-difference variance summed over pixels: equal %.4e, optimal %.4e (%.2fx)\n", spread[0], spread[1],
              spread[1] / spread[0]);
  EXPECT_LT(spread[1], 0.9 * spread[0]) << "equal " << spread[0] << ", optimal " << spread[1];
}

// Whole renders, paired: an exact and a stochastic render with the same seed trace the
// same camera rays and light samples (the estimators draw from a stream of their own), so
// per pixel their difference D has mean 0 exactly when the estimator is unbiased, and only
// the estimator's own noise: the light sampling's, which the unpaired comparison of two
// sets of seeds had to beat, cancels. Over 64 seeds, per penumbra pixel and for the mean
// over all penumbra pixels, |mean D| must stay within 5.42 standard errors (Student t, 63
// degrees of freedom, two-sided 1e-6 per check: the 3 x 5 x (at most 65) checks fail
// together by chance with probability below 1e-3; seeds fixed). The smallest bias of the
// penumbra mean the test detects with probability 0.9 is (5.42 + 1.30) standard errors; it
// is printed, and it must be below 5 % of the mean penumbra radiance (measured: 1.1 % for
// the control variate with an inside proxy to 4.8 % for eq. 8 with a general one, at 128
// shadow rays per pixel and seed); the pairing's standard error must be below the
// unpaired comparison's of as many renders (measured: 1.3 to 3 times below). The learned
// control variate traces exactly where its proxy does not pay (the coarse ball's box and
// general proxy): the fourth case, a ball proxy of a 20 480-triangle ball, is one where it
// pays; wherever most of its segments took the control variate, its noise must show.
TEST(StochasticVisibility, PairedPixelMeansShowNoBiasInPenumbrae) {
  struct Case {
    InstanceProxy proxy;
    int ball_levels;
  };
  const std::vector<Case> cases = {{{ProxyKind::outside, "aabb", box({-1, -1, 1}, {1, 1, 3}), {}, true}, 3},
                                   {{ProxyKind::inside, "inside:1", {}, {{{0, 0, 2}, 0.9}}, true}, 3},
                                   {{ProxyKind::general, "general", sphere_set_mesh({{{0.3, 0, 2}, 0.8}}, 2), {}}, 3},
                                   {{ProxyKind::general, "ball of a fine ball", {}, {{{0, 0, 2}, 1.0}}}, 5}};
  constexpr int seeds = 64;
  constexpr double critical = 5.42, power = 1.30;
  constexpr double kDetectableBias = 0.05;  // of the mean penumbra radiance, power 0.9
  for (const auto& [proxy, ball_levels] : cases) {
    const TwoInstances s = penumbra_view(proxy, ball_levels);
    const RenderWorld world(s.scene, s.proxies);
    struct Variant {
      StochasticEstimator estimator;
      ProbabilityMode probabilities;
    };
    for (const Variant variant : {Variant{StochasticEstimator::term_choice, ProbabilityMode::equal},
                                  Variant{StochasticEstimator::term_choice, ProbabilityMode::adaptive},
                                  Variant{StochasticEstimator::term_choice, ProbabilityMode::optimal},
                                  Variant{StochasticEstimator::control_variate, ProbabilityMode::equal},
                                  Variant{StochasticEstimator::control_variate, ProbabilityMode::adaptive},
                                  Variant{StochasticEstimator::control_variate, ProbabilityMode::learned}}) {
      const std::string label = proxy.spec + " " + std::string(name_of(variant.estimator)) + " " +
                                std::string(name_of(variant.probabilities));
      const std::size_t n = 64;
      std::vector<std::vector<double>> exact(seeds), difference(seeds);
      std::uint64_t segments = 0, traced_exactly = 0;
      for (int seed = 0; seed < seeds; ++seed) {
        const RenderOptions exact_options{.spp = 32, .shadow_rays = 4, .seed = 1000u + static_cast<unsigned>(seed)};
        RenderOptions stochastic = exact_options;
        stochastic.visibility = VisibilityMode::stochastic;
        stochastic.probabilities = variant.probabilities;
        stochastic.estimator = variant.estimator;
        stochastic.cost_heuristic = variant.probabilities == ProbabilityMode::adaptive && variant.estimator == StochasticEstimator::term_choice;
        stochastic.probe_rays = 4;
        stochastic.probe_passes = variant.estimator == StochasticEstimator::control_variate ? 2 : 0;
        stochastic.correction_scale = 0.5;  // aggressive: most corrections skipped
        stochastic.gate = false;  // the estimator itself, wherever it would not pay
        const Image a = render(s.scene, world, exact_options).image;
        const RenderResult stochastic_result = render(s.scene, world, stochastic);
        const Image& b = stochastic_result.image;
        segments += stochastic_result.stats.shadow_rays;
        traced_exactly += stochastic_result.stats.control_variate.traced_exactly;
        ASSERT_TRUE(all_finite(b));
        for (std::size_t i = 0; i < n; ++i) {
          exact[seed].push_back(a.pixels[i].x());
          difference[seed].push_back(b.pixels[i].x() - a.pixels[i].x());
        }
      }
      auto mean_and_error = [&](auto&& value) {
        double sum = 0, square = 0;
        for (int seed = 0; seed < seeds; ++seed) sum += value(seed);
        const double mean = sum / seeds;
        for (int seed = 0; seed < seeds; ++seed) square += (value(seed) - mean) * (value(seed) - mean);
        return std::pair(mean, std::sqrt(square / (seeds - 1) / seeds));
      };
      double brightest = 0;
      std::vector<double> exact_mean(n);
      for (std::size_t i = 0; i < n; ++i) {
        exact_mean[i] = mean_and_error([&](int seed) { return exact[seed][i]; }).first;
        brightest = std::max(brightest, exact_mean[i]);
      }
      std::vector<std::size_t> penumbra;
      double penumbra_radiance = 0;
      for (std::size_t i = 0; i < n; ++i)
        if (exact_mean[i] > 0.1 * brightest && exact_mean[i] < 0.9 * brightest) {
          penumbra.push_back(i);
          penumbra_radiance += exact_mean[i];
        }
      ASSERT_GE(penumbra.size(), 8u) << label;
      penumbra_radiance /= static_cast<double>(penumbra.size());
      int noisy = 0;
      for (const std::size_t i : penumbra) {
        const auto [mean, error] = mean_and_error([&](int seed) { return difference[seed][i]; });
        EXPECT_LE(std::abs(mean), critical * error + 1e-12) << label << " pixel " << i;
        noisy += error > 0 ? 1 : 0;
      }
      // The estimator did work: it adds noise where proxy and mesh disagree. (The learned
      // control variate may give its penumbra pixels to exact tracing and keep the rest,
      // where proxy and mesh agree and a skipped correction adds no noise; the fine ball's
      // proxy pays, and there it must estimate most segments.)
      const double estimated = 1 - static_cast<double>(traced_exactly) / static_cast<double>(segments);
      if (ball_levels == 5) {
        EXPECT_GT(estimated, 0.5) << label;
      }
      if (estimated > 0.5) {
        EXPECT_GT(noisy, 0) << label << ", segments estimated " << estimated;
      }
      const auto [bias, error] = mean_and_error([&](int seed) {
        double sum = 0;
        for (const std::size_t i : penumbra) sum += difference[seed][i];
        return sum / static_cast<double>(penumbra.size());
      });
      // What an unpaired comparison (stochastic and exact renders from different seeds)
      // could resolve with the same renders: the standard error of a difference of means.
      auto penumbra_mean = [&](int seed, bool stochastic) {
        double sum = 0;
        for (const std::size_t i : penumbra) sum += exact[seed][i] + (stochastic ? difference[seed][i] : 0.0);
        return sum / static_cast<double>(penumbra.size());
      };
      const double unpaired = std::hypot(mean_and_error([&](int seed) { return penumbra_mean(seed, false); }).second,
                                         mean_and_error([&](int seed) { return penumbra_mean(seed, true); }).second);
      const double detectable = (critical + power) * error;
      std::printf("%-50s penumbra pixels %2zu, mean D %+.2e +- %.2e (unpaired +- %.2e), detectable bias %.2f %% of %.3e, "
                  "segments estimated %.3f\n",
                  label.c_str(), penumbra.size(), bias, error, unpaired, 100 * detectable / penumbra_radiance, penumbra_radiance,
                  estimated);
      EXPECT_LE(std::abs(bias), critical * error + 1e-12) << label;
      EXPECT_LT(detectable, kDetectableBias * penumbra_radiance) << label;
      EXPECT_LT(error, unpaired) << label;
    }
  }
}

// The learned control variate weighs its proxy's cost and noise against the mesh's, per
// pixel (learned_choice with the render's modelled costs): a ball proxy of a 20 480-triangle
// ball is cheap and rarely wrong, and answers most segments (its pixels need not explore);
// a ball of 1.3 times its radius (320 triangles) is cheap too but blocks two fifths of the
// segments through it wrongly, and gives way to exact tracing in most pixels, after some
// exploring; a proxy as costly as the ball's own mesh (the coarse ball itself, moved by
// 2 % of its radius) and the coarse ball's box (a clipped solid, tested outside Embree)
// can never pay, so no pixel explores them at all, and the image is exact's bit for bit.
// Either way the image stays within the paired noise of exact's (the gate only ever swaps
// in exact answers), and is the same
// rendered on one thread (the fine ball's image holds pixels of both kinds).
TEST(StochasticVisibility, LearnedControlVariateTracesExactlyWhereItsProxyDoesNotPay) {
  struct Case {
    InstanceProxy proxy;
    int ball_levels;
    double least_exact_share, most_exact_share;
    std::optional<bool> explores;  // nullopt: either
    bool traces_proxy;
  };
  const std::vector<Case> cases = {
      {{ProxyKind::general, "fine ball", {}, {{{0, 0, 2}, 1.0}}}, 5, 0.02, 0.3, std::nullopt, true},
      {{ProxyKind::general, "large ball", sphere_set_mesh({{{0, 0, 2}, 1.3}}, 2), {}}, 5, 0.6, 1.0, true, true},
      {{ProxyKind::outside, "aabb", box({-1, -1, 1}, {1, 1, 3}), {}, true}, 3, 1.0, 1.0, false, false},
      {{ProxyKind::general, "moved ball", sphere_set_mesh({{{0.02, 0, 2}, 1.0}}, 3), {}}, 3, 1.0, 1.0, false, false}};
  for (const Case& c : cases) {
    TwoInstances s = penumbra_view(c.proxy, c.ball_levels);
    s.scene.camera.width = s.scene.camera.height = 48;  // 9 tiles
    const RenderWorld world(s.scene, s.proxies);
    const RenderOptions exact{.spp = 32, .shadow_rays = 4, .seed = 77};
    RenderOptions learned = exact;
    learned.visibility = VisibilityMode::stochastic;
    learned.estimator = StochasticEstimator::control_variate;
    learned.probabilities = ProbabilityMode::learned;
    const RenderResult a = render(s.scene, world, exact), b = render(s.scene, world, learned);
    const RenderStats& stats = b.stats;
    {
      // The choices, evidence and costs are the pixels' own: one thread gives the same image.
      const tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
      const RenderResult one = render(s.scene, world, learned);
      EXPECT_EQ(one.image.pixels, b.image.pixels) << c.proxy.spec;
      EXPECT_EQ(one.stats.control_variate.traced_exactly, stats.control_variate.traced_exactly) << c.proxy.spec;
    }
    const double share = static_cast<double>(stats.control_variate.traced_exactly) / static_cast<double>(stats.shadow_rays);
    std::printf("%-12s segments traced exactly %.3f, explored %.4f, corrections per segment %.3f\n", c.proxy.spec.c_str(), share,
                static_cast<double>(stats.control_variate.explored) / static_cast<double>(stats.shadow_rays),
                static_cast<double>(stats.control_variate.after_hit + stats.control_variate.after_miss) /
                    static_cast<double>(stats.shadow_rays));
    EXPECT_GE(share, c.least_exact_share) << c.proxy.spec;
    EXPECT_LE(share, c.most_exact_share) << c.proxy.spec;
    if (c.explores) {
      EXPECT_EQ(stats.control_variate.explored > 0, *c.explores) << c.proxy.spec;
    }
    EXPECT_EQ(stats.proxy_tests > 0, c.traces_proxy) << c.proxy.spec;  // a proxy that cannot pay is never traced
    // What the choice weighed is in the stats, for both instances.
    ASSERT_TRUE(stats.learned_costs.is_object()) << c.proxy.spec;
    EXPECT_GT(stats.learned_costs["noise_per_segment"].get<double>(), 0) << c.proxy.spec;
    EXPECT_EQ(stats.learned_costs["instances"].size(), 2u) << c.proxy.spec;
    // Where no instance's proxy could pay whatever its evidence, the render is exact
    // visibility from the first segment (no per-pixel learning): every segment traced
    // exactly, and the proxy alone never (a p1 map of zeros).
    EXPECT_EQ(stats.learned_costs["traced_exactly_everywhere"].get<bool>(), !c.traces_proxy) << c.proxy.spec;
    if (!c.traces_proxy) {
      EXPECT_EQ(stats.control_variate.traced_exactly, stats.shadow_rays) << c.proxy.spec;
      for (const Color& p1 : b.p1_map.pixels) {
        ASSERT_EQ(p1.x(), 0.0) << c.proxy.spec;
      }
    }
    double difference = 0, total = 0;
    for (std::size_t i = 0; i < a.image.pixels.size(); ++i) {
      difference += b.image.pixels[i].x() - a.image.pixels[i].x();
      total += a.image.pixels[i].x();
    }
    EXPECT_LT(std::abs(difference), 0.02 * total) << c.proxy.spec;
    // A proxy that can never pay leaves exact's image, bit for bit (the same camera and
    // light samples, every segment traced against the meshes alone).
    if (c.explores == false) {
      EXPECT_EQ(b.image.pixels, a.image.pixels) << c.proxy.spec;
    }
  }
  // The cost-blind rule (adaptive) neither gates nor reports costs.
  const TwoInstances s = penumbra_view({ProxyKind::general, "fine ball", {}, {{{0, 0, 2}, 1.0}}}, 5);
  const RenderWorld world(s.scene, s.proxies);
  RenderOptions adaptive_options{.spp = 4, .seed = 77};
  adaptive_options.visibility = VisibilityMode::stochastic;
  adaptive_options.estimator = StochasticEstimator::control_variate;
  adaptive_options.probabilities = ProbabilityMode::adaptive;
  const RenderResult adaptive = render(s.scene, world, adaptive_options);
  EXPECT_EQ(adaptive.stats.control_variate.traced_exactly, 0u);
  EXPECT_TRUE(adaptive.stats.learned_costs.is_null());
}

// The gate per instance: with the ball's points marked to trace exactly and the floor's
// not, adaptive eq. 8 answers the ball's segments as the meshes do (0 or 1, each counted as
// traced exactly, no probe, no term), and probes and draws terms on the floor.
TEST(StochasticVisibility, AdaptiveEq8GateIsPerInstance) {
  const TwoInstances s = penumbra_view({ProxyKind::general, "fine ball", {}, {{{0, 0, 2}, 1.0}}}, 5);
  const RenderWorld world(s.scene, s.proxies);
  const LightSampler lights(s.scene);
  RenderOptions options{.visibility = VisibilityMode::stochastic, .probabilities = ProbabilityMode::adaptive};
  VisibilityContext context{s.scene, world, options, lights, 1, {}, {}, {}, {0, 1}};
  const std::unique_ptr<Visibility> visibility = make_term_choice_visibility(context);
  const std::unique_ptr<PointVisibility> answers = visibility->point_visibility();
  PixelRandom choices(3, 0, 0), random(4, 0, 0);
  std::array<RenderStats, 2> stats;  // per instance of the point
  std::array<int, 2> points{};
  double p1_sum = 0, p1_count = 0;
  for (int i = 0; i < 400; ++i) {
    const double reach = i % 2 == 0 ? 3.0 : 1.0;  // every other ray over the ball
    const Vertex from(reach * (2 * random.uniform() - 1), reach * (2 * random.uniform() - 1), 6);
    const std::optional<SurfaceHit> hit = world.intersect(from, Vertex(0, 0, -1));
    if (!hit || hit->light >= 0) continue;
    const std::size_t own = static_cast<std::size_t>(hit->instance);
    ++points[own];
    const ShadingPoint point{.pixel = 0, .pass = 0, .hit = &*hit,
                             .position = hit->position + world.surface_offset(hit->position, hit->distance) * hit->normal,
                             .choices = &choices, .stats = &stats[own], .p1_sum = &p1_sum, .p1_count = &p1_count};
    answers->begin(point);
    for (int k = 0; k < 4; ++k) {
      const Vertex end(-2 + 4 * random.uniform(), -2 + 4 * random.uniform(), 5.5);
      const double value = answers->to_light(end);
      if (own == 1) {
        EXPECT_EQ(value, world.mesh_blocks(point.position, end) ? 0.0 : 1.0);
      }
    }
    answers->end();
  }
  ASSERT_GT(points[0], 50);
  ASSERT_GT(points[1], 50);
  EXPECT_EQ(stats[1].eq8.traced_exactly, 4u * static_cast<unsigned>(points[1]));
  EXPECT_EQ(stats[1].probe_rays + stats[1].proxy_tests + stats[1].eq8.terms[0] + stats[1].eq8.terms[1] + stats[1].eq8.terms[2], 0u);
  EXPECT_EQ(stats[0].eq8.traced_exactly, 0u);
  EXPECT_GT(stats[0].probe_rays, 0u);
  EXPECT_EQ(stats[0].eq8.terms[0] + stats[0].eq8.terms[1] + stats[0].eq8.terms[2], 4u * static_cast<unsigned>(points[0]));
}

// eq8_predicted_ratio() against the numbers worked by hand: an outside proxy that blocks
// 40 % of the segments and is never wrong there (f_miss = 1) gets p1 = 0.95 and p2 = 0.05
// at the floor 0.05, so eq. 8 adds 0.6 (1 / 0.95 - 1) to a segment, and its work is camera
// + proxy + 0.05 x 0.4 x correction, plus the probes. A proxy 10x cheaper than its mesh
// pays where the probes are shared (16 probes in one pass of 80, over 4 shadow rays: 0.05
// per segment), not where every point probes 16 times for one shadow ray. The rates of a
// side the kind proves right do not count (an outside proxy's misses, here 30 % "wrong");
// a general proxy wrong half the time never pays; no noise gives +infinity.
TEST(StochasticVisibility, Eq8PredictedRatioWeighsNoiseWorkAndProbes) {
  CorrectionPrior prior;
  prior.share = {0.6, 0.4};
  prior.disagreeing = {0.3, 0.0};  // wrong when letting through: an outside proxy cannot be
  const SegmentQueryCosts work{.camera = 2, .exact = 40, .proxy = 4, .correction = 38};
  const double noise = 0.5;
  const double shared = eq8_predicted_ratio(ProxyKind::outside, prior, work, noise, 0.05, 0.05, false);
  const double added = 0.6 * (1 / 0.95 - 1);
  const double expected = (noise + added) * (2 + 4 + 38 * 0.05 * 0.4 + 0.05 * (4 + 38)) / (noise * (2 + 40));
  EXPECT_NEAR(shared, expected, 1e-9 * expected);
  EXPECT_LT(shared, kLearnedPaysBelow);
  EXPECT_GE(eq8_predicted_ratio(ProxyKind::outside, prior, work, noise, 16.0, 0.05, false), kLearnedPaysBelow);
  CorrectionPrior wrong = prior;
  wrong.disagreeing = {0.5, 0.5};
  EXPECT_GE(eq8_predicted_ratio(ProxyKind::general, wrong, work, noise, 0.0, 0.05, false), kLearnedPaysBelow);
  EXPECT_TRUE(std::isinf(eq8_predicted_ratio(ProxyKind::outside, prior, work, 0.0, 0.05, 0.05, false)));
}

// Adaptive eq. 8 with direct light traces exactly from the points of an instance where,
// at the instance's modelled costs and ray types, its variance x work (probe rays
// included) is not below kLearnedPaysBelow of exact's. Probing every point (16 probes, one
// shadow ray per sample), it cannot pay anywhere: the render is exact visibility, exact's
// image bit for bit, without a probe, a proxy query or a drawn term. --no-gate keeps eq. 8
// everywhere (the probes run again).
TEST(StochasticVisibility, AdaptiveEq8TracesExactlyWhereItCannotPay) {
  TwoInstances s = penumbra_view({ProxyKind::general, "fine ball", {}, {{{0, 0, 2}, 1.0}}}, 5);
  s.scene.camera.width = s.scene.camera.height = 24;
  const RenderWorld world(s.scene, s.proxies);
  RenderOptions exact{.spp = 8, .shadow_rays = 1, .seed = 31};
  RenderOptions adaptive = exact;
  adaptive.visibility = VisibilityMode::stochastic;
  adaptive.probabilities = ProbabilityMode::adaptive;
  adaptive.probe_rays = 16;
  const RenderResult a = render(s.scene, world, exact), b = render(s.scene, world, adaptive);
  ASSERT_TRUE(b.stats.learned_costs.is_object());
  EXPECT_TRUE(b.stats.learned_costs["traced_exactly_everywhere"].get<bool>());
  for (const nlohmann::json& instance : b.stats.learned_costs["instances"]) {
    ASSERT_TRUE(instance.contains("eq8_predicted_ratio"));
    if (!instance["eq8_predicted_ratio"].is_null()) {
      EXPECT_GE(instance["eq8_predicted_ratio"].get<double>(), kLearnedPaysBelow);
    }
  }
  EXPECT_EQ(b.image.pixels, a.image.pixels);
  EXPECT_EQ(b.stats.eq8.traced_exactly, b.stats.shadow_rays);
  EXPECT_EQ(b.stats.probe_rays, 0u);
  EXPECT_EQ(b.stats.proxy_tests, 0u);
  EXPECT_EQ(b.stats.eq8.terms[0] + b.stats.eq8.terms[1] + b.stats.eq8.terms[2], 0u);

  // What the gate weighed: noise, costs and ray types for both instances, neither paying
  // here (eq. 8's term (a) adds 1/p1 - 1 to every free segment, a ball proxy costs 0.75 of
  // the fine ball's mesh in modelled work, and the probes add 16 queries of each per point).
  EXPECT_EQ(b.stats.learned_costs["instances"].size(), 2u);
  EXPECT_GT(b.stats.learned_costs["noise_per_segment"].get<double>(), 0);

  // Without the gate, eq. 8 probes and draws its terms at every point.
  adaptive.spp = 8, adaptive.shadow_rays = 1, adaptive.probe_passes = 0;
  adaptive.gate = false;
  const RenderResult e = render(s.scene, world, adaptive);
  EXPECT_TRUE(e.stats.learned_costs.is_null());
  EXPECT_EQ(e.stats.eq8.traced_exactly, 0u);
  EXPECT_GT(e.stats.probe_rays, 0u);
  EXPECT_GT(e.stats.eq8.terms[0], 0u);
}

}  // namespace
}  // namespace visproxy
