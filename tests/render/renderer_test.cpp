#include "visproxy/render/renderer.h"
#include "render/render_test_scenes.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <numbers>

#include "visproxy/core/errors.h"

#include "visproxy/mesh/sphere_set.h"
#include "test_support.h"

namespace visproxy {
namespace {

using testing::box;
using testing::quad;

// A diffuse plane z = 0 (albedo 0.5) under a 1 x 1 light at height 1 facing down, camera
// straight above looking down with a narrow field of view.
Scene plane_under_light(double light_x) {
  Scene scene;
  scene.meshes.push_back({"plane", {}, quad({-5, -5, 0}, {10, 0, 0}, {0, 10, 0}), {}});
  scene.instances.push_back({"plane", Eigen::Affine3d::Identity(), Color::Constant(0.5), {}});
  AreaLight light;
  light.radiance = Color(2.0, 1.0, 0.5);
  const Vertex c(light_x - 0.5, -0.5, 1.0), u(0, 1, 0), v(1, 0, 0);  // u x v points down
  light.triangles = {{c, c + u, c + u + v}, {c, c + u + v, c + v}};
  scene.lights.push_back(light);
  scene.camera.from = {0, 0, 0.5};
  scene.camera.at = {0, 0, 0};
  scene.camera.up = {0, 1, 0};
  scene.camera.fov_degrees = 2;
  scene.camera.width = scene.camera.height = 5;
  return scene;
}

// Lambert's formula for the irradiance at x (normal n) from a uniform polygon of radiance
// L: E = L / 2 * sum_i angle(v_i, v_i+1) * n . normalize(v_i x v_i+1), v_i = corner_i - x.
double lambert_irradiance(const Vertex& x, const Vertex& n, const std::vector<Vertex>& polygon) {
  double sum = 0;
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const Vertex a = (polygon[i] - x).normalized(), b = (polygon[(i + 1) % polygon.size()] - x).normalized();
    sum += std::acos(std::clamp(a.dot(b), -1.0, 1.0)) * n.dot(a.cross(b).normalized());
  }
  return std::abs(sum) / 2;
}

// Known answer: with nothing between, each pixel's mean over 8 independent renders lies
// within the 99.9 % Student-t interval (7 degrees of freedom: 5.41 standard errors) of
// albedo / pi * L * E from Lambert's formula (the pixel footprint is 0.004 wide; the
// irradiance changes by far less than the noise across it).
TEST(Renderer, PlaneUnderParallelogramLightMatchesLambertsFormula) {
  const Scene scene = plane_under_light(0.3);
  const RenderWorld world(scene, std::vector<MeshProxies>(scene.instances.size()));
  constexpr int runs = 8;
  std::vector<Image> images;
  for (int run = 0; run < runs; ++run)
    images.push_back(render(scene, world, {.spp = 256, .shadow_rays = 4, .seed = 100u + static_cast<unsigned>(run)}).image);
  const std::vector<Vertex> light = {{-0.2, -0.5, 1}, {-0.2, 0.5, 1}, {0.8, 0.5, 1}, {0.8, -0.5, 1}};
  const double tan_half = std::tan(std::numbers::pi / 180);
  int checked = 0;
  for (int py = 0; py < 5; ++py)
    for (int px = 0; px < 5; ++px) {
      // Camera looks down -z with up +y: right is +x... forward x up = (0,0,-1) x (0,1,0) = (1,0,0).
      const Vertex x((2 * (px + 0.5) / 5 - 1) * tan_half * 0.5, (1 - 2 * (py + 0.5) / 5) * tan_half * 0.5, 0);
      const double expected = 0.5 / std::numbers::pi * 2.0 * lambert_irradiance(x, {0, 0, 1}, light);
      double mean = 0, square = 0;
      for (const Image& image : images) mean += image.at(px, py).x() / runs;
      for (const Image& image : images) square += std::pow(image.at(px, py).x() - mean, 2);
      const double standard_error = std::sqrt(square / (runs - 1) / runs);
      EXPECT_LE(std::abs(mean - expected), 5.41 * standard_error) << px << "," << py << " mean " << mean << " expected " << expected;
      EXPECT_LT(standard_error, 0.01 * expected);  // the test is sharp: below 1 % noise
      // The other channels scale with the radiance.
      EXPECT_NEAR(images[0].at(px, py).y() / images[0].at(px, py).x(), 0.5, 1e-9);
      ++checked;
    }
  EXPECT_EQ(checked, 25);
}

TEST(Renderer, SameSeedSameImageWhateverTheThreads) {
  const Scene scene = plane_under_light(0.0);
  const RenderWorld world(scene, std::vector<MeshProxies>(scene.instances.size()));
  const RenderResult a = render(scene, world, {.spp = 4, .seed = 7});
  RenderResult b;
  {
    const tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    b = render(scene, world, {.spp = 4, .seed = 7});
  }
  const RenderResult c = render(scene, world, {.spp = 4, .seed = 8});
  EXPECT_EQ(a.image.pixels, b.image.pixels);
  EXPECT_NE(a.image.pixels, c.image.pixels);
  EXPECT_EQ(a.stats.passes, 4);
  EXPECT_EQ(a.stats.camera_samples, 4u * 25u);
}

// A scene for the modes' invariants: a floor, a ball with an outside box and an inside
// ball, a second ball squashed and turned (non-uniform scale) with a bounded-hull-like
// box, and `crowd` small boxes in a ring (each with its box as outside proxy; beyond 31
// instances ray-mask bits are shared). Image 96 x 64: 24 tiles of 16 x 16.
struct ModeScene {
  Scene scene;
  std::vector<MeshProxies> proxies;
};

ModeScene mode_scene(int crowd) {
  ModeScene s;
  s.scene.meshes.push_back({"floor", {}, quad({-6, -6, 0}, {12, 0, 0}, {0, 12, 0}), {}});
  s.scene.meshes.push_back({"ball", {}, sphere_set_mesh({{{0, 0, 0}, 1.0}}, 3), {}});
  s.scene.meshes.push_back({"cube", {}, box({-0.2, -0.2, 0}, {0.2, 0.2, 0.4}), {}});
  s.scene.instances.push_back({"floor", Eigen::Affine3d::Identity(), Color::Constant(0.6), {}});
  Eigen::Affine3d first = Eigen::Affine3d::Identity();
  first.translate(Vertex(-0.8, 0, 1.3));
  s.scene.instances.push_back({"ball", first, Color(0.7, 0.5, 0.3), {}});
  Eigen::Affine3d squashed = Eigen::Affine3d::Identity();
  squashed.translate(Vertex(1.4, 0.5, 0.8)).rotate(Eigen::AngleAxisd(0.6, Vertex(1, 1, 0).normalized())).scale(Vertex(1.2, 0.4, 0.7));
  s.scene.instances.push_back({"ball", squashed, Color(0.3, 0.6, 0.5), {}});
  for (int i = 0; i < crowd; ++i) {
    Eigen::Affine3d t = Eigen::Affine3d::Identity();
    const double angle = 2 * std::numbers::pi * i / crowd;
    t.translate(Vertex(3.5 * std::cos(angle), 3.5 * std::sin(angle), 0)).rotate(Eigen::AngleAxisd(angle, Vertex::UnitZ()));
    s.scene.instances.push_back({"cube", t, Color::Constant(0.5), {}});
  }
  AreaLight light;
  light.radiance = Color::Constant(6);
  const Vertex c(-0.5, -1.5, 4), u(0, 1.5, 0), v(1.5, 0, 0);
  light.triangles = {{c, c + u, c + u + v}, {c, c + u + v, c + v}};
  s.scene.lights.push_back(light);
  s.scene.camera.from = {0.5, -7, 5};
  s.scene.camera.at = {0, 0, 0.5};
  s.scene.camera.up = {0, 0, 1};
  s.scene.camera.fov_degrees = 50;
  s.scene.camera.width = 96;
  s.scene.camera.height = 64;
  s.proxies.resize(s.scene.instances.size());
  const InstanceProxy ball_box{ProxyKind::outside, "aabb", box({-1, -1, -1}, {1, 1, 1}), {}, true};
  const InstanceProxy ball_core{ProxyKind::inside, "inside:1", {}, {{{0, 0, 0}, 0.95}}, true};
  for (const std::size_t i : {std::size_t{1}, std::size_t{2}}) {
    s.proxies[i].outside = ball_box;
    s.proxies[i].inside = ball_core;
    s.proxies[i].stochastic = i == 1 ? ball_box : ball_core;
  }
  const InstanceProxy cube_box{ProxyKind::outside, "aabb", box({-0.25, -0.25, -0.05}, {0.25, 0.25, 0.45}), {}, true};
  for (std::size_t i = 3; i < s.proxies.size(); ++i) s.proxies[i].outside = s.proxies[i].stochastic = cube_box;
  return s;
}

// Every mode gives the same image whatever the number of threads, on an image of many tiles.
TEST(Renderer, EveryModeIsIndependentOfTheThreads) {
  const ModeScene s = mode_scene(8);
  const RenderWorld world(s.scene, s.proxies);
  std::vector<RenderOptions> modes;
  modes.push_back({.visibility = VisibilityMode::exact, .spp = 3, .shadow_rays = 2, .seed = 11});
  modes.push_back({.visibility = VisibilityMode::bounds, .spp = 3, .shadow_rays = 2, .seed = 11});
  modes.push_back({.visibility = VisibilityMode::stochastic, .probabilities = ProbabilityMode::adaptive, .probe_rays = 4,
                   .probe_passes = 2, .spp = 3, .shadow_rays = 2, .seed = 11});
  modes.push_back({.visibility = VisibilityMode::stochastic, .probabilities = ProbabilityMode::learned,
                   .estimator = StochasticEstimator::control_variate, .spp = 3, .shadow_rays = 2, .seed = 11});
  // Virtual point lights: exact (ray packets), occluder disks, and the control variate with
  // disks as V' and learned probabilities (the squashed ball's proxy is a sphere set).
  for (const VisibilityMode visibility : {VisibilityMode::exact, VisibilityMode::spheres, VisibilityMode::stochastic})
    modes.push_back({.integrator = IntegratorKind::vpl, .visibility = visibility, .probabilities = ProbabilityMode::learned,
                     .estimator = StochasticEstimator::control_variate, .spp = 2, .shadow_rays = 1, .seed = 11, .vpls = 48,
                     .bounces = 2});
  // Adaptive eq. 8 with VPLs, through its gate and without it.
  for (const bool gate : {true, false}) {
    modes.push_back({.integrator = IntegratorKind::vpl, .visibility = VisibilityMode::stochastic, .probabilities = ProbabilityMode::adaptive,
                     .probe_rays = 4, .probe_passes = 1, .spp = 2, .shadow_rays = 1, .seed = 11, .vpls = 48, .bounces = 2});
    modes.back().gate = gate;
  }
  for (const RenderOptions& options : modes) {
    const RenderResult many = render(s.scene, world, options);
    RenderResult one;
    {
      const tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
      one = render(s.scene, world, options);
    }
    EXPECT_EQ(many.image.pixels, one.image.pixels) << name_of(options.integrator) << " " << name_of(options.visibility) << " "
                                                    << name_of(options.probabilities) << (options.gate ? "" : " --no-gate");
    EXPECT_EQ(many.stats.to_json(), [&] {
      nlohmann::json j = one.stats.to_json();
      j["seconds"] = many.stats.seconds;
      return j;
    }());
  }
}

// A session continued in runs of 1, 2 and 3 passes gives one render's 6 passes bit for bit
// in every mode, the learned ones included (each pixel keeps what it learned between runs),
// and its stats add up; a run stops at options.spp whatever it asks for, and a run with a
// time limit renders at least one pass.
TEST(Renderer, SessionContinuedInRunsIsOneRender) {
  const ModeScene s = mode_scene(8);
  const RenderWorld world(s.scene, s.proxies);
  std::vector<RenderOptions> modes;
  modes.push_back({.visibility = VisibilityMode::exact, .spp = 6, .seed = 5});
  modes.push_back({.visibility = VisibilityMode::bounds, .spp = 6, .shadow_rays = 2, .seed = 5});
  modes.push_back({.visibility = VisibilityMode::stochastic, .probabilities = ProbabilityMode::adaptive, .probe_rays = 4,
                   .probe_passes = 2, .spp = 6, .seed = 5});
  modes.push_back({.visibility = VisibilityMode::stochastic, .probabilities = ProbabilityMode::optimal, .spp = 6, .seed = 5});
  modes.push_back({.visibility = VisibilityMode::stochastic, .probabilities = ProbabilityMode::learned,
                   .estimator = StochasticEstimator::control_variate, .spp = 6, .seed = 5});
  modes.push_back({.integrator = IntegratorKind::vpl, .visibility = VisibilityMode::stochastic,
                   .probabilities = ProbabilityMode::learned, .estimator = StochasticEstimator::control_variate, .spp = 6,
                   .seed = 5, .vpls = 32, .bounces = 2});
  for (const RenderOptions& options : modes) {
    const std::string mode = std::string(name_of(options.integrator)) + " " + std::string(name_of(options.visibility)) + " " +
                             std::string(name_of(options.probabilities));
    const RenderResult whole = render(s.scene, world, options);
    RenderSession session(s.scene, world, options);
    EXPECT_EQ(session.passes(), 0) << mode;
    EXPECT_EQ(session.run(1), 1) << mode;
    EXPECT_EQ(session.run(2), 2) << mode;
    const RenderResult halfway = session.result();
    EXPECT_EQ(halfway.stats.passes, 3) << mode;
    EXPECT_EQ(halfway.stats.camera_samples, 3u * 96u * 64u) << mode;
    EXPECT_EQ(session.run(100), 3) << mode;  // stops at options.spp
    EXPECT_EQ(session.run(1), 0) << mode;
    const RenderResult continued = session.result();
    EXPECT_EQ(continued.image.pixels, whole.image.pixels) << mode;
    EXPECT_NE(halfway.image.pixels, whole.image.pixels) << mode;
    EXPECT_EQ(continued.p1_map.pixels, whole.p1_map.pixels) << mode;
    EXPECT_EQ(continued.stats.to_json(), [&] {
      nlohmann::json j = whole.stats.to_json();
      j["seconds"] = continued.stats.seconds;
      return j;
    }()) << mode;
    EXPECT_GE(continued.stats.seconds, halfway.stats.seconds) << mode;
  }
  RenderSession timed(s.scene, world, {.spp = 1000, .seed = 5});
  EXPECT_EQ(timed.run(1000, 1e-9), 1);
}

// Bounds gives exact's image bit for bit: where the inside proofs fire, where proxies touch
// their mesh (the cubes' boxes hold them with 0.05 to spare, the balls' boxes touch them),
// beyond 31 instances and under a non-uniform scale; with one shadow ray per sample (every
// segment a point's first, answered without the light shaft) and with three (the later
// ones through the shaft).
TEST(Renderer, BoundsIsExactWithInsideProofsSharedMaskBitsAndSquashedInstances) {
  const ModeScene s = mode_scene(40);
  ASSERT_GT(s.scene.instances.size(), 31u);
  const RenderWorld world(s.scene, s.proxies);
  EXPECT_TRUE(world.notes().empty()) << world.notes().front();
  for (const int shadow_rays : {1, 3}) {
    const auto [a, b] = testing::exact_and_bounds(s.scene, world, {.spp = 4, .shadow_rays = shadow_rays, .seed = 17});
    EXPECT_EQ(a.image.pixels, b.image.pixels) << shadow_rays;
    EXPECT_GT(b.stats.bounds.occluded, 100u) << shadow_rays;
    EXPECT_GT(b.stats.bounds.unoccluded, 100u) << shadow_rays;
    EXPECT_GT(b.stats.bounds.traced, 0u) << shadow_rays;
    EXPECT_LT(b.stats.exact_tests, a.stats.exact_tests) << shadow_rays;
    if (shadow_rays == 1) {
      EXPECT_EQ(b.stats.bounds.shafts_culled, 0u);  // no shaft was formed
    }
  }
}

TEST(Renderer, OptionsThatCannotGiveACorrectImageAreRefused) {
  const Scene scene = plane_under_light(0.0);
  const RenderWorld world(scene, std::vector<MeshProxies>(scene.instances.size()));
  auto refused = [&](RenderOptions options) {
    try {
      render(scene, world, options);
    } catch (const Error& error) {
      return std::string(error.what());
    }
    return std::string();
  };
  EXPECT_NE(refused({.shadow_rays = 0}).find("shadow_rays"), std::string::npos);
  EXPECT_NE(refused({.spp = 0}).find("spp"), std::string::npos);
  EXPECT_NE(refused({.visibility = VisibilityMode::stochastic, .probabilities = ProbabilityMode::adaptive, .probability_floor = 0})
                .find("biased"),
            std::string::npos);
  EXPECT_NE(refused({.visibility = VisibilityMode::stochastic, .probabilities = ProbabilityMode::learned,
                     .estimator = StochasticEstimator::control_variate, .probability_floor = 0})
                .find("probability_floor"),
            std::string::npos);
  EXPECT_NE(refused({.visibility = VisibilityMode::stochastic, .probabilities = ProbabilityMode::learned}).find("control-variate"),
            std::string::npos);
  EXPECT_NE(refused({.visibility = VisibilityMode::stochastic, .probabilities = ProbabilityMode::optimal,
                     .estimator = StochasticEstimator::control_variate})
                .find("eq. 8"),
            std::string::npos);
  EXPECT_NE(refused({.visibility = VisibilityMode::stochastic, .probabilities = ProbabilityMode::optimal, .probability_floor = 0})
                .find("probability_floor"),
            std::string::npos);
  EXPECT_NE(refused({.visibility = VisibilityMode::stochastic, .probabilities = ProbabilityMode::adaptive, .probe_rays = 0})
                .find("probe"),
            std::string::npos);
  EXPECT_NE(refused({.probability_floor = 0.5}).find("1/3"), std::string::npos);
  EXPECT_NE(refused({.correction_scale = 0}).find("correction_scale"), std::string::npos);
  EXPECT_NE(refused({.seconds = -1}).find("seconds"), std::string::npos);
  // A zero floor with equal probabilities is fine: no term is left out.
  EXPECT_EQ(refused({.visibility = VisibilityMode::stochastic, .probability_floor = 0, .spp = 1}), "");
}

// Counted traversal: deterministic work figures, and the same answers as Embree's
// traversal up to float rounding of grazing rays.
TEST(Renderer, CountedRenderIsDeterministicAndAgreesWithEmbree) {
  Scene scene = plane_under_light(0.0);
  // A floating box between the plane and the light casts a shadow.
  scene.meshes.push_back({"box", {}, box({-0.1, -0.1, 0.4}, {0.1, 0.1, 0.6}), {}});
  scene.instances.push_back({"box", Eigen::Affine3d::Identity(), Color::Constant(0.5), {}});
  scene.camera.from = {0, 0.2, 3};
  scene.camera.fov_degrees = 60;
  scene.camera.width = scene.camera.height = 24;
  const std::vector<MeshProxies> none(scene.instances.size());
  const RenderWorld embree(scene, none), counted(scene, none, {.counting = true});
  const RenderOptions options{.spp = 4, .shadow_rays = 2, .seed = 3};
  const RenderResult a = render(scene, embree, options);
  const RenderResult b = render(scene, counted, options);
  const RenderResult c = render(scene, counted, options);
  EXPECT_FALSE(a.stats.counted);
  ASSERT_TRUE(b.stats.counted);
  EXPECT_GT(b.stats.traversal_steps, b.stats.shadow_rays);
  EXPECT_GT(b.stats.primitive_tests, 0u);
  EXPECT_EQ(b.stats.traversal_steps, c.stats.traversal_steps);
  EXPECT_EQ(b.stats.primitive_tests, c.stats.primitive_tests);
  EXPECT_EQ(b.image.pixels, c.image.pixels);
  std::size_t different = 0, shadowed = 0;
  for (std::size_t i = 0; i < a.image.pixels.size(); ++i) {
    different += a.image.pixels[i] != b.image.pixels[i];
    shadowed += a.image.pixels[i].x() < 0.5 * a.image.pixels[0].x();
  }
  EXPECT_GT(shadowed, 0u);                            // the box does cast a shadow
  EXPECT_LE(different, a.image.pixels.size() / 100);  // grazing rays only
}

}  // namespace
}  // namespace visproxy
