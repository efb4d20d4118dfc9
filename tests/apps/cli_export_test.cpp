// `visproxy export` on the 2CylinderEngine glTF (29 meshes, 82 nodes): a GLB and a glTF
// that the Khronos glTF validator passes with 0 errors, holding the engine's own nodes and
// every proxy with its claim kept; bad requests get one line, exit 2 and no file.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "apps/cli_test_support.h"
#include "test_support.h"
#include "visproxy/asset/gltf_document.h"
#include "visproxy/core/files.h"

namespace visproxy {
namespace {

using nlohmann::json;

class CliExport : public testing::ScratchFolder {
 protected:
  void SetUp() override {
    ScratchFolder::SetUp();
    engine_ =
        std::filesystem::path(VISPROXY_ASSIMP_MODEL_DIR) / "glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb";
    if (!std::filesystem::exists(engine_)) GTEST_SKIP() << engine_ << " is missing (Debian's assimp-testmodels)";
    proxies_ = folder_ / "engine";
    const auto built = testing::run_visproxy(
        "build '" + engine_.string() + "' -o '" + proxies_.string() +
        "' --proxy obb --proxy hull --proxy quadric:512 --proxy spheres:25 --hausdorff-samples 1000");
    ASSERT_EQ(built.exit_code, 0) << built.err;
  }

  // The Khronos validator's verdict on `files` (exit code 0: no errors), or a skip note.
  static testing::CommandResult validate(const std::string& files) {
    const std::string command = std::string("NODE_PATH='") + VISPROXY_NODE_MODULES + "' '" + VISPROXY_NODE + "' '" +
                                VISPROXY_SOURCE_DIR + "/tests/asset/validate_gltf.js' " + files;
    testing::CommandResult result;
    FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
    char buffer[4096];
    for (std::size_t got; (got = std::fread(buffer, 1, sizeof buffer, pipe)) > 0;) result.out.append(buffer, got);
    const int status = ::pclose(pipe);
    result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return result;
  }

