#include "visproxy/scene/scene.h"

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "visproxy/core/errors.h"
#include "schema_support.h"
#include "test_support.h"

namespace visproxy {
namespace {

using nlohmann::json;

// A scene that uses every key the format has, with inline meshes only: two meshes, one
// named so that its JSON path needs quotes, a parallelogram light and a mesh light.
json full_scene() {
  return json::parse(R"({
    "format": "visproxy-scene",
    "format_version": 1,
    "description": "every key of the format",
    "meshes": {
      "floor": {"positions": [[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]], "triangles": [[0, 2, 1], [0, 3, 2]], "subdivide": 1},
      "tall box": {"positions": [[0, 0, 0], [1, 0, 0], [0, 2, 0], [0, 0, 1]],
                   "triangles": [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]}
    },
    "instances": [
      {"mesh": "floor", "albedo": [0.5, 0.5, 0.5], "transform": {"matrix": [2, 0, 0, 0, 0, 1, 0, 0, 0, 0, 2, 0, 0, 0, 0, 1]}},
      {"mesh": "tall box", "albedo": 0.7, "proxies": ["hull", "inside:4"],
       "transform": {"scale": [1, 2, 1], "rotate": {"axis": [0, 1, 0], "degrees": 30}, "translate": [0, 0.5, 0],
                     "fit": {"base": [0, 0, 0], "height": 0.5}}}
    ],
    "lights": [
      {"type": "parallelogram", "corner": [-0.2, 2, -0.2], "edge1": [0.4, 0, 0], "edge2": [0, 0, 0.4], "radiance": [5, 5, 5]},
      {"type": "mesh", "mesh": "tall box", "transform": {"scale": 0.1, "translate": [0, 3, 0]}, "radiance": 2, "two_sided": true}
    ],
    "camera": {"from": [0, 1, 4], "at": [0, 0.5, 0], "up": [0, 1, 0], "fov_degrees": 40, "width": 64, "height": 48}
  })");
}

Scene parse(const json& scene) { return parse_scene(scene.dump(), "scene.json"); }

// The message parse_scene gives for `text`, or "accepted".
std::string error_of_text(const std::string& text) {
  try {
    parse_scene(text, "scene.json");
    return "accepted";
  } catch (const InvalidInputError& error) {
    EXPECT_EQ(error.file(), "scene.json");
    return error.what();
  }
}

std::string error_of(const json& scene) { return error_of_text(scene.dump()); }

// `scene` with the value at `pointer` replaced, or removed.
json with(json scene, const char* pointer, const json& value) {
  scene[json::json_pointer(pointer)] = value;
  return scene;
}
json without(json scene, const char* pointer) {
  const json::json_pointer where(pointer);
  scene[where.parent_pointer()].erase(where.back());
  return scene;
}

TEST(Scene, ReadsEveryKey) {
  const Scene scene = parse(full_scene());
  ASSERT_EQ(scene.meshes.size(), 2u);
  EXPECT_EQ(scene.mesh("tall box").mesh.triangles.size(), 4u);
  EXPECT_EQ(scene.mesh("floor").mesh.triangles.size(), 8u);  // subdivided once
  ASSERT_EQ(scene.instances.size(), 2u);
  EXPECT_EQ(scene.instances[0].transform.linear().diagonal(), Eigen::Vector3d(2, 1, 2));
  EXPECT_EQ(scene.instances[1].albedo, Color::Constant(0.7));
  EXPECT_EQ(scene.instances[1].proxies, (std::vector<std::string>{"hull", "inside:4"}));
  // fit: the box stands on the origin, 0.5 tall.
  BoundingBox box;
  for (const Vertex& p : scene.mesh("tall box").mesh.positions) box.extend(scene.instances[1].transform * p);
  EXPECT_NEAR(box.min.y(), 0, 1e-12);
  EXPECT_NEAR(box.max.y(), 0.5, 1e-12);
  ASSERT_EQ(scene.lights.size(), 2u);
  EXPECT_EQ(scene.lights[0].triangles.size(), 2u);
  EXPECT_EQ(scene.lights[1].triangles.size(), 4u);
  EXPECT_TRUE(scene.lights[1].two_sided);
  EXPECT_EQ(scene.lights[1].radiance, Color::Constant(2));
  EXPECT_EQ(scene.camera.width, 64);
  EXPECT_EQ(scene.camera.height, 48);
}

struct Malformed {
  const char* name;
  const char* pointer;  // JSON pointer of the value to replace
  json value;           // its new value (ignored when `remove` is set: the key is removed)
  const char* message;  // what parse_scene must say after "scene.json: ", exactly
  bool remove = false;
};

void PrintTo(const Malformed& input, std::ostream* out) { *out << input.name; }

class SceneRejects : public ::testing::TestWithParam<Malformed> {};

TEST_P(SceneRejects, NamingTheFileAndTheJsonPath) {
  const Malformed& input = GetParam();
  const json scene =
      input.remove ? without(full_scene(), input.pointer) : with(full_scene(), input.pointer, input.value);
  EXPECT_EQ(error_of(scene), std::string("scene.json: ") + input.message);
}

INSTANTIATE_TEST_SUITE_P(
    Paths, SceneRejects,
    ::testing::Values(
        Malformed{"fit_height_zero", "/instances/1/transform/fit/height", 0,
                  "instances[1].transform.fit.height: must be a positive number"},
        Malformed{"fit_height_text", "/instances/1/transform/fit/height", "tall",
                  "instances[1].transform.fit.height: must be a positive number"},
        Malformed{"edge_of_two_numbers", "/lights/0/edge1", json::array({1, 0}),
                  "lights[0].edge1: expected an array of 3 numbers"},
        Malformed{"edge_with_text", "/lights/0/edge2", json::array({1, "0", 0}),
                  "lights[0].edge2: expected an array of 3 numbers"},
        Malformed{"mesh_file_number", "/meshes/floor/file", 3, "meshes.floor.file: must be a string"},
        Malformed{"position_in_quoted_mesh", "/meshes/tall box/positions/2", json::array({0, 2}),
                  "meshes[\"tall box\"].positions[2]: expected an array of 3 numbers"},
        Malformed{"triangle_index_range", "/meshes/floor/triangles/1/2", 4,
                  "meshes.floor.triangles[1][2]: expected an integer from 0 to 3"},
        Malformed{"triangle_index_negative", "/meshes/floor/triangles/0/0", -1,
                  "meshes.floor.triangles[0][0]: expected an integer from 0 to 3"},
        Malformed{"triangle_of_two", "/meshes/floor/triangles/0", json::array({0, 1}),
                  "meshes.floor.triangles[0]: expected an array of 3 vertex indices"},
        Malformed{"no_triangles", "/meshes/floor/triangles", json::array(),
                  "meshes.floor.triangles: expected a non-empty array of triangles"},
        Malformed{"mesh_not_object", "/meshes/floor", json::array(), "meshes.floor: expected an object"},
        Malformed{"instance_unknown_mesh", "/instances/0/mesh", "ceiling",
                  "instances[0].mesh: no mesh named \"ceiling\""},
        Malformed{"instance_without_mesh", "/instances/0/mesh", nullptr, "instances[0]: missing \"mesh\"", true},
        Malformed{"albedo_above_one", "/instances/0/albedo", json::array({0.5, 1.5, 0.5}),
                  "instances[0].albedo: above 1 reflects more light than it receives"},
        Malformed{"albedo_negative", "/instances/1/albedo", -0.5, "instances[1].albedo: must not be negative"},
        Malformed{"proxy_spec_number", "/instances/1/proxies/1", 40, "instances[1].proxies[1]: must be a string"},
        Malformed{"matrix_and_scale", "/instances/0/transform/scale", 2,
                  "instances[0].transform: \"matrix\" and \"scale\" exclude each other"},
        Malformed{"matrix_not_affine", "/instances/0/transform/matrix/12", 1,
                  "instances[0].transform.matrix: must be affine (last row 0 0 0 1)"},
        Malformed{"matrix_short", "/instances/0/transform/matrix", json::array({1, 0, 0, 1}),
                  "instances[0].transform.matrix: expected an array of 16 numbers (a row-major 4x4 matrix)"},
        Malformed{"scale_negative", "/lights/1/transform/scale", -1,
                  "lights[1].transform.scale: must be a positive number"},
        Malformed{"rotation_axis_zero", "/instances/1/transform/rotate/axis", json::array({0, 0, 0}),
                  "instances[1].transform.rotate.axis: must not be zero"},
        Malformed{"rotation_without_degrees", "/instances/1/transform/rotate/degrees", nullptr,
                  "instances[1].transform.rotate: missing \"degrees\"", true},
        Malformed{"singular_scale", "/lights/1/transform/scale", json::array({1, 0, 1}),
                  "lights[1].transform: singular"},
        Malformed{"fit_flat_mesh", "/instances/1/transform/scale", json::array({1, 0, 1}),
                  "instances[1].transform.fit: cannot fit a mesh that is flat in y"},
        Malformed{"fit_overflows",
                  "/instances/1/transform",
                  {{"scale", {1e300, 1e-300, 1e300}}, {"fit", {{"base", {0, 0, 0}}, {"height", 0.5}}}},
                  "instances[1].transform: not finite (the product overflows)"},
        Malformed{"position_beyond_1e100", "/meshes/floor/positions/1", json::array({1, 0, 2e100}),
                  "meshes.floor.positions[1]: a coordinate beyond 1e100 in magnitude, which geometry in double "
                  "precision cannot square and cube"},
        Malformed{"placed_beyond_1e100", "/instances/0/transform/matrix/3", 1e101,
                  "instances[0].transform: places the mesh beyond 1e100 in magnitude, which geometry in double "
                  "precision cannot square and cube"},
        Malformed{"two_sided_text", "/lights/1/two_sided", "yes", "lights[1].two_sided: must be true or false"},
        Malformed{"subdivide_too_deep", "/meshes/floor/subdivide", 5, "meshes.floor.subdivide: expected an integer from 0 to 4"},
        Malformed{"subdivide_negative", "/meshes/floor/subdivide", -1, "meshes.floor.subdivide: expected an integer from 0 to 4"},
        Malformed{"subdivide_text", "/meshes/floor/subdivide", "2", "meshes.floor.subdivide: expected an integer from 0 to 4"},
        Malformed{"light_type_unknown", "/lights/0/type", "spot",
                  "lights[0].type: must be \"parallelogram\" or \"mesh\""},
        Malformed{"light_type_number", "/lights/0/type", 1, "lights[0].type: must be \"parallelogram\" or \"mesh\""},
        Malformed{"light_mesh_unknown", "/lights/1/mesh", "lamp", "lights[1].mesh: no mesh named \"lamp\""},
        Malformed{"light_edges_parallel", "/lights/0/edge2", json::array({0.8, 0, 0}),
                  "lights[0]: \"edge1\" and \"edge2\" are parallel: the light has no area"},
        Malformed{"light_corner_overflows",
                  "/lights/0",
                  {{"type", "parallelogram"},
                   {"corner", {1.7e308, 0, 0}},
                   {"edge1", {1.7e308, 0, 0}},
                   {"edge2", {0, 0, 1}},
                   {"radiance", 1}},
                  "lights[0]: a corner is not finite (its coordinates overflow)"},
        Malformed{"radiance_text", "/lights/0/radiance", "bright",
                  "lights[0].radiance: expected an array of 3 numbers (r, g, b) or one number"},
        Malformed{"no_lights", "/lights", json::array(), "lights: expected a non-empty array"},
        Malformed{"camera_width_zero", "/camera/width", 0, "camera.width: expected an integer from 1 to 16384"},
        Malformed{"camera_height_fraction", "/camera/height", 2.5,
                  "camera.height: expected an integer from 1 to 16384"},
        Malformed{"camera_fov_180", "/camera/fov_degrees", 180, "camera.fov_degrees: must be in (0, 180)"},
        Malformed{"camera_at_from", "/camera/at", json::array({0, 1, 4}),
                  "camera: \"from\", \"at\" and \"up\" do not define a view (zero or parallel)"},
        Malformed{"camera_missing", "/camera", nullptr, "missing \"camera\"", true},
        Malformed{"description_number", "/description", 3, "description: must be a string"},
        Malformed{"format_number", "/format", 7, "not a visproxy scene (\"format\" is not \"visproxy-scene\")"},
        Malformed{"format_version_two", "/format_version", 2,
                  "format_version: unsupported (this visproxy reads version 1)"}),
    [](const ::testing::TestParamInfo<Malformed>& param_info) { return std::string(param_info.param.name); });

TEST(Scene, RejectsTextThatIsNotJsonNamingTheLine) {
  EXPECT_EQ(error_of_text("{\n  \"format\": \"visproxy-scene\",\n  oops\n}"), "scene.json:3: not valid JSON");
  EXPECT_EQ(error_of_text("{\"format\": \"visproxy-scene\", \"x\": 1e999}"), "scene.json: not valid JSON");
  EXPECT_EQ(error_of_text("[]"), "scene.json: not a visproxy scene (\"format\" is not \"visproxy-scene\")");
}

using SceneMeshFile = testing::ScratchFolder;

TEST_F(SceneMeshFile, IsReadRelativeToTheSceneWithItsWarningsPassedOn) {
  std::ofstream(folder_ / "blender.ply")
      << "ply\nformat ascii 1.0\nCreated by Blender3D 247 - www.blender.org\nelement vertex 3\nproperty float x\n"
         "property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
         "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  const json scene = with(full_scene(), "/meshes/floor", {{"file", "blender.ply"}});
  std::vector<std::string> warnings;
  const Scene read =
      parse_scene(scene.dump(), folder_ / "scene.json", [&](const std::string& w) { warnings.push_back(w); });
  EXPECT_EQ(read.mesh("floor").file, folder_ / "blender.ply");
  EXPECT_EQ(read.mesh("floor").mesh.triangles.size(), 1u);
  EXPECT_EQ(warnings,
            std::vector<std::string>{(folder_ / "blender.ply").string() +
                                     ":3: unknown header line 'Created by Blender3D 247 - www.blender.org' ignored"});
  EXPECT_THROW(
      parse_scene(with(full_scene(), "/meshes/floor", {{"file", "nowhere.off"}}).dump(), folder_ / "scene.json"),
      IOError);
}

// A mesh file of 262 088 triangles subdivided 4 times would hold 67 M triangles: refused
// before any is made, naming the JSON path.
TEST_F(SceneMeshFile, SubdivisionBeyond64MTrianglesIsRefused) {
  constexpr int side = 363;  // vertices per row: 2 x 362^2 = 262088 triangles
  std::string off = "OFF\n" + std::to_string(side * side) + " " + std::to_string(2 * (side - 1) * (side - 1)) + " 0\n";
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x) off += std::to_string(x) + " " + std::to_string(y) + " 0\n";
  for (int y = 0; y + 1 < side; ++y)
    for (int x = 0; x + 1 < side; ++x) {
      const int a = y * side + x, b = a + 1, c = a + side, d = c + 1;
      off += "3 " + std::to_string(a) + " " + std::to_string(b) + " " + std::to_string(d) + "\n3 " + std::to_string(a) + " " +
             std::to_string(d) + " " + std::to_string(c) + "\n";
    }
  std::ofstream(folder_ / "grid.off") << off;
  const json scene = with(full_scene(), "/meshes/floor", {{"file", "grid.off"}, {"subdivide", 4}});
  try {
    parse_scene(scene.dump(), folder_ / "scene.json");
    ADD_FAILURE() << "accepted";
  } catch (const InvalidInputError& error) {
    EXPECT_EQ(std::string(error.what()), (folder_ / "scene.json").string() +
                                             ": meshes.floor.subdivide: would make 262088 x 4^4 triangles, more than 64000000");
  }
}

