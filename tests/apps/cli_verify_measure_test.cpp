// `visproxy verify`, `measure` and `report` on a real mesh: every claim holds, a proxy
// edited to let the mesh out fails with its counterexample, figures land in the manifest
// (and match its schema), reruns are reproducible, bad input gets one line and exit 2,
// and the HTML report renders in a real browser.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "apps/cli_test_support.h"
#include "visproxy/core/files.h"
#include "visproxy/mesh/triangle_mesh.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/mesh/write_mesh.h"
#include "test_meshes.h"
#include "test_support.h"

namespace visproxy {
namespace {

using nlohmann::json;

class CliVerifyMeasure : public testing::ScratchFolder {
 protected:
  void SetUp() override {
    ScratchFolder::SetUp();
    mesh_ = testing::cgal_mesh("knot1.off").string();
    proxies_ = folder_ / "proxies";
    const auto result = testing::run_visproxy("build '" + mesh_ + "' -o '" + proxies_.string() +
                                              "' --proxy aabb --proxy hull --proxy wrap --proxy quadric:256");
    ASSERT_EQ(result.exit_code, 0) << result.err;
  }
  json manifest() const { return json::parse(read_file(proxies_ / "manifest.json")); }
  testing::CommandResult run(const std::string& command, const std::string& extra = "") const {
    return testing::run_visproxy(command + " '" + mesh_ + "' '" + proxies_.string() + "'" + extra);
  }
  std::string mesh_;
  std::filesystem::path proxies_;
};

TEST_F(CliVerifyMeasure, EveryClaimHoldsAndIsRecorded) {
  const auto result = run("verify");
  ASSERT_EQ(result.exit_code, 0) << result.out << result.err;
  EXPECT_NE(result.out.find("4 of 4 claims hold"), std::string::npos) << result.out;
  const json m = manifest();
  testing::expect_matches_schema(m);
  for (const json& entry : m.at("proxies")) {
    SCOPED_TRACE(entry.at("name").get<std::string>());
    const json& verify = entry.at("verify");
    EXPECT_TRUE(verify.at("holds").get<bool>());
    EXPECT_TRUE(verify.at("counterexample").is_null());
    if (entry.at("kind") == "outside") {
      EXPECT_EQ(verify.at("claim"), "contains the mesh");
      EXPECT_GE(verify.at("margin").get<double>(), 0.0);
    } else {
      EXPECT_EQ(verify.at("claim"), "none");
      EXPECT_GT(verify.at("hausdorff_world").get<double>(), 0.0);
    }
  }
  // The wrap keeps a positive distance from the mesh; the hull touches it.
  EXPECT_GT(m.at("proxies")[2].at("verify").at("margin").get<double>(), 0.0);
  EXPECT_EQ(m.at("proxies")[1].at("verify").at("margin").get<double>(), 0.0);
}

// One hull vertex (a vertex of the mesh) pulled towards the centre: that mesh vertex now
// pokes out of the proxy. For the wrap, one vertex pushed just beneath the mesh's surface:
// its triangles cross the mesh while every mesh vertex stays inside. Both must fail, naming the proxy and the counterexample.
TEST_F(CliVerifyMeasure, ProxyEditedToLetTheMeshOutFails) {
  TriangleMesh hull = read_mesh(proxies_ / "hull.ply", {.weld = Weld::never, .on_warning = {}});
  const BoundingBox box = bounding_box(hull);
  const Vertex centre = 0.5 * (box.min + box.max);
  hull.positions[0] = centre + 0.97 * (hull.positions[0] - centre);
  write_mesh(proxies_ / "hull.ply", hull);
  // The wrap vertex nearest to a mesh triangle moves just beneath that triangle.
  const TriangleMesh mesh = read_mesh(mesh_);
  const Triangle& t = mesh.triangles[100];
  const Vertex a = mesh.positions[t[0]], b = mesh.positions[t[1]], c = mesh.positions[t[2]];
  const Vertex inside = (a + b + c) / 3 - 1e-3 * box.diagonal() * (b - a).cross(c - a).normalized();
  TriangleMesh wrap = read_mesh(proxies_ / "wrap.ply", {.weld = Weld::never, .on_warning = {}});
  std::size_t nearest = 0;
  for (std::size_t v = 0; v < wrap.positions.size(); ++v)
    if ((wrap.positions[v] - inside).norm() < (wrap.positions[nearest] - inside).norm()) nearest = v;
  wrap.positions[nearest] = inside;
  write_mesh(proxies_ / "wrap.ply", wrap);

  const auto result = run("verify");
  EXPECT_EQ(result.exit_code, 1) << result.out;
  EXPECT_NE(result.err.find("hull (outside) fails: mesh vertex"), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("is outside the proxy"), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("wrap (outside) fails: mesh"), std::string::npos) << result.err;
  EXPECT_NE(result.out.find("2 of 4 claims hold"), std::string::npos) << result.out;
  const json m = manifest();
  EXPECT_FALSE(m.at("proxies")[1].at("verify").at("holds").get<bool>());
  EXPECT_LT(m.at("proxies")[1].at("verify").at("margin").get<double>(), 0.0);
  EXPECT_FALSE(m.at("proxies")[2].at("verify").at("holds").get<bool>());
  EXPECT_TRUE(m.at("proxies")[0].at("verify").at("holds").get<bool>());
}

// Hand-edited proxy files of a cube's hull, judged as they are: nothing but the kind is
// read from the manifest.
class CliVerifyEdited : public testing::ScratchFolder {
 protected:
  void SetUp() override {
    ScratchFolder::SetUp();
    mesh_ = folder_ / "cube.ply";
    write_mesh(mesh_, testing::unit_cube());
    proxies_ = folder_ / "proxies";
    const auto result = testing::run_visproxy("build '" + mesh_.string() + "' -o '" + proxies_.string() + "' --proxy hull");
    ASSERT_EQ(result.exit_code, 0) << result.err;
  }
  // Replaces hull.ply by `hull` and, as a user editing by hand would, the entry's counts
  // (and, when given, its spec and method).
  void edit(const TriangleMesh& hull, const std::string& spec = "") {
    write_mesh(proxies_ / "hull.ply", hull);
    json m = json::parse(read_file(proxies_ / "manifest.json"));
    json& entry = m.at("proxies")[0];
    entry["triangles"] = hull.triangles.size();
    entry["primitives"] = hull.triangles.size();
    entry["vertices"] = hull.positions.size();
    if (!spec.empty()) entry["spec"] = spec, entry["method"] = spec;
    write_file_atomically(proxies_ / "manifest.json", m.dump(2));
  }
  testing::CommandResult verify() const {
    return testing::run_visproxy("verify '" + mesh_.string() + "' '" + proxies_.string() + "'");
  }
  std::filesystem::path mesh_, proxies_;
};

TEST_F(CliVerifyEdited, HullWithATriangleRemovedIsNotClosed) {
  TriangleMesh open = read_mesh(proxies_ / "hull.ply", {.weld = Weld::never, .on_warning = {}});
  open.triangles.pop_back();
  edit(open);
  const auto result = verify();
  EXPECT_EQ(result.exit_code, 1) << result.out << result.err;
  EXPECT_NE(result.err.find("hull (outside) fails: the proxy is not closed"), std::string::npos) << result.err;
}

// The top face dented down to the cube's centre: every mesh vertex (the corners) is still
// on the proxy, but the mesh's top face lies above the dent.
TEST_F(CliVerifyEdited, DentedHullFailsThoughEveryVertexIsOnIt) {
  TriangleMesh dented = testing::unit_cube();
  dented.triangles.erase(dented.triangles.begin() + 2, dented.triangles.begin() + 4);  // the top, z = 1
  dented.positions.emplace_back(0.5, 0.5, 0.5);
  for (const Triangle& t : std::vector<Triangle>{{4, 5, 8}, {5, 7, 8}, {7, 6, 8}, {6, 4, 8}}) dented.triangles.push_back(t);
  edit(dented);
  const auto result = verify();
  EXPECT_EQ(result.exit_code, 1) << result.out << result.err;
  EXPECT_NE(result.err.find("lies in no convex part of the proxy"), std::string::npos) << result.err;
}

// The verdict follows the file, not the name: the true hull passes under any spec, and a
// non-convex proxy is not passed for being called a hull.
TEST_F(CliVerifyEdited, VerdictDoesNotDependOnTheSpecInTheManifest) {
  const TriangleMesh hull = read_mesh(proxies_ / "hull.ply", {.weld = Weld::never, .on_warning = {}});
  for (const std::string spec : {"wrap", "outer:512", "hull"}) {
    edit(hull, spec);
    const auto result = verify();
    EXPECT_EQ(result.exit_code, 0) << spec << result.err;
    const json verdict = json::parse(read_file(proxies_ / "manifest.json")).at("proxies")[0].at("verify");
    EXPECT_TRUE(verdict.at("holds").get<bool>());
    EXPECT_EQ(verdict.at("checked").at("triangles_in_convex_parts"), 12) << "every face touches the hull";
    EXPECT_EQ(verdict.at("mesh_hash").get<std::string>().size(), 16u);
  }
}

// CGAL's camel and cow are closed but self-intersect (20 and 101 pairs): inside:40 builds,
// and verify proves every sphere inside their solids by winding number.
TEST_F(CliVerifyEdited, InsideSpheresOfSelfIntersectingMeshesVerify) {
  for (const char* name : {"camel.off", "cow.off"}) {
    const std::string mesh = testing::cgal_mesh(name).string();
    const std::filesystem::path out = folder_ / name;
    const auto info = testing::run_visproxy("info --json '" + mesh + "'");
    ASSERT_EQ(info.exit_code, 0);
    const json report = json::parse(info.out);
    EXPECT_TRUE(report.at("self_intersecting").get<bool>()) << name;
    EXPECT_TRUE(report.at("bounds_solid").get<bool>()) << name;
    const auto built = testing::run_visproxy("build '" + mesh + "' -o '" + out.string() + "' --proxy inside:40");
    ASSERT_EQ(built.exit_code, 0) << built.err;
    const auto verified = testing::run_visproxy("verify '" + mesh + "' '" + out.string() + "'");
    EXPECT_EQ(verified.exit_code, 0) << verified.out << verified.err;
    EXPECT_NE(verified.out.find("1 of 1 claims hold"), std::string::npos) << verified.out;
  }
}

// inner:N on the knot is an inside proxy made of triangles: verify proves it, no measured
// line contradicts it, and a vertex pushed out of the mesh by hand makes it fail; an input
// with boundary edges has no solid to lie in and gets exit 2 naming the file and the defect.
TEST_F(CliVerifyEdited, InnerHullIsProvedMeasuredAndRefusedWhenEdited) {
  const std::string mesh = testing::cgal_mesh("knot1.off").string();
  const std::filesystem::path out = folder_ / "inner";
  const auto built = testing::run_visproxy("build '" + mesh + "' -o '" + out.string() + "' --proxy inner:256,grid=48");
  ASSERT_EQ(built.exit_code, 0) << built.err;
  const json entry = json::parse(read_file(out / "manifest.json")).at("proxies")[0];
  EXPECT_EQ(entry.at("kind"), "inside");
  EXPECT_EQ(entry.at("primitive_type"), "triangle");
  EXPECT_LE(entry.at("primitives").get<std::size_t>(), 256u);
  EXPECT_TRUE(entry.at("result").at("reached_target").get<bool>());

  const auto verified = testing::run_visproxy("verify '" + mesh + "' '" + out.string() + "'");
  ASSERT_EQ(verified.exit_code, 0) << verified.out << verified.err;
  EXPECT_NE(verified.out.find("1 of 1 claims hold"), std::string::npos) << verified.out;
  const auto measured = testing::run_visproxy("measure '" + mesh + "' '" + out.string() + "' --rays 20000 --timed-rays 1000");
  ASSERT_EQ(measured.exit_code, 0) << measured.err;
  const json measurement = json::parse(read_file(out / "manifest.json")).at("proxies")[0].at("measure");
  EXPECT_EQ(measurement.at("rays_contradicting_claim").get<std::uint64_t>(), 0u);
  EXPECT_GT(measurement.at("f_hit").at("value").get<double>(), 0.5);
  testing::expect_matches_schema(json::parse(read_file(out / "manifest.json")));

  // The proxy vertex nearest the mesh, pushed out through the surface.
  TriangleMesh inner = read_mesh(out / "inner-256-grid=48.ply", {.weld = Weld::never, .on_warning = {}});
  const TriangleMesh knot = read_mesh(mesh);
  const BoundingBox box = bounding_box(inner);
  const Vertex centre = 0.5 * (box.min + box.max);
  std::size_t farthest = 0;
  for (std::size_t v = 0; v < inner.positions.size(); ++v)
    if ((inner.positions[v] - centre).norm() > (inner.positions[farthest] - centre).norm()) farthest = v;
  inner.positions[farthest] = centre + 1.5 * (inner.positions[farthest] - centre);
  write_mesh(out / "inner-256-grid=48.ply", inner);
  const auto edited = testing::run_visproxy("verify '" + mesh + "' '" + out.string() + "'");
  EXPECT_EQ(edited.exit_code, 1) << edited.out << edited.err;
  EXPECT_NE(edited.err.find("inner-256-grid=48 (inside) fails: proxy vertex " + std::to_string(farthest)),
            std::string::npos)
      << edited.err;

  const std::string open = testing::cgal_mesh("elephant-with-holes.off").string();
  const auto refused = testing::run_visproxy("build '" + open + "' -o '" + (folder_ / "open").string() + "' --proxy inner:64");
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_EQ(refused.err.find('\n'), refused.err.size() - 1) << refused.err;
  EXPECT_NE(refused.err.find("elephant-with-holes.off"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("boundary edges"), std::string::npos) << refused.err;
  EXPECT_FALSE(std::filesystem::exists(folder_ / "open" / "manifest.json"));
}

TEST_F(CliVerifyMeasure, MeasureRecordsFiguresReproducibly) {
  const auto first = run("measure", " --rays 40000 --seed 5 --timed-rays 2000");
  ASSERT_EQ(first.exit_code, 0) << first.err;
  EXPECT_NE(first.out.find("40000 isotropic lines (seed 5)"), std::string::npos) << first.out;
  const json a = manifest();
  testing::expect_matches_schema(a);
  for (const json& entry : a.at("proxies")) {
    SCOPED_TRACE(entry.at("name").get<std::string>());
    const json& m = entry.at("measure");
    const auto counts = m.at("counts").get<std::vector<std::uint64_t>>();
    EXPECT_EQ(counts[0] + counts[1] + counts[2] + counts[3], 40000u);
    const json& p = m.at("probabilities");
    EXPECT_NEAR(p.at("p1").get<double>() + p.at("p2").get<double>() + p.at("p3").get<double>(), 1.0, 1e-12);
    EXPECT_GT(m.at("cost_ns_per_ray").at("mesh").get<double>(), 0.0);
    if (entry.at("kind") == "outside") {
      EXPECT_EQ(counts[1], 0u);  // nothing gets past an outside proxy
      EXPECT_EQ(m.at("f_hit").at("value").get<double>(), 1.0);
      EXPECT_EQ(p.at("p3").get<double>(), 0.0);
      EXPECT_GE(m.at("gssa_ratio").at("value").get<double>(), 1.0);
    }
  }
  // Bigger outside proxies let fewer free rays through: aabb < hull < wrap.
  const auto f_miss = [&](std::size_t i) { return a.at("proxies")[i].at("measure").at("f_miss").at("value").get<double>(); };
  EXPECT_LT(f_miss(0), f_miss(1));
  EXPECT_LT(f_miss(1), f_miss(2));

  ASSERT_EQ(run("measure", " --rays 40000 --seed 5 --timed-rays 2000").exit_code, 0);
  const json b = manifest();
  for (std::size_t i = 0; i < a.at("proxies").size(); ++i)
    EXPECT_EQ(a.at("proxies")[i].at("measure").at("counts"), b.at("proxies")[i].at("measure").at("counts"));
}

// Shadow segments of the Cornell box against the bunny placed in it, and a mesh the scene
// does not hold.
TEST_F(CliVerifyMeasure, MeasureOnSceneShadowSegments) {
  const std::string bunny = testing::cgal_mesh("bunny00.off").string();
  const auto folder = folder_ / "bunny";
  ASSERT_EQ(testing::run_visproxy("build '" + bunny + "' -o '" + folder.string() + "' --proxy aabb --proxy hull").exit_code, 0);
  const std::string scene = (std::filesystem::path(VISPROXY_SOURCE_DIR) / "data/scenes/cornell.json").string();
  const auto result = testing::run_visproxy("measure '" + bunny + "' '" + folder.string() + "' --scene '" + scene +
                                            "' --rays 20000 --timed-rays 1000");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find("20000 shadow segments of"), std::string::npos) << result.out;
  const json m = json::parse(read_file(folder / "manifest.json"));
  for (const json& entry : m.at("proxies")) {
    const json& measured = entry.at("measure");
    EXPECT_EQ(measured.at("rays").at("kind"), "scene shadow segments");
    EXPECT_EQ(measured.at("rays").at("instances_of_mesh"), 1);
    const auto counts = measured.at("counts").get<std::vector<std::uint64_t>>();
    EXPECT_EQ(counts[0] + counts[1] + counts[2] + counts[3], 20000u);
    // Not verified yet: bounds cannot use the proxy, and its render is not timed.
    EXPECT_FALSE(measured.at("render_time").contains("bounds")) << entry.at("name");
    EXPECT_TRUE(measured.at("render_time").contains("eq8")) << entry.at("name");
    EXPECT_EQ(counts[1], 0u);     // outside proxies: nothing the bunny blocks gets past them
    EXPECT_GT(counts[0], 100u);   // the bunny does shadow part of the box
  }
  testing::expect_matches_schema(m);
  // The share of a sample's time that the bunny's shadow tests take in this scene: what the
  // render gains is Amdahl's part of what the shadow rays gain.
  const json& share = m.at("render_share");
  EXPECT_EQ(share.at("scene"), scene);
  EXPECT_GT(share.at("share").get<double>(), 0.0);
  EXPECT_LT(share.at("share").get<double>(), 1.0);
  EXPECT_LE(std::max(share.at("width").get<int>(), share.at("height").get<int>()), 128);
  // Timed in 6 rounds of a render pass and a pass of the segments: the share is the median
  // round's, inside the rounds' range, and the medians of its parts give it back within
  // that range (each round's ratio bounds the ratio of the medians).
  EXPECT_EQ(share.at("rounds").get<int>(), 6);
  const double low = share.at("share_range").at(0).get<double>(), high = share.at("share_range").at(1).get<double>();
  EXPECT_LE(low, share.at("share").get<double>());
  EXPECT_GE(high, share.at("share").get<double>());
  const double of_medians = share.at("shadow_rays_per_camera_sample").get<double>() *
                            share.at("mesh_ns_per_shadow_ray").get<double>() / share.at("ns_per_camera_sample").get<double>();
  EXPECT_GE(of_medians, 0.95 * low);  // 5 %: a round's shadow rays per sample differ from the whole's
  EXPECT_LE(of_medians, 1.05 * high);
  // The recommendation is made on the scene's rays, and says so, per shadow ray and per render
  // (bounds rest on proved claims).
  ASSERT_EQ(testing::run_visproxy("verify '" + bunny + "' '" + folder.string() + "'").exit_code, 0);
  const auto report = testing::run_visproxy("report '" + folder.string() + "' --no-pictures");
  ASSERT_EQ(report.exit_code, 0) << report.err;
  const json recommendation = json::parse(read_file(folder / "recommendation.json"));
  EXPECT_EQ(recommendation["rays"], "20000 shadow rays of the scene " + scene);
  EXPECT_EQ(recommendation["render_share"]["share"], share.at("share"));
  EXPECT_EQ(recommendation["render_share"]["share_range"], share.at("share_range"));
  const json& bounds = recommendation["uses"]["bounds"];
  ASSERT_TRUE(bounds.contains("render_efficiency")) << bounds.dump();
  // Bounds leave the noise as it is: the render's figure is Amdahl's law of the ray's.
  const double s = share.at("share").get<double>(), e = bounds["efficiency"].get<double>();
  EXPECT_NEAR(bounds["render_efficiency"].get<double>(), 1 / ((1 - s) + s / e), 1e-9);
  EXPECT_NE(bounds["sentence"].get<std::string>().find("over the render of " + scene + ", whose samples spend"),
            std::string::npos)
      << bounds["sentence"];
  // Measured again on isotropic lines, the folder no longer claims a render share.
  ASSERT_EQ(testing::run_visproxy("measure '" + bunny + "' '" + folder.string() + "' --rays 2000 --timed-rays 500").exit_code, 0);
  EXPECT_FALSE(json::parse(read_file(folder / "manifest.json")).contains("render_share"));
  ASSERT_EQ(testing::run_visproxy("report '" + folder.string() + "' --no-pictures").exit_code, 0);
  const json isotropic = json::parse(read_file(folder / "recommendation.json"));
  EXPECT_TRUE(isotropic["render_share"].is_null());
  EXPECT_FALSE(isotropic["uses"]["bounds"].contains("render_efficiency"));
  // Back on the scene for the checks below.
  ASSERT_EQ(testing::run_visproxy("measure '" + bunny + "' '" + folder.string() + "' --scene '" + scene +
                                  "' --rays 20000 --timed-rays 1000")
                .exit_code,
            0);
  // Each proxy's render passes, timed in turns with exact's: bounds only now that verify
  // has proved the outside claims (the first measure ran before verify), eq. 8 and the
  // learned control variate always; the
  // report's render figure for those uses then takes the timed passes.
  {
    const json timed = json::parse(read_file(folder / "manifest.json"));
    for (const json& entry : timed.at("proxies")) {
      const json& times = entry.at("measure").at("render_time");
      EXPECT_EQ(times.at("rounds"), 6);
      for (const char* use : {"bounds", "eq8", "control_variate"}) {
        ASSERT_TRUE(times.contains(use)) << entry.at("name") << " " << use;
        const double t = times.at(use).at("pass_time_over_exact").get<double>();
        EXPECT_GT(t, 0.0);
        EXPECT_LE(times.at(use).at("range").at(0).get<double>(), t);
        EXPECT_GE(times.at(use).at("range").at(1).get<double>(), t);
      }
    }
    testing::expect_matches_schema(timed);
  }
  ASSERT_EQ(testing::run_visproxy("report '" + folder.string() + "' --no-pictures").exit_code, 0);
  {
    const json advice = json::parse(read_file(folder / "recommendation.json"));
    for (const json& p : advice.at("proxies"))
      for (const char* use : {"bounds", "eq8", "control_variate"}) {
        EXPECT_EQ(p.at(use).at("render_timed"), true) << p.at("name") << " " << use;
      }
    EXPECT_NE(advice.at("uses").at("bounds").at("sentence").get<std::string>().find("its render passes timed"), std::string::npos);
  }
  EXPECT_NE(read_file(folder / "report.md").find("Predicted on 20000 shadow rays of the scene"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(folder / "pictures"));
  // The knot is not in the Cornell box.
  const auto absent = run("measure", " --scene '" + scene + "' --rays 1000");
  EXPECT_EQ(absent.exit_code, 2);
  EXPECT_NE(absent.err.find("no instance of the scene uses the measured mesh"), std::string::npos) << absent.err;
}

TEST_F(CliVerifyMeasure, BadInputGetsOneLineAndExitTwo) {
  const std::string other = testing::cgal_mesh("knot2.off").string();
  struct Case {
    std::string arguments, fragment;
  };
  const std::vector<Case> cases = {
      {"verify '" + other + "' '" + proxies_.string() + "'", "knot2.off: is not the mesh the proxies were built from"},
      {"measure '" + mesh_ + "' '" + (folder_ / "nowhere").string() + "'", "manifest.json"},
      {"report '" + folder_.string() + "'", "manifest.json"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.arguments);
    const auto result = testing::run_visproxy(c.arguments);
    EXPECT_EQ(result.exit_code, 2);
    EXPECT_EQ(result.err.find('\n'), result.err.size() - 1) << result.err;
    EXPECT_NE(result.err.find(c.fragment), std::string::npos) << result.err;
  }
  // A proxy file that went missing is named.
  std::filesystem::remove(proxies_ / "wrap.ply");
  const auto missing = run("verify");
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find("wrap.ply"), std::string::npos) << missing.err;
}

TEST_F(CliVerifyMeasure, ReportListsEveryProxyRecommendsOneAndRendersInABrowser) {
  ASSERT_EQ(run("verify").exit_code, 0);
  ASSERT_EQ(run("measure", " --rays 20000 --timed-rays 1000").exit_code, 0);
  const auto result = testing::run_visproxy("report '" + proxies_.string() + "' --picture-size 96");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find("For shadow rays through the control variate, "), std::string::npos) << result.out;
  const std::string markdown = read_file(proxies_ / "report.md");
  const std::string svg = read_file(proxies_ / "f_miss.svg");
  for (const char* name : {"| aabb |", "| hull |", "| wrap |", "| quadric-256 |"})
    EXPECT_NE(markdown.find(name), std::string::npos) << name;
  EXPECT_NE(markdown.find("knot1.off"), std::string::npos);
  std::size_t points = 0;
  for (std::size_t at = 0; (at = svg.find("<circle cx", at)) != std::string::npos; ++at) ++points;
  EXPECT_EQ(points, 4u + 3u);  // one per proxy, three in the legend

