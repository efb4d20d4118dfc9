// `visproxy info` on real meshes, as text and as JSON.

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "apps/cli_test_support.h"
#include "test_meshes.h"
#include "test_support.h"

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

using CliInfoWarnings = testing::ScratchFolder;

TEST_F(CliInfoWarnings, BlenderPlyHeaderLineIsReportedOnStderr) {
  const auto path = folder_ / "blender.ply";
  std::ofstream(path, std::ios::binary)
      << "ply\nformat ascii 1.0\nCreated by Blender3D 247 - www.blender.org, source file: 'tetra.blend'\n"
         "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
         "element face 4\nproperty list uchar uint vertex_indices\nend_header\n"
         "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
  const auto result = testing::run_visproxy("info --json '" + path.string() + "'");
  EXPECT_EQ(result.exit_code, 0) << result.err;
  EXPECT_EQ(result.err, "visproxy: warning: " + path.string() +
                            ":3: unknown header line 'Created by Blender3D 247 - www.blender.org, source file: "
                            "'tetra.blend'' ignored\n");
  const nlohmann::json json = nlohmann::json::parse(result.out);
  EXPECT_EQ(json.at("vertices"), 4);
  EXPECT_EQ(json.at("triangles"), 4);
  EXPECT_EQ(json.at("watertight"), true);
}

}  // namespace
}  // namespace visproxy

namespace visproxy {
namespace {

// Assimp's formats through the CLI: a glTF 2.0 binary model and a Collada one are read,
// built and verified; every file of assimp-testmodels' `invalid/` folder gets one line
// naming it and exit code 2.
TEST(CliInfo, AssimpFormatsAreReadAndBrokenFilesGetOneLineAndExitTwo) {
  const std::filesystem::path models = VISPROXY_ASSIMP_MODEL_DIR;
  const std::filesystem::path engine = models / "glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb";
  const auto info = testing::run_visproxy("info --json '" + engine.string() + "'");
  ASSERT_EQ(info.exit_code, 0) << info.err;
  const nlohmann::json json = nlohmann::json::parse(info.out);
  EXPECT_EQ(json.at("format"), "Assimp");
  EXPECT_EQ(json.at("triangles"), 121496);
  EXPECT_EQ(json.at("components"), 86);  // the engine's parts, placed by their nodes and welded
  testing::expect_described(json, "info.schema.json");
  const auto folder = std::filesystem::temp_directory_path() / ("visproxy-assimp-" + std::to_string(::getpid()));
  const auto build = testing::run_visproxy("build '" + engine.string() + "' -o '" + folder.string() + "' --proxy hull:64");
  ASSERT_EQ(build.exit_code, 0) << build.err;
  const auto verify = testing::run_visproxy("verify '" + engine.string() + "' '" + folder.string() + "'");
  EXPECT_EQ(verify.exit_code, 0) << verify.out << verify.err;
  std::filesystem::remove_all(folder);

  int refused = 0;
  for (const auto& item : std::filesystem::directory_iterator(models / "invalid")) {
    if (!item.is_regular_file()) continue;
    const auto result = testing::run_visproxy("info '" + item.path().string() + "'");
    EXPECT_EQ(result.exit_code, 2) << item.path() << result.out << result.err;
    EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
    EXPECT_EQ(result.err.rfind("visproxy: " + item.path().string() + ":", 0), 0u) << result.err;
    EXPECT_TRUE(result.out.empty()) << result.out;
    ++refused;
  }
  EXPECT_GE(refused, 10);
}

}  // namespace
}  // namespace visproxy
