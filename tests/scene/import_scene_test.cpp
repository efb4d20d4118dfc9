#include "visproxy/scene/import_scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>

#include "visproxy/core/errors.h"
#include "visproxy/core/files.h"
#include "test_support.h"

namespace visproxy {
namespace {

using nlohmann::json;

const std::filesystem::path kBoxes = std::filesystem::path(VISPROXY_SOURCE_DIR) / "data/scenes/boxes.gltf";

// data/scenes/boxes.gltf: a floor, one box mesh used by two nodes under a parent node
// (translated, rotated 30 degrees about +Y, scaled), an emissive lamp of strength 12 and a
// camera at (0, 2, 4.5) aimed at (0, 0.4, 0) with yfov 0.7 at aspect 4:3.
TEST(ImportScene, GltfNodesBecomeInstancesTheLampALightTheCameraTheCamera) {
  const Scene scene = load_scene(kBoxes);
  ASSERT_EQ(scene.meshes.size(), 2u);     // the floor and the box (the lamp is a light)
  ASSERT_EQ(scene.instances.size(), 3u);  // the floor and the box twice
  int boxes = 0;
  for (const SceneInstance& instance : scene.instances) {
    const SceneMesh& mesh = scene.mesh(instance.mesh);
    if (mesh.mesh.triangles.size() != 12) continue;
    ++boxes;
    EXPECT_EQ(mesh.mesh.positions.size(), 8u);  // welded
    // The big box: T(0, 0, 0.2) T(-0.6, 0, 0) R_y(30) S(0.8), its corner (0.5, 1, 0.5).
    const Vertex corner = instance.transform * Vertex(0.5, 1, 0.5);
    const double c = std::cos(std::numbers::pi / 6), s = std::sin(std::numbers::pi / 6);
    const Vertex big(-0.6 + 0.8 * (c * 0.5 + s * 0.5), 0.8, 0.2 + 0.8 * (-s * 0.5 + c * 0.5));
    const Vertex small(0.7 + 0.45 * 0.5, 0.7, 0.5 + 0.45 * 0.5);
    EXPECT_TRUE((corner - big).norm() < 1e-6 || (corner - small).norm() < 1e-6) << corner.transpose();
    EXPECT_NEAR(instance.albedo.x(), 0.7, 1e-6);
    EXPECT_NEAR(instance.albedo.y(), 0.15, 1e-6);
  }
  EXPECT_EQ(boxes, 2);
  ASSERT_EQ(scene.lights.size(), 1u);
  EXPECT_EQ(scene.lights[0].triangles.size(), 2u);
  EXPECT_NEAR(scene.lights[0].radiance.x(), 12.0, 1e-5);  // emissiveFactor x emissiveStrength
  EXPECT_NEAR(scene.lights[0].radiance.z(), 8.4, 1e-5);
  for (const auto& t : scene.lights[0].triangles) {
    EXPECT_NEAR(t[0].y(), 2.5, 1e-6);
    EXPECT_LT((t[1] - t[0]).cross(t[2] - t[0]).y(), 0);  // facing down, at the boxes
  }
  EXPECT_LT((scene.camera.from - Vertex(0, 2, 4.5)).norm(), 1e-6);
  const Vertex view = (scene.camera.at - scene.camera.from).normalized();
  EXPECT_LT((view - (Vertex(0, 0.4, 0) - Vertex(0, 2, 4.5)).normalized()).norm(), 1e-6);
  EXPECT_NEAR(scene.camera.fov_degrees, 0.7 * 180 / std::numbers::pi, 1e-4);
  EXPECT_EQ(scene.camera.width, 320);
  EXPECT_EQ(scene.camera.height, 240);
}

class ImportSceneFiles : public testing::ScratchFolder {
 protected:
  json boxes() const { return json::parse(read_file(kBoxes)); }
  std::filesystem::path write(const std::string& name, const json& value) const {
    std::ofstream(folder_ / name) << value.dump();
    return folder_ / name;
  }
  std::string error_of(const std::filesystem::path& path) const {
    try {
      load_scene(path);
      return "loaded";
    } catch (const Error& error) {
      return error.what();
    }
  }
};

TEST_F(ImportSceneFiles, AJsonSceneImportsTheFileAndNamesTheProxiesOfItsInstances) {
  const std::filesystem::path gltf = write("boxes.gltf", boxes());
  const json scene = {{"format", "visproxy-scene"},
                      {"format_version", 1},
                      {"import", {{"file", "boxes.gltf"}, {"proxies", {"hull", "inside:8"}}}},
                      {"meshes", {{"pole", {{"positions", {{0, 0, 0}, {0.1, 0, 0}, {0, 1, 0}, {0, 0, 0.1}}},
                                            {"triangles", {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}}}}}},
                      {"instances", {{{"mesh", "pole"}, {"albedo", 0.5}}}}};
  const Scene loaded = load_scene(write("scene.json", scene));
  ASSERT_EQ(loaded.instances.size(), 4u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(loaded.instances[i].proxies, (std::vector<std::string>{"hull", "inside:8"}));
    EXPECT_EQ(loaded.mesh(loaded.instances[i].mesh).file, gltf);
  }
  EXPECT_TRUE(loaded.instances[3].proxies.empty());
  EXPECT_EQ(loaded.lights.size(), 1u);  // the lamp; the scene has none of its own
  EXPECT_LT((loaded.camera.from - Vertex(0, 2, 4.5)).norm(), 1e-6);  // the file's camera

  json clash = scene;
  clash["meshes"] = {{"boxes.gltf:floor", clash["meshes"]["pole"]}};
  clash["instances"] = json::array();
  EXPECT_NE(error_of(write("clash.json", clash)).find("the imported file has a mesh of this name"), std::string::npos);

  // Per mesh: only the boxes name proxies; a name the file does not have is refused.
  json per_mesh = scene;
  per_mesh["import"]["proxies"] = {{"boxes.gltf:box", {"inside:8"}}};
  const Scene boxes_only = load_scene(write("per-mesh.json", per_mesh));
  for (const SceneInstance& instance : boxes_only.instances)
    EXPECT_EQ(instance.proxies.size(), instance.mesh == "boxes.gltf:box" ? 1u : 0u) << instance.mesh;
  per_mesh["import"]["proxies"] = {{"boxes.gltf:crate", {"inside:8"}}};
  EXPECT_NE(error_of(write("unknown.json", per_mesh)).find("import.proxies[\"boxes.gltf:crate\"]: the imported file has no mesh of this name"),
            std::string::npos)
      << error_of(write("unknown.json", per_mesh));
}

TEST_F(ImportSceneFiles, BrokenGltfFilesAreRefusedWithOneLineNamingThem) {
  json no_light = boxes();
  no_light["materials"][2].erase("emissiveFactor");
  EXPECT_NE(error_of(write("no-light.gltf", no_light)).find("no-light.gltf: no light"), std::string::npos);

  // Three nested scales of 1e35, each within float, place the innermost box at 1e105.
  json far = boxes();
  far["nodes"][1]["scale"] = {1e35, 1e35, 1e35};
  far["nodes"][2]["scale"] = {1e35, 1e35, 1e35};
  far["nodes"][1]["children"] = {2};
  far["nodes"][2]["children"] = {3};
  far["nodes"][3]["scale"] = {1e35, 1e35, 1e35};
  const std::string beyond = error_of(write("far.gltf", far));
  EXPECT_NE(beyond.find("far.gltf: "), std::string::npos) << beyond;
  EXPECT_NE(beyond.find("1e100"), std::string::npos) << beyond;

  json broken = boxes();
  broken["nodes"][0]["mesh"] = 7;
  const std::string missing_mesh = error_of(write("broken.gltf", broken));
  EXPECT_EQ(missing_mesh.rfind((folder_ / "broken.gltf").string() + ": ", 0), 0u) << missing_mesh;
  EXPECT_EQ(missing_mesh.find('\n'), std::string::npos) << missing_mesh;

  EXPECT_NE(error_of(folder_ / "missing.glb").find("cannot open"), std::string::npos);
  std::ofstream(folder_ / "garbage.glb") << "glTF\x02\x00\x00\x00garbage";
  EXPECT_NE(error_of(folder_ / "garbage.glb").find("garbage.glb: Assimp cannot read it"), std::string::npos);
}

}  // namespace
}  // namespace visproxy