TEST(Scene, FileAndInlineGeometryExcludeEachOther) {
  EXPECT_EQ(error_of(with(full_scene(), "/meshes/floor/file", "floor.off")),
            "scene.json: meshes.floor: give either \"file\" or \"positions\" and \"triangles\", not both");
}

// The schema and the reader agree: the full scene is described by the schema; every key
// the schema requires, the reader requires; the bounds the schema states are the reader's.
class SceneSchema : public ::testing::Test {
 protected:
  const json schema = testing::read_schema("scene.schema.json");
  const json& property(const char* pointer) const { return schema.at(json::json_pointer(pointer)); }
};

TEST_F(SceneSchema, DescribesTheFullScene) { testing::expect_described(full_scene(), schema, schema, "scene"); }

TEST_F(SceneSchema, EveryRequiredKeyIsRequiredByTheReader) {
  // Where each schema object with "required" keys is found in the full scene.
  const std::pair<const char*, const char*> objects[] = {
      {"", ""},
      {"/anyOf/0", ""},  // without "import", a scene gives its own meshes, instances, lights and camera
      {"/properties/instances/items", "/instances/0"},
      {"/properties/lights/items", "/lights/0"},
      {"/properties/camera", "/camera"},
      {"/$defs/transform/properties/rotate", "/instances/1/transform/rotate"},
      {"/$defs/transform/properties/fit", "/instances/1/transform/fit"},
  };
  std::size_t checked = 0;
  for (const auto& [schema_pointer, scene_pointer] : objects) {
    const json& part = schema.at(json::json_pointer(schema_pointer));
    ASSERT_TRUE(part.contains("required")) << schema_pointer;
    for (const json& key : part.at("required")) {
      const std::string pointer = std::string(scene_pointer) + "/" + key.get<std::string>();
      const std::string message = error_of(without(full_scene(), pointer.c_str()));
      if (key == "format") {
        EXPECT_NE(message.find("not a visproxy scene"), std::string::npos) << message;
      } else {
        EXPECT_NE(message.find("missing \"" + key.get<std::string>() + "\""), std::string::npos)
            << pointer << ": " << message;
      }
      ++checked;
    }
  }
  EXPECT_GE(checked, 14u);
}