  // The recommendation: every proxy's figures, bounds only from the proved outside ones.
  const json recommendation = json::parse(read_file(proxies_ / "recommendation.json"));
  testing::expect_described(recommendation, "recommendation.schema.json");
  ASSERT_EQ(recommendation["proxies"].size(), 4u);
  for (const json& p : recommendation["proxies"]) {
    const bool outside = p["name"] == "aabb" || p["name"] == "hull" || p["name"] == "wrap";
    EXPECT_EQ(p["proved_kind"], outside ? "outside" : "general") << p["name"];
    EXPECT_EQ(p["bounds"]["usable"], outside) << p["name"];
  }
  EXPECT_NE(markdown.find(recommendation["uses"]["control_variate"]["sentence"].get<std::string>()), std::string::npos);
  // What to ship comes first: for each use a file that is there, exactly where the proxy is
  // shown cheaper than the mesh, with the shadow it would cast on its own; else keep the mesh.
  EXPECT_EQ(markdown.find("## What to ship"), markdown.find("## "));
  for (const char* use : {"control_variate", "eq8", "bounds"}) {
    const json& choice = recommendation["uses"][use];
    const std::string ship = choice["ship"].get<std::string>();
    EXPECT_NE(markdown.find(ship), std::string::npos) << ship;
    EXPECT_NE(result.out.find(ship), std::string::npos) << ship;
    const bool beats = choice.value("beats_mesh", false);
    ASSERT_EQ(choice["file"].is_string(), beats) << ship;
    if (beats) {
      const std::string file = choice["file"].get<std::string>();
      EXPECT_TRUE(std::filesystem::is_regular_file(proxies_ / file)) << file;
      EXPECT_NE(ship.find(", ship " + file + " ("), std::string::npos) << ship;
      EXPECT_NE(ship.find("(cast on its own, it would miss "), std::string::npos) << ship;
    } else {
      EXPECT_NE(ship.find(", keep the mesh: no proxy is shown cheaper"), std::string::npos) << ship;
    }
  }
  // The pictures, as files and in the page.
  for (const char* file : {"mesh-shadow.png", "aabb-overlay.png", "hull-shadow.png", "wrap-difference.png", "quadric-256-overlay.png"})
    EXPECT_TRUE(std::filesystem::is_regular_file(proxies_ / "pictures" / file)) << file;
  const std::string html = read_file(proxies_ / "report.html");
  std::size_t images = 0;
  for (std::size_t at = 0; (at = html.find("src=\"data:image/png;base64,", at)) != std::string::npos; ++at) ++images;
  EXPECT_EQ(images, 4u * 4u);

