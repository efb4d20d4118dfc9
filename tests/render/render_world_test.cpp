// The render world's proofs on inputs built to break them: lights inside proxies, closed
// rooms, closed convex instances without proxies, unproved proxies, proxies that touch
// their mesh, scenes far from the origin, and devices without ray masks.

#include "visproxy/render/world/render_world.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "visproxy/core/random.h"
#include "visproxy/mesh/sphere_set.h"
#include "visproxy/proxy/inner_hull.h"
#include "render/render_test_scenes.h"
#include "test_meshes.h"
#include "visproxy/render/world/box_tree.h"
#include "visproxy/render/renderer.h"
#include "visproxy/render/visibility/visibility.h"
#include "visproxy/trace/embree_support.h"
#include "visproxy/verify/containment.h"
#include "visproxy/verify/sphere_containment.h"

namespace visproxy {
namespace {

using testing::box;
using testing::quad;

TriangleMesh inverted(TriangleMesh mesh) {
  for (Triangle& t : mesh.triangles) std::swap(t[1], t[2]);
  return mesh;
}

TriangleMesh joined(const TriangleMesh& a, const TriangleMesh& b) {
  TriangleMesh mesh = a;
  append_mesh(mesh, b);
  return mesh;
}

AreaLight downward_light(const Vertex& centre, double size) {
  AreaLight light;
  const Vertex corner = centre - Vertex(0.5 * size, 0.5 * size, 0), u(0, size, 0), v(size, 0, 0);  // u x v points down
  light.triangles = {{corner, corner + u, corner + u + v}, {corner, corner + u + v, corner + v}};
  light.radiance = Color::Constant(4);
  return light;
}

double mean_estimate(const RenderWorld& world, const Vertex& from, const Vertex& to, int own, ProxyKind kind, int draws = 20000) {
  Random random(77);
  RenderStats stats;
  double sum = 0;
  for (int i = 0; i < draws; ++i)
    sum += control_variate_visibility(world, from, to, own, equal_correction_probabilities(kind), random.uniform(), true, stats).visibility;
  return sum / draws;
}

// A hollow shell (the cube [-2, 2]^3 with the cavity [-1, 1]^3) whose outside proxy is a
// ball-like icosphere of radius 4, a light above the shell inside that proxy, and a floor
// in the cavity: every floor point is in shadow. Both ends of a floor-to-light segment lie
// inside the traced proxy, which it therefore never crosses: a world that took "crosses no
// face" for "misses the proxy" would light the floor.
struct LampInsideProxy {
  Scene scene;
  std::vector<MeshProxies> proxies;
};

LampInsideProxy lamp_inside_proxy(const TriangleMesh& proxy_mesh) {
  LampInsideProxy s;
  s.scene.meshes.push_back({"shell", {}, joined(box({-2, -2, -2}, {2, 2, 2}), inverted(box({-1, -1, -1}, {1, 1, 1}))), {}});
  s.scene.meshes.push_back({"floor", {}, quad({-0.8, -0.8, -0.9}, {1.6, 0, 0}, {0, 1.6, 0}), {}});
  s.scene.instances.push_back({"shell", Eigen::Affine3d::Identity(), Color::Constant(0.5), {}});
  s.scene.instances.push_back({"floor", Eigen::Affine3d::Identity(), Color::Constant(0.5), {}});
  s.scene.lights.push_back(downward_light({0, 0, 3}, 1));
  s.scene.camera.from = {0, 0, 0.5};
  s.scene.camera.at = {0, 0, -0.9};
  s.scene.camera.up = {0, 1, 0};
  s.scene.camera.fov_degrees = 40;  // the floor fills the image
  s.scene.camera.width = s.scene.camera.height = 16;
  const InstanceProxy proxy{ProxyKind::outside, "ball", proxy_mesh, {}, true};
  EXPECT_TRUE(check_containment(proxy.mesh, s.scene.meshes[0].mesh).contained());  // the claim holds
  s.proxies.resize(2);
  s.proxies[0].stochastic = proxy;
  s.proxies[0].outside = proxy;
  return s;
}

TEST(RenderWorld, LampInsideATracedOutsideProxyIsNotProvedFree) {
  const LampInsideProxy s = lamp_inside_proxy(sphere_set_mesh({{{0, 0, 0}, 4.0}}, 2));  // 320 faces: traced
  const RenderWorld world(s.scene, s.proxies);
  ASSERT_FALSE(world.notes().empty());
  EXPECT_NE(world.notes().front().find("a light lies inside"), std::string::npos) << world.notes().front();
  EXPECT_EQ(world.stochastic_kind(1), ProxyKind::general);
  // A floor point to the light: blocked by the shell, and the outside test says so.
  const Vertex from(0.1, 0.2, -0.89), to(0.1, 0.1, 2.99);
  EXPECT_TRUE(world.mesh_blocks(from, to, {.skip = 1, .only = -1}));
  EXPECT_TRUE(world.outside_blocks(from, to, {.skip = 1, .only = -1}));
  EXPECT_NEAR(mean_estimate(world, from, to, 1, world.stochastic_kind(1)), 0.0, 0.05);
  const auto [a, b] = testing::exact_and_bounds(s.scene, world, {.spp = 4, .shadow_rays = 2, .seed = 5});
  EXPECT_EQ(a.image.pixels, b.image.pixels);
  EXPECT_EQ(b.stats.bounds.unoccluded, 0u);
  EXPECT_GT(b.stats.shadow_rays, 0u);
  for (const Color& c : a.image.pixels) EXPECT_EQ(c, Color::Zero());
}

TEST(RenderWorld, LampInsideAClippedOutsideProxyMeetsItsSolid) {
  const LampInsideProxy s = lamp_inside_proxy(box({-3.5, -3.5, -3.5}, {3.5, 3.5, 3.5}));  // 12 faces: clipped
  const RenderWorld world(s.scene, s.proxies);
  EXPECT_TRUE(world.notes().empty());
  EXPECT_EQ(world.stochastic_kind(1), ProxyKind::outside);  // a solid needs no light outside it
  EXPECT_TRUE(world.proxy_blocks({0.1, 0.2, -0.89}, {0.1, 0.1, 2.99}, {.skip = 1, .only = -1}));
  const auto [a, b] = testing::exact_and_bounds(s.scene, world, {.spp = 4, .shadow_rays = 2, .seed = 5});
  EXPECT_EQ(a.image.pixels, b.image.pixels);
}

// A closed room (a box facing inwards) is a solid whose inside is its air: a ball in the
// air is "inside" it. With the light in the room, a segment through that ball proves
// nothing. A box on the floor, a small ball-shaped occluder above the room's centre with a
// loose box as its outside proxy (so bounds reaches its inside test), the room's ball in
// between.
struct ClosedRoom {
  Scene scene;
  std::vector<MeshProxies> proxies;
};

ClosedRoom closed_room() {
  ClosedRoom s;
  s.scene.meshes.push_back({"room", {}, inverted(box({-3, -3, -3}, {3, 3, 3})), {}});
  s.scene.meshes.push_back({"crate", {}, box({-0.5, -0.5, -3}, {0.5, 0.5, -2}), {}});
  s.scene.meshes.push_back({"bead", {}, sphere_set_mesh({{{0, 0, 1.5}, 0.3}}, 2), {}});
  for (const char* name : {"room", "crate", "bead"}) s.scene.instances.push_back({name, Eigen::Affine3d::Identity(), Color::Constant(0.5), {}});
  s.scene.lights.push_back(downward_light({0, 0, 2.9}, 1.5));
  s.scene.camera.from = {2, -2.5, 0};
  s.scene.camera.at = {0, 0, -2.2};
  s.scene.camera.up = {0, 0, 1};
  s.scene.camera.fov_degrees = 40;
  s.scene.camera.width = s.scene.camera.height = 24;
  const InstanceProxy room_ball{ProxyKind::inside, "inside:1", {}, {{{0, 0, 0}, 1.0}}, true};
  const Sphere ball = room_ball.spheres[0];
  EXPECT_TRUE(check_spheres_inside(s.scene.meshes[0].mesh, {&ball, 1}).contained());  // proved: the air is its solid
  s.proxies.resize(3);
  s.proxies[0].stochastic = room_ball;
  s.proxies[0].inside = room_ball;
  s.proxies[2].outside = InstanceProxy{ProxyKind::outside, "aabb", box({-0.5, -0.5, 1}, {0.5, 0.5, 2}), {}, true};
  return s;
}

TEST(RenderWorld, ClosedRoomsInsideProxyProvesNothingAboutItsAir) {
  const ClosedRoom s = closed_room();
  const RenderWorld world(s.scene, s.proxies);
  EXPECT_FALSE(world.has_inside_proxies());
  EXPECT_EQ(world.stochastic_kind(1), ProxyKind::general);
  ASSERT_FALSE(world.notes().empty());
  // From the crate's top through the room's ball to the light: free.
  const Vertex from(0.2, 0.1, -1.99), to(0.3, 0.2, 2.89);
  EXPECT_FALSE(world.mesh_blocks(from, to));
  EXPECT_NEAR(mean_estimate(world, from, to, 1, world.stochastic_kind(1)), 1.0, 0.05);
  const auto [a, b] = testing::exact_and_bounds(s.scene, world, {.spp = 4, .shadow_rays = 4, .seed = 9});
  EXPECT_EQ(a.image.pixels, b.image.pixels);
  EXPECT_EQ(b.stats.bounds.occluded, 0u);
  EXPECT_GT(b.stats.bounds.traced, 0u);  // the bead's loose box sent segments to the exact test
}

// The same room seen from outside (faces outwards, light outside), on a floor.
ClosedRoom room_seen_from_outside() {
  ClosedRoom s = closed_room();
  s.scene.meshes[0].mesh = box({-3, -3, -3}, {3, 3, 3});
  s.scene.lights = {downward_light({0, 0, 5}, 1.5)};
  s.scene.camera.from = {5, -6, 4};
  s.scene.camera.at = {0, 0, 0};
  s.scene.instances.resize(1);
  s.proxies.resize(1);
  s.scene.meshes[1].mesh = quad({-9, -9, -3.01}, {18, 0, 0}, {0, 18, 0});  // a floor under the room
  s.scene.instances.push_back({"crate", Eigen::Affine3d::Identity(), Color::Constant(0.5), {}});
  s.proxies.resize(2);
  return s;
}

// Seen from outside, the room's ball proves.
TEST(RenderWorld, InsideProxyProvesWhenTheLightIsOutsideTheSolid) {
  const ClosedRoom s = room_seen_from_outside();
  const RenderWorld world(s.scene, s.proxies);
  EXPECT_TRUE(world.has_inside_proxies());
  EXPECT_EQ(world.stochastic_kind(1), ProxyKind::inside);
  EXPECT_TRUE(world.notes().empty());
}

// inner:N is an inside proxy made of triangles: built on the room seen from outside, it
// keeps its clearance (1e-4 of the diagonal, far above the float rounding bound), so the
// world uses it as an inside proxy, and bounds proves umbrae with it yet renders exactly
// what exact visibility renders.
TEST(RenderWorld, InnerHullIsUsedAsAnInsideProxy) {
  ClosedRoom s = room_seen_from_outside();
  const InnerHullResult inner = build_inner_hull(s.scene.meshes[0].mesh, {.max_triangles = 64, .grid_cells = 16});
  ASSERT_TRUE(inner.clearance_kept);
  ASSERT_TRUE(check_containment(s.scene.meshes[0].mesh, inner.mesh, {.contents_solid = true}).contained());
  const InstanceProxy proxy{ProxyKind::inside, "inner:64", inner.mesh, {}, true};
  s.proxies.assign(2, {});
  s.proxies[0].stochastic = proxy;
  s.proxies[0].inside = proxy;
  const RenderWorld world(s.scene, s.proxies);
  EXPECT_TRUE(world.has_inside_proxies());
  EXPECT_EQ(world.stochastic_kind(1), ProxyKind::inside);  // segments from the floor
  EXPECT_TRUE(world.notes().empty()) << world.notes().front();
  // From the floor under the room's middle straight up to the light: through the proxy.
  EXPECT_TRUE(world.inside_blocks({0.1, 0.2, -3.005}, {0.2, 0.1, 4.99}));
  const auto [a, b] = testing::exact_and_bounds(s.scene, world, {.spp = 4, .shadow_rays = 4, .seed = 9});
  EXPECT_EQ(a.image.pixels, b.image.pixels);
  EXPECT_GT(b.stats.bounds.occluded, 0u);
}

// A closed convex instance without a proxy stands in for itself exactly: a glass case
// around the light and the objects. Were it held as a clipped solid in the stochastic
// scene, every segment inside it would meet it, and with an inside proxy elsewhere (the
// ball's) the estimator would return 0 for all of them.
TEST(RenderWorld, ClosedConvexInstanceWithoutProxyIsTracedExactly) {
  Scene scene;
  scene.meshes.push_back({"case", {}, box({-3, -3, -3}, {3, 3, 3}), {}});
  scene.meshes.push_back({"ball", {}, sphere_set_mesh({{{0, 0, 0}, 1.0}}, 3), {}});
  scene.meshes.push_back({"floor", {}, quad({-2.5, -2.5, -2.5}, {5, 0, 0}, {0, 5, 0}), {}});
  for (const char* name : {"case", "ball", "floor"}) scene.instances.push_back({name, Eigen::Affine3d::Identity(), Color::Constant(0.5), {}});
  scene.lights.push_back(downward_light({0, 0, 2.5}, 1));
  std::vector<MeshProxies> proxies(3);
  proxies[1].stochastic = InstanceProxy{ProxyKind::inside, "inside:1", {}, {{{0, 0, 0}, 0.9}}, true};
  const RenderWorld world(scene, proxies);
  EXPECT_EQ(world.stochastic_kind(2), ProxyKind::inside);  // the case is exact, the ball inside
  const Vertex from(2, 2, -2.49), to(0.2, 0.2, 2.49);  // beside the ball, inside the case
  EXPECT_FALSE(world.mesh_blocks(from, to, {.skip = 2, .only = -1}));
  EXPECT_FALSE(world.proxy_blocks(from, to, {.skip = 2, .only = -1}));
  EXPECT_NEAR(mean_estimate(world, from, to, 2, ProxyKind::inside), 1.0, 1e-12);
}

// A proxy whose claim is not proved is a general proxy: here a box too small to hold the
// ball, labelled outside. Taken at its word, segments missing the box but not the ball
// would be free.
TEST(RenderWorld, UnprovedProxiesAreGeneral) {
  Scene scene;
  scene.meshes.push_back({"floor", {}, quad({-4, -4, 0}, {8, 0, 0}, {0, 8, 0}), {}});
  scene.meshes.push_back({"ball", {}, sphere_set_mesh({{{0, 0, 2}, 1.0}}, 3), {}});
  scene.instances.push_back({"floor", Eigen::Affine3d::Identity(), Color::Constant(0.5), {}});
  scene.instances.push_back({"ball", Eigen::Affine3d::Identity(), Color::Constant(0.5), {}});
  scene.lights.push_back(downward_light({0, 0, 5}, 2));
  scene.camera.from = {0, -5, 3};
  scene.camera.at = {0, 0, 0};
  scene.camera.up = {0, 0, 1};
  scene.camera.width = scene.camera.height = 16;
  std::vector<MeshProxies> proxies(2);
  const InstanceProxy small{ProxyKind::outside, "aabb", box({-0.5, -0.5, 1.5}, {0.5, 0.5, 2.5}), {}, false};
  EXPECT_FALSE(check_containment(small.mesh, scene.meshes[1].mesh).contained());
  proxies[1].stochastic = small;
  proxies[1].outside = small;
  const RenderWorld world(scene, proxies);
  EXPECT_EQ(world.stochastic_kind(0), ProxyKind::general);
  ASSERT_EQ(world.notes().size(), 1u);
  EXPECT_NE(world.notes()[0].find("not proved"), std::string::npos);
  const Vertex from(0.8, 0, 0.01), to(0.8, 0, 4.99);  // through the ball's rim, beside the box
  EXPECT_TRUE(world.mesh_blocks(from, to));
  EXPECT_FALSE(world.proxy_blocks(from, to, {.skip = 0, .only = -1}));
  EXPECT_TRUE(world.outside_blocks(from, to, {.skip = 0, .only = -1}));  // the ball's own mesh stands in
  EXPECT_NEAR(mean_estimate(world, from, to, 0, world.stochastic_kind(0)), 0.0, 0.05);
  const auto [a, b] = testing::exact_and_bounds(scene, world, {.spp = 4, .shadow_rays = 2, .seed = 3});
  EXPECT_EQ(a.image.pixels, b.image.pixels);
}

// Rounding to float: an inside ball that touches its mesh (the exact proof allows it) is
// shrunk before Embree sees it, and a convex hull that touches its mesh at every vertex is
// scaled out before it is traced. The cube's corners are not floats (0.1, 1.2), so its
// float faces lie a hair off the exact ones the ball touches: chords through the ball's
// cap just inside a face would meet the unshrunk ball and miss the float cube.
TEST(RenderWorld, TouchingProxiesStayConservativeUnderFloatRounding) {
  Scene scene;
  const TriangleMesh cube = box({0.1, 0.1, 0.1}, {1.2, 1.2, 1.2});
  scene.meshes.push_back({"cube", {}, cube, {}});
  scene.meshes.push_back({"ball", {}, sphere_set_mesh({{{0, 0, 0}, 1.0}}, 3), {}});
  scene.instances.push_back({"cube", Eigen::Affine3d::Identity(), Color::Constant(0.5), {}});
  Eigen::Affine3d placed = Eigen::Affine3d::Identity();
  placed.translate(Vertex(3, 0.3, 0.2)).rotate(Eigen::AngleAxisd(0.7, Vertex(1, 2, 3).normalized()));
  scene.instances.push_back({"ball", placed, Color::Constant(0.5), {}});
  scene.lights.push_back(downward_light({0.5, 0.5, 8}, 1));
  std::vector<MeshProxies> proxies(2);
  // The largest double radius the exact check passes: the ball touches all six faces.
  Sphere ball{{0.65, 0.65, 0.65}, 0.55 * (1 + 1e-15)};
  while (!check_spheres_inside(cube, {&ball, 1}).contained()) ball.radius = std::nextafter(ball.radius, 0.0);
  ASSERT_GT(ball.radius, 0.55 * (1 - 1e-15));
  const InstanceProxy touching{ProxyKind::inside, "inside:1", {}, {ball}, true};
  proxies[0].inside = touching;
  // The ball mesh's vertices are its own hull's: a hull that touches the mesh everywhere.
  const InstanceProxy hull{ProxyKind::outside, "hull", scene.meshes[1].mesh, {}, true};
  ASSERT_TRUE(check_containment(hull.mesh, scene.meshes[1].mesh).contained());
  proxies[1].outside = hull;
  proxies[1].stochastic = hull;
  const RenderWorld world(scene, proxies);
  EXPECT_TRUE(world.has_inside_proxies());
  EXPECT_EQ(world.stochastic_kind(0), ProxyKind::outside);
  EXPECT_TRUE(world.notes().empty());
  Random random(31);
  int inside_hits = 0, grazing = 0;
  const TriangleMesh& ball_mesh = scene.meshes[1].mesh;
  for (int i = 0; i < 20000; ++i) {
    // A chord just inside the bottom face z = 0.1, through the ball's cap: every other one
    // within a few float spacings of the face (where the exact ball pokes out of the float
    // cube), the others up to 1e-4 above it.
    const bool thin = i % 2 == 0;
    const double z = 0.1 + (thin ? (random.uniform() * 12 - 2) * 1e-9 : random.uniform() * 1e-4);
    const double y = 0.65 + (random.uniform() - 0.5) * (thin ? 6e-5 : 1e-3);
    const Vertex from(-2, y, z), to(3, y + 1e-4, z);
    if (world.inside_blocks(from, to)) {
      ++inside_hits;
      EXPECT_TRUE(world.mesh_blocks(from, to, {.skip = -1, .only = 0})) << "z - 0.1 = " << z - 0.1;
    }
    // A line tangent to the ball mesh at one of its vertices (both ends outside).
    const Vertex vertex = placed * ball_mesh.positions[static_cast<std::size_t>(i) % ball_mesh.positions.size()];
    const Vertex out = (vertex - placed * Vertex::Zero()).normalized();
    const Vertex side = out.cross(Vertex(0.3, 0.5, 0.8)).normalized();
    const Vertex jitter = out * (random.uniform() - 0.5) * 1e-7;
    const Vertex start = vertex - 2 * side + jitter, end = vertex + 2 * side + jitter;
    if (world.mesh_blocks(start, end, {.skip = -1, .only = 1})) {
      ++grazing;
      EXPECT_TRUE(world.outside_blocks(start, end, {.skip = -1, .only = 1}));
      EXPECT_TRUE(world.proxy_blocks(start, end, {.skip = -1, .only = 1}));
    }
  }
  EXPECT_GT(inside_hits, 100);
  EXPECT_GT(grazing, 100);
}

// The same scene placed a million units from the origin renders as it does at the origin:
// points are handed to Embree relative to the scene's centre and meshes relative to their
// own, and surface offsets follow the coordinates' magnitude there. Bounds stays exact.
// Hundreds of instances, far from the origin: the proxies go into a tree, and a segment
// through any one proxy must still find it, one between the rows must find none, and
// instances_where must list what a scan of every instance lists.
TEST(RenderWorld, ManyInstancesFarFromTheOriginAreFoundThroughTheTree) {
  const Vertex offset(4.0e6, -3.0e6, 2.0e5);
  Scene scene;
  scene.meshes.push_back({"cube", {}, box({-0.4, -0.4, -0.4}, {0.4, 0.4, 0.4}), {}});
  std::vector<MeshProxies> proxies;
  const InstanceProxy cube_box{ProxyKind::outside, "aabb", box({-0.45, -0.45, -0.45}, {0.45, 0.45, 0.45}), {}, true};
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j) {
      Eigen::Affine3d t = Eigen::Affine3d::Identity();
      t.translate(offset + Vertex(2.0 * i, 2.0 * j, 0)).rotate(Eigen::AngleAxisd(0.1 * (i + j), Vertex::UnitZ()));
      scene.instances.push_back({"cube", t, Color::Constant(0.5), {}});
      proxies.push_back({.stochastic = cube_box, .outside = cube_box, .inside = std::nullopt});
    }
  scene.lights.push_back(downward_light(offset + Vertex(20, 20, 10), 1));
  const RenderWorld world(scene, proxies);
  for (std::size_t k = 0; k < scene.instances.size(); ++k) {
    const Vertex centre = scene.instances[k].transform.translation();
    EXPECT_TRUE(world.proxy_blocks(centre + Vertex(0.3, -0.2, 5), centre - Vertex(0.2, -0.1, 5))) << k;
    EXPECT_TRUE(world.mesh_blocks(centre + Vertex(0.3, -0.2, 5), centre - Vertex(0.2, -0.1, 5))) << k;
  }
  for (int i = 0; i < 19; ++i) {  // between the columns, along the rows: the boxes reach 0.64 from a centre
    const Vertex x = offset + Vertex(2.0 * i + 1, -5, 0);
    EXPECT_FALSE(world.proxy_blocks(x, x + Vertex(0, 50, 0))) << i;
  }
  Random random(5);
  std::vector<std::size_t> listed;
  for (int s = 0; s < 200; ++s) {
    const Vertex from = offset + Vertex(40 * random.uniform() - 1, 40 * random.uniform() - 1, 2 * random.uniform() - 1);
    const Vertex to = offset + Vertex(40 * random.uniform() - 1, 40 * random.uniform() - 1, 2 * random.uniform() - 1);
    const auto meets = [&](const BoundingBox& b, const Sphere& ball) {
      return segment_meets_box(from, to, b) && segment_meets_ball(ball, from, to - from, 0.0, 1.0);
    };
    world.instances_where(meets, listed);
    std::vector<std::size_t> expected;
    for (std::size_t k = 0; k < scene.instances.size(); ++k)
      if (meets(world.instance_bounds(k), world.instance_sphere(k))) expected.push_back(k);
    EXPECT_EQ(listed, expected) << s;
    bool proxy_met = false;
    for (const std::size_t k : expected) proxy_met = proxy_met || world.mesh_blocks(from, to, {.skip = -1, .only = int(k)});
    if (proxy_met) {
      EXPECT_TRUE(world.proxy_blocks(from, to)) << s;  // the proxies hold the cubes
    }
  }
}

TEST(RenderWorld, SceneFarFromTheOriginRendersAsAtTheOrigin) {
  auto make = [](const Vertex& shift) {
    Scene scene;
    TriangleMesh floor = quad(shift + Vertex(-3, -3, 0), {6, 0, 0}, {0, 6, 0});
    TriangleMesh crate = box(shift + Vertex(-0.3, -0.3, 0), shift + Vertex(0.3, 0.3, 0.4));
    scene.meshes.push_back({"floor", {}, floor, {}});
    scene.meshes.push_back({"crate", {}, crate, {}});
    scene.instances.push_back({"floor", Eigen::Affine3d::Identity(), Color::Constant(0.5), {}});
    scene.instances.push_back({"crate", Eigen::Affine3d::Identity(), Color::Constant(0.5), {}});
    scene.lights.push_back(downward_light(shift + Vertex(0.4, 0.2, 2), 0.8));
    scene.camera.from = shift + Vertex(0, -3, 2.5);
    scene.camera.at = shift;
    scene.camera.up = {0, 0, 1};
    scene.camera.width = scene.camera.height = 24;
    return scene;
  };
  const Scene near = make(Vertex::Zero()), far = make(Vertex(1e6, -2e6, 3e6));
  std::vector<MeshProxies> proxies(2);
  proxies[1].outside = InstanceProxy{ProxyKind::outside, "aabb", box({-0.3, -0.3, 0}, {0.3, 0.3, 0.4}), {}, true};
  std::vector<MeshProxies> far_proxies = proxies;
  for (Vertex& p : far_proxies[1].outside->mesh.positions) p += Vertex(1e6, -2e6, 3e6);
  const RenderWorld near_world(near, proxies), far_world(far, far_proxies);
  const RenderOptions options{.spp = 8, .shadow_rays = 2, .seed = 21};
  const Image a = render(near, near_world, options).image, b = render(far, far_world, options).image;
  double difference = 0, total = 0;
  for (std::size_t i = 0; i < a.pixels.size(); ++i) {
    difference += (a.pixels[i] - b.pixels[i]).cwiseAbs().sum();
    total += a.pixels[i].sum();
  }
  EXPECT_GT(total, 0.0);
  EXPECT_LT(difference, 1e-3 * total) << difference << " of " << total;
  EXPECT_EQ(testing::exact_and_bounds(far, far_world, options).second.image.pixels, b.pixels);
}

// Without ray masks every hit goes through the filter function: the same images.
TEST(RenderWorld, FilterFunctionsGiveTheImagesOfRayMasks) {
  const LampInsideProxy s = lamp_inside_proxy(box({-3.5, -3.5, -3.5}, {3.5, 3.5, 3.5}));
  Scene scene = s.scene;
  scene.camera.from = {0, -6, 5};
  scene.camera.at = {0, 0, 0};
  scene.camera.up = {0, 0, 1};
  scene.meshes.push_back({"ground", {}, quad({-9, -9, -2.5}, {18, 0, 0}, {0, 18, 0}), {}});
  scene.instances.push_back({"ground", Eigen::Affine3d::Identity(), Color::Constant(0.5), {}});
  scene.lights = {downward_light({1, 1, 6}, 2)};
  std::vector<MeshProxies> proxies = s.proxies;
  proxies.resize(3);
  const RenderWorld masked(scene, proxies), filtered(scene, proxies, {.ray_masks = false});
  for (const VisibilityMode mode : {VisibilityMode::exact, VisibilityMode::bounds, VisibilityMode::stochastic}) {
    RenderOptions options{.visibility = mode, .spp = 3, .shadow_rays = 2, .seed = 4};
    const RenderResult a = render(scene, masked, options), b = render(scene, filtered, options);
    EXPECT_EQ(a.image.pixels, b.image.pixels) << name_of(mode);
    double sum = 0;
    for (const Color& c : a.image.pixels) sum += c.x();
    EXPECT_GT(sum, 0.0);
  }
}

}  // namespace
}  // namespace visproxy

