// What a recorded verdict proves: the claim of the kind it was made for, on the files it
// was made on, every file the folder ships included. Folders tampered with by hand: kinds
// swapped, verdicts swapped between entries or copied from another folder, files swapped,
// an OBJ or a PLY scaled by hand.

#include "visproxy/folder/verdict.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "visproxy/folder/proxy_folder.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/mesh/sphere_set.h"
#include "visproxy/mesh/write_mesh.h"
#include "visproxy/proxy/build_proxies.h"
#include "visproxy/folder/proxy_folder.h"
#include "test_support.h"

namespace visproxy {
namespace {

using nlohmann::json;

// A bumpy closed ball and a proxy folder of it (hull, obb, inside:4, spheres:4), every
// verdict recorded as `visproxy verify` records it.
class Verdicts : public testing::ScratchFolder {
 protected:
  void SetUp() override {
    ScratchFolder::SetUp();
    mesh_ = bumpy_ball(0.2);
    manifest_ = build_into(folder_, mesh_);
  }

  static TriangleMesh bumpy_ball(double amplitude) {
    TriangleMesh mesh = sphere_set_mesh({Sphere{Vertex::Zero(), 1.0}}, 2);
    for (Vertex& p : mesh.positions) p *= 1 + amplitude * std::sin(3 * p.x()) * std::cos(2 * p.y());
    return mesh;
  }

  static json build_into(const std::filesystem::path& folder, const TriangleMesh& mesh) {
    BuildOptions options;
    options.hausdorff_samples = 500;
    options.gssa_lines = 2000;
    const std::vector<BuiltProxy> built = build_proxies(mesh, "ball", parse_proxy_specs({"hull", "obb", "inside:4", "spheres:4"}), options);
    json manifest = write_proxy_folder(folder, {.path = "ball", .weld = "auto", .vertices = mesh.positions.size(),
                                                 .triangles = mesh.triangles.size(), .components = 1, .bounds = bounding_box(mesh)},
                                       built, options);
    for (json& entry : manifest["proxies"]) entry["verify"] = verify_proxy(mesh, manifest, entry, read_proxy_geometry(folder, entry));
    write_manifest(folder, manifest);
    return manifest;
  }

  static json& entry(json& manifest, const std::string& name) {
    for (json& e : manifest["proxies"])
      if (e["name"] == name) return e;
    throw std::runtime_error("no entry " + name);
  }

  bool proves(json manifest, const std::string& name) {
    const json& e = entry(manifest, name);
    return verdict_proves(e["verify"], e, mesh_, read_proxy_geometry(folder_, e));
  }

