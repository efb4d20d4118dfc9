// The virtual-point-light integrator: light paths leave VPLs where the lights shine and
// carry the lights' flux; a furnace and a point light over a plane match their closed
// forms; grouped connections answer as single rays; the control variate with occluder
// disks as V' is unbiased, while the disks alone are not.

#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "visproxy/core/errors.h"
#include "visproxy/core/random.h"
#include "visproxy/mesh/sphere_set.h"
#include "visproxy/render/integrators/integrator.h"
#include "visproxy/render/renderer.h"
#include "render/render_test_scenes.h"
#include "visproxy/render/world/virtual_point_lights.h"
#include "visproxy/render/visibility/occluder_disks.h"

namespace visproxy {
namespace {

using testing::box;
using testing::quad;

AreaLight square_light(const Vertex& corner, const Vertex& u, const Vertex& v, const Color& radiance, bool two_sided = false) {
  AreaLight light;
  light.radiance = radiance;
  light.two_sided = two_sided;
  light.triangles = {{corner, corner + u, corner + u + v}, {corner, corner + u + v, corner + v}};
  return light;
}

// A floor (z = 0, instance 0) and a ceiling (z = 2, instance 1), 10^4 wide (a path from
// the light escapes between them with probability below 1e-7), with a 0.4 x 0.4
// light at z = 1 between them whose front faces down.
Scene floor_and_ceiling(bool two_sided) {
  Scene scene;
  scene.meshes.push_back({"floor", {}, quad({-5000, -5000, 0}, {10000, 0, 0}, {0, 10000, 0}), {}});
  scene.meshes.push_back({"ceiling", {}, quad({-5000, -5000, 2}, {10000, 0, 0}, {0, 10000, 0}), {}});
  scene.instances.push_back({"floor", Eigen::Affine3d::Identity(), Color(0.5, 0.4, 0.3), {}});
  scene.instances.push_back({"ceiling", Eigen::Affine3d::Identity(), Color::Constant(0.8), {}});
  // u x v = (0, 0.4, 0) x (0.4, 0, 0) points down.
  scene.lights.push_back(square_light({-0.2, -0.2, 1}, {0, 0.4, 0}, {0.4, 0, 0}, Color(3, 2, 1), two_sided));
  return scene;
}

// Light paths leave their lights on the side the light faces, and together carry its flux
// Le x area x pi (twice that for a two-sided light) to their first hits: with a floor and
// a ceiling too large to miss, every path of a one-sided light ends on the floor, and the
// VPLs' powers sum to the flux up to rounding. A two-sided light sends each path to either
// side with probability 1/2: the floor's share stays within 5 binomial standard errors.
TEST(VirtualPointLights, LeaveTheLightOnItsFrontAndCarryItsFlux) {
  for (const bool two_sided : {false, true}) {
    const Scene scene = floor_and_ceiling(two_sided);
    const RenderWorld world(scene, std::vector<MeshProxies>(scene.instances.size()));
    const int paths = 4000;
    const std::vector<VirtualPointLight> vpls = trace_virtual_point_lights(scene, world, {.paths = paths, .bounces = 1, .seed = 5});
    ASSERT_EQ(vpls.size(), static_cast<std::size_t>(paths));
    Color power = Color::Zero();
    int on_floor = 0;
    for (const VirtualPointLight& v : vpls) {
      power += v.power;
      on_floor += v.instance == 0 ? 1 : 0;
      EXPECT_EQ(v.bounce, 1);
      EXPECT_NEAR(v.normal.norm(), 1, 1e-12);
      // The normal faces the side the path came from: the light's plane z = 1; the path
      // travelled at least the gap between the planes (its connections' ends clear the
      // rounding of that length).
      EXPECT_GT(v.normal.dot(Vertex(0, 0, 1) - v.position), 0);
      EXPECT_GE(v.distance, 1 - 1e-6);
    }
    const Color flux = scene.lights[0].radiance * (0.16 * std::numbers::pi * (two_sided ? 2 : 1));
    EXPECT_LT((power - flux).norm(), 1e-9 * flux.norm()) << "two-sided " << two_sided;
    if (!two_sided) {
      EXPECT_EQ(on_floor, paths);
    } else {
      EXPECT_NEAR(on_floor, paths / 2, 5 * std::sqrt(paths * 0.25));
    }
    // Deterministic for a seed, and the seed matters.
    const auto again = trace_virtual_point_lights(scene, world, {.paths = paths, .bounces = 1, .seed = 5});
    const auto other = trace_virtual_point_lights(scene, world, {.paths = paths, .bounces = 1, .seed = 6});
    EXPECT_EQ(again.front().position, vpls.front().position);
    EXPECT_NE(other.front().position, vpls.front().position);
  }
}

// Second-bounce VPLs carry the first surface's albedo: a path from the floor goes up to the
// ceiling (it cannot meet the floor again), so with B = 2 every bounce-2 VPL lies on the
// ceiling with the power of its bounce-1 VPL times the floor's albedo.
TEST(VirtualPointLights, LaterBouncesCarryTheAlbedoOfTheSurfacesLeft) {
  const Scene scene = floor_and_ceiling(false);
  const RenderWorld world(scene, std::vector<MeshProxies>(scene.instances.size()));
  const std::vector<VirtualPointLight> vpls = trace_virtual_point_lights(scene, world, {.paths = 500, .bounces = 2, .seed = 9});
  int second = 0;
  for (std::size_t i = 0; i + 1 < vpls.size(); ++i) {
    if (vpls[i + 1].bounce != 2) continue;
    ++second;
    EXPECT_EQ(vpls[i].bounce, 1);
    EXPECT_EQ(vpls[i + 1].instance, 1);
    EXPECT_LT((vpls[i + 1].power - vpls[i].power.cwiseProduct(scene.instances[0].albedo)).norm(), 1e-12);
  }
  EXPECT_EQ(second, 500);
}

// The batched geometric term is the single one, bit for bit, light by light: the same
// facing answer and the same G, also for lights exactly in the shading point's tangent
// plane, behind it, facing away, and at the shading point itself (which faces nothing).
TEST(VirtualPointLights, BatchedGeometryIsTheSingleOne) {
  Random random(5);
  std::vector<VirtualPointLight> lights;
  const Vertex x(0.25, -0.5, 1e3), n = Vertex(0.3, -0.4, 1).normalized();
  for (int i = 0; i < 2000; ++i) {
    VirtualPointLight light{.position = Vertex::Zero(), .normal = Vertex::UnitZ(), .power = Color::Ones(), .brdf = Color::Ones()};
    const Vertex d(2 * random.uniform() - 1, 2 * random.uniform() - 1, 2 * random.uniform() - 1);
    light.position = x + (i % 10 == 0 ? d - d.dot(n) * n : d) * (i % 3 == 0 ? 1e-3 : 1.0);
    if (i % 97 == 0) light.position = x;
    light.normal = Vertex(2 * random.uniform() - 1, 2 * random.uniform() - 1, 2 * random.uniform() - 1).normalized();
    lights.push_back(light);
  }
  const VplArrays arrays(lights);
  std::vector<double> geometric(lights.size());
  std::vector<std::int64_t> faces(lights.size());
  vpl_geometry(x, n, arrays, geometric.data(), faces.data());
  int facing = 0;
  for (std::size_t i = 0; i < lights.size(); ++i) {
    const VplGeometry single = vpl_geometry(x, n, lights[i]);
    ASSERT_EQ(faces[i] != 0, single.faces) << i;
    ASSERT_EQ(geometric[i], single.faces ? single.geometric : 0.0) << i;
    facing += single.faces ? 1 : 0;
  }
  EXPECT_GT(facing, 200);
  EXPECT_LT(facing, 800);
}

// A point light over a plane: one given VPL at (-2, 0, 0.5) facing (1, 0, -1) / sqrt 2, no
// area light. The plane's radiance is albedo/pi x power x brdf x cos_x cos_v / d^2; a wall
// at x = -1 (y < 0, outside the camera's view) shadows exactly the half y < 0 of the
// patch the camera sees. Each pixel's mean over its jittered samples must lie between the
// least and the largest closed-form value over the pixel's footprint (the radiance is
// monotonic across a footprint this small), or be 0 in the shadow.
TEST(VplIntegrator, PointLightOverAPlaneMatchesTheClosedFormAndItsShadow) {
  Scene scene;
  scene.meshes.push_back({"plane", {}, quad({-5, -5, 0}, {10, 0, 0}, {0, 10, 0}), {}});
  scene.meshes.push_back({"wall", {}, box({-1.05, -3, 0}, {-1, 0, 1}), {}});
  const double albedo = 0.6;
  scene.instances.push_back({"plane", Eigen::Affine3d::Identity(), Color::Constant(albedo), {}});
  scene.instances.push_back({"wall", Eigen::Affine3d::Identity(), Color::Constant(0.5), {}});
  scene.camera.from = {0, 0, 1.5};
  scene.camera.at = {0, 0, 0};
  scene.camera.up = {0, 1, 0};
  scene.camera.fov_degrees = 40;
  scene.camera.width = scene.camera.height = 16;
  const RenderWorld world(scene, std::vector<MeshProxies>(scene.instances.size()));
  const VirtualPointLight light{{-2, 0, 0.5}, Vertex(1, 0, -1).normalized(), Color(2, 1, 0.5), Color::Constant(0.7 / std::numbers::pi), -1, 1};
  const std::vector<VirtualPointLight> lights = {light};
  const RenderResult result = render(scene, world, {.integrator = IntegratorKind::vpl, .spp = 8, .seed = 3, .vpl_clamp = 0,
                                                    .virtual_point_lights = &lights});
  auto closed_form = [&](const Vertex& x) {
    const Vertex w = light.position - x;
    const double d2 = w.squaredNorm(), d = std::sqrt(d2);
    return albedo / std::numbers::pi * light.brdf.x() * (w.z() / d) * (-light.normal.dot(w) / d) / d2;
  };
  const double half = std::tan(20 * std::numbers::pi / 180) * 1.5;  // half the patch's width
  int lit = 0, shadowed = 0;
  for (int py = 0; py < 16; ++py)
    for (int px = 0; px < 16; ++px) {
      double lo = 1e300, hi = 0;
      for (int corner = 0; corner < 4; ++corner) {
        const double x = (2.0 * (px + (corner & 1)) / 16 - 1) * half, y = (1 - 2.0 * (py + (corner >> 1)) / 16) * half;
        const double value = closed_form({x, y, 0});
        lo = std::min(lo, value), hi = std::max(hi, value);
      }
      const Color pixel = result.image.pixels[static_cast<std::size_t>(py * 16 + px)];
      if (py >= 8) {  // y < 0: behind the wall
        EXPECT_EQ(pixel.x(), 0) << px << " " << py;
        ++shadowed;
      } else {
        EXPECT_GE(pixel.x() / light.power.x(), lo * (1 - 1e-9)) << px << " " << py;
        EXPECT_LE(pixel.x() / light.power.x(), hi * (1 + 1e-9)) << px << " " << py;
        EXPECT_NEAR(pixel.y() / pixel.x(), 0.5, 1e-12);
        ++lit;
      }
    }
  EXPECT_EQ(lit, 128);
  EXPECT_EQ(shadowed, 128);
  EXPECT_EQ(result.stats.integrator["virtual_point_lights"], 1);
  EXPECT_EQ(result.stats.integrator["virtual_point_lights_given"], true);
}

// The white furnace, for a closed sphere: a diffuse sphere of radius R = 1 and albedo a
// around a small one-sided spherical light of radius r = 0.1 at its centre (radiance Le,
// flux P = pi Le A). On a sphere every surface element sees every other with the same
// form factor, so all light reflected more than once is uniform: with irradiance
// E1 = P / (4 pi R^2) from the light, the radiance after k reflections is
// P / (4 pi^2 R^2) a^k, and the VPL integrator (direct light plus B bounces of VPLs)
// must give P / (4 pi^2 R^2) (a + a^2 + ... + a^(B+1)). The mean over the image's pixels
// must lie within 4.9 standard errors of it (two-sided 1e-6) plus 0.5 % for the tessellation
// (20480 facets: the facets' distance to the centre and the form factor between facets
// differ from the sphere's by about 1e-3; measured: +0.05 % for B = 1 and 3, printed).
TEST(VplIntegrator, WhiteFurnaceMatchesTheClosedForm) {
  Scene scene;
  scene.meshes.push_back({"sphere", {}, sphere_set_mesh({{{0, 0, 0}, 1.0}}, 5), {}});
  const double a = 0.5;
  scene.instances.push_back({"sphere", Eigen::Affine3d::Identity(), Color::Constant(a), {}});
  const TriangleMesh lamp = sphere_set_mesh({{{0, 0, 0}, 0.1}}, 3);
  AreaLight light;
  double area = 0;
  for (const auto& t : lamp.triangles) {
    const std::array<Vertex, 3> corners = {lamp.positions[t[0]], lamp.positions[t[1]], lamp.positions[t[2]]};
    light.triangles.push_back(corners);
    area += 0.5 * (corners[1] - corners[0]).cross(corners[2] - corners[0]).norm();
    // The lamp emits outwards: its winding's normal points away from the centre.
    ASSERT_GT((corners[1] - corners[0]).cross(corners[2] - corners[0]).dot(corners[0]), 0);
  }
  light.radiance = Color::Ones();
  scene.lights.push_back(light);
  scene.camera.from = {0, 0, -0.3};
  scene.camera.at = {0, 0, -1};
  scene.camera.up = {0, 1, 0};
  scene.camera.fov_degrees = 90;
  scene.camera.width = scene.camera.height = 16;
  const RenderWorld world(scene, std::vector<MeshProxies>(1));
  const double flux = std::numbers::pi * area;
  for (const int bounces : {1, 3}) {
    double sum = 0;
    for (int k = 1; k <= bounces + 1; ++k) sum += std::pow(a, k);
    const double expected = flux / (4 * std::numbers::pi * std::numbers::pi) * sum;
    const RenderResult result = render(scene, world, {.integrator = IntegratorKind::vpl, .spp = 16, .shadow_rays = 16, .seed = 21,
                                                      .vpls = 512, .bounces = bounces, .vpl_seed = 4});
    double mean = 0, square = 0;
    for (const Color& c : result.image.pixels) mean += c.x();
    mean /= static_cast<double>(result.image.pixels.size());
    for (const Color& c : result.image.pixels) square += (c.x() - mean) * (c.x() - mean);
    const double pixels = static_cast<double>(result.image.pixels.size());
    const double error = std::sqrt(square / (pixels - 1) / pixels);
    std::printf("furnace, %d bounce(s): image mean %.6f, closed form %.6f (%+.3f %%), standard error %.2e, clamped %.2e\n", bounces,
                mean, expected, 100 * (mean / expected - 1), error, result.stats.integrator["clamped_energy_fraction"].get<double>());
    EXPECT_NEAR(mean, expected, 4.9 * error + 0.005 * expected) << bounces << " bounces";
    // Without the indirect light the image would be off by far more than the tolerance.
    EXPECT_GT(std::abs(mean - flux / (4 * std::numbers::pi * std::numbers::pi) * a), 0.2 * expected);
  }
}

// Bounds with VPLs gives the exact image bit for bit: its light samples use the proofs of a
// box's outside proxy, its VPL connections are traced as exact traces them (packets or
// single rays alike).
TEST(VplIntegrator, BoundsGivesTheExactImage) {
  Scene scene = floor_and_ceiling(false);
  scene.meshes.push_back({"box", {}, box({-0.3, -0.3, 0.2}, {0.3, 0.3, 0.5}), {}});
  scene.instances.push_back({"box", Eigen::Affine3d::Identity(), Color::Constant(0.6), {}});
  scene.camera.from = {0, -3, 1.5};
  scene.camera.at = {0, 0, 0.3};
  scene.camera.up = {0, 0, 1};
  scene.camera.fov_degrees = 50;
  scene.camera.width = 40;
  scene.camera.height = 24;
  std::vector<MeshProxies> proxies(scene.instances.size());
  proxies[2].outside = InstanceProxy{ProxyKind::outside, "aabb", box({-0.35, -0.35, 0.15}, {0.35, 0.35, 0.55}), {}, true};
  const RenderWorld world(scene, proxies);
  for (const bool group : {true, false}) {
    RenderOptions options{.integrator = IntegratorKind::vpl, .spp = 2, .shadow_rays = 2, .seed = 5, .vpls = 64, .bounces = 2};
    options.group_connections = group;
    const RenderResult exact = render(scene, world, options);
    options.visibility = VisibilityMode::bounds;
    const RenderResult bounds = render(scene, world, options);
    EXPECT_EQ(exact.image.pixels, bounds.image.pixels) << "group " << group;
    EXPECT_GT(bounds.stats.bounds.unoccluded, 0u);
    EXPECT_GT(bounds.stats.vpl_connections, 0u);
  }
}

TEST(VplIntegrator, OptionsThatCannotGiveACorrectImageAreRefused) {
  const Scene scene = floor_and_ceiling(false);
  const RenderWorld world(scene, std::vector<MeshProxies>(scene.instances.size()));
  auto refused = [&](RenderOptions options) {
    options.integrator = IntegratorKind::vpl;
    try {
      render(scene, world, options);
    } catch (const Error& error) {
      return std::string(error.what());
    }
    return std::string();
  };
  EXPECT_NE(refused({.vpls = 0}).find("vpls"), std::string::npos);
  EXPECT_NE(refused({.bounces = 0}).find("bounces"), std::string::npos);
  EXPECT_NE(refused({.vpl_clamp = -1}).find("vpl_clamp"), std::string::npos);
  EXPECT_NE(refused({.vpl_clamp = std::nan("")}).find("vpl_clamp"), std::string::npos);
  std::vector<VirtualPointLight> bad = {{{0, 0, 1}, {0, 0, -1}, Color(1, std::nan(""), 1), Color::Ones(), -1, 1}};
  EXPECT_NE(refused({.virtual_point_lights = &bad}).find("virtual point lights"), std::string::npos);
  bad[0].power = Color::Ones();
  bad[0].normal = {0, 0, -2};  // not a unit vector
  EXPECT_NE(refused({.virtual_point_lights = &bad}).find("unit normals"), std::string::npos);
  bad[0].normal = {0, 0, -1};
  bad[0].bounce = 0;
  EXPECT_NE(refused({.virtual_point_lights = &bad}).find("bounce"), std::string::npos);
  bad[0].bounce = 1;
  bad[0].distance = -1;
  EXPECT_NE(refused({.virtual_point_lights = &bad}).find("distance"), std::string::npos);
  bad[0].distance = 0;
  EXPECT_EQ(refused({.spp = 1, .virtual_point_lights = &bad}), "");
}

// Grouped queries (Embree packets) answer every segment as a single query does: 40 boxes
// under random rotations (mask bits shared beyond 31), 1000 origins with 37 ends each (not
// a multiple of the packet width), and filters that skip, keep one, or keep a set of bits.
TEST(RenderWorld, GroupedQueriesAnswerAsSingleOnes) {
  Scene scene;
  scene.meshes.push_back({"box", {}, box({-0.3, -0.3, -0.3}, {0.3, 0.3, 0.3}), {}});
  Random random(77);
  for (int i = 0; i < 40; ++i) {
    Eigen::Affine3d t = Eigen::Affine3d::Identity();
    t.translate(Vertex(4 * random.uniform() - 2, 4 * random.uniform() - 2, 4 * random.uniform() - 2))
        .rotate(Eigen::AngleAxisd(6 * random.uniform(), Vertex(random.uniform(), random.uniform(), 1).normalized()));
    scene.instances.push_back({"box", t, Color::Constant(0.5), {}});
  }
  scene.lights.push_back(square_light({-0.1, -0.1, 5}, {0, 0.2, 0}, {0.2, 0, 0}, Color::Ones()));
  const RenderWorld world(scene, std::vector<MeshProxies>(scene.instances.size()));
  ASSERT_GE(world.packet_width(), 1);
  const std::vector<InstanceFilter> filters = {
      {}, {.skip = 3, .only = -1}, {.skip = -1, .only = 35}, {.skip = -1, .only = -1, .bits = instance_bit(2) | instance_bit(7)}};
  int blocked = 0, total = 0;
  for (int o = 0; o < 1000; ++o) {
    const Vertex from(6 * random.uniform() - 3, 6 * random.uniform() - 3, 6 * random.uniform() - 3);
    std::vector<Vertex> ends;
    for (int e = 0; e < 37; ++e) ends.emplace_back(6 * random.uniform() - 3, 6 * random.uniform() - 3, 6 * random.uniform() - 3);
    const InstanceFilter& filter = filters[static_cast<std::size_t>(o) % filters.size()];
    std::vector<std::uint8_t> grouped(ends.size(), 7);
    world.mesh_blocks(from, ends, grouped, filter);
    for (std::size_t e = 0; e < ends.size(); ++e) {
      const bool single = world.mesh_blocks(from, ends[e], filter);
      ASSERT_EQ(grouped[e] != 0, single) << "origin " << o << " end " << e;
      ASSERT_LE(grouped[e], 1);
      blocked += single ? 1 : 0;
      ++total;
    }
  }
  // Both answers occur often enough for the comparison to mean something.
  EXPECT_GT(blocked, total / 10);
  EXPECT_LT(blocked, total * 9 / 10);
  std::vector<std::uint8_t> wrong_size(3);
  EXPECT_THROW(world.mesh_blocks(Vertex::Zero(), std::vector<Vertex>(4, Vertex::Ones()), wrong_size), Error);
}

// A floor (instance 0, traced exactly: it has no proxy) under VPLs at z = 5 facing down,
// and a ball of radius 1 at (0, 0, 2) (instance 1) whose sphere-set proxy is off centre
// (0.3, 0, 2), radius 0.8: the occluder disks are wrong for some connections both ways.
struct DiskScene {
  Scene scene;
  std::vector<MeshProxies> proxies;
  std::vector<VirtualPointLight> lights;
};

DiskScene disk_scene() {
  DiskScene s;
  s.scene.meshes.push_back({"floor", {}, quad({-4, -4, 0}, {8, 0, 0}, {0, 8, 0}), {}});
  s.scene.meshes.push_back({"ball", {}, sphere_set_mesh({{{0, 0, 2}, 1.0}}, 3), {}});
  s.scene.instances.push_back({"floor", Eigen::Affine3d::Identity(), Color::Constant(0.5), {}});
  s.scene.instances.push_back({"ball", Eigen::Affine3d::Identity(), Color::Constant(0.5), {}});
  s.proxies.resize(2);
  s.proxies[1].stochastic = InstanceProxy{ProxyKind::general, "spheres:1", {}, {{{0.3, 0, 2}, 0.8}}, false};
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j)
      s.lights.push_back({{-1 + 0.5 * i, -1 + 0.5 * j, 5}, {0, 0, -1}, Color::Constant(0.4), Color::Constant(1 / std::numbers::pi), -1, 1});
  s.scene.camera.from = {0, -3.2, 0.6};
  s.scene.camera.at = {0, 0, 0};
  s.scene.camera.up = {0, 0, 1};
  s.scene.camera.fov_degrees = 70;
  s.scene.camera.width = s.scene.camera.height = 8;
  return s;
}

// Paired renders (same seed: same camera samples; the estimator draws from its own stream)
// of exact and stochastic visibility with fixed VPLs: per pixel, the difference D has mean
// 0 exactly when the estimate is unbiased. Over 48 seeds the mean D over the penumbra
// pixels must stay within 5.6 standard errors (Student t, 47 degrees of freedom, two-sided
// 1e-6); the smallest bias the test detects with probability 0.9, (5.6 + 1.3) standard
// errors, must be below 3 % of the penumbra's radiance (printed). The occluder disks
// alone, biased by design, must fail the same check: the test can tell.
TEST(VplIntegrator, ControlVariateWithOccluderDisksIsUnbiasedAndTheDisksAloneAreNot) {
  const DiskScene s = disk_scene();
  const RenderWorld world(s.scene, s.proxies);
  constexpr int seeds = 48;
  constexpr double critical = 5.6, power = 1.3;
  struct Variant {
    std::string label;
    VisibilityMode visibility;
    ProbabilityMode probabilities;
    bool biased;
  };
  for (const Variant& variant : {Variant{"control variate, equal", VisibilityMode::stochastic, ProbabilityMode::equal, false},
                                 Variant{"control variate, learned", VisibilityMode::stochastic, ProbabilityMode::learned, false},
                                 Variant{"occluder disks alone", VisibilityMode::spheres, ProbabilityMode::equal, true}}) {
    const std::size_t n = 64;
    std::vector<std::vector<double>> exact(seeds), difference(seeds);
    for (int seed = 0; seed < seeds; ++seed) {
      RenderOptions options{.integrator = IntegratorKind::vpl, .spp = 16, .seed = 500u + static_cast<unsigned>(seed),
                            .vpl_clamp = 0, .virtual_point_lights = &s.lights};
      const Image a = render(s.scene, world, options).image;
      options.visibility = variant.visibility;
      options.estimator = StochasticEstimator::control_variate;
      options.probabilities = variant.probabilities;
      options.correction_scale = 0.5;
      options.gate = false;  // the estimator itself (here its corrections would not pay)
      const RenderResult b = render(s.scene, world, options);
      ASSERT_TRUE(all_finite(b.image));
      if (variant.visibility == VisibilityMode::stochastic) {
        EXPECT_GT(b.stats.disks.tests, 0u);
        EXPECT_GT(b.stats.control_variate.after_miss, 0u);
        EXPECT_GT(b.stats.control_variate.after_hit, 0u);
      }
      for (std::size_t i = 0; i < n; ++i) {
        exact[seed].push_back(a.pixels[i].x());
        difference[seed].push_back(b.image.pixels[i].x() - a.pixels[i].x());
      }
    }
    std::vector<double> exact_mean(n, 0.0);
    double brightest = 0;
    for (std::size_t i = 0; i < n; ++i) {
      for (int seed = 0; seed < seeds; ++seed) exact_mean[i] += exact[seed][i] / seeds;
      brightest = std::max(brightest, exact_mean[i]);
    }
    std::vector<std::size_t> penumbra;
    double radiance = 0;
    for (std::size_t i = 0; i < n; ++i)
      if (exact_mean[i] > 0.05 * brightest && exact_mean[i] < 0.95 * brightest) penumbra.push_back(i), radiance += exact_mean[i];
    ASSERT_GE(penumbra.size(), 8u);
    radiance /= static_cast<double>(penumbra.size());
    std::vector<double> d(seeds, 0.0);
    for (int seed = 0; seed < seeds; ++seed)
      for (const std::size_t i : penumbra) d[seed] += difference[seed][i] / static_cast<double>(penumbra.size());
    double mean = 0, square = 0;
    for (const double v : d) mean += v / seeds;
    for (const double v : d) square += (v - mean) * (v - mean);
    const double error = std::sqrt(square / (seeds - 1) / seeds);
    std::printf("%-26s penumbra pixels %2zu, mean D %+.3e +- %.2e, detectable bias %.2f %% of %.3e\n", variant.label.c_str(),
                penumbra.size(), mean, error, 100 * (critical + power) * error / radiance, radiance);
    if (variant.biased) {
      EXPECT_GT(std::abs(mean), critical * error) << variant.label;
    } else {
      EXPECT_LE(std::abs(mean), critical * error + 1e-12) << variant.label;
      EXPECT_LT((critical + power) * error, 0.03 * radiance) << variant.label;
      EXPECT_GT(error, 0) << variant.label;  // the corrections did work
    }
  }
}

// A crowd of 60 instances (beyond the 31 mask bits) far from the origin, each with a
// sphere set of one ball sticking out of its mesh's box, one ball the floor cuts (shading
// points inside it) and four specks of radius 1e-4 (the single-precision test's coarsest
// cones), over a floor without one. Disks made lazily through the instance tree give the
// images of every disk made at each point, bit for bit, in every mode that uses disks.
struct CrowdScene {
  Scene scene;
  std::vector<MeshProxies> proxies;
};

CrowdScene disk_crowd(const Vertex& offset, bool one_ball = false) {
  CrowdScene c;
  c.scene.meshes.push_back({"floor", {}, quad(offset + Vertex(-6, -6, 0), {12, 0, 0}, {0, 12, 0}), {}});
  c.scene.meshes.push_back({"ball", {}, sphere_set_mesh({{{0, 0, 0.6}, 0.4}}, 2), {}});
  c.scene.instances.push_back({"floor", Eigen::Affine3d::Identity(), Color::Constant(0.5), {}});
  c.proxies.resize(1);
  Random random(3);
  for (int i = 0; i < 60; ++i) {
    Eigen::Affine3d t = Eigen::Affine3d::Identity();
    t.translate(offset + Vertex(1.4 * (i % 8) - 5, 1.4 * (i / 8) - 5, 0)).rotate(Eigen::AngleAxisd(0.3 * i, Vertex::UnitZ()));
    c.scene.instances.push_back({"ball", t, Color::Constant(0.6), {}});
    std::vector<Sphere> balls = {{{0.1, 0, 0.7}, 0.55}, {{0, 0, 0.05}, 0.2}};
    for (int k = 0; k < 4; ++k) balls.push_back({{random.uniform() - 0.5, random.uniform() - 0.5, 0.3 + random.uniform()}, 1e-4});
    if (one_ball) balls = {balls[i % 3 == 0 ? 0 : 2 + i % 4]};  // a cluster of one: its bound is the ball, grown by 2^-40
    MeshProxies p;
    p.stochastic = InstanceProxy{ProxyKind::general, "spheres:6", {}, balls, false};
    c.proxies.push_back(p);
  }
  AreaLight light;
  light.radiance = Color::Constant(20);
  const Vertex corner = offset + Vertex(-1, -1, 6), u(0, 2, 0), v(2, 0, 0);
  light.triangles = {{corner, corner + u, corner + u + v}, {corner, corner + u + v, corner + v}};
  c.scene.lights.push_back(light);
  c.scene.camera.from = offset + Vertex(0, -9, 5);
  c.scene.camera.at = offset;
  c.scene.camera.up = {0, 0, 1};
  c.scene.camera.fov_degrees = 60;
  c.scene.camera.width = 48, c.scene.camera.height = 32;
  return c;
}

TEST(OccluderDisks, LazyDisksGiveTheImagesOfEveryDisk) {
  for (const Vertex& offset : {Vertex(0, 0, 0), Vertex(2.0e5, -3.0e5, 1.0e4)}) {
    const CrowdScene c = disk_crowd(offset);
    const RenderWorld world(c.scene, c.proxies);
    for (const SelfShadow self : {SelfShadow::none, SelfShadow::heuristic, SelfShadow::exact})
      for (const bool clusters : {true, false})
        for (const VisibilityMode visibility : {VisibilityMode::spheres, VisibilityMode::stochastic}) {
          // Equal probabilities: with learned ones the control variate would not pay on this
          // crowd of cheap meshes and many balls, and the render would trace exactly.
          RenderOptions options{.integrator = IntegratorKind::vpl, .visibility = visibility, .probabilities = ProbabilityMode::equal,
                                .estimator = StochasticEstimator::control_variate, .spp = 2, .seed = 7, .vpls = 64, .bounces = 2};
          options.self_shadow = self, options.disk_clusters = clusters;
          options.disk_lazy_from = std::size_t{1} << 30;  // every disk at every point
          const RenderResult every = render(c.scene, world, options);
          options.disk_lazy_from = 1;
          const RenderResult lazy = render(c.scene, world, options);
          const std::string label = std::string(name_of(visibility)) + " " + std::string(name_of(self)) +
                                    (clusters ? " clusters" : " no clusters") + " offset " + std::to_string(offset.x());
          EXPECT_EQ(every.image.pixels, lazy.image.pixels) << label;
          EXPECT_LT(lazy.stats.disks.tests, every.stats.disks.tests) << label;  // the tree left disks untested
          EXPECT_GT(lazy.stats.disks.tests, 0u) << label;
          EXPECT_EQ(every.stats.disks.clusters, 0u) << label;  // no tree to give clusters
          EXPECT_GT(lazy.stats.disks.clusters, 0u) << label;
        }
    // The direct integrator's shadow rays through the same disks.
    RenderOptions direct{.visibility = VisibilityMode::spheres, .spp = 2, .shadow_rays = 3, .seed = 7};
    direct.disk_lazy_from = std::size_t{1} << 30;
    const RenderResult every = render(c.scene, world, direct);
    direct.disk_lazy_from = 1;
    EXPECT_EQ(every.image.pixels, render(c.scene, world, direct).image.pixels);
  }
}

// Segments that graze the specks' cones, where single precision errs most: one point's
// lazy disks (through the tree) answer as all of its disks do, segment by segment and in
// groups, with rays at angles from the cone's edge of -1e-3 to 1e-3 radians. With one
// ball per instance each cluster's bound is its ball: the cone a lazy point tests
// before it makes a cluster's disks is then as narrow as it can be, and a segment just
// inside the ball's cone must still reach the disk.
void expect_lazy_disks_answer_as_every_disk_at_the_cones_edges(bool one_ball) {
  SCOPED_TRACE(one_ball ? "one ball per cluster" : "six balls per cluster");
  const CrowdScene c = disk_crowd(Vertex(2.0e5, -3.0e5, 1.0e4), one_ball);
  const RenderWorld world(c.scene, c.proxies);
  const std::size_t instances = c.scene.instances.size();
  const OccluderDiskIndex lazy_index(world, instances, 1), every_index(world, instances, std::size_t{1} << 30);
  ASSERT_TRUE(lazy_index.lazy());
  ASSERT_FALSE(every_index.lazy());
  Random random(11);
  std::size_t hidden = 0, shown = 0;
  for (int point = 0; point < 40; ++point) {
    SurfaceHit hit;
    hit.instance = 0;
    hit.normal = Vertex::UnitZ();
    hit.position = Vertex(2.0e5, -3.0e5, 1.0e4) + Vertex(10 * random.uniform() - 5, 10 * random.uniform() - 5, 1e-3);
    PointDisks lazy, every;
    lazy.begin(lazy_index, hit, hit.position, false, true, 4096, true);
    every.begin(every_index, hit, hit.position, false, true, 4096, true);
    std::vector<Vertex> ends;
    for (std::size_t i = 1; i < instances; ++i)
      for (const Sphere& ball : world.occluder_spheres(i)) {
        const Vertex v = ball.center - hit.position;
        const double t = v.norm();
        if (t <= ball.radius || v.z() <= 0) continue;
        const double gamma = std::asin(ball.radius / t);
        const Vertex side = v.cross(Vertex(random.uniform(), random.uniform(), random.uniform())).normalized();
        for (const double off : {-1e-3, -1e-5, -1e-7, 0.0, 1e-7, 1e-5, 1e-3}) {
          const Eigen::AngleAxisd turn(gamma + off, side);
          ends.push_back(hit.position + (turn * v) * (1.0 + 2.0 * random.uniform()));
        }
      }
    std::uint64_t tests = 0;
    std::vector<std::uint8_t> a(ends.size()), b(ends.size());
    lazy.occludes(ends, a, tests);
    every.occludes(ends, b, tests);
    for (std::size_t k = 0; k < ends.size(); ++k) {
      ASSERT_EQ(a[k], b[k]) << "point " << point << " segment " << k;
      EXPECT_EQ(lazy.occludes(ends[k], tests), b[k] != 0) << "point " << point << " segment " << k;
      (b[k] ? hidden : shown) += 1;
    }
  }
  EXPECT_GT(hidden, one_ball ? 400u : 1000u);
  EXPECT_GT(shown, one_ball ? 400u : 1000u);
}

TEST(OccluderDisks, LazyDisksAnswerAsEveryDiskAtTheConesEdges) { expect_lazy_disks_answer_as_every_disk_at_the_cones_edges(false); }

TEST(OccluderDisks, LazyDisksAnswerAsEveryDiskAtTheBoundsEdges) { expect_lazy_disks_answer_as_every_disk_at_the_cones_edges(true); }

// The learned control variate with occluder disks decides for the whole scene, before the
// render, whether it can pay. On the crowd (60 instances of a 642-triangle ball, 360 balls
// made per point, 64 VPLs, far from the origin) the disks' set-up and tests cost more than
// the meshes: the render traces every segment exactly and gives exact's image bit for bit,
// without a disk test. Over the disk scene's ball (1280 triangles) with a centred ball of
// proxy it keeps the control variate, whose corrections then run; with the off-centre ball
// of the unbiasedness test it would not.
TEST(VplIntegrator, LearnedControlVariateTracesExactlyWhereItsDisksCannotPay) {
  const CrowdScene c = disk_crowd(Vertex(2.0e5, -3.0e5, 1.0e4));
  const RenderWorld world(c.scene, c.proxies);
  RenderOptions options{.integrator = IntegratorKind::vpl, .spp = 4, .seed = 9, .vpls = 64, .bounces = 2};
  const RenderResult exact = render(c.scene, world, options);
  options.visibility = VisibilityMode::stochastic;
  options.estimator = StochasticEstimator::control_variate;
  options.probabilities = ProbabilityMode::learned;
  const RenderResult learned = render(c.scene, world, options);
  ASSERT_TRUE(learned.stats.disk_gate.is_object());
  std::printf("crowd: %s\n", learned.stats.disk_gate.dump().c_str());
  EXPECT_TRUE(learned.stats.disk_gate["traced_exactly_everywhere"].get<bool>());
  EXPECT_GE(learned.stats.disk_gate["work_ratio"].get<double>() * learned.stats.disk_gate["variance_ratio"].get<double>(),
            kLearnedPaysBelow);
  EXPECT_EQ(learned.image.pixels, exact.image.pixels);
  EXPECT_EQ(learned.stats.disks.tests, 0u);
  EXPECT_EQ(learned.stats.exact_tests, exact.stats.exact_tests);
  EXPECT_EQ(learned.stats.control_variate.traced_exactly, learned.stats.exact_tests);
  EXPECT_TRUE(exact.stats.disk_gate.is_null());

  DiskScene s = disk_scene();
  s.proxies[1].stochastic->spheres = {{{0, 0, 2}, 0.95}};  // centred: the disks are wrong only near the rim
  const RenderWorld ball_world(s.scene, s.proxies);
  RenderOptions ball{.integrator = IntegratorKind::vpl, .visibility = VisibilityMode::stochastic, .probabilities = ProbabilityMode::learned,
                     .estimator = StochasticEstimator::control_variate, .spp = 8, .seed = 3, .virtual_point_lights = &s.lights};
  ball.correction_scale = 0.25;  // the default with VPLs
  const RenderResult kept = render(s.scene, ball_world, ball);
  ASSERT_TRUE(kept.stats.disk_gate.is_object());
  std::printf("ball: %s\n", kept.stats.disk_gate.dump().c_str());
  EXPECT_FALSE(kept.stats.disk_gate["traced_exactly_everywhere"].get<bool>());
  EXPECT_LT(kept.stats.disk_gate["work_ratio"].get<double>() * kept.stats.disk_gate["variance_ratio"].get<double>(), kLearnedPaysBelow);
  EXPECT_GT(kept.stats.disks.tests, 0u);
  EXPECT_GT(kept.stats.control_variate.after_miss + kept.stats.control_variate.after_hit, 0u);
  DiskScene off = disk_scene();
  off.proxies[1].stochastic->spheres = {{{1.5, 0, 2}, 0.8}};  // beside the ball: wrong for most connections it meets
  const RenderWorld off_world(off.scene, off.proxies);
  const RenderResult gated = render(off.scene, off_world, ball);
  std::printf("ball beside the mesh: %s\n", gated.stats.disk_gate.dump().c_str());
  // Not by a hair: the variance x work product is a quarter beyond the threshold.
  EXPECT_GT(gated.stats.disk_gate["variance_ratio"].get<double>() * gated.stats.disk_gate["work_ratio"].get<double>(),
            1.25 * kLearnedPaysBelow);
  EXPECT_TRUE(gated.stats.disk_gate["traced_exactly_everywhere"].get<bool>());
  EXPECT_EQ(gated.stats.disks.tests, 0u);
}

// With occluder disks as V', segments to area lights are traced exactly: over the disk
// scene lit by an area light and no VPLs, the control variate's image is exact's, bit for
// bit, with probabilities equal or learned; with VPLs it is not (the connections are
// estimated).
TEST(VplIntegrator, ControlVariateTracesSegmentsToLightsExactly) {
  DiskScene s = disk_scene();
  s.scene.lights.push_back(square_light({-0.5, -0.5, 4}, {0, 1, 0}, {1, 0, 0}, Color::Constant(5)));
  const RenderWorld world(s.scene, s.proxies);
  const std::vector<VirtualPointLight> none;
  for (const bool vpls : {false, true})
    for (const ProbabilityMode probabilities : {ProbabilityMode::equal, ProbabilityMode::learned}) {
      RenderOptions options{.integrator = IntegratorKind::vpl, .spp = 4, .shadow_rays = 2, .seed = 4,
                            .virtual_point_lights = vpls ? &s.lights : &none};
      const RenderResult exact = render(s.scene, world, options);
      options.visibility = VisibilityMode::stochastic;
      options.estimator = StochasticEstimator::control_variate;
      options.probabilities = probabilities;
      options.correction_scale = 0.25;
      const RenderResult estimate = render(s.scene, world, options);
      const std::string label = std::string(vpls ? "VPLs " : "no VPLs ") + std::string(name_of(probabilities));
      if (vpls) {
        EXPECT_NE(estimate.image.pixels, exact.image.pixels) << label;
        EXPECT_GT(estimate.stats.disks.tests, 0u) << label;
      } else {
        EXPECT_EQ(estimate.image.pixels, exact.image.pixels) << label;
        EXPECT_EQ(estimate.stats.disks.tests, 0u) << label;
        EXPECT_GT(estimate.stats.shadow_rays, 0u) << label;
      }
    }
}

// What an integrator reports each segment to be worth (PointVisibility::contributions) is
// what the segment adds to the luminance of the point's value when visible: with every
// segment answered 0 or 1 at random, the luminance of the value is the sum of the reported
// contributions of the segments answered 1, at 200 points of the disk scene under an area
// light and 25 VPLs, for the direct and the VPL integrator.
class RecordingAnswers final : public PointVisibility {
 public:
  void begin(const ShadingPoint&) override { answers.clear(), worth.clear(); }
  double to_light(const Vertex&) override { return draw(); }
  double connection(const Vertex&) override { return draw(); }
  bool wants_contributions() const override { return true; }
  void contributions(std::span<const double> luminance) override { worth.assign(luminance.begin(), luminance.end()); }
  std::vector<double> answers, worth;