  std::filesystem::path engine_, proxies_;
};

TEST_F(CliExport, EngineGlbAndGltfPassTheKhronosValidatorWithEveryClaimKept) {
  const std::filesystem::path glb = folder_ / "out" / "engine.glb";
  std::filesystem::create_directories(glb.parent_path());
  const auto exported = testing::run_visproxy("export '" + proxies_.string() + "' -o '" + glb.string() + "'");
  ASSERT_EQ(exported.exit_code, 0) << exported.out << exported.err;
  EXPECT_NE(exported.out.find("4 of 4 claims kept"), std::string::npos) << exported.out;
  const auto gltf = testing::run_visproxy("export '" + proxies_.string() + "' -o '" +
                                          (folder_ / "engine.gltf").string() + "' --proxy hull --progress never");
  ASSERT_EQ(gltf.exit_code, 0) << gltf.out << gltf.err;

  const GltfDocument source = GltfDocument::read(engine_);
  const GltfDocument document = GltfDocument::read(glb);
  const std::size_t source_nodes = source.json().at("nodes").size();
  EXPECT_EQ(source_nodes, 82u);
  ASSERT_EQ(document.json().at("nodes").size(), source_nodes + 4);
  EXPECT_EQ(document.json().at("meshes").size(), source.json().at("meshes").size() + 4);
  for (std::size_t i = 0; i < source_nodes; ++i) ASSERT_EQ(document.json()["nodes"][i], source.json()["nodes"][i]) << i;
  for (std::size_t i = source_nodes; i < source_nodes + 4; ++i) {
    const json& extras = document.json()["nodes"][i].at("extras").at("visproxy");
    EXPECT_EQ(extras.at("shadow_only"), true);
    EXPECT_EQ(extras.at("source"), "2CylinderEngine.glb");
    EXPECT_EQ(extras.at("proved"), extras.at("kind") != "general");
  }
  EXPECT_EQ(document.json()["nodes"][source_nodes + 1].at("extras").at("visproxy").at("kind"), "outside");

  if (std::string(VISPROXY_NODE).empty() ||
      !std::filesystem::exists(std::filesystem::path(VISPROXY_NODE_MODULES) / "gltf-validator"))
    GTEST_SKIP()
        << "Node.js or the npm package gltf-validator is not installed (cmake/bootstrap.sh test installs them): "
           "the Khronos validation is skipped";
  const auto verdict =
      validate("'" + glb.string() + "' '" + (folder_ / "engine.gltf").string() + "' '" + engine_.string() + "'");
  EXPECT_EQ(verdict.exit_code, 0) << verdict.out;
  EXPECT_NE(verdict.out.find("engine.glb: 0 errors"), std::string::npos) << verdict.out;
  EXPECT_NE(verdict.out.find("engine.gltf: 0 errors"), std::string::npos) << verdict.out;

  // The validator catches what it should: the GLB with an accessor's max cut below its data.
  json broken = document.json();
  broken["accessors"][broken["meshes"].back()["primitives"][0]["attributes"]["POSITION"].get<std::size_t>()]["max"][0] =
      -1e30;
  // Written as .gltf with the GLB's binary chunk embedded (the document's own writer).
  json as_gltf = json::parse(GltfDocument::read(glb).gltf());
  as_gltf["accessors"] = broken["accessors"];
  write_file_atomically(folder_ / "broken.gltf", as_gltf.dump());
  const auto refused = validate("'" + (folder_ / "broken.gltf").string() + "'");
  EXPECT_EQ(refused.exit_code, 1) << refused.out;
  EXPECT_NE(refused.out.find("ACCESSOR_MAX_MISMATCH"), std::string::npos) << refused.out;
}

// The round trip the pipeline needs: build --per-mesh, verify, export; each proxy hangs
// under every node that shows its mesh, which Assimp reads back as the proxy's parent.
TEST_F(CliExport, PerMeshProxiesHangUnderEveryNodeThatShowsTheirMesh) {
  const std::filesystem::path parts = folder_ / "parts";
  const auto built = testing::run_visproxy("build '" + engine_.string() + "' -o '" + parts.string() +
                                           "' --per-mesh --proxy obb --proxy hull --hausdorff-samples 500");
  ASSERT_EQ(built.exit_code, 0) << built.err;
  EXPECT_NE(built.out.find("29 of 29 meshes built"), std::string::npos) << built.out;
  const json asset = json::parse(read_file(parts / "asset.json"));
  ASSERT_EQ(asset.at("parts").size(), 29u);
  const json schema = testing::read_schema("asset.schema.json");
  testing::expect_described(asset, schema, schema, "asset.json");
  std::size_t instances = 0;
  for (const json& part : asset["parts"]) instances += part["instances"].size();
  const auto verified = testing::run_visproxy("verify '" + engine_.string() + "' '" + parts.string() + "'");
  ASSERT_EQ(verified.exit_code, 0) << verified.err;
  EXPECT_NE(verified.out.find("58 of 58 claims hold over 29 meshes"), std::string::npos) << verified.out;
  // One part read on its own, as ASSET:MESH.
  const auto info = testing::run_visproxy("info '" + engine_.string() + ":body_24'");
  EXPECT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE(info.out.find("312"), std::string::npos) << info.out;
  EXPECT_NE(info.out.find("(Assimp glb, its mesh body_24,"), std::string::npos) << info.out;
  const auto missing = testing::run_visproxy("info '" + engine_.string() + ":no_such_part'");
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find("holds no mesh named 'no_such_part'"), std::string::npos) << missing.err;

  // measure and report go mesh by mesh too; the report has a row per mesh and a total.
  const auto measured = testing::run_visproxy("measure '" + engine_.string() + "' '" + parts.string() +
                                              "' --rays 2000 --timed-rays 500 --progress never");
  ASSERT_EQ(measured.exit_code, 0) << measured.err;
  EXPECT_NE(measured.out.find("the proxies of 29 meshes"), std::string::npos) << measured.out;
  const auto reported = testing::run_visproxy("report '" + parts.string() + "' --no-pictures");
  ASSERT_EQ(reported.exit_code, 0) << reported.err;
  const json summary = json::parse(read_file(parts / "recommendation.json"));
  ASSERT_EQ(summary.at("parts").size(), 29u);
  const json summary_schema = testing::read_schema("asset-recommendation.schema.json");
  testing::expect_described(summary, summary_schema, summary_schema, "recommendation.json");
  std::size_t asset_triangles = 0;
  for (const json& part : asset["parts"])
    asset_triangles += part["instances"].size() * part["triangles"].get<std::size_t>();
  EXPECT_EQ(summary.at("total").at("triangles"), asset_triangles);
  for (const auto& [use, shipped] : summary.at("total").at("shipped_triangles").items()) {
    std::size_t sum = 0;
    for (const json& row : summary["parts"]) {
      const json& choice = row["uses"][use];
      sum += row["instances"].get<std::size_t>() * choice["triangles"].get<std::size_t>();
      if (choice["file"].is_null())
        EXPECT_EQ(choice["triangles"], row["triangles"]) << use;
      else
        EXPECT_TRUE(std::filesystem::exists(parts / choice["file"].get<std::string>())) << choice["file"];
    }
    EXPECT_EQ(shipped.get<std::size_t>(), sum) << use;
  }
  const std::string report = read_file(parts / "report.md");
  EXPECT_EQ(std::count(report.begin(), report.end(), '\n'), 4 + 2 + 29 + 1) << report;
  EXPECT_TRUE(std::filesystem::exists(parts / "body_24" / "report.md"));

