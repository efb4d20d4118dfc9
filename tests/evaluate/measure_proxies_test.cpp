#include "visproxy/evaluate/measure_proxies.h"

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "test_meshes.h"
#include "visproxy/measure/cost_model.h"

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
  const ProxyGeometry huge{
      .type = PrimitiveType::triangle, .mesh = scaled(mesh, 10, center), .spheres = {}, .files_problem = {}};
  const ProxyGeometry same{.type = PrimitiveType::triangle, .mesh = mesh, .spheres = {}, .files_problem = {}};
  json manifest = {{"proxies", {{{"name", "huge"}, {"kind", "outside"}}, {{"name", "same"}, {"kind", "outside"}}}}};
  const json measured = measure_proxies(
      mesh, manifest, [&](const json&, std::size_t index) { return index == 0 ? huge : same; },
      {.rays = 40000, .seed = 5, .scene = {}, .timing = {.rays = 100, .blocks = 1}, .on_start = {}, .on_warning = {}});
  const json& big = measured["proxies"][0]["measure"];
  EXPECT_EQ(big["rays_contradicting_claim"], 0);
  EXPECT_EQ(big["f_hit"]["value"], 1.0);
  EXPECT_GT(big["rays"]["proxy_sphere_radius"].get<double>(),
            10 * big["rays"]["sphere"]["radius"].get<double>() * 0.99);
  EXPECT_EQ(big["counts"][1], 0);
  EXPECT_EQ(big["counts"][3], 0);
  EXPECT_GT(big["counts"][0], 0);
  // A proxy within the sphere keeps the chords, and blocks exactly the lines the mesh does.
  const json& own = measured["proxies"][1]["measure"];
  EXPECT_FALSE(own["rays"].contains("proxy_sphere_radius"));
  EXPECT_EQ(own["counts"][1], 0);
  EXPECT_EQ(own["counts"][2], 0);
}

// Six proxies timed in one run fit the cost model (measure/cost_model.h): each proxy's
// interval holds its timed ratio and its blocks', the work counted on the timed rays is
// the same numbers in a second run (only the timings move), a proxy that is the mesh
// itself does the mesh's work, and balls are counted as balls. With fewer proxies than
// the fit needs, the manifest says so and the blocks' range is the interval read.
TEST(MeasureProxies, TheCostModelsIntervalsHoldTheTimingsAndTheWorkIsTheSameEachRun) {
  const TriangleMesh mesh = testing::torus(1.0, 0.3, 96, 48);
  auto geometry = [](TriangleMesh m) {
    return ProxyGeometry{.type = PrimitiveType::triangle, .mesh = std::move(m), .spheres = {}, .files_problem = {}};
  };
  TriangleMesh box = unit_cube();
  for (Vertex& p : box.positions) p = Vertex(-1.3, -1.3, -0.3) + p.cwiseProduct(Vertex(2.6, 2.6, 0.6));
  std::vector<ProxyGeometry> proxies = {geometry(mesh), geometry(testing::torus(1.0, 0.3, 8, 4)),
                                        geometry(testing::torus(1.0, 0.3, 16, 8)),
                                        geometry(testing::torus(1.0, 0.3, 32, 16)), geometry(box)};
  ProxyGeometry balls{.type = PrimitiveType::sphere, .mesh = {}, .spheres = {}, .files_problem = {}};
  for (int i = 0; i < 12; ++i) {
    const double a = 2 * 3.141592653589793 * i / 12;
    balls.spheres.push_back({Vertex(std::cos(a), std::sin(a), 0), 0.25});
  }
  proxies.push_back(balls);
  json manifest = {{"proxies", json::array()}};
  for (std::size_t i = 0; i < proxies.size(); ++i)
    manifest["proxies"].push_back({{"name", "p" + std::to_string(i)}, {"kind", "general"}});
  const MeasureOptions options{
      .rays = 20000, .seed = 3, .scene = {}, .timing = {.rays = 4000, .blocks = 3}, .on_start = {}, .on_warning = {}};
  auto read = [&](const json&, std::size_t index) { return proxies[index]; };
  const json first = measure_proxies(mesh, manifest, read, options),
             second = measure_proxies(mesh, manifest, read, options);
  ASSERT_TRUE(first["cost_model"]["fitted"].get<bool>()) << first["cost_model"].dump();
  EXPECT_EQ(first["cost_model"]["observations"], proxies.size());
  EXPECT_EQ(first["cost_model"]["mesh_work"], second["cost_model"]["mesh_work"]);
  for (std::size_t i = 0; i < proxies.size(); ++i) {
    const json& measure = first["proxies"][i]["measure"];
    const json& cost = measure["cost_ns_per_ray"];
    EXPECT_EQ(cost["work"], second["proxies"][i]["measure"]["cost_ns_per_ray"]["work"]) << i;
    const auto interval = cost_ratio_interval(measure);
    ASSERT_TRUE(interval) << i;
    EXPECT_LE((*interval)[0], cost["proxy_over_mesh"].get<double>()) << i;
    EXPECT_GE((*interval)[1], cost["proxy_over_mesh"].get<double>()) << i;
    EXPECT_LE((*interval)[0], cost["proxy_over_mesh_range"][0].get<double>()) << i;
    EXPECT_GE((*interval)[1], cost["proxy_over_mesh_range"][1].get<double>()) << i;
    EXPECT_GT(cost["predicted"]["proxy_over_mesh"].get<double>(), 0) << i;
    EXPECT_EQ(cost["work"]["balls"].get<double>() > 0, i == 5) << i;
    EXPECT_EQ(cost["work"]["triangles"].get<double>() > 0, i != 5) << i;
  }
  EXPECT_EQ(first["proxies"][0]["measure"]["cost_ns_per_ray"]["work"], first["cost_model"]["mesh_work"]);
  // The coarsest torus does less work per ray than the mesh it stands for.
  EXPECT_LT(first["proxies"][1]["measure"]["cost_ns_per_ray"]["work"]["nodes"].get<double>(),
            first["cost_model"]["mesh_work"]["nodes"].get<double>());

  json few = {{"proxies", json::array()}};
  for (std::size_t i = 0; i + 1 < kCostModelMinimumObservations; ++i)
    few["proxies"].push_back({{"name", "p" + std::to_string(i)}, {"kind", "general"}});
  const json alone = measure_proxies(mesh, few, read, options);
  EXPECT_FALSE(alone["cost_model"]["fitted"].get<bool>());
  EXPECT_NE(alone["cost_model"]["why_not"].get<std::string>().find("fewer than"), std::string::npos);
  const json& measure = alone["proxies"][0]["measure"];
  EXPECT_FALSE(measure["cost_ns_per_ray"].contains("predicted"));
  EXPECT_EQ(cost_ratio_interval(measure),
            (std::array<double, 2>{measure["cost_ns_per_ray"]["proxy_over_mesh_range"][0].get<double>(),
                                   measure["cost_ns_per_ray"]["proxy_over_mesh_range"][1].get<double>()}));
}

}  // namespace
}  // namespace visproxy
