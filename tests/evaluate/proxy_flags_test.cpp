// Flags before shipping: each is raised where it should be and only there, from the
// manifest as build and measure write it.

#include "visproxy/evaluate/proxy_flags.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "schema_support.h"

namespace visproxy {
namespace {

using nlohmann::json;

json measured(const std::string& name, const std::string& kind, double primitives, double f_hit, double f_miss,
              double cost_low, double cost_high, bool holds = true, const std::string& type = "triangle") {
  return {{"name", name},
          {"kind", kind},
          {"primitive_type", type},
          {"primitives", primitives},
          {"result", json::object()},
          {"verify", {{"holds", holds}}},
          {"measure",
           {{"f_hit", {{"value", f_hit}}},
            {"f_miss", {{"value", f_miss}}},
            {"cost_ns_per_ray",
             {{"proxy_over_mesh", 0.5 * (cost_low + cost_high)}, {"proxy_over_mesh_range", {cost_low, cost_high}}}}}}};
}

json manifest_of(json proxies, double triangles = 70000) {
  return {{"mesh", {{"path", "mesh.off"}, {"triangles", triangles}}}, {"proxies", std::move(proxies)}};
}

std::vector<std::string> flagged(const json& manifest, const std::string& flag) {
  std::vector<std::string> names;
  for (const ProxyFlag& f : proxy_flags(manifest))
    if (f.flag == flag) names.push_back(f.proxy);
  return names;
}

TEST(ProxyFlags, AProxyBeatenOnEveryMeasureIsNamedWithTheOneThatBeatsIt) {
  const json manifest = manifest_of({measured("big", "general", 2000, 0.95, 0.90, 0.30, 0.36),
                                     measured("small", "general", 500, 0.96, 0.91, 0.28, 0.33),
                                     measured("other", "general", 400, 0.80, 0.99, 0.20, 0.25)});
  EXPECT_EQ(flagged(manifest, "beaten"), std::vector<std::string>{"big"});
  const std::vector<ProxyFlag> flags = proxy_flags(manifest);
  ASSERT_EQ(flags.size(), 1u);
  EXPECT_NE(flags[0].text.find("beaten by small"), std::string::npos) << flags[0].text;
  EXPECT_NE(flags[0].text.find("ship small instead"), std::string::npos) << flags[0].text;
}

TEST(ProxyFlags, NotBeatenWhereTheOtherLosesOnAnyMeasure) {
  // Fewer primitives and higher fractions, but measurably dearer (ranges apart).
  EXPECT_TRUE(flagged(manifest_of({measured("big", "general", 2000, 0.95, 0.90, 0.30, 0.36),
                                   measured("small", "general", 500, 0.96, 0.91, 0.40, 0.45)}),
                      "beaten")
                  .empty());
  // Cost ranges that overlap are not told apart: beaten.
  EXPECT_EQ(flagged(manifest_of({measured("big", "general", 2000, 0.95, 0.90, 0.30, 0.41),
                                 measured("small", "general", 500, 0.96, 0.91, 0.40, 0.45)}),
                    "beaten"),
            std::vector<std::string>{"big"});
  // Lower f_miss.
  EXPECT_TRUE(flagged(manifest_of({measured("big", "general", 2000, 0.95, 0.90, 0.3, 0.3),
                                   measured("small", "general", 500, 0.96, 0.89, 0.3, 0.3)}),
                      "beaten")
                  .empty());
  // A proved outside claim is not beaten by a general proxy, nor by an outside one whose
  // claim fails; that one, a general proxy in effect, beats the general one.
  EXPECT_EQ(flagged(manifest_of({measured("hull", "outside", 2000, 1.0, 0.90, 0.3, 0.3),
                                 measured("rough", "general", 500, 1.0, 0.95, 0.2, 0.2),
                                 measured("broken", "outside", 400, 1.0, 0.96, 0.2, 0.2, false)}),
                    "beaten"),
            std::vector<std::string>{"rough"});
  // Spheres and triangles are not compared; equal figures flag nothing.
  EXPECT_TRUE(flagged(manifest_of({measured("tris", "general", 2000, 0.9, 0.9, 0.3, 0.3),
                                   measured("balls", "general", 100, 0.95, 0.95, 0.2, 0.2, true, "sphere"),
                                   measured("twin", "general", 2000, 0.9, 0.9, 0.3, 0.3)}),
                      "beaten")
                  .empty());
}

TEST(ProxyFlags, MissedTargetsLargeProxiesAndStrayBalls) {
  json over = measured("outer-64", "outside", 90, 1, 0.9, 0.1, 0.1);
  over["result"] = {{"reached_target", false}};
  json parts = measured("outer-64-parts", "outside", 900, 1, 0.9, 0.1, 0.1);
  parts["result"] = {{"components", {{{"reached_target", true}}, {{"reached_target", false}}, {{"reached_target", false}}}}};
  json met = measured("quadric-512", "general", 512, 0.9, 0.9, 0.1, 0.1);
  met["result"] = {{"reached_target", true}};
  const json huge = measured("hull", "outside", 80000, 1, 0.5, 2, 2);
  json balls = measured("spheres-64", "general", 64, 0.9, 0.9, 0.1, 0.1, true, "sphere");
  balls["result"] = {{"balls_centred_outside_mesh_box", 3}};
  json tidy = measured("spheres-32", "general", 32, 0.9, 0.9, 0.1, 0.1, true, "sphere");
  tidy["result"] = {{"balls_centred_outside_mesh_box", 0}};
  const json manifest = manifest_of({over, parts, met, huge, balls, tidy});
  EXPECT_EQ(flagged(manifest, "missed_target"), (std::vector<std::string>{"outer-64", "outer-64-parts"}));
  EXPECT_EQ(flagged(manifest, "larger_than_mesh"), std::vector<std::string>{"hull"});
  EXPECT_EQ(flagged(manifest, "balls_outside_mesh_box"), std::vector<std::string>{"spheres-64"});
  for (const ProxyFlag& f : proxy_flags(manifest)) {
    if (f.proxy == "outer-64-parts" && f.flag == "missed_target") {
      EXPECT_NE(f.text.find("2 of 3 components"), std::string::npos) << f.text;
    }
    if (f.proxy == "spheres-64" && f.flag == "balls_outside_mesh_box") {
      EXPECT_NE(f.text.find("3 of its 64 balls"), std::string::npos) << f.text;
    }
  }
  // As recommendation.json holds them.
  json recommendation = {{"format", "visproxy-recommendation"}, {"format_version", 1}, {"mesh", "mesh.off"},
                         {"rays", "lines"}, {"seed", 1}, {"efficiency", "x"},
                         {"uses", {{"control_variate", {{"sentence", "s"}, {"proxy", nullptr}, {"efficiency", nullptr}, {"interval", nullptr}}},
                                   {"eq8", {{"sentence", "s"}, {"proxy", nullptr}, {"efficiency", nullptr}, {"interval", nullptr}}},
                                   {"bounds", {{"sentence", "s"}, {"proxy", nullptr}, {"efficiency", nullptr}, {"interval", nullptr}}}}},
                         {"proxies", json::array()}};
  recommendation["flags"] = flags_json(proxy_flags(manifest));
  testing::expect_described(recommendation, "recommendation.schema.json");
}

}  // namespace
}  // namespace visproxy