namespace visproxy {
namespace {

// Convex shells, the proof that lets VPL connections skip rooms and walls, on inputs built
// to break it: an open room (five walls: the open side must not be treated as a wall, and
// a segment through a wall must not be skipped), an L-shaped box that is not convex (no
// shell), a reflecting, non-uniform transform, points within the margin of a wall, and
// 20 000 random segments whose ends the shell holds, which the mesh must never block.
TEST(RenderWorld, ConvexShellsHoldOnlyWhatTheirMeshCannotBlock) {
  TriangleMesh room = box({-1, 0, -1}, {1, 2, 1});
  // Drop the two triangles of the face z = 1 (the open side).
  std::vector<Triangle> walls;
  for (const Triangle& t : room.triangles)
    if (!(room.positions[t[0]].z() == 1 && room.positions[t[1]].z() == 1 && room.positions[t[2]].z() == 1)) walls.push_back(t);
  ASSERT_EQ(walls.size(), 10u);
  room.triangles = walls;
  TriangleMesh ell = joined(box({0, 0, 0}, {2, 1, 1}), box({0, 1, 0}, {1, 2, 1}));  // not convex
  Scene scene;
  scene.meshes.push_back({"room", {}, room, {}});
  scene.meshes.push_back({"ell", {}, ell, {}});
  Eigen::Affine3d mirrored = Eigen::Affine3d::Identity();
  mirrored.translate(Vertex(10, 0, 0)).scale(Vertex(-1.5, 0.5, 2));  // reflects x, stretches y and z
  scene.instances.push_back({"room", Eigen::Affine3d::Identity(), Color::Constant(0.5), {}});
  scene.instances.push_back({"room", mirrored, Color::Constant(0.5), {}});
  Eigen::Affine3d far_away = Eigen::Affine3d::Identity();
  far_away.translate(Vertex(0, 0, 20));
  scene.instances.push_back({"ell", far_away, Color::Constant(0.5), {}});
  scene.lights.push_back(downward_light({0, 1.9, 0}, 0.2));
  const RenderWorld world(scene, std::vector<MeshProxies>(scene.instances.size()));
  const unsigned first = instance_bit(0), second = instance_bit(1), ell_bit = instance_bit(2);

  EXPECT_EQ(world.convex_shells_holding({0, 1, 0}) & first, first);     // inside the room
  EXPECT_EQ(world.convex_shells_holding({0, 1, 5}) & first, first);     // beyond the open side: no wall there
  EXPECT_EQ(world.convex_shells_holding({0, 1, -1.5}) & first, 0u);     // behind the back wall
  EXPECT_EQ(world.convex_shells_holding({0, 2 - 1e-13, 0}) & first, 0u);  // within the margin of the ceiling
  EXPECT_EQ(world.convex_shells_holding({10, 0.5, 0}) & second, second);  // inside the mirrored room
  EXPECT_EQ(world.convex_shells_holding({10, 0.5, 0}) & first, 0u);
  EXPECT_EQ(world.convex_shells_holding({10, 1.5, 0}) & second, 0u);     // above its squashed ceiling (y = 1)
  for (const Vertex& p : {Vertex(0.5, 0.5, 20.5), Vertex(1.5, 0.5, 20.5), Vertex(5, 5, 25)})
    EXPECT_EQ(world.convex_shells_holding(p) & ell_bit, 0u);  // the L shape has no shell
  // A segment from inside the room through a wall is not skipped: one end is not held.
  EXPECT_TRUE(world.mesh_blocks({0, 1, 0}, {0, 1, -1.5}, {.skip = -1, .only = 0}));

  // Segments between held points, near the walls and through the open side: never blocked.
  Random random(8);
  int held_pairs = 0;
  for (int i = 0; i < 20000; ++i) {
    auto point = [&] {
      return Vertex(2.2 * random.uniform() - 1.1, 2.2 * random.uniform() - 0.1, 3 * random.uniform() - 1.1);
    };
    const Vertex a = point(), b = point();
    if ((world.convex_shells_holding(a) & world.convex_shells_holding(b) & first) == 0) continue;
    ++held_pairs;
    ASSERT_FALSE(world.mesh_blocks(a, b, {.skip = -1, .only = 0})) << a.transpose() << " -> " << b.transpose();
  }
  EXPECT_GT(held_pairs, 5000);
}

// A closed box whose top face is a fan of 2000 slivers, its vertices turned into a tilted
// frame (so that Embree's float normals of the slivers tilt off their plane), a thin light
// a hair (1e-4 of the box's diagonal) below the top face's plane, beside the box, and the
// camera above the top face. The box's aabb (proved) is its outside proxy, a ball inside it
// its inside proxy.
struct SliverFan {
  Scene scene;
  std::vector<MeshProxies> proxies;
  Eigen::Affine3d frame;  // the fan box's own frame to object (= world) space
  Vertex size;
};

SliverFan sliver_fan(double hair) {
  SliverFan s;
  s.size = Vertex(1.3, 1.1, 0.4);
  s.frame = Eigen::Translation3d(0.37, -0.21, 0.13) * Eigen::AngleAxisd(0.7, Vertex(1, 2, 3).normalized());
  TriangleMesh mesh = testing::sliver_fan_box(s.size, 2000);
  for (Vertex& p : mesh.positions) p = s.frame * p;
  const double diagonal = s.size.norm();
  TriangleMesh aabb = box(bounding_box(mesh).min, bounding_box(mesh).max);
  s.scene.meshes.push_back({"fan", {}, mesh, {}});
  s.scene.instances.push_back({"fan", Eigen::Affine3d::Identity(), Color::Constant(0.7), {}});
  AreaLight light;
  const Vertex corner = s.frame * Vertex(1.15 * s.size.x(), 0.3, s.size.z() - hair * diagonal);
  const Vertex u = s.frame.linear() * Vertex(0.6, 0, 0), v = s.frame.linear() * Vertex(0, 0.03, 0);
  light.triangles = {{corner, corner + u, corner + u + v}, {corner, corner + u + v, corner + v}};
  light.radiance = Color::Constant(20);
  light.two_sided = true;
  s.scene.lights.push_back(light);
  s.scene.camera.from = s.frame * Vertex(0.5 * s.size.x(), 0.5 * s.size.y(), 2.2);
  s.scene.camera.at = s.frame * Vertex(0.5 * s.size.x(), 0.5 * s.size.y(), s.size.z());
  s.scene.camera.up = s.frame.linear() * Vertex(0, 1, 0);
  s.scene.camera.fov_degrees = 38;  // the top face fills the image
  s.scene.camera.width = 40;
  s.scene.camera.height = 32;
  const InstanceProxy outside{ProxyKind::outside, "aabb", aabb, {}, true};
  const InstanceProxy inside{ProxyKind::inside, "inside:1", {}, {{s.frame * (0.5 * s.size), 0.15}}, true};
  EXPECT_TRUE(check_containment(outside.mesh, mesh).contained());
  EXPECT_TRUE(check_spheres_inside(mesh, {&inside.spheres[0], 1}).contained());
  s.proxies.resize(1);
  s.proxies[0].stochastic = outside;
  s.proxies[0].outside = outside;
  s.proxies[0].inside = inside;
  return s;
}

// Double-precision segment-triangle test (closed triangle, closed segment).
bool segment_meets_triangle(const Vertex& p, const Vertex& q, const Vertex& a, const Vertex& b, const Vertex& c) {
  const Vertex d = q - p, e1 = b - a, e2 = c - a, h = d.cross(e2);
  const double det = e1.dot(h);
  if (det == 0) return false;
  const Vertex s = p - a;
  const double u = s.dot(h) / det;
  if (u < 0 || u > 1) return false;
  const Vertex qv = s.cross(e1);
  const double v = d.dot(qv) / det, t = e2.dot(qv) / det;
  return v >= 0 && u + v <= 1 && t >= 0 && t <= 1;
}

// The shortcut "the own mesh lies behind the tangent plane" decides by the hit triangle's
// exact plane: a segment it declares clear misses every triangle of the mesh in exact
// (double) arithmetic, by Embree's rounding bound, even where the float normal of a sliver
// puts the light in front of the face while it lies behind its plane.
TEST(RenderWorld, OwnMeshShortcutUsesTheExactPlaneOfASliver) {
  const SliverFan s = sliver_fan(1e-4);
  const RenderWorld world(s.scene, s.proxies);
  const TriangleMesh& mesh = s.scene.meshes[0].mesh;
  const AreaLight& light = s.scene.lights[0];
  Random random(31);
  int on_top = 0, declared_clear = 0, float_normal_fooled = 0;
  const Vertex up = s.frame.linear() * Vertex(0, 0, 1);
  for (int i = 0; i < 4000; ++i) {
    const double x = 0.02 + 0.96 * random.uniform(), y = 0.02 + 0.96 * random.uniform();
    const Vertex target = s.frame * Vertex(x * s.size.x(), y * s.size.y(), s.size.z());
    const Vertex origin = target + 1.5 * (up + 0.3 * Vertex(random.uniform() - 0.5, random.uniform() - 0.5, random.uniform() - 0.5));
    const std::optional<SurfaceHit> hit = world.intersect(origin, (target - origin).normalized());
    if (!hit || hit->instance != 0 || !(hit->own_plane.normal.dot(up) > 0.999)) continue;
    ++on_top;
    ASSERT_TRUE(hit->own_mesh_behind);  // a face of a convex box
    const Vertex from = hit->position + world.surface_offset(hit->position, hit->distance) * hit->normal;
    // Ends on the light (a hair below the plane) and above the box.
    const auto& t = light.triangles[random.below(2)];
    const double a = random.uniform(), b = random.uniform() * (1 - a);
    const Vertex ends[2] = {t[0] + a * (t[1] - t[0]) + b * (t[2] - t[0]), hit->position + 2 * up + 0.5 * (s.frame.linear() * Vertex(random.uniform(), 0, 0))};
    for (const Vertex& end : ends) {
      if (hit->normal.dot(end - from) > 0 && hit->own_plane.height(end) < 0) ++float_normal_fooled;
      if (!hit->own_mesh_clear_of(from, end)) continue;
      ++declared_clear;
      for (const Triangle& tri : mesh.triangles)
        ASSERT_FALSE(segment_meets_triangle(from, end, mesh.positions[tri[0]], mesh.positions[tri[1]], mesh.positions[tri[2]]))
            << "a segment declared clear of the own mesh meets it";
      EXPECT_FALSE(world.mesh_blocks(from, end));
    }
  }
  EXPECT_GT(on_top, 2000);
  EXPECT_GT(declared_clear, on_top / 2);  // the ends above the box
  EXPECT_GT(float_normal_fooled, 20);     // the adversarial case occurs: float normals put the light in front
}

// On that scene, bounds gives exact's image, lightcuts' proofs agree with the traced
// lights at error 0, and eq. 8 and the control variate agree with exact within 4 standard
// errors of their paired differences (the same camera and light samples). With the float
// normal's "behind the tangent plane", bounds differed in hundreds of pixels and the
// estimators' bias was tens of standard errors.
TEST(RenderWorld, ShortcutsStayExactOnASliverFanUnderAGrazingLight) {
  for (const double hair : {1e-4, 1e-6}) {
    const SliverFan s = sliver_fan(hair);
    const RenderWorld world(s.scene, s.proxies, {.counting = false, .ray_masks = true, .keep_solids = true});
    ASSERT_TRUE(world.notes().empty()) << world.notes().front();
    const auto [a, b] = testing::exact_and_bounds(s.scene, world, {.spp = 4, .shadow_rays = 4, .seed = 3});
    std::size_t differing = 0, lit = 0;
    for (std::size_t i = 0; i < a.image.pixels.size(); ++i) {
      differing += a.image.pixels[i] != b.image.pixels[i] ? 1 : 0;
      lit += a.image.pixels[i].sum() > 0 ? 1 : 0;
    }
    EXPECT_EQ(differing, 0u) << "hair " << hair;
    EXPECT_GT(b.stats.shadow_rays, 40u);  // samples the float normals put in front of the light

    RenderOptions cuts{.integrator = IntegratorKind::lightcuts, .spp = 1, .seed = 4, .light_points = 64};
    cuts.lightcut = {.error = 0, .max_cut = 1000, .bounds = VisibilityBounds::none, .check_proofs = false};
    const RenderResult none = render(s.scene, world, cuts);
    cuts.lightcut = {.error = 0, .max_cut = 1000, .bounds = VisibilityBounds::both, .check_proofs = true};
    const RenderResult both = render(s.scene, world, cuts);
    EXPECT_EQ(none.image.pixels, both.image.pixels) << "hair " << hair;
    EXPECT_EQ(both.stats.integrator["proof_disagreements"].get<std::uint64_t>(), 0u) << "hair " << hair;

    for (const StochasticEstimator estimator : {StochasticEstimator::term_choice, StochasticEstimator::control_variate}) {
      RenderOptions options{.spp = 16, .shadow_rays = 4, .seed = 9};
      const Image exact = render(s.scene, world, options).image;
      options.visibility = VisibilityMode::stochastic;
      options.estimator = estimator;
      const Image estimate = render(s.scene, world, options).image;
      double sum = 0, squares = 0;
      for (std::size_t i = 0; i < exact.pixels.size(); ++i) {
        const double d = estimate.pixels[i].sum() - exact.pixels[i].sum();
        sum += d, squares += d * d;
      }
      const double z = squares > 0 ? sum / std::sqrt(squares) : 0.0;
      EXPECT_LT(std::abs(z), 4.0) << name_of(estimator) << ", hair " << hair;
    }
  }
}

}  // namespace
}  // namespace visproxy