  const std::filesystem::path glb = folder_ / "engine-parts.glb";
  const auto exported = testing::run_visproxy("export '" + parts.string() + "' -o '" + glb.string() + "'");
  ASSERT_EQ(exported.exit_code, 0) << exported.err;
  EXPECT_NE(exported.out.find("58 of 58 claims kept"), std::string::npos) << exported.out;
  const GltfDocument document = GltfDocument::read(glb);
  const json& nodes = document.json().at("nodes");
  ASSERT_EQ(nodes.size(), 82u + 2 * instances);
  // Every proxy node is the child of a source node showing a mesh, named after that mesh's part.
  std::size_t proxy_children = 0;
  for (std::size_t i = 0; i < 82; ++i)
    for (const json& child : nodes[i].value("children", json::array()))
      if (child.get<std::size_t>() >= 82) {
        ++proxy_children;
        const json& proxy = nodes[child.get<std::size_t>()];
        EXPECT_TRUE(nodes[i].contains("mesh")) << i;
        const json& extras = proxy.at("extras").at("visproxy");
        EXPECT_EQ(proxy.at("name"), extras.at("part").get<std::string>() + "." + extras.at("proxy").get<std::string>());
        EXPECT_EQ(extras.at("proved"), true);
      }
  EXPECT_EQ(proxy_children, 2 * instances);
  if (!std::string(VISPROXY_NODE).empty() &&
      std::filesystem::exists(std::filesystem::path(VISPROXY_NODE_MODULES) / "gltf-validator")) {
    const auto verdict = validate("'" + glb.string() + "'");
    EXPECT_EQ(verdict.exit_code, 0) << verdict.out;
    EXPECT_NE(verdict.out.find("engine-parts.glb: 0 errors"), std::string::npos) << verdict.out;
  }
}

// Built again into the same folder from another asset, the old meshes' folders go and
// files of the user's own stay.
TEST_F(CliExport, RebuildingAPerMeshFolderRemovesTheMeshesItNoLongerLists) {
  const std::filesystem::path parts = folder_ / "parts";
  ASSERT_EQ(testing::run_visproxy("build '" + engine_.string() + "' -o '" + parts.string() +
                                  "' --per-mesh --proxy obb --hausdorff-samples 200")
                .exit_code,
            0);
  ASSERT_TRUE(std::filesystem::exists(parts / "body_24" / "manifest.json"));
  write_file_atomically(parts / "notes.txt", "mine\n");
  const std::filesystem::path box =
      std::filesystem::path(VISPROXY_ASSIMP_MODEL_DIR) / "glTF2/BoxTextured-glTF-Binary/BoxTextured.glb";
  const auto rebuilt = testing::run_visproxy("build '" + box.string() + "' -o '" + parts.string() +
                                             "' --per-mesh --proxy obb --hausdorff-samples 200");
  ASSERT_EQ(rebuilt.exit_code, 0) << rebuilt.err;
  const json asset = json::parse(read_file(parts / "asset.json"));
  std::size_t folders = 0;
  for (const auto& item : std::filesystem::directory_iterator(parts)) folders += item.is_directory();
  EXPECT_EQ(folders, asset.at("parts").size());
  EXPECT_FALSE(std::filesystem::exists(parts / "body_24"));
  EXPECT_TRUE(std::filesystem::exists(parts / "notes.txt"));
}

TEST_F(CliExport, BadRequestsGetOneLineAndNoFile) {
  const std::filesystem::path ply = folder_ / "engine.ply";
  const auto two = testing::run_visproxy("export '" + proxies_.string() + "' -o '" + ply.string() + "'");
  EXPECT_EQ(two.exit_code, 2);
  EXPECT_NE(two.err.find("a PLY file holds one mesh"), std::string::npos) << two.err;
  EXPECT_EQ(std::count(two.err.begin(), two.err.end(), '\n'), 1) << two.err;
  EXPECT_FALSE(std::filesystem::exists(ply));
  const auto unknown = testing::run_visproxy("export '" + proxies_.string() + "' -o '" + (folder_ / "x.glb").string() +
                                             "' --proxy wrap");
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_NE(unknown.err.find("lists no proxy named 'wrap'"), std::string::npos) << unknown.err;
  EXPECT_FALSE(std::filesystem::exists(folder_ / "x.glb"));
}

}  // namespace
}  // namespace visproxy