 private:
  double draw() {
    answers.push_back(random_.uniform() < 0.5 ? 0.0 : 1.0);
    return answers.back();
  }
  Random random_{17};
};

TEST(Integrators, ReportWhatEachSegmentIsWorth) {
  DiskScene s = disk_scene();
  s.scene.lights.push_back(square_light({-0.5, -0.5, 4}, {0, 1, 0}, {1, 0, 0}, Color(5, 3, 1)));
  s.scene.instances[1].albedo = Color(0.2, 0.5, 0.8);
  const RenderWorld world(s.scene, s.proxies);
  const LightSampler lights(s.scene);
  for (const IntegratorKind kind : {IntegratorKind::direct, IntegratorKind::vpl}) {
    const RenderOptions options{.integrator = kind, .shadow_rays = 3, .virtual_point_lights = &s.lights};
    const std::unique_ptr<Integrator> integrator = make_integrator(IntegratorContext{s.scene, world, options, lights});
    RecordingAnswers answers;
    RenderStats stats;
    PixelRandom choices(1, 0, 0), random(2, 0, 0);
    double p1_sum = 0, p1_count = 0;
    int points = 0;
    for (int i = 0; i < 1000 && points < 200; ++i) {
      const double x = -3 + 6 * random.uniform(), y = -3 + 6 * random.uniform();
      const std::optional<SurfaceHit> hit = world.intersect(Vertex(x, y, 6), Vertex(0, 0, -1));
      if (!hit || hit->light >= 0) continue;
      const ShadingPoint point{.pixel = 0, .pass = 0, .hit = &*hit,
                               .position = hit->position + world.surface_offset(hit->position, hit->distance) * hit->normal,
                               .choices = &choices, .stats = &stats, .p1_sum = &p1_sum, .p1_count = &p1_count};
      const Color brdf = s.scene.instances[static_cast<std::size_t>(hit->instance)].albedo / std::numbers::pi;
      answers.begin(point);
      const double value = integrator->shade(point, brdf, random, answers).mean();
      answers.end();
      ASSERT_EQ(answers.worth.size(), answers.answers.size()) << name_of(kind);
      if (answers.answers.empty()) continue;  // no light or VPL in front of the point
      ++points;
      double sum = 0, scale = 0;
      for (std::size_t k = 0; k < answers.worth.size(); ++k) sum += answers.answers[k] * answers.worth[k], scale += answers.worth[k];
      EXPECT_GT(scale, 0) << name_of(kind);
      EXPECT_NEAR(value, sum, 1e-12 * scale) << name_of(kind) << " point " << points;
    }
    EXPECT_EQ(points, 200) << name_of(kind);
  }
}

// Self-shadowing (occluding-spheres §4.2), on a floor whose own sphere set is one ball of
// radius 0.4 at height 0.5 over the point the camera sees, under a light straight above:
// with `none` the ball shadows the floor, with `heuristic` it is skipped (t = 0.5 < 2R),
// with `exact` the floor's mesh is traced instead (nothing shadows it). A second instance
// with the same ball is never skipped: it shadows the floor in every mode.
TEST(OccluderDisks, SelfShadowingModes) {
  for (const bool other : {false, true}) {
    Scene scene;
    scene.meshes.push_back({"floor", {}, quad({-2, -2, 0}, {4, 0, 0}, {0, 4, 0}), {}});
    scene.meshes.push_back({"speck", {}, box({5, 5, 5}, {5.01, 5.01, 5.01}), {}});
    scene.instances.push_back({"floor", Eigen::Affine3d::Identity(), Color::Constant(0.5), {}});
    scene.instances.push_back({"speck", Eigen::Affine3d::Identity(), Color::Constant(0.5), {}});
    scene.lights.push_back(square_light({-0.05, -0.05, 3}, {0, 0.1, 0}, {0.1, 0, 0}, Color::Constant(10)));
    scene.camera.from = {0, -0.3, 0.2};
    scene.camera.at = {0, 0, 0};
    scene.camera.up = {0, 0, 1};
    scene.camera.fov_degrees = 2;
    scene.camera.width = scene.camera.height = 2;
    std::vector<MeshProxies> proxies(2);
    const InstanceProxy ball{ProxyKind::general, "spheres:1", {}, {{{0, 0, 0.5}, 0.4}}, false};
    if (other) {
      proxies[1].stochastic = ball;  // the speck's sphere set hangs over the floor
    } else {
      proxies[0].stochastic = ball;
    }
    const RenderWorld world(scene, proxies);
    for (const SelfShadow self : {SelfShadow::none, SelfShadow::heuristic, SelfShadow::exact}) {
      const RenderResult result = render(scene, world, {.visibility = VisibilityMode::spheres, .spp = 2, .seed = 1, .self_shadow = self});
      const double mean = result.image.pixels[0].x();
      const bool shadowed = other || self == SelfShadow::none;
      if (shadowed) {
        EXPECT_EQ(mean, 0) << name_of(self) << " other " << other;
      } else {
        EXPECT_GT(mean, 0) << name_of(self) << " other " << other;
      }
    }
  }
}


// Adaptive eq. 8 with VPLs weighs each instance's points before the render (Eq8Gate). On
// the crowd far from the origin (60 cheap meshes, each under a sphere set wrong for many
// connections), eq. 8 cannot pay anywhere: the render gives exact's image bit for bit,
// draws no term and probes nothing. Without the gate, eq. 8 runs.
TEST(VplIntegrator, AdaptiveEq8TracesExactlyWhereItCannotPay) {
  const CrowdScene c = disk_crowd(Vertex(2.0e5, -3.0e5, 1.0e4));
  const RenderWorld world(c.scene, c.proxies);
  RenderOptions options{.integrator = IntegratorKind::vpl, .spp = 4, .seed = 9, .vpls = 64, .bounces = 2};
  const RenderResult exact = render(c.scene, world, options);
  options.visibility = VisibilityMode::stochastic;
  options.estimator = StochasticEstimator::term_choice;
  options.probabilities = ProbabilityMode::adaptive;
  const RenderResult gated = render(c.scene, world, options);
  ASSERT_TRUE(gated.stats.eq8_gate.is_object());
  const nlohmann::json& instances = gated.stats.eq8_gate["instances"];
  ASSERT_EQ(instances.size(), c.scene.instances.size());
  std::size_t weighed = 0;
  for (const nlohmann::json& instance : instances)
    if (!instance["predicted_ratio"].is_null()) {
      EXPECT_GE(instance["predicted_ratio"].get<double>(), kLearnedPaysBelow) << instance.dump();
      ++weighed;
    }
  EXPECT_GE(weighed, 10u);  // the floor and the balls the pairs met
  EXPECT_EQ(gated.image.pixels, exact.image.pixels);
  EXPECT_EQ(gated.stats.exact_tests, exact.stats.exact_tests);
  EXPECT_EQ(gated.stats.eq8.traced_exactly, gated.stats.exact_tests);
  EXPECT_EQ(gated.stats.eq8.terms[0] + gated.stats.eq8.terms[1] + gated.stats.eq8.terms[2], 0u);
  EXPECT_EQ(gated.stats.probe_rays, 0u);
  EXPECT_TRUE(exact.stats.eq8_gate.is_null());

  options.gate = false;
  const RenderResult ungated = render(c.scene, world, options);
  EXPECT_TRUE(ungated.stats.eq8_gate.is_null());
  EXPECT_GT(ungated.stats.eq8.terms[0], 0u);
  EXPECT_GT(ungated.stats.probe_rays, 0u);
}

// Where a proxy stands in well for a heavy mesh (a ball of 82 K triangles with a ball
// just inside it as its proxy) and connections go one by one, the gate keeps eq. 8 for the
// floor's points, whose rest of the scene is that ball: their terms are drawn. The
// ball's own points, whose rest is the floor without a proxy, are weighed apart. Given
// VPLs and no area light, adaptive probes nothing (it used to sample an empty light list).
// With the proxy beside the ball, the variance it would add decides against it.
TEST(VplIntegrator, AdaptiveEq8GateKeepsEq8WhereItPays) {
  DiskScene s = disk_scene();
  s.scene.meshes[1].mesh = sphere_set_mesh({{{0, 0, 2}, 1.0}}, 6);
  s.proxies[1].stochastic->spheres = {{{0, 0, 2}, 0.9999}};
  for (int i = 0; i < 16; ++i)
    for (int j = 0; j < 16; ++j)
      s.lights.push_back({{-2 + 0.25 * i, -2 + 0.25 * j, 5}, {0, 0, -1}, Color::Constant(0.02), Color::Constant(1 / std::numbers::pi), -1, 1});
  RenderOptions options{.integrator = IntegratorKind::vpl, .visibility = VisibilityMode::stochastic, .probabilities = ProbabilityMode::adaptive,
                        .estimator = StochasticEstimator::term_choice, .spp = 16, .seed = 4, .virtual_point_lights = &s.lights};
  options.group_connections = false;
  options.probe_passes = 2;  // a pixel whose first sample finds no surface still probes in its second
  options.probability_floor = 0.01;
  {
    // Given VPLs and no area light: nothing to probe, equal probabilities.
    const RenderWorld unlit(s.scene, s.proxies);
    const RenderResult r = render(s.scene, unlit, options);
    EXPECT_TRUE(all_finite(r.image));
    EXPECT_EQ(r.stats.probe_rays, 0u);
  }
  s.scene.lights.push_back(square_light({-0.5, -0.5, 6}, {0, 1, 0}, {1, 0, 0}, Color::Constant(20)));
  const RenderWorld world(s.scene, s.proxies);
  const RenderResult r = render(s.scene, world, options);
  ASSERT_TRUE(r.stats.eq8_gate.is_object());
  std::printf("eq8 gate: %s\n", r.stats.eq8_gate.dump().c_str());
  const nlohmann::json& floor = r.stats.eq8_gate["instances"][0];
  ASSERT_FALSE(floor["predicted_ratio"].is_null());
  EXPECT_LT(floor["predicted_ratio"].get<double>(), kLearnedPaysBelow);
  EXPECT_GT(r.stats.eq8.terms[0], 0u);
  EXPECT_GT(r.stats.probe_rays, 0u);

  // The same heavy ball with its proxy beside it: as cheap, but wrong for most connections
  // it meets. The work alone would pay; the variance it adds does not, and the render is
  // exact's, bit for bit.
  s.proxies[1].stochastic->spheres = {{{1.5, 0, 2}, 0.8}};
  const RenderWorld beside(s.scene, s.proxies);
  const RenderResult gated = render(s.scene, beside, options);
  std::printf("proxy beside the ball: %s\n", gated.stats.eq8_gate.dump().c_str());
  const nlohmann::json& weighed = gated.stats.eq8_gate["instances"][0];
  EXPECT_LT(weighed["work_ratio"].get<double>(), kLearnedPaysBelow);
  EXPECT_GE(weighed["predicted_ratio"].get<double>(), kLearnedPaysBelow);
  RenderOptions exact_options = options;
  exact_options.visibility = VisibilityMode::exact;
  EXPECT_EQ(gated.image.pixels, render(s.scene, beside, exact_options).image.pixels);
  EXPECT_EQ(gated.stats.eq8.traced_exactly, gated.stats.exact_tests);
}

// Given VPLs and no area light (a caller's own lights through the runtime API): every
// strategy, estimator, way of choosing probabilities and gate renders a finite image with
// the VPL integrator (lightcuts refuses all but exact visibility); none may read the empty
// list of area lights.
TEST(VplIntegrator, EveryModeRendersGivenVplsWithoutAreaLights) {
  const DiskScene s = disk_scene();
  const RenderWorld world(s.scene, s.proxies);
  RenderOptions base{.integrator = IntegratorKind::vpl, .spp = 3, .seed = 2, .virtual_point_lights = &s.lights};
  const Image exact = render(s.scene, world, base).image;
  ASSERT_TRUE(all_finite(exact));
  std::size_t rendered = 0;
  for (const IntegratorKind integrator : {IntegratorKind::vpl, IntegratorKind::lightcuts})
    for (const VisibilityMode visibility : {VisibilityMode::exact, VisibilityMode::bounds, VisibilityMode::spheres, VisibilityMode::stochastic})
      for (const StochasticEstimator estimator : {StochasticEstimator::term_choice, StochasticEstimator::control_variate})
        for (const ProbabilityMode probabilities :
             {ProbabilityMode::equal, ProbabilityMode::adaptive, ProbabilityMode::learned, ProbabilityMode::optimal})
          for (const bool gate : {true, false}) {
            RenderOptions options = base;
            options.integrator = integrator, options.visibility = visibility, options.estimator = estimator;
            options.probabilities = probabilities, options.gate = gate;
            const std::string label = std::string(name_of(integrator)) + " " + std::string(name_of(visibility)) + " " +
                                      std::string(name_of(estimator)) + " " + std::string(name_of(probabilities)) +
                                      (gate ? "" : " --no-gate");
            try {
              const RenderResult r = render(s.scene, world, options);
              EXPECT_TRUE(all_finite(r.image)) << label;
              EXPECT_EQ(r.image.pixels.size(), exact.pixels.size()) << label;
              ++rendered;
            } catch (const Error& error) {
              // Refused only where the options contradict each other: lightcuts with any
              // strategy but exact, eq. 8 with learned probabilities, the control variate
              // with optimal ones.
              const bool contradictory =
                  (integrator == IntegratorKind::lightcuts && visibility != VisibilityMode::exact) ||
                  (visibility == VisibilityMode::stochastic &&
                   ((estimator == StochasticEstimator::term_choice && probabilities == ProbabilityMode::learned) ||
                    (estimator == StochasticEstimator::control_variate && probabilities == ProbabilityMode::optimal)));
              EXPECT_TRUE(contradictory) << label << ": " << error.what();
              EXPECT_FALSE(std::string(error.what()).empty()) << label;
            }
          }
  EXPECT_GE(rendered, 64u);
}

}  // namespace
}  // namespace visproxy
