#include "visproxy/folder/proxy_folder.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/core/files.h"
#include "visproxy/mesh/sphere_set.h"
#include "visproxy/proxy/proxy_spec.h"
#include "test_support.h"

namespace visproxy {
namespace {

using nlohmann::json;

// The fields a manifest written by `visproxy build` has that the readers check.
json manifest() {
  return json::parse(R"({
    "format": "visproxy-manifest", "format_version": 1, "generator": "visproxy 0.1.0",
    "mesh": {"path": "tetra.off", "weld": "auto", "vertices": 4, "triangles": 4, "components": 1,
             "bbox": {"min": [0, 0, 0], "max": [1, 1, 1], "diagonal": 1.7320508075688772}},
    "options": {"seed": 1},
    "proxies": [
      {"name": "hull", "kind": "outside", "file": "hull.ply", "primitive_type": "triangle", "primitives": 4, "triangles": 4},
      {"name": "inside-2", "kind": "inside", "file": "inside-2.json", "primitive_type": "sphere", "primitives": 2}
    ]
  })");
}

std::string error_of(const json& value) {
  try {
    parse_manifest(value.dump(), "folder/manifest.json");
    return "accepted";
  } catch (const InvalidInputError& error) {
    return error.what();
  }
}

json with(json value, const char* pointer, const json& replacement) {
  value[json::json_pointer(pointer)] = replacement;
  return value;
}

TEST(ParseManifest, AcceptsWhatBuildWrites) {
  const json read = parse_manifest(manifest().dump(2), "folder/manifest.json");
  EXPECT_EQ(read, manifest());
  EXPECT_EQ(entry_kind(read.at("proxies").at(1)), ProxyKind::inside);
}

TEST(ParseManifest, RejectsMalformedFieldsNamingTheJsonPath) {
  const std::pair<json, std::string> cases[] = {
      {json::array(), "not a visproxy manifest (\"format\" is not \"visproxy-manifest\")"},
      {with(manifest(), "/format", 1), "not a visproxy manifest (\"format\" is not \"visproxy-manifest\")"},
      {with(manifest(), "/format_version", "1"), "format_version: unsupported (this visproxy reads version 1)"},
      {with(manifest(), "/generator", 0), "generator: must be a string"},
      {with(manifest(), "/mesh/vertices", -4), "mesh.vertices: expected a count (a non-negative integer)"},
      {with(manifest(), "/mesh/triangles", "4"), "mesh.triangles: expected a count (a non-negative integer)"},
      {with(manifest(), "/mesh/bbox/max", json::array({1, 1})), "mesh.bbox.max: expected an array of 3 numbers"},
      {with(manifest(), "/mesh/weld", "sometimes"), "mesh.weld: must be one of {auto, never, always}"},
      {with(manifest(), "/mesh/path", json::array()), "mesh.path: must be a string"},
      {with(manifest(), "/options", 1), "options: expected an object"},
      {with(manifest(), "/proxies", json::object()), "proxies: expected an array of proxy entries"},
      {with(manifest(), "/proxies/1", 7), "proxies[1]: expected an object"},
      {with(manifest(), "/proxies/0/kind", 3), "proxies[0].kind: must be \"outside\", \"inside\" or \"general\""},
      {with(manifest(), "/proxies/1/kind", "around"),
       "proxies[1].kind: must be \"outside\", \"inside\" or \"general\""},
      {with(manifest(), "/proxies/0/name", nullptr), "proxies[0].name: must be a string"},
      {with(manifest(), "/proxies/1/file", 2), "proxies[1].file: must be a string"},
      {with(manifest(), "/proxies/0/primitive_type", "cone"),
       "proxies[0].primitive_type: must be \"triangle\", \"box\" or \"sphere\""},
      {with(manifest(), "/proxies/1/primitives", 2.5),
       "proxies[1].primitives: expected a count (a non-negative integer)"},
      {with(manifest(), "/proxies/0/triangles", "4"),
       "proxies[0].triangles: expected a count (a non-negative integer)"},
  };
  for (const auto& [value, message] : cases) EXPECT_EQ(error_of(value), "folder/manifest.json: " + message) << value;
  json missing = manifest();
  missing["mesh"].erase("bbox");
  EXPECT_EQ(error_of(missing), "folder/manifest.json: mesh: missing \"bbox\"");
}

// Inputs fuzz_readers found (minimised): both made read_manifest or the commands after it
// throw nlohmann::json's exceptions instead of an InvalidInputError.
TEST(ParseManifest, FuzzFindings) {
  try {
    parse_manifest(R"({"":"vispet","format":[]})", "manifest.json");
    ADD_FAILURE() << "accepted";
  } catch (const InvalidInputError& error) {
    EXPECT_EQ(std::string(error.what()),
              "manifest.json: not a visproxy manifest (\"format\" is not \"visproxy-manifest\")");
  }
  json no_min = manifest();
  no_min["mesh"]["bbox"].erase("min");  // read_manifest_mesh reads bbox.min
  EXPECT_EQ(error_of(no_min), "folder/manifest.json: mesh.bbox: missing \"min\"");
}

TEST(ParseManifest, RejectsTextThatIsNotJsonNamingTheLine) {
  EXPECT_THROW(parse_manifest("{\n\"format\": }", "folder/manifest.json"), InvalidInputError);
  try {
    parse_manifest("{\n\"format\": }", "folder/manifest.json");
  } catch (const InvalidInputError& error) {
    EXPECT_EQ(std::string(error.what()), "folder/manifest.json:2: not valid JSON");
  }
}

using ReadManifest = testing::ScratchFolder;

TEST_F(ReadManifest, ReadsFolderSlashManifestJson) {
  write_manifest(folder_, manifest());
  EXPECT_EQ(read_manifest(folder_), manifest());
  EXPECT_THROW(read_manifest(folder_ / "missing"), IOError);
}

// Built again into the same folder with fewer proxies: the ones no longer listed go, every
// other file stays, and a hand-edited manifest cannot make it remove anything outside.
class RebuiltFolder : public testing::ScratchFolder {
 protected:
  json build(const std::vector<std::string>& specs) {
    const TriangleMesh mesh = sphere_set_mesh({Sphere{Vertex(0.5, 0.25, 0), 1.0}}, 1);
    BuildOptions options;
    options.hausdorff_samples = 200;
    options.gssa_lines = 1000;
    return build_proxy_folder(folder_ / "proxies", mesh, "ball.ply", Weld::automatic, parse_proxy_specs(specs), options)
        .manifest;
  }
  bool has(const char* name) const { return std::filesystem::exists(folder_ / "proxies" / name); }
};

TEST_F(RebuiltFolder, RemovesTheProxiesItNoLongerListsAndNothingElse) {
  build({"aabb", "hull", "spheres:4"});
  ASSERT_TRUE(has("hull.ply") && has("hull.obj") && has("spheres-4.json") && has("spheres-4.ply"));
  write_file_atomically(folder_ / "proxies" / "notes.txt", "mine\n");
  const json manifest = build({"aabb"});
  EXPECT_EQ(manifest["proxies"].size(), 1u);
  EXPECT_TRUE(has("aabb.ply") && has("aabb.obj") && has("manifest.json") && has("notes.txt"));
  EXPECT_FALSE(has("hull.ply") || has("hull.obj") || has("spheres-4.json") || has("spheres-4.ply"));
}

TEST_F(RebuiltFolder, AHandEditedManifestCannotRemoveFilesOutsideTheFolder) {
  build({"aabb"});
  write_file_atomically(folder_ / "victim.txt", "keep\n");
  std::filesystem::create_directories(folder_ / "proxies" / "sub");
  write_file_atomically(folder_ / "proxies" / "sub" / "inner.txt", "keep\n");
  json edited = read_manifest(folder_ / "proxies");
  edited["proxies"][0]["files"] = json::array({"../victim.txt", (folder_ / "victim.txt").string(), "sub/inner.txt", "sub",
                                               ".", "..", "manifest.json", "aabb.ply"});
  write_manifest(folder_ / "proxies", edited);
  build({"hull"});
  EXPECT_TRUE(std::filesystem::exists(folder_ / "victim.txt"));
  EXPECT_TRUE(has("sub/inner.txt") && has("manifest.json") && has("hull.ply"));
  EXPECT_FALSE(has("aabb.ply"));  // a plain name it listed
  EXPECT_TRUE(has("aabb.obj"));   // no longer listed by the edited manifest: not known to be ours
}

TEST_F(RebuiltFolder, AnUnreadableManifestRemovesNothing) {
  build({"aabb"});
  write_file_atomically(folder_ / "proxies" / "manifest.json", "{ not json");
  build({"hull"});
  EXPECT_TRUE(has("aabb.ply") && has("aabb.obj") && has("hull.ply"));
  EXPECT_EQ(read_manifest(folder_ / "proxies")["proxies"][0]["name"], "hull");
}

}  // namespace
}  // namespace visproxy
