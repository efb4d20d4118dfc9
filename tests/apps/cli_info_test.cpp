// `visproxy info` on real meshes, as text and as JSON.

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "apps/cli_test_support.h"
#include "test_meshes.h"

namespace visproxy {
namespace {

nlohmann::json info_json(const std::string& mesh) {
  const auto result = testing::run_visproxy("info --json '" + testing::cgal_mesh(mesh).string() + "'");
  EXPECT_EQ(result.exit_code, 0) << result.err;
  EXPECT_TRUE(result.err.empty()) << result.err;
  return nlohmann::json::parse(result.out);
}

TEST(CliInfo, BunnyIsWatertight) {
  const nlohmann::json json = info_json("bunny00.off");
  EXPECT_EQ(json.at("vertices"), 37706);
  EXPECT_EQ(json.at("triangles"), 75408);
  EXPECT_EQ(json.at("components"), 1);
  EXPECT_EQ(json.at("boundary_edges"), 0);
  EXPECT_EQ(json.at("non_manifold_edges"), 0);
  EXPECT_EQ(json.at("self_intersecting"), false);
  EXPECT_EQ(json.at("outward_oriented"), true);
  EXPECT_EQ(json.at("watertight"), true);
  EXPECT_GT(json.at("volume").get<double>(), 0);
  EXPECT_EQ(json.at("format"), "OFF");
}

TEST(CliInfo, MeshesWithHolesAreNotWatertight) {
  for (const char* mesh : {"elephant-with-holes.off", "ChineseDragon-10kv.off"}) {
    const nlohmann::json json = info_json(mesh);
    EXPECT_EQ(json.at("watertight"), false) << mesh;
    EXPECT_GT(json.at("boundary_edges").get<int>(), 0) << mesh;
    EXPECT_TRUE(json.at("volume").is_null()) << mesh;
  }
}

TEST(CliInfo, TextReportNamesTheFileAndUnits) {
  const auto path = testing::cgal_mesh("knot1.off");
  const auto result = testing::run_visproxy("info '" + path.string() + "'");
  EXPECT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find(path.string()), std::string::npos);
  EXPECT_NE(result.out.find("watertight             yes"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("mesh units^2"), std::string::npos);
}

TEST(CliInfo, StlIsWeldedUnlessAskedNotTo) {
  const auto path = testing::cgal_mesh("sphere.stl").string();
  const auto welded = nlohmann::json::parse(testing::run_visproxy("info --json '" + path + "'").out);
  EXPECT_EQ(welded.at("watertight"), true);
  const auto soup = nlohmann::json::parse(testing::run_visproxy("info --json --weld never '" + path + "'").out);
  EXPECT_EQ(soup.at("vertices"), 3 * soup.at("triangles").get<int>());
  EXPECT_EQ(soup.at("watertight"), false);
}

}  // namespace
}  // namespace visproxy