  TriangleMesh mesh_;
  json manifest_;
};

TEST_F(Verdicts, ProveTheirOwnKindsClaimOnTheirOwnFiles) {
  for (const char* name : {"hull", "obb", "inside-4"}) EXPECT_TRUE(proves(manifest_, name)) << name;
  EXPECT_FALSE(proves(manifest_, "spheres-4"));  // general: no claim to prove
  EXPECT_EQ(entry(manifest_, "hull")["verify"]["kind"], "outside");
  EXPECT_EQ(entry(manifest_, "hull")["verify"]["files"], json::array({"hull.ply", "hull.obj"}));
}

TEST_F(Verdicts, SwappedKindsProveNothing) {
  json m = manifest_;
  std::swap(entry(m, "hull")["kind"], entry(m, "inside-4")["kind"]);
  EXPECT_FALSE(proves(m, "hull"));
  EXPECT_FALSE(proves(m, "inside-4"));
  // Verified again with the kind the manifest now states, neither holds.
  for (const char* name : {"hull", "inside-4"}) {
    const json& e = entry(m, name);
    EXPECT_FALSE(verify_proxy(mesh_, m, e, read_proxy_geometry(folder_, e))["holds"].get<bool>()) << name;
  }
  // A general proxy called inside: its verdict claimed nothing.
  json g = manifest_;
  entry(g, "spheres-4")["kind"] = "inside";
  EXPECT_FALSE(proves(g, "spheres-4"));
}

TEST_F(Verdicts, SwappedOrCopiedVerdictsProveNothing) {
  json m = manifest_;
  std::swap(entry(m, "hull")["verify"], entry(m, "obb")["verify"]);
  EXPECT_FALSE(proves(m, "hull"));
  EXPECT_FALSE(proves(m, "obb"));
  // The claim strings swapped along with the kinds.
  json c = manifest_;
  std::swap(entry(c, "hull")["kind"], entry(c, "inside-4")["kind"]);
  std::swap(entry(c, "hull")["verify"]["claim"], entry(c, "inside-4")["verify"]["claim"]);
  EXPECT_FALSE(proves(c, "hull"));
  EXPECT_FALSE(proves(c, "inside-4"));
  // A verdict copied from a folder of another mesh.
  const std::filesystem::path other = folder_ / "other";
  const json other_manifest = build_into(other, bumpy_ball(0.1));
  json d = manifest_;
  entry(d, "hull")["verify"] = other_manifest["proxies"][0]["verify"];
  entry(d, "inside-4")["verify"] = other_manifest["proxies"][2]["verify"];
  EXPECT_FALSE(proves(d, "hull"));
  EXPECT_FALSE(proves(d, "inside-4"));
}

TEST_F(Verdicts, SwappedFilesProveNothing) {
  json m = manifest_;
  for (const char* extension : {".ply", ".obj"}) {
    std::filesystem::rename(folder_ / (std::string("hull") + extension), folder_ / "swap");
    std::filesystem::rename(folder_ / (std::string("obb") + extension), folder_ / (std::string("hull") + extension));
    std::filesystem::rename(folder_ / "swap", folder_ / (std::string("obb") + extension));
  }
  for (const char* key : {"primitives", "vertices", "triangles"}) std::swap(entry(m, "hull")[key], entry(m, "obb")[key]);
  EXPECT_FALSE(proves(m, "hull"));
  EXPECT_FALSE(proves(m, "obb"));
}

// The folder ships NAME.ply and NAME.obj: an OBJ shrunk by hand makes the folder's claim
// false though the PLY is untouched; verify says which file disagrees.
TEST_F(Verdicts, AnObjEditedByHandBreaksTheClaim) {
  TriangleMesh obj = read_mesh(folder_ / "hull.obj", {.weld = Weld::never, .on_warning = {}});
  for (Vertex& p : obj.positions) p *= 0.97;
  write_mesh(folder_ / "hull.obj", obj);
  const json& e = entry(manifest_, "hull");
  const ProxyGeometry geometry = read_proxy_geometry(folder_, e);
  EXPECT_NE(geometry.files_problem.find("hull.obj does not hold the proxy of hull.ply: vertex"), std::string::npos) << geometry.files_problem;
  EXPECT_FALSE(proves(manifest_, "hull"));
  const json verdict = verify_proxy(mesh_, manifest_, e, geometry);
  EXPECT_FALSE(verdict["holds"].get<bool>());
  EXPECT_NE(verdict["counterexample"].get<std::string>().find("hull.obj"), std::string::npos);
  // A sphere set's drawing edited, or a listed file gone, is found the same way.
  TriangleMesh drawing = read_mesh(folder_ / "inside-4.ply", {.weld = Weld::never, .on_warning = {}});
  drawing.positions[0].x() += 1e-9;
  write_mesh(folder_ / "inside-4.ply", drawing);
  EXPECT_FALSE(proves(manifest_, "inside-4"));
  std::filesystem::remove(folder_ / "obb.obj");
  EXPECT_NE(read_proxy_geometry(folder_, entry(manifest_, "obb")).files_problem.find("obb.obj is listed but missing"), std::string::npos);
}

// A file list naming a path outside the folder is refused, not read.
TEST_F(Verdicts, FilesOutsideTheFolderAreRefused) {
  json e = entry(manifest_, "hull");
  e["files"] = json::array({"hull.ply", "../hull.obj"});
  EXPECT_THROW(read_proxy_geometry(folder_, e), InvalidInputError);
}

}  // namespace
}  // namespace visproxy