TEST_F(SceneSchema, BoundsAreTheReaders) {
  const json& camera = property("/properties/camera/properties");
  for (const char* extent : {"width", "height"}) {
    const std::string pointer = std::string("/camera/") + extent;
    const int minimum = camera.at(extent).at("minimum"), maximum = camera.at(extent).at("maximum");
    EXPECT_EQ(error_of(with(full_scene(), pointer.c_str(), minimum)), "accepted") << extent;
    EXPECT_EQ(error_of(with(full_scene(), pointer.c_str(), maximum)), "accepted") << extent;
    EXPECT_NE(error_of(with(full_scene(), pointer.c_str(), minimum - 1)), "accepted") << extent;
    EXPECT_NE(error_of(with(full_scene(), pointer.c_str(), maximum + 1)), "accepted") << extent;
  }
  const double fov_low = camera.at("fov_degrees").at("exclusiveMinimum"),
               fov_high = camera.at("fov_degrees").at("exclusiveMaximum");
  EXPECT_NE(error_of(with(full_scene(), "/camera/fov_degrees", fov_low)), "accepted");
  EXPECT_NE(error_of(with(full_scene(), "/camera/fov_degrees", fov_high)), "accepted");
  EXPECT_EQ(error_of(with(full_scene(), "/camera/fov_degrees", fov_low + 0.5)), "accepted");
  EXPECT_EQ(error_of(with(full_scene(), "/camera/fov_degrees", fov_high - 0.5)), "accepted");

  const double height_low = property("/$defs/transform/properties/fit/properties/height").at("exclusiveMinimum");
  EXPECT_NE(error_of(with(full_scene(), "/instances/1/transform/fit/height", height_low)), "accepted");
  const double scale_low = property("/$defs/transform/properties/scale/oneOf/0").at("exclusiveMinimum");
  EXPECT_NE(error_of(with(full_scene(), "/lights/1/transform/scale", scale_low)), "accepted");
  for (const json& colour : property("/$defs/color/oneOf")) {
    const double low = colour.contains("minimum") ? colour.at("minimum").get<double>()
                                                  : colour.at("items").at("minimum").get<double>();
    const json below = colour.at("type") == "number" ? json(low - 0.25) : json::array({0.5, low - 0.25, 0.5});
    const json at = colour.at("type") == "number" ? json(low) : json::array({0.5, low, 0.5});
    EXPECT_NE(error_of(with(full_scene(), "/instances/0/albedo", below)), "accepted") << colour;
    EXPECT_EQ(error_of(with(full_scene(), "/instances/0/albedo", at)), "accepted") << colour;
  }
}

TEST_F(SceneSchema, LightTypesAreTheReaders) {
  const json& types = property("/properties/lights/items/properties/type/enum");
  EXPECT_EQ(types, json::array({"parallelogram", "mesh"}));
  EXPECT_NE(error_of(with(full_scene(), "/lights/0/type", "spot")), "accepted");
}

}  // namespace
}  // namespace visproxy
