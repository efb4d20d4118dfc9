// `visproxy build`: the default set on a real mesh, the manifest against its schema,
// containment of every outside proxy, byte-identical reruns, and bad input.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "apps/cli_test_support.h"
#include "core/files.h"
#include "mesh/read_mesh.h"
#include "test_meshes.h"
#include "test_support.h"
#include "verify/containment.h"

namespace visproxy {
namespace {

using nlohmann::json;

class CliBuild : public testing::ScratchFolder {};

TEST_F(CliBuild, DefaultSetOnKnotWritesEveryProxyAndAValidManifest) {
  const auto mesh_path = testing::cgal_mesh("knot1.off");
  const auto result = testing::run_visproxy("build '" + mesh_path.string() + "' -o '" + folder_.string() + "'");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find("8 proxies of"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("outer-512"), std::string::npos) << result.out;

  const json manifest = json::parse(read_file(folder_ / "manifest.json"));
  testing::expect_matches_schema(manifest);
  EXPECT_EQ(manifest.at("mesh").at("triangles"), 6400);
  const TriangleMesh mesh = read_mesh(mesh_path);

  std::vector<std::string> names;
  for (const json& entry : manifest.at("proxies")) {
    const std::string name = entry.at("name");
    SCOPED_TRACE(name);
    names.push_back(name);
    const TriangleMesh proxy = read_mesh(folder_ / entry.at("file").get<std::string>());
    EXPECT_EQ(read_mesh(folder_ / (name + ".obj")), proxy);
    EXPECT_EQ(entry.at("triangles").get<std::size_t>(), proxy.triangles.size());
    if (entry.at("primitive_type") == "triangle") {
      EXPECT_EQ(entry.at("primitives").get<std::size_t>(), proxy.triangles.size());
    }
    if (entry.at("kind") == "outside") {
      // Convex proxies contain the surface when they contain its vertices; the wraps are
      // checked for surface crossings too.
      const bool convex = name == "aabb" || name == "obb" || name.starts_with("hull");
      const Containment containment = check_containment(proxy, mesh, {.check_surface = !convex});
      EXPECT_TRUE(containment.contained()) << containment.vertices_outside << " vertices outside, "
                                           << containment.crossing_triangle_pairs << " crossings";
    }
    EXPECT_GE(entry.at("error").at("hausdorff_relative").get<double>(), 0.0);
  }
  EXPECT_EQ(names, (std::vector<std::string>{"aabb", "obb", "hull", "hull-32", "wrap", "outer-512", "quadric-512",
                                             "cluster-0.03"}));
  const json& entries = manifest.at("proxies");
  EXPECT_LE(entries[3].at("result").at("faces").get<int>(), 32);
  EXPECT_LE(entries[6].at("triangles").get<int>(), 512);
  EXPECT_EQ(entries[0].at("primitive_type"), "box");
  EXPECT_EQ(entries[0].at("primitives"), 1);
  EXPECT_EQ(entries[6].at("kind"), "general");
}

TEST_F(CliBuild, SameInputAndOptionsGiveByteIdenticalFiles) {
  const auto mesh_path = testing::cgal_mesh("knot2.off");
  const std::string proxies = " --proxy obb --proxy hull:18 --proxy wrap --proxy outer:128 --proxy quadric:256 --proxy cluster:0.05";
  for (const char* run : {"a", "b"}) {
    const auto result = testing::run_visproxy("build '" + mesh_path.string() + "' -o '" + (folder_ / run).string() + "'" + proxies);
    ASSERT_EQ(result.exit_code, 0) << result.err;
  }
  std::size_t compared = 0;
  for (const auto& file : std::filesystem::directory_iterator(folder_ / "a")) {
    if (file.path().filename() == "manifest.json") continue;  // holds build times
    EXPECT_EQ(read_file(file.path()), read_file(folder_ / "b" / file.path().filename())) << file.path();
    ++compared;
  }
  EXPECT_EQ(compared, 12u);
}

TEST_F(CliBuild, BadSpecOrBadMeshFailsWithOneLineAndWritesNothing) {
  const auto out = folder_ / "out";
  struct Case {
    std::string arguments;
    std::string fragment;
  };
  const std::string knot = testing::cgal_mesh("knot1.off").string();
  std::ofstream(folder_ / "line.obj") << "v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\n";
  const std::vector<Case> cases = {
      {"'" + knot + "' -o '" + out.string() + "' --proxy hull:2", "--proxy 'hull:2'"},
      {"'" + knot + "' -o '" + out.string() + "' --proxy spheres", "unknown proxy"},
      {"'" + knot + "' -o '" + out.string() + "' --proxy aabb --proxy aabb", "asked for twice"},
      {"'" + (folder_ / "missing.off").string() + "' -o '" + out.string() + "'", "missing.off"},
      {"'" + testing::cgal_mesh("b9.ply").string() + "' -o '" + out.string() + "'", "b9.ply: contains no faces"},
      {"'" + (folder_ / "line.obj").string() + "' -o '" + out.string() + "' --proxy aabb", "line.obj: aabb: "},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.arguments);
    const auto result = testing::run_visproxy("build " + c.arguments);
    EXPECT_EQ(result.exit_code, 2);
    EXPECT_TRUE(result.out.empty()) << result.out;
    ASSERT_FALSE(result.err.empty());
    EXPECT_EQ(result.err.find('\n'), result.err.size() - 1) << result.err;
    EXPECT_NE(result.err.find(c.fragment), std::string::npos) << result.err;
    EXPECT_FALSE(std::filesystem::exists(out));
  }
}

}  // namespace
}  // namespace visproxy
