#include "render/renderer.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <numbers>

#include "mesh/sphere_set.h"
#include "test_support.h"

namespace visproxy {
namespace {

TriangleMesh quad(const Vertex& corner, const Vertex& u, const Vertex& v) {
  TriangleMesh mesh;
  mesh.positions = {corner, corner + u, corner + u + v, corner + v};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  return mesh;
}

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

}  // namespace
}  // namespace visproxy