  // A proxy edited by hand after verify: its verdict no longer proves it, so bounds drop it.
  {
    TriangleMesh hull = read_mesh(proxies_ / "hull.ply");
    hull.positions[0] *= 1.001;
    write_mesh(proxies_ / "hull.ply", hull);
  }
  ASSERT_EQ(testing::run_visproxy("report '" + proxies_.string() + "' --no-pictures").exit_code, 0);
  const json edited = json::parse(read_file(proxies_ / "recommendation.json"));
  EXPECT_EQ(edited["proxies"][1]["name"], "hull");
  EXPECT_EQ(edited["proxies"][1]["proved_kind"], "general");
  EXPECT_EQ(edited["proxies"][1]["bounds"]["usable"], false);

  const std::string chromium = VISPROXY_CHROMIUM;
  if (chromium.empty()) GTEST_SKIP() << "chromium not found at configure time (cmake/bootstrap.sh test installs it)";
  const std::string dom_path = (folder_ / "dom.html").string();
  const std::string command = "'" + chromium + "' --headless --no-sandbox --disable-gpu --dump-dom 'file://" +
                              (proxies_ / "report.html").string() + "' > '" + dom_path + "' 2>/dev/null";
  ASSERT_EQ(std::system(command.c_str()), 0);
  const std::string dom = read_file(dom_path);
  // The script ran (it marks the table sortable) and the rows are there, as the browser built them.
  EXPECT_NE(dom.find("data-sortable=\"ready\""), std::string::npos);
  std::size_t rows = 0;
  for (std::size_t at = 0; (at = dom.find("<tr>", at)) != std::string::npos; ++at) ++rows;
  EXPECT_EQ(rows, 1u + 4u);
  EXPECT_NE(dom.find(">quadric-256<"), std::string::npos);
  EXPECT_NE(dom.find("<svg"), std::string::npos);
}

TEST_F(CliVerifyMeasure, ReportNeedsTheMeshItWasBuiltFrom) {
  const std::string other = testing::cgal_mesh("knot2.off").string();
  const auto wrong = testing::run_visproxy("report '" + proxies_.string() + "' --mesh '" + other + "'");
  EXPECT_EQ(wrong.exit_code, 2);
  EXPECT_NE(wrong.err.find("knot2.off: is not the mesh the proxies were built from"), std::string::npos) << wrong.err;
  // A manifest whose mesh is not where it says: the mesh is named, with the way out.
  json m = manifest();
  m["mesh"]["path"] = (folder_ / "moved.off").string();
  write_file_atomically(proxies_ / "manifest.json", m.dump(2));
  const auto moved = testing::run_visproxy("report '" + proxies_.string() + "'");
  EXPECT_EQ(moved.exit_code, 2);
  EXPECT_EQ(moved.err.find('\n'), moved.err.size() - 1) << moved.err;
  EXPECT_NE(moved.err.find("moved.off"), std::string::npos) << moved.err;
  EXPECT_NE(moved.err.find("--mesh"), std::string::npos) << moved.err;
  EXPECT_FALSE(std::filesystem::exists(proxies_ / "report.html"));  // nothing half-written
  EXPECT_EQ(testing::run_visproxy("report '" + proxies_.string() + "' --no-pictures --mesh '" + mesh_ + "'").exit_code, 0);
}

}  // namespace
}  // namespace visproxy