namespace visproxy {
namespace {

// Tori around one light, with every kind of stochastic proxy a split test meets: a clipped
// convex box (outside), a traced coarse torus (general), balls (general), none (exact), and
// a floor; `shift` moves the whole scene.
Scene split_test_scene(const Vertex& shift, std::vector<MeshProxies>& proxies) {
  Scene scene;
  scene.meshes.push_back({"ring", {}, testing::torus(1.0, 0.35, 48, 16), {}});
  scene.meshes.push_back({"floor", {}, quad(shift + Vertex(-6, -6, -1), {12, 0, 0}, {0, 12, 0}), {}});
  const Vertex places[4] = {{-2.2, -2.2, 0}, {2.2, -2.2, 0.3}, {-2.2, 2.2, 0.6}, {2.2, 2.2, 0.1}};
  for (int i = 0; i < 4; ++i) {
    Eigen::Affine3d transform = Eigen::Affine3d::Identity();
    transform.translate(shift + places[i]).rotate(Eigen::AngleAxisd(0.4 * (i + 1), Vertex(1, 0.5, 0).normalized()));
    scene.instances.push_back({"ring", transform, Color::Constant(0.5), {}});
  }
  scene.instances.push_back({"floor", Eigen::Affine3d::Identity(), Color::Constant(0.5), {}});
  scene.lights.push_back(downward_light(shift + Vertex(0, 0, 4), 1.5));
  scene.camera.from = shift + Vertex(0, -7, 5);
  scene.camera.at = shift;
  scene.camera.up = {0, 0, 1};
  scene.camera.width = scene.camera.height = 24;
  proxies.assign(scene.instances.size(), {});
  proxies[0].stochastic = InstanceProxy{ProxyKind::outside, "aabb", box({-1.4, -1.4, -0.4}, {1.4, 1.4, 0.4}), {}, true};
  proxies[1].stochastic = InstanceProxy{ProxyKind::general, "quadric:64", testing::torus(1.0, 0.3, 8, 4), {}, false};
  std::vector<Sphere> balls;
  for (int k = 0; k < 12; ++k) {
    const double angle = 2 * std::numbers::pi * k / 12;
    balls.push_back({Vertex(std::cos(angle), std::sin(angle), 0), 0.3});
  }
  proxies[2].stochastic = InstanceProxy{ProxyKind::general, "spheres:12", {}, balls, false};
  // Outside proxies for bounds: the box (clipped) and a ball of 320 faces (traced).
  proxies[0].outside = proxies[0].stochastic;
  proxies[1].outside = InstanceProxy{ProxyKind::outside, "ball", sphere_set_mesh({{{0, 0, 0}, 1.5}}, 2), {}, true};
  return scene;  // instances 3 (a ring) and 4 (the floor) have no proxy: traced exactly
}

// Split scenes answer every segment as the own mesh and then the other instances'
// stochastic or outside proxies would, one by one, on segments from points near and inside
// the tori and below the floor (own mesh blocking, a proxy blocking, both, neither), near
// the origin and 10^6 away from it, with ray masks and with the filter function alone; one
// query answers each segment, where a clear one cost two one by one. Beyond
// kSplitScenesUpTo instances, and in counting worlds, there are no split scenes and the
// answers are the same.
TEST(RenderWorld, SplitScenesAnswerAsTheOwnMeshThenTheProxies) {
  for (const Vertex& shift : {Vertex(0, 0, 0), Vertex(1e6, -1e6, 5e5)}) {
    std::vector<MeshProxies> proxies;
    const Scene scene = split_test_scene(shift, proxies);
    const RenderWorld split(scene, proxies), plain(scene, proxies, {.split_scenes = false}),
        unmasked(scene, proxies, {.ray_masks = false});  // split scenes whose filter alone leaves out instances
    Random random(5);
    const auto uniform = [&](double low, double high) { return low + (high - low) * random.uniform(); };
    for (int own = 0; own < static_cast<int>(scene.instances.size()); ++own) {
      EXPECT_TRUE(split.has_split_scene(own));
      EXPECT_FALSE(plain.has_split_scene(own));
      std::array<std::array<int, 3>, 2> seen{};  // per role and answer
      for (int k = 0; k < 3000; ++k) {
        const Vertex from = shift + Vertex(uniform(-3.5, 3.5), uniform(-3.5, 3.5), uniform(-1.4, 1.2));  // some below the floor
        const Vertex to = shift + Vertex(uniform(-0.7, 0.7), uniform(-0.7, 0.7), 3.99);
        // Bounds asks for the outside proxies of some instances only (those its light shaft meets).
        const unsigned some = static_cast<unsigned>(random.uniform() * 32) | instance_bit(1);
        for (const SplitProxies role : {SplitProxies::stochastic, SplitProxies::outside})
          for (const bool trace_own : {true, false}) {
            const unsigned bits = role == SplitProxies::outside && k % 2 == 1 ? some : InstanceFilter{}.bits;
            const InstanceFilter rest{.skip = own, .only = -1, .bits = bits};
            SplitAnswer expected = SplitAnswer::clear;
            if (trace_own && plain.mesh_blocks(from, to, {.skip = -1, .only = own}))
              expected = SplitAnswer::own_blocks;
            else if (role == SplitProxies::stochastic ? plain.proxy_blocks(from, to, rest) : plain.outside_blocks(from, to, rest))
              expected = SplitAnswer::proxy_blocks;
            std::uint64_t exact = 0, proxy = 0, plain_exact = 0, plain_proxy = 0;
            ASSERT_EQ(split.split_blocks(from, to, own, trace_own, exact, proxy, role, bits), expected) << own << " " << k;
            ASSERT_EQ(plain.split_blocks(from, to, own, trace_own, plain_exact, plain_proxy, role, bits), expected) << own << " " << k;
            std::uint64_t unused = 0;
            ASSERT_EQ(unmasked.split_blocks(from, to, own, trace_own, unused, unused, role, bits), expected) << own << " " << k;
            // The joint traversal answers alone, whatever blocks.
            if (trace_own) {
              EXPECT_EQ(exact + proxy, 1u);
            }
            if (trace_own) ++seen[static_cast<std::size_t>(role)][static_cast<std::size_t>(expected)];
              if (trace_own && expected == SplitAnswer::clear) {
              EXPECT_EQ(plain_exact + plain_proxy, 2u);
            }
          }
      }
      // Every answer was met, so the comparison covered each path.
      for (const auto& role : seen)
        for (const int count : role) EXPECT_GT(count, 20) << "instance " << own;
    }
    // The control variate and eq. 8 with splitting render the same images either way.
    for (const StochasticEstimator estimator : {StochasticEstimator::control_variate, StochasticEstimator::term_choice}) {
      const RenderOptions options{.visibility = VisibilityMode::stochastic, .estimator = estimator, .spp = 4, .shadow_rays = 2, .seed = 9};
      const RenderResult a = render(scene, split, options), b = render(scene, plain, options);
      EXPECT_EQ(a.image.pixels, b.image.pixels);
      EXPECT_LT(a.stats.exact_tests + a.stats.proxy_tests, b.stats.exact_tests + b.stats.proxy_tests);
    }
    // Bounds gives exact's image with either world, with fewer queries through the joint one.
    for (const int shadow_rays : {1, 3}) {
      const RenderOptions options{.spp = 4, .shadow_rays = shadow_rays, .seed = 9};
      const auto [exact, joint] = testing::exact_and_bounds(scene, split, options);
      const auto [unused, one_by_one] = testing::exact_and_bounds(scene, plain, options);
      EXPECT_EQ(joint.image.pixels, exact.image.pixels);
      EXPECT_EQ(one_by_one.image.pixels, exact.image.pixels);
      EXPECT_GT(joint.stats.bounds.unoccluded, 100u);
      EXPECT_LT(joint.stats.exact_tests + joint.stats.proxy_tests, one_by_one.stats.exact_tests + one_by_one.stats.proxy_tests);
    }
  }
  // No split scenes beyond kSplitScenesUpTo instances, nor when counting.
  std::vector<MeshProxies> proxies;
  Scene many = split_test_scene(Vertex::Zero(), proxies);
  while (many.instances.size() <= kSplitScenesUpTo) {
    many.instances.push_back(many.instances[3]);
    many.instances.back().transform.translate(Vertex(0, 0, 0.01 * static_cast<double>(many.instances.size())));
    proxies.push_back(proxies[1]);
  }
  std::vector<MeshProxies> few;
  const Scene small = split_test_scene(Vertex::Zero(), few);
  const RenderWorld crowded(many, proxies), counting(small, few, {.counting = true});
  EXPECT_FALSE(crowded.has_split_scene(0));
  EXPECT_FALSE(counting.has_split_scene(0));
  // There, the answers are the own mesh's and then the proxies', one by one.
  Random random(8);
  for (int k = 0; k < 500; ++k) {
    const Vertex from(-3.5 + 7 * random.uniform(), -3.5 + 7 * random.uniform(), -1.4 + 2.6 * random.uniform());
    const Vertex to(-0.7 + 1.4 * random.uniform(), -0.7 + 1.4 * random.uniform(), 3.99);
    const int own = k % 8;
    const SplitAnswer expected = crowded.mesh_blocks(from, to, {.skip = -1, .only = own})              ? SplitAnswer::own_blocks
                                 : crowded.proxy_blocks(from, to, {.skip = own, .only = -1}) ? SplitAnswer::proxy_blocks
                                                                                                       : SplitAnswer::clear;
    std::uint64_t exact = 0, proxy = 0;
    EXPECT_EQ(crowded.split_blocks(from, to, own, true, exact, proxy), expected) << k;
    EXPECT_EQ(exact + proxy, expected == SplitAnswer::own_blocks ? 1u : 2u) << k;
  }
}

}  // namespace
}  // namespace visproxy
