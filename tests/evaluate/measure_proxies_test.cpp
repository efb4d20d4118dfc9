#include "visproxy/evaluate/measure_proxies.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "test_meshes.h"
#include "visproxy/estimator/efficiency.h"
#include "visproxy/measure/cost_model.h"
#include "visproxy/render/renderer.h"
#include "visproxy/scene/scene.h"

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

// The render's noise with a use, predicted by measure --scene from the ray types of the
// render's own camera samples and the exact render's noise within a pixel, against the
// noise of that use in renders: a torus over a floor under a small light above and a wide
// one to the side (whose light sampling is noise the proxies do not touch), an outside box
// and a coarse general torus as proxies, eq. 8 and the control variate at equal
// probabilities. 96 renders of one sample per pixel give each pixel's variance; the ratio
// of their sums over 1 200 pixels lies within 10 % of the prediction (it came within 1-4 %:
// the prediction's and the renders' sampling noise are each a few per cent here). The
// shadow ray's own variance ratio, which takes visibility for the render's only noise,
// misses eq. 8's by more than half and the control variate's by more than twice the
// prediction's miss: the test tells the two apart.
TEST(MeasureProxies, TheRendersNoiseWithAUseIsPredictedFromItsOwnCameraSamples) {
  const TriangleMesh ring = testing::torus(1.0, 0.35, 48, 16);
  const std::filesystem::path dir = std::filesystem::path(::testing::TempDir()) / "render_noise";
  std::filesystem::create_directories(dir);
  const std::filesystem::path scene_path = dir / "scene.json";
  {
    json positions = json::array(), triangles = json::array();
    for (const Vertex& p : ring.positions) positions.push_back({p.x(), p.y(), p.z()});
    for (const Triangle& t : ring.triangles) triangles.push_back({t[0], t[1], t[2]});
    const json scene = {
        {"format", "visproxy-scene"},
        {"format_version", 1},
        {"meshes",
         {{"ring", {{"positions", positions}, {"triangles", triangles}}},
          {"floor", {{"positions", {{-4, -4, 0}, {4, -4, 0}, {4, 4, 0}, {-4, 4, 0}}}, {"triangles", {{0, 1, 2}, {0, 2, 3}}}}}}},
        {"instances",
         {{{"mesh", "floor"}, {"albedo", {0.7, 0.7, 0.7}}},
          {{"mesh", "ring"}, {"albedo", {0.8, 0.5, 0.3}}, {"transform", {{"translate", {0.3, 0, 1.0}}}}}}},
        {"lights",
         {{{"type", "parallelogram"}, {"corner", {-0.4, -0.4, 3.5}}, {"edge1", {0, 0.8, 0}}, {"edge2", {0.8, 0, 0}}, {"radiance", {10, 10, 10}}},
          {{"type", "parallelogram"}, {"corner", {5, -1.5, 0.2}}, {"edge1", {0, 0, 3}}, {"edge2", {0, 3, 0}}, {"radiance", {2, 2, 3}}}}},
        {"camera", {{"from", {0, -5, 4}}, {"at", {0, 0, 0.3}}, {"up", {0, 0, 1}}, {"fov_degrees", 60}, {"width", 40}, {"height", 30}}}};
    std::ofstream(scene_path) << scene.dump();
  }
  TriangleMesh box = unit_cube();
  for (Vertex& p : box.positions) p = Vertex(-1.36, -1.36, -0.36) + p.cwiseProduct(Vertex(2.72, 2.72, 0.72));
  const std::vector<std::pair<ProxyKind, TriangleMesh>> proxies = {{ProxyKind::outside, box},
                                                                   {ProxyKind::general, testing::torus(1.0, 0.3, 8, 4)}};
  json manifest = {{"proxies", {{{"name", "box"}, {"kind", "outside"}}, {{"name", "coarse"}, {"kind", "general"}}}}};
  const json measured = measure_proxies(
      ring, manifest,
      [&](const json&, std::size_t index) {
        return ProxyGeometry{.type = PrimitiveType::triangle, .mesh = proxies[index].second, .spheres = {}, .files_problem = {}};
      },
      {.rays = 20000, .seed = 7, .scene = scene_path, .timing = {.rays = 500, .blocks = 1}, .on_start = {}, .on_warning = {}});
  const json& noise = measured.at("render_share").at("noise");
  const double exact_variance = noise.at("exact_variance_per_sample").get<double>();
  ASSERT_GT(exact_variance, 0);
  EXPECT_LT(noise.at("standard_error").get<double>(), 0.1 * exact_variance);

  const Scene scene = load_scene(scene_path);
  constexpr int kRenders = 96;
  // Per pixel, the variance over kRenders renders of one sample; summed over the image.
  auto summed_variance = [&](const RenderWorld& world, RenderOptions options) {
    const std::size_t pixels = static_cast<std::size_t>(scene.camera.width * scene.camera.height);
    std::vector<Color> sum(pixels, Color::Zero()), squares(pixels, Color::Zero());
    options.spp = 1;
    for (int k = 0; k < kRenders; ++k) {
      options.seed = 1000 + static_cast<std::uint64_t>(k);
      const Image image = render(scene, world, options).image;
      for (std::size_t i = 0; i < pixels; ++i) sum[i] += image.pixels[i], squares[i] += image.pixels[i].cwiseProduct(image.pixels[i]);
    }
    double total = 0;  // per channel, as mean_squared_error counts it
    for (std::size_t i = 0; i < pixels; ++i)
      total += (squares[i] - sum[i].cwiseProduct(sum[i]) / kRenders).sum() / 3 / (kRenders - 1);
    return total;
  };
  for (std::size_t p = 0; p < proxies.size(); ++p) {
    std::vector<MeshProxies> world_proxies(2);
    world_proxies[1].stochastic = InstanceProxy{proxies[p].first, manifest["proxies"][p]["name"], proxies[p].second, {}, true};
    const RenderWorld world(scene, world_proxies);
    const double exact = summed_variance(world, {});
    const json& by_type = measured["proxies"][p]["measure"]["render_noise"]["squared_contribution_by_type"];
    std::array<double, 4> weighted{};
    for (std::size_t t = 0; t < 4; ++t) weighted[t] = by_type[t].get<double>();
    EXPECT_GT(weighted[0] + weighted[1] + weighted[2], 0) << p;  // the proxies do change segments here
    const json& counts = measured["proxies"][p]["measure"]["counts"];
    RayTypeCounts ray_counts;
    for (std::size_t t = 0; t < 4; ++t) ray_counts.counts[t] = counts[t].get<std::uint64_t>();
    const RayTypeFractions fractions = RayTypeFractions::from(ray_counts);
    const ProxyKind kind = proxies[p].first;
    // The render's exact noise per pixel is the one the pairs of samples found.
    const double pixels = scene.camera.width * scene.camera.height;
    EXPECT_NEAR(exact / pixels / exact_variance, 1.0, 0.1);
    std::array<double, 4> own{};
    for (std::size_t t = 0; t < 4; ++t) own[t] = noise["own_instances_squared_contribution_by_type"][t].get<double>();
    EXPECT_GT(own[3], 0);
    EXPECT_EQ(own[1] + own[2], 0);
    for (const ProxyUse use : {ProxyUse::term_choice, ProxyUse::control_variate}) {
      // Equal probabilities for the floor's segments (the rest of the scene is the proxy's
      // kind) and for the ring's own (the rest is exact: outside).
      UseSetting setting, own_setting;
      setting.term = equal_probabilities(kind);
      setting.correction = equal_correction_probabilities(kind);
      own_setting.term = equal_probabilities(ProxyKind::outside);
      own_setting.correction = equal_correction_probabilities(ProxyKind::outside);
      const double predicted = render_variance_ratio(weighted, added_variance_by_type(use, setting), exact_variance) +
                               render_variance_ratio(own, added_variance_by_type(use, own_setting), exact_variance) - 1;
      RenderOptions options{.visibility = VisibilityMode::stochastic,
                            .estimator = use == ProxyUse::term_choice ? StochasticEstimator::term_choice
                                                                      : StochasticEstimator::control_variate};
      const double rendered = summed_variance(world, options) / exact;
      EXPECT_NEAR(rendered / predicted, 1.0, 0.1) << manifest["proxies"][p]["name"] << " " << use_name(use) << ": rendered "
                                                   << rendered << ", predicted " << predicted;
      const double mesh_variance = fractions.v_avg() * (1 - fractions.v_avg());
      const double ray = use == ProxyUse::term_choice ? estimator_variance(fractions, setting.term) / mesh_variance
                                                       : control_variate_variance(fractions, setting.correction) / mesh_variance;
      // The shadow ray's ratio misses the render: by far for eq. 8, which adds noise to
      // every ray it does not trace exactly.
      EXPECT_GT(std::abs(rendered / ray - 1), use == ProxyUse::term_choice ? 0.5 : 2 * std::abs(rendered / predicted - 1))
          << use_name(use) << ": the shadow ray's ratio " << ray << " is not told apart";
    }
  }
}

}  // namespace
}  // namespace visproxy
