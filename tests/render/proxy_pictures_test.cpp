// Pictures of a proxy and its shadow: a proved outside proxy never misses shadow and a
// proved inside proxy never adds any, even far from the origin and with the light inside
// the proxy; the mesh as its own proxy changes nothing; a proxy moved by hand shows both
// colours; the pixels do not depend on the number of threads.

#include "visproxy/render/proxy_pictures.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>

#include "render/render_test_scenes.h"
#include "test_meshes.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/mesh/sphere_set.h"
#include "visproxy/verify/containment.h"
#include "visproxy/verify/sphere_containment.h"

namespace visproxy {
namespace {

constexpr ProxyPictureOptions kSmall{.size = 64, .light_samples_per_side = 5};

TriangleMesh knot() { return read_mesh(testing::cgal_mesh("knot1.off")); }

InstanceProxy outside_box(const TriangleMesh& mesh) {
  const BoundingBox b = bounding_box(mesh);
  InstanceProxy proxy{ProxyKind::outside, "aabb", testing::box(b.min, b.max), {}, true};
  EXPECT_TRUE(check_containment(proxy.mesh, mesh).contained());  // the claim the flag asserts
  return proxy;
}

double mean(const std::vector<double>& values) {
  double sum = 0;
  for (double v : values) sum += v;
  return sum / static_cast<double>(values.size());
}

// Pixels whose colour is mostly the given channel (red for missed shadow, blue for extra).
std::size_t pixels_leaning(const Image& image, int channel) {
  return static_cast<std::size_t>(std::count_if(image.pixels.begin(), image.pixels.end(), [&](const Color& c) {
    const double others = (c.sum() - c[channel]) / 2;
    return c[channel] > 0.3 && c[channel] > 2 * others;
  }));
}

// Pixels where the channel stands out of the grey of the mesh and the background.
std::size_t pixels_tinted(const Image& image, int channel) {
  return static_cast<std::size_t>(std::count_if(image.pixels.begin(), image.pixels.end(), [&](const Color& c) {
    return c[channel] > std::max(c[(channel + 1) % 3], c[(channel + 2) % 3]) + 0.05;
  }));
}

TEST(ProxyPictures, TheMeshCastsAShadowOnTheGround) {
  const ProxyPictureStage stage(knot(), kSmall);
  const std::vector<double>& light = stage.mesh_light_fractions();
  ASSERT_EQ(light.size(), 64u * 64u);
  const auto [lo, hi] = std::minmax_element(light.begin(), light.end());
  EXPECT_EQ(*lo, 0.0);  // umbra somewhere
  EXPECT_EQ(*hi, 1.0);  // fully lit ground around it
  EXPECT_GT(mean(light), 0.5);
  EXPECT_EQ(stage.mesh_shadow().width, 64);
}

TEST(ProxyPictures, AProvedOutsideProxyMissesNoShadowAndAProvedInsideOneAddsNone) {
  const TriangleMesh ball = sphere_set_mesh({{{0.3, -0.2, 0.1}, 1.0}}, 3);
  const ProxyPictureStage stage(ball, kSmall);
  const ProxyPictures box = stage.pictures(outside_box(ball));
  EXPECT_EQ(box.missed_shadow, 0.0);
  EXPECT_GT(box.extra_shadow, 0.05);  // a box's shadow is larger than a ball's
  EXPECT_EQ(pixels_leaning(box.difference, 0), 0u);
  EXPECT_GT(pixels_leaning(box.difference, 2), 0u);

  const std::vector<Sphere> inner = {{{0.3, -0.2, 0.1}, 0.8}};
  ASSERT_TRUE(check_spheres_inside(ball, inner).contained());
  const ProxyPictures spheres = stage.pictures({ProxyKind::inside, "inside", {}, inner, true});
  EXPECT_EQ(spheres.extra_shadow, 0.0);
  EXPECT_GT(spheres.missed_shadow, 0.05);
  EXPECT_EQ(pixels_leaning(spheres.difference, 2), 0u);
  EXPECT_GT(pixels_leaning(spheres.difference, 0), 0u);
  // The inside proxy shows through the mesh in its colour (green), the box over it in blue.
  EXPECT_GT(pixels_tinted(spheres.overlay, 1), 400u);
  EXPECT_EQ(pixels_tinted(spheres.overlay, 2), 0u);
  EXPECT_GT(pixels_tinted(box.overlay, 2), 400u);
  EXPECT_EQ(pixels_tinted(box.overlay, 1), 0u);
}

TEST(ProxyPictures, AProvedOutsideProxyOfAKnotMissesNoShadowFarFromTheOrigin) {
  TriangleMesh mesh = knot();
  const ProxyPictureStage near_stage(mesh, kSmall);
  const std::vector<double> near = near_stage.proxy_light_fractions(outside_box(mesh));
  const double d = bounding_box(mesh).diagonal();
  const Eigen::Affine3d far_away(Eigen::Translation3d(Vertex(3e5, -2e5, 4e5) * d));
  mesh = transformed_mesh(mesh, far_away);
  const ProxyPictureStage far_stage(mesh, kSmall);
  const ProxyPictures far = far_stage.pictures(outside_box(mesh));
  EXPECT_EQ(far.missed_shadow, 0.0);
  // The same picture, up to Embree's float rounding relative to the mesh's extent.
  const std::vector<double> far_light = far_stage.proxy_light_fractions(outside_box(mesh));
  double differ = 0;
  for (std::size_t i = 0; i < near.size(); ++i) differ += std::abs(near[i] - far_light[i]);
  EXPECT_LT(differ / static_cast<double>(near.size()), 1e-3);
  double mesh_differ = 0;
  for (std::size_t i = 0; i < near.size(); ++i)
    mesh_differ += std::abs(near_stage.mesh_light_fractions()[i] - far_stage.mesh_light_fractions()[i]);
  EXPECT_LT(mesh_differ / static_cast<double>(near.size()), 1e-3);
}

TEST(ProxyPictures, TheMeshAsItsOwnProxyChangesNothing) {
  const TriangleMesh mesh = knot();
  const ProxyPictureStage stage(mesh, kSmall);
  const ProxyPictures same = stage.pictures({ProxyKind::general, "mesh", mesh, {}, false});
  EXPECT_EQ(same.missed_shadow, 0.0);
  EXPECT_EQ(same.extra_shadow, 0.0);
  EXPECT_EQ(same.shadow.pixels, stage.mesh_shadow().pixels);
}

TEST(ProxyPictures, AProxyMovedByHandShowsMissedAndExtraShadow) {
  const TriangleMesh mesh = knot();
  const ProxyPictureStage stage(mesh, kSmall);
  const double d = bounding_box(mesh).diagonal();
  const TriangleMesh moved = transformed_mesh(mesh, Eigen::Affine3d(Eigen::Translation3d(0.3 * d, 0, 0)));
  // Claimed outside, not proved (a file moved by hand): the pictures show what it does.
  const ProxyPictures p = stage.pictures({ProxyKind::outside, "moved", moved, {}, false});
  EXPECT_GT(p.missed_shadow, 0.2);
  EXPECT_GT(p.extra_shadow, 0.2);
  EXPECT_GT(pixels_leaning(p.difference, 0), 20u);
  EXPECT_GT(pixels_leaning(p.difference, 2), 20u);
}

TEST(ProxyPictures, ALightInsideAProvedOutsideProxyLeavesTheGroundInItsShadow) {
  const TriangleMesh mesh = knot();
  const ProxyPictureStage stage(mesh, kSmall);
  const BoundingBox b = bounding_box(mesh);
  const double d = b.diagonal();
  // A box holding the mesh, the light and the ground: every segment from the ground to the
  // light lies in its solid.
  InstanceProxy huge{ProxyKind::outside,
                     "huge",
                     testing::box(b.min - Vertex::Constant(10 * d), b.max + Vertex::Constant(10 * d)),
                     {},
                     true};
  const ProxyPictures p = stage.pictures(huge);
  EXPECT_EQ(p.missed_shadow, 0.0);
  for (double v : stage.proxy_light_fractions(huge)) ASSERT_EQ(v, 0.0);
}

TEST(ProxyPictures, AnEmptyProxyMissesTheWholeShadow) {
  const ProxyPictureStage stage(knot(), kSmall);
  const ProxyPictures p = stage.pictures({ProxyKind::general, "empty", {}, {}, false});
  EXPECT_DOUBLE_EQ(p.missed_shadow, 1.0);
  EXPECT_EQ(p.extra_shadow, 0.0);
}

TEST(ProxyPictures, PixelsDoNotDependOnTheNumberOfThreads) {
  const TriangleMesh mesh = knot();
  const InstanceProxy spheres{ProxyKind::general, "balls", {}, {{{0, 0, 0}, 0.5}, {{1, 0.5, 0}, 0.4}}, false};
  ProxyPictures one, many;
  {
    tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    const ProxyPictureStage stage(mesh, {.size = 96, .light_samples_per_side = 4});
    one = stage.pictures(spheres);
  }
  const ProxyPictureStage stage(mesh, {.size = 96, .light_samples_per_side = 4});
  many = stage.pictures(spheres);
  EXPECT_EQ(one.overlay.pixels, many.overlay.pixels);
  EXPECT_EQ(one.shadow.pixels, many.shadow.pixels);
  EXPECT_EQ(one.difference.pixels, many.difference.pixels);
}

TEST(ProxyPictures, AMeshWithNoExtentIsRefused) {
  TriangleMesh point;
  point.positions = {{1, 1, 1}, {1, 1, 1}, {1, 1, 1}};
  point.triangles = {{0, 1, 2}};
  EXPECT_THROW(ProxyPictureStage stage(point), Error);
}

}  // namespace
}  // namespace visproxy
