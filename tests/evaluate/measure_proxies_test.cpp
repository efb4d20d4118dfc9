#include "visproxy/evaluate/measure_proxies.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "test_meshes.h"

namespace visproxy {
namespace {

using nlohmann::json;

using testing::unit_cube;

TriangleMesh scaled(TriangleMesh mesh, double factor, const Vertex& center) {
  for (Vertex& p : mesh.positions) p = center + factor * (p - center);
  return mesh;
}

// An outside proxy far larger than the mesh's bounding sphere: every chord of that sphere
// starts and ends inside the proxy's solid and crosses none of its surface. Traced on the
// chords, the proxy would miss every line the mesh blocks (f_hit 0, every such line
// "contradicting" a claim that holds); traced on the lines, it blocks every one of them,
// since each passes through the sphere, which the proxy holds.
TEST(MeasureProxies, AnOutsideProxyBeyondTheBoundingSphereIsTracedOnTheWholeLines) {
  const TriangleMesh mesh = unit_cube();
  const Vertex center(0.5, 0.5, 0.5);
  const ProxyGeometry huge{.type = PrimitiveType::triangle, .mesh = scaled(mesh, 10, center), .spheres = {}, .files_problem = {}};
  const ProxyGeometry same{.type = PrimitiveType::triangle, .mesh = mesh, .spheres = {}, .files_problem = {}};
  json manifest = {{"proxies", {{{"name", "huge"}, {"kind", "outside"}}, {{"name", "same"}, {"kind", "outside"}}}}};
  const json measured = measure_proxies(
      mesh, manifest, [&](const json&, std::size_t index) { return index == 0 ? huge : same; },
      {.rays = 40000, .seed = 5, .scene = {}, .timing = {.rays = 100, .blocks = 1}, .on_start = {}, .on_warning = {}});
  const json& big = measured["proxies"][0]["measure"];
  EXPECT_EQ(big["rays_contradicting_claim"], 0);
  EXPECT_EQ(big["f_hit"]["value"], 1.0);
  EXPECT_GT(big["rays"]["proxy_sphere_radius"].get<double>(), 10 * big["rays"]["sphere"]["radius"].get<double>() * 0.99);
  EXPECT_EQ(big["counts"][1], 0);
  EXPECT_EQ(big["counts"][3], 0);
  EXPECT_GT(big["counts"][0], 0);
  // A proxy within the sphere keeps the chords, and blocks exactly the lines the mesh does.
  const json& own = measured["proxies"][1]["measure"];
  EXPECT_FALSE(own["rays"].contains("proxy_sphere_radius"));
  EXPECT_EQ(own["counts"][1], 0);
  EXPECT_EQ(own["counts"][2], 0);
}

}  // namespace
}  // namespace visproxy
