// `visproxy build`: the default set on a real mesh, the manifest against its schema,
// containment of every outside proxy, byte-identical reruns, and bad input.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "apps/cli_test_support.h"
#include "visproxy/core/files.h"
#include "visproxy/mesh/read_mesh.h"
#include "test_meshes.h"
#include "test_support.h"
#include "visproxy/mesh/sphere_set.h"
#include "visproxy/verify/containment.h"
#include "visproxy/verify/sphere_containment.h"

namespace visproxy {
namespace {

using nlohmann::json;

class CliBuild : public testing::ScratchFolder {};

TEST_F(CliBuild, DefaultSetOnKnotWritesEveryProxyAndAValidManifest) {
  const auto mesh_path = testing::cgal_mesh("knot1.off");
  const auto result = testing::run_visproxy("build '" + mesh_path.string() + "' -o '" + folder_.string() + "'");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find("9 proxies of"), std::string::npos) << result.out;
  // cluster-0.03 keeps most of the small knot's 6400 triangles: the default set leaves it out, saying so.
  EXPECT_NE(result.err.find("visproxy build: skipping cluster-0.03: it has "), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("of the mesh's 6400 triangles (the default set keeps proxies of at most 10 %)"), std::string::npos)
      << result.err;
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
    if (entry.at("primitive_type") == "sphere") {
      const std::vector<Sphere> spheres = read_sphere_set(folder_ / entry.at("file").get<std::string>());
      EXPECT_EQ(entry.at("primitives").get<std::size_t>(), spheres.size());
      EXPECT_EQ(read_mesh(folder_ / (name + ".ply")), sphere_set_mesh(spheres));
      if (entry.at("kind") == "inside") {
        EXPECT_TRUE(check_spheres_inside(mesh, spheres).contained());
      }
      continue;
    }
    const TriangleMesh proxy = read_mesh(folder_ / entry.at("file").get<std::string>());
    EXPECT_EQ(read_mesh(folder_ / (name + ".obj")), proxy);
    EXPECT_EQ(entry.at("triangles").get<std::size_t>(), proxy.triangles.size());
    if (entry.at("primitive_type") == "triangle") {
      EXPECT_EQ(entry.at("primitives").get<std::size_t>(), proxy.triangles.size());
    }
    if (entry.at("kind") == "outside") {
      // The whole surface: vertices, and every triangle either clear of the proxy's surface or
      // in one convex part of it.
      const Containment containment = check_containment(proxy, mesh);
      EXPECT_TRUE(containment.contained()) << containment.vertices_outside << " vertices outside, "
                                           << containment.triangles_unproved << " triangles unproved";
    }
    EXPECT_GE(entry.at("error").at("hausdorff_relative").get<double>(), 0.0);
  }
  EXPECT_EQ(names, (std::vector<std::string>{"aabb", "obb", "hull", "hull-32", "wrap", "outer-512", "quadric-512",
                                             "inside-40", "spheres-100"}));
  const json& entries = manifest.at("proxies");
  EXPECT_LE(entries[3].at("result").at("faces").get<int>(), 32);
  EXPECT_LE(entries[6].at("triangles").get<int>(), 512);
  EXPECT_EQ(entries[0].at("primitive_type"), "box");
  EXPECT_EQ(entries[0].at("primitives"), 1);
  EXPECT_EQ(entries[6].at("kind"), "general");
}

// Progress goes to stderr: as plain lines in a log with --progress always, never by default
// when stderr is not a terminal (as here), and never with --progress never.
TEST_F(CliBuild, ProgressLinesInALogOnlyWhenAskedFor) {
  const auto mesh_path = testing::cgal_mesh("knot1.off");
  const std::string mesh = "'" + mesh_path.string() + "' ";
  const std::string dir = "'" + (folder_ / "p").string() + "'";
  const auto always = testing::run_visproxy("build " + mesh + "-o " + dir + " --proxy aabb --proxy hull:8 --progress always");
  ASSERT_EQ(always.exit_code, 0) << always.err;
  EXPECT_NE(always.err.find("visproxy build: 1/2 (0 % done) building "), std::string::npos) << always.err;
  EXPECT_NE(always.err.find("visproxy build: 2/2 (50 % done) building "), std::string::npos) << always.err;
  EXPECT_NE(always.err.find("s left\n"), std::string::npos) << always.err;
  EXPECT_EQ(always.err.find('\r'), std::string::npos) << "no terminal control in a log";
  const auto verify = testing::run_visproxy("verify " + mesh + dir + " --progress always");
  ASSERT_EQ(verify.exit_code, 0) << verify.err;
  EXPECT_NE(verify.err.find("visproxy verify: 2/2 (50 % done) verifying hull-8"), std::string::npos) << verify.err;
  const auto measure = testing::run_visproxy("measure " + mesh + dir + " --rays 2000 --timed-rays 100 --progress always");
  ASSERT_EQ(measure.exit_code, 0) << measure.err;
  EXPECT_NE(measure.err.find("visproxy measure: 1/2 (0 % done) measuring aabb"), std::string::npos) << measure.err;
  for (const std::string quiet : {"", " --progress never"}) {
    const auto result = testing::run_visproxy("verify " + mesh + dir + quiet);
    ASSERT_EQ(result.exit_code, 0) << result.err;
    EXPECT_EQ(result.err.find("% done"), std::string::npos) << result.err;
  }
  const auto bad = testing::run_visproxy("verify " + mesh + dir + " --progress sometimes");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("{auto, always, never}"), std::string::npos) << bad.err;
}

TEST_F(CliBuild, SameInputAndOptionsGiveByteIdenticalFiles) {
  const auto mesh_path = testing::cgal_mesh("knot2.off");
  const std::string proxies =
      " --proxy obb --proxy hull:18 --proxy wrap --proxy outer:128 --proxy quadric:256 --proxy cluster:0.05"
      " --proxy spheres:50,10 --proxy inside:5";
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
  EXPECT_EQ(compared, 18u);
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
      {"'" + knot + "' -o '" + out.string() + "' --proxy sphere", "unknown proxy"},
      {"'" + knot + "' -o '" + out.string() + "' --proxy spheres", "expected spheres:N"},
      {"'" + knot + "' -o '" + out.string() + "' --proxy inside:0", "at least 1"},
      {"'" + knot + "' -o '" + out.string() + "' --proxy spheres:100,pair=d3", "unknown spheres parameter"},
      {"'" + knot + "' -o '" + out.string() + "' --proxy spheres:100,25 --proxy spheres:25", "asked for twice"},
      {"'" + knot + "' -o '" + out.string() + "' --proxy spheres:100 --tets voronoi", "--tets"},
      {"'" + testing::cgal_mesh("elephant-with-holes.off").string() + "' -o '" + out.string() + "' --proxy inside:40",
       "inside:40: the mesh is not closed (1353 boundary edges)"},
      {"'" + testing::cgal_mesh("elephant-with-holes.off").string() + "' -o '" + out.string() +
           "' --proxy spheres:100 --tets tetgen",
       "--tets normals"},
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

TEST_F(CliBuild, SphereLevelsAndInsideSpheresWriteJsonAndPlyDescribedByTheSchema) {
  const auto mesh_path = testing::cgal_mesh("knot1.off");
  const auto result = testing::run_visproxy("build '" + mesh_path.string() + "' -o '" + folder_.string() +
                                            "' --proxy spheres:25,250,pair=d1 --proxy inside:10");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_TRUE(result.err.empty()) << result.err;
  EXPECT_NE(result.out.find("GSSA ratio"), std::string::npos) << result.out;
  const json manifest = json::parse(read_file(folder_ / "manifest.json"));
  testing::expect_matches_schema(manifest);
  EXPECT_EQ(manifest.at("options").at("tets"), "normals");
  const json result_schema = testing::manifest_schema().at("properties").at("proxies").at("items").at("properties").at("result");
  const TriangleMesh mesh = read_mesh(mesh_path);
  std::vector<std::string> names;
  for (const json& entry : manifest.at("proxies")) {
    const std::string name = entry.at("name");
    SCOPED_TRACE(name);
    names.push_back(name);
    for (const auto& [key, value] : entry.at("result").items())
      EXPECT_TRUE(result_schema.at("properties").contains(key)) << "result." << key;
    EXPECT_EQ(entry.at("primitive_type"), "sphere");
    EXPECT_EQ(entry.at("file"), name + ".json");
    EXPECT_EQ(entry.at("files"), json::array({name + ".json", name + ".ply"}));
    EXPECT_FALSE(std::filesystem::exists(folder_ / (name + ".obj")));
    const std::vector<Sphere> spheres = read_sphere_set(folder_ / (name + ".json"));
    EXPECT_EQ(entry.at("primitives").get<std::size_t>(), spheres.size());
    const TriangleMesh icospheres = read_mesh(folder_ / (name + ".ply"));
    EXPECT_EQ(entry.at("triangles").get<std::size_t>(), icospheres.triangles.size());
    const json& ratio = entry.at("result").at("gssa_ratio");
    EXPECT_LE(ratio.at("lower").get<double>(), ratio.at("value").get<double>());
    EXPECT_GE(ratio.at("upper").get<double>(), ratio.at("value").get<double>());
    EXPECT_EQ(entry.at("result").at("gssa_lines"), 100000);
  }
  EXPECT_EQ(names, (std::vector<std::string>{"spheres-250", "spheres-25", "inside-10"}));
  const json& entries = manifest.at("proxies");
  EXPECT_EQ(entries[0].at("primitives"), 250);
  EXPECT_EQ(entries[1].at("primitives"), 25);
  EXPECT_EQ(entries[0].at("spec"), "spheres:25,250,pair=d1");
  EXPECT_EQ(entries[0].at("params").at("pair_distance"), "d1");
  EXPECT_EQ(entries[0].at("build_seconds"), entries[1].at("build_seconds"));  // one pass
  EXPECT_EQ(entries[2].at("kind"), "inside");
  EXPECT_EQ(entries[2].at("primitives"), 10);
  EXPECT_EQ(entries[2].at("result").at("lines_hitting_spheres_not_mesh"), 0);
  EXPECT_LT(entries[2].at("result").at("gssa_ratio").at("value").get<double>(), 1.0);
  EXPECT_GT(entries[2].at("result").at("covered_volume_fraction").at("value").get<double>(), 0.2);  // 10 balls in a knot
  EXPECT_TRUE(check_spheres_inside(mesh, read_sphere_set(folder_ / "inside-10.json")).contained());
}

TEST_F(CliBuild, TetgenTetrahedraOnAWatertightMesh) {
  const auto result = testing::run_visproxy("build '" + testing::cgal_mesh("knot1.off").string() + "' -o '" +
                                            folder_.string() + "' --proxy spheres:100 --tets tetgen");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const json manifest = json::parse(read_file(folder_ / "manifest.json"));
  EXPECT_EQ(manifest.at("options").at("tets"), "tetgen");
  const json& entry = manifest.at("proxies").at(0);
  EXPECT_EQ(entry.at("params").at("tets"), "tetgen");
  EXPECT_EQ(entry.at("result").at("initial_spheres"), entry.at("result").at("tetrahedra"));
  EXPECT_EQ(read_sphere_set(folder_ / "spheres-100.json").size(), 100u);
}

TEST_F(CliBuild, DefaultSetOnAMeshWithHolesLeavesOutInsideWithOneNote) {
  const auto result = testing::run_visproxy("build '" + testing::cgal_mesh("elephant-with-holes.off").string() + "' -o '" +
                                            folder_.string() + "'");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_EQ(result.err,
            "visproxy build: skipping inside-40: the mesh is not closed (1353 boundary edges): an inside proxy "
            "needs a closed mesh\n");
  EXPECT_NE(result.out.find("9 proxies of"), std::string::npos) << result.out;
  const json manifest = json::parse(read_file(folder_ / "manifest.json"));
  for (const json& entry : manifest.at("proxies")) EXPECT_NE(entry.at("name"), "inside-40");
  EXPECT_EQ(manifest.at("proxies").back().at("name"), "spheres-100");
  EXPECT_FALSE(std::filesystem::exists(folder_ / "inside-40.json"));
}

TEST_F(CliBuild, InsideSpheresPassVisproxyVerifyUntilOneGrows) {
  const std::string mesh = testing::cgal_mesh("knot1.off").string();
  ASSERT_EQ(testing::run_visproxy("build '" + mesh + "' -o '" + folder_.string() + "' --proxy inside:12").exit_code, 0);
  const auto good = testing::run_visproxy("verify '" + mesh + "' '" + folder_.string() + "'");
  EXPECT_EQ(good.exit_code, 0) << good.out << good.err;
  EXPECT_EQ(json::parse(read_file(folder_ / "manifest.json")).at("proxies").at(0).at("verify").at("holds"), true);
  // Sphere 7 grows by 1 % of the diagonal: it now crosses the surface.
  std::vector<Sphere> spheres = read_sphere_set(folder_ / "inside-12.json");
  spheres[7].radius += 0.01 * json::parse(read_file(folder_ / "manifest.json")).at("mesh").at("bbox").at("diagonal").get<double>();
  write_sphere_set(folder_ / "inside-12.json", spheres);
  const auto bad = testing::run_visproxy("verify '" + mesh + "' '" + folder_.string() + "'");
  EXPECT_EQ(bad.exit_code, 1) << bad.out << bad.err;
  const json entry = json::parse(read_file(folder_ / "manifest.json")).at("proxies").at(0);
  EXPECT_EQ(entry.at("verify").at("holds"), false);
  EXPECT_NE(entry.at("verify").at("counterexample").get<std::string>().find("sphere 7 "), std::string::npos);
  EXPECT_LT(entry.at("verify").at("margin").get<double>(), 0.0);
}

// A builder that runs out of memory is named, with exit code 3 and no output folder. The
// limit of 25 MiB lets the bunny be read and the box built, but not the alpha wrap (about
// 36 MiB here; the bunny reads within 20). At 5 MiB the reading fails, and says so. One
// builder at a time: at once, the box's error measure may be the one that runs out.
TEST_F(CliBuild, BuilderOutOfMemoryIsNamedAndLeavesNoOutput) {
  const std::string mesh = testing::cgal_mesh("bunny00.off").string();
  const std::filesystem::path out = folder_ / "out";
  const auto result = testing::run_visproxy("build '" + mesh + "' -o '" + out.string() +
                                            "' --proxy aabb --proxy wrap --builders-at-once 1 --memory-limit 0.025");
  EXPECT_EQ(result.exit_code, 3) << result.err;
  EXPECT_EQ(result.err, "visproxy: " + mesh + ": wrap: out of memory while building it\n");
  EXPECT_FALSE(std::filesystem::exists(out));
  const auto reading = testing::run_visproxy("build '" + mesh + "' -o '" + out.string() + "' --proxy aabb --memory-limit 0.005");
  EXPECT_EQ(reading.exit_code, 3) << reading.err;
  EXPECT_EQ(reading.err, "visproxy: " + mesh + ": out of memory while reading it\n");
  EXPECT_FALSE(std::filesystem::exists(out));
  const auto roomy = testing::run_visproxy("build '" + mesh + "' -o '" + out.string() + "' --proxy aabb --proxy wrap --memory-limit 8");
  EXPECT_EQ(roomy.exit_code, 0) << roomy.err;
}

// A build past its time limit names the steps in progress, exits 3 and writes nothing: the
// bunny's outer:512 (about 1.5 s) under 0.5 s, and the error measure of a box over 10^7
// samples (over a minute) under 1 s, after the box itself was built in milliseconds.
TEST_F(CliBuild, BuildOutOfTimeNamesTheStepAndLeavesNoOutput) {
  const std::string mesh = testing::cgal_mesh("bunny00.off").string();
  const std::filesystem::path out = folder_ / "out";
  const auto building = testing::run_visproxy("build '" + mesh + "' -o '" + out.string() +
                                              "' --proxy aabb --proxy outer:512 --builders-at-once 1 --time-limit 0.5");
  EXPECT_EQ(building.exit_code, 3) << building.err;
  EXPECT_EQ(building.err, "visproxy: " + mesh + ": outer:512: out of time while building it (--time-limit 0.5 s)\n");
  EXPECT_FALSE(std::filesystem::exists(out));
  // Two builders at once (outer:512 about 1.5 s, wrap about 0.9 s): both are named.
  const auto both = testing::run_visproxy("build '" + mesh + "' -o '" + out.string() +
                                          "' --proxy wrap --proxy outer:512 --builders-at-once 2 --time-limit 0.3");
  EXPECT_EQ(both.exit_code, 3) << both.err;
  EXPECT_EQ(both.err, "visproxy: " + mesh +
                          ": outer:512: out of time while building it; wrap: out of time while building it "
                          "(--time-limit 0.3 s)\n");
  EXPECT_FALSE(std::filesystem::exists(out));
  const auto measuring = testing::run_visproxy("build '" + mesh + "' -o '" + out.string() +
                                               "' --proxy aabb --hausdorff-samples 10000000 --time-limit 1");
  EXPECT_EQ(measuring.exit_code, 3) << measuring.err;
  EXPECT_EQ(measuring.err, "visproxy: " + mesh + ": aabb: out of time while measuring its error (--time-limit 1 s)\n");
  EXPECT_FALSE(std::filesystem::exists(out));
  const auto in_time = testing::run_visproxy("build '" + mesh + "' -o '" + out.string() + "' --proxy aabb --time-limit 600");
  EXPECT_EQ(in_time.exit_code, 0) << in_time.err;
  EXPECT_TRUE(std::filesystem::exists(out / "manifest.json"));
}

}  // namespace
}  // namespace visproxy
