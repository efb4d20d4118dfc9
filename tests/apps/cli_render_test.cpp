// `visproxy render` and `generate` as a user runs them: the shipped Cornell box and a
// generated hairball render, `bounds` gives the bit-identical image of `exact`, no mode
// (including adaptive probabilities with a zero floor) produces NaN or infinity, and bad
// scenes get one line naming the file.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "apps/cli_test_support.h"
#include "visproxy/core/errors.h"
#include "visproxy/core/files.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/mesh/write_mesh.h"
#include "visproxy/image/image.h"
#include "test_support.h"

namespace visproxy {
namespace {

using nlohmann::json;

class CliRender : public testing::ScratchFolder {
 public:
  testing::CommandResult render(const std::filesystem::path& scene, const std::string& name, const std::string& options) {
    return testing::run_visproxy("render '" + scene.string() + "' -o '" + (folder_ / (name + ".pfm")).string() +
                                 "' --cache '" + (folder_ / "cache").string() + "' " + options);
  }
  Image image(const std::string& name) const { return read_pfm(folder_ / (name + ".pfm")); }
  const std::filesystem::path& folder() const { return folder_; }
};

std::filesystem::path cornell() { return std::filesystem::path(VISPROXY_SOURCE_DIR) / "data/scenes/cornell.json"; }

void expect_bounds_identical_and_finite(CliRender& test, const std::filesystem::path& scene, const std::string& size) {
  for (const char* mode : {"exact", "bounds", "stochastic"}) {
    const auto result = test.render(scene, mode, std::string("--visibility ") + mode + " --spp 3 --shadow-rays 2 --seed 9 " + size);
    ASSERT_EQ(result.exit_code, 0) << mode << ": " << result.err;
  }
  const auto adaptive = test.render(scene, "adaptive",
                                    "--visibility stochastic --probabilities adaptive --cost-heuristic --probability-floor 0.01 "
                                    "--probe-rays 4 --spp 2 --maps " + size);
  ASSERT_EQ(adaptive.exit_code, 0) << adaptive.err;
  // The control variate with extreme probabilities: the smallest floor, corrections almost never traced.
  const auto learned = test.render(scene, "learned",
                                   "--visibility stochastic --estimator control-variate --probabilities learned "
                                   "--probability-floor 1e-6 --correction-scale 0.01 --spp 3 --maps " + size);
  ASSERT_EQ(learned.exit_code, 0) << learned.err;
  // A zero floor would give ray types no sample has shown probability 0: refused, one line.
  const auto zero = test.render(scene, "zero", "--visibility stochastic --probabilities adaptive --probability-floor 0 " + size);
  EXPECT_EQ(zero.exit_code, 2);
  EXPECT_NE(zero.err.find("probability_floor must be positive"), std::string::npos) << zero.err;
  EXPECT_FALSE(std::filesystem::exists(test.folder() / "zero.pfm"));
  const auto probed = test.render(scene, "probed",
                                  "--visibility stochastic --estimator control-variate --probabilities adaptive --probe-passes 1 "
                                  "--probe-rays 2 --spp 2 " + size);
  ASSERT_EQ(probed.exit_code, 0) << probed.err;
  const auto optimal = test.render(scene, "optimal", "--visibility stochastic --probabilities optimal --spp 2 " + size);
  ASSERT_EQ(optimal.exit_code, 0) << optimal.err;
  const json optimal_stats = json::parse(read_file(test.folder() / "optimal.stats.json"));
  EXPECT_EQ(optimal_stats["probabilities"], "optimal");
  EXPECT_EQ(optimal_stats["stats"]["optimal_probabilities"]["general"].size(), 3u) << optimal_stats["stats"].dump();
  // Optimal probabilities are eq. 8's: with the control variate, refused in one line.
  const auto optimal_cv =
      test.render(scene, "optimal-cv", "--visibility stochastic --estimator control-variate --probabilities optimal " + size);
  EXPECT_EQ(optimal_cv.exit_code, 2);
  EXPECT_NE(optimal_cv.err.find("optimal needs --estimator eq8"), std::string::npos) << optimal_cv.err;
  for (const char* name : {"exact", "bounds", "stochastic", "adaptive", "learned", "probed", "optimal"})
    testing::expect_described(json::parse(read_file(test.folder() / (std::string(name) + ".stats.json"))), "render-stats.schema.json");
  const Image exact = test.image("exact");
  EXPECT_EQ(exact.pixels, test.image("bounds").pixels);  // bit-identical
  double brightest = 0;
  for (const Color& c : exact.pixels) brightest = std::max(brightest, c.maxCoeff());
  EXPECT_GT(brightest, 0.0);
  for (const char* name : {"exact", "stochastic", "adaptive", "learned", "probed"}) EXPECT_TRUE(all_finite(test.image(name))) << name;
}

TEST_F(CliRender, ShippedSceneIsDescribedByTheSchema) {
  testing::expect_described(json::parse(read_file(cornell())), "scene.schema.json");
}

TEST_F(CliRender, CornellBoxBoundsMatchesExactAndEveryModeIsFinite) {
  expect_bounds_identical_and_finite(*this, cornell(), "--width 48 --height 48");
  const json stats = json::parse(read_file(folder_ / "bounds.stats.json"));
  EXPECT_EQ(stats.at("visibility"), "bounds");
  EXPECT_EQ(stats.at("instances")[3].at("outside_proxy"), "outer:512");
  EXPECT_GT(stats.at("stats").at("bounds").at("unoccluded_by_outside_proxies").get<std::uint64_t>(), 0u);
  EXPECT_TRUE(std::filesystem::exists(folder_ / "adaptive.png"));
  EXPECT_TRUE(std::filesystem::exists(folder_ / "adaptive.p1.png"));
  EXPECT_TRUE(std::filesystem::exists(folder_ / "adaptive.cost.png"));
  // The proxies were built once into the cache and are found there the second time.
  const auto again = render(cornell(), "again", "--visibility bounds --spp 1 --width 8 --height 8");
  ASSERT_EQ(again.exit_code, 0);
  EXPECT_EQ(again.err.find("building"), std::string::npos) << again.err;
}

// data/scenes/boxes.gltf renders as it is, and a JSON scene that imports it and names
// proxies for its instances renders every mode, bounds bit for bit equal to exact.
TEST_F(CliRender, GltfSceneRendersAndItsImportedInstancesUseProxies) {
  const std::filesystem::path gltf = std::filesystem::path(VISPROXY_SOURCE_DIR) / "data/scenes/boxes.gltf";
  const auto direct = render(gltf, "gltf", "--spp 2 --width 40 --height 30");
  ASSERT_EQ(direct.exit_code, 0) << direct.err;
  double sum = 0;
  for (const Color& c : image("gltf").pixels) sum += c.sum();
  EXPECT_GT(sum, 0);
  const json scene = {{"format", "visproxy-scene"}, {"format_version", 1},
                      {"import", {{"file", gltf.string()}, {"proxies", {{"boxes.gltf:box", {"hull", "inside:8"}}}}}}};
  testing::expect_described(scene, "scene.schema.json");
  std::ofstream(folder_ / "imports.json") << scene.dump();
  expect_bounds_identical_and_finite(*this, folder_ / "imports.json", "--width 40 --height 30");
  const json stats = json::parse(read_file(folder_ / "bounds.stats.json"));
  EXPECT_EQ(stats.at("instances")[0].at("outside_proxy"), nullptr);  // the floor names none
  for (const int box : {1, 2}) {
    EXPECT_EQ(stats.at("instances")[box].at("outside_proxy"), "hull");
    EXPECT_EQ(stats.at("instances")[box].at("inside_proxy"), "inside:8");
  }
}

TEST_F(CliRender, GeneratedHairballBoundsMatchesExact) {
  const auto generated = testing::run_visproxy("generate hairball --triangles 20000 -o '" + (folder_ / "hairball").string() + "'");
  ASSERT_EQ(generated.exit_code, 0) << generated.err;
  EXPECT_TRUE(std::filesystem::exists(folder_ / "hairball" / "proxies" / "manifest.json"));
  testing::expect_described(json::parse(read_file(folder_ / "hairball" / "hairball.json")), "scene.schema.json");
  expect_bounds_identical_and_finite(*this, folder_ / "hairball" / "hairball.json", "--width 40 --height 30");
}

// `generate forest` records a verdict for every outside claim, so a render proves nothing
// again; every mode renders it, bounds bit for bit as exact. A proxy shrunk by hand after
// generation no longer matches its verdict: the render verifies it again, finds it fails,
// uses it as a general proxy, and bounds still gives exact's image.
TEST_F(CliRender, GeneratedForestRendersInEveryModeAndAnEditedProxyIsProvedAgain) {
  const std::filesystem::path out = folder_ / "forest";
  const auto generated = testing::run_visproxy("generate forest --trees 40 --species 2 --tree-triangles 4000,6000 --width 40 "
                                               "--height 30 -o '" + out.string() + "'");
  ASSERT_EQ(generated.exit_code, 0) << generated.err;
  testing::expect_described(json::parse(read_file(out / "forest.json")), "scene.schema.json");
  std::size_t proved = 0;
  for (const char* folder : {"proxies-0", "proxies-1"}) {
    const json written = json::parse(read_file(out / folder / "manifest.json"));
    for (const json& entry : written.at("proxies"))
      if (entry.at("kind") == "outside") {
        EXPECT_EQ(entry.at("verify").at("holds"), true) << folder << " " << entry.at("name");
        ++proved;
      }
  }
  EXPECT_EQ(proved, 6u);  // aabb, hull:32 and outer:512 of each species
  const auto first = render(out / "forest.json", "first", "--visibility bounds --spp 1 --width 40 --height 30");
  ASSERT_EQ(first.exit_code, 0) << first.err;
  EXPECT_EQ(first.err.find("verified"), std::string::npos) << first.err;
  expect_bounds_identical_and_finite(*this, out / "forest.json", "--width 40 --height 30");

  // Shrink species 0's aabb (the outside proxy bounds uses) to half its size about its
  // centre, as a careless edit would.
  const json manifest = json::parse(read_file(out / "proxies-0" / "manifest.json"));
  std::filesystem::path aabb;
  for (const json& entry : manifest.at("proxies"))
    if (entry.at("name") == "aabb") aabb = out / "proxies-0" / entry.at("file").get<std::string>();
  ASSERT_FALSE(aabb.empty());
  TriangleMesh shrunk = read_mesh(aabb);
  const BoundingBox box = bounding_box(shrunk);
  for (Vertex& p : shrunk.positions) p = 0.5 * (box.min + box.max) + 0.5 * (p - 0.5 * (box.min + box.max));
  write_mesh(aabb, shrunk);
  const std::string options = "--spp 2 --shadow-rays 2 --seed 5 --width 40 --height 30";
  const auto exact = render(out / "forest.json", "edited-exact", "--visibility exact " + options);
  const auto bounds = render(out / "forest.json", "edited-bounds", "--visibility bounds " + options);
  ASSERT_EQ(exact.exit_code, 0) << exact.err;
  ASSERT_EQ(bounds.exit_code, 0) << bounds.err;
  EXPECT_NE(bounds.err.find("verified aabb of tree0: does not hold"), std::string::npos) << bounds.err;
  EXPECT_EQ(image("edited-exact").pixels, image("edited-bounds").pixels);
  const json stats = json::parse(read_file(folder_ / "edited-bounds.stats.json"));
  EXPECT_GT(stats.at("stats").at("bounds").at("unoccluded_by_outside_proxies").get<std::uint64_t>(), 0u);  // tree1's box still proves
}

// `generate room` writes a scene the schema describes; lightcuts renders it with and without
// visibility bounds; with both (inscribed balls as inside proxies) the proofs agree with
// every traced representative, the cut shrinks, and the maps are written; a cut reference of
// another size, or one given without --maps, gets one line and no image.
TEST_F(CliRender, GeneratedRoomRendersWithLightcutsAndProvedBounds) {
  const std::filesystem::path scene = folder_ / "room.json";
  const auto generated = testing::run_visproxy("generate room -o '" + scene.string() + "' --width 48 --height 36 --proxy hull --proxy inside:40");
  ASSERT_EQ(generated.exit_code, 0) << generated.err;
  testing::expect_described(json::parse(read_file(scene)), "scene.schema.json");
  const auto plain = render(scene, "plain", "--integrator lightcuts --spp 1 --light-points 256 --maps");
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  const auto both = render(scene, "both", "--integrator lightcuts --spp 1 --light-points 256 --visibility-bounds both --check-proofs --maps "
                                          "--cut-reference '" + (folder_ / "plain.cut.pfm").string() + "'");
  ASSERT_EQ(both.exit_code, 0) << both.err;
  EXPECT_NE(both.out.find("proofs checked: 0 disagreed"), std::string::npos) << both.out;
  const json a = json::parse(read_file(folder_ / "plain.stats.json")), b = json::parse(read_file(folder_ / "both.stats.json"));
  testing::expect_described(a, "render-stats.schema.json");
  testing::expect_described(b, "render-stats.schema.json");
  EXPECT_EQ(b["visibility_bounds"], "both");
  EXPECT_EQ(b["stats"]["integrator"]["proof_disagreements"], 0);
  EXPECT_GT(b["stats"]["integrator"]["clusters_proved_unoccluded"].get<std::uint64_t>(), 0u);
  EXPECT_GT(b["stats"]["integrator"]["clusters_proved_occluded"].get<std::uint64_t>(), 0u);
  EXPECT_LT(b["stats"]["integrator"]["cut_size_mean"].get<double>(), a["stats"]["integrator"]["cut_size_mean"].get<double>());
  for (const char* map : {"plain.cut.png", "both.cut.png", "both.cut.pfm", "both.cut-reduction.png"})
    EXPECT_TRUE(std::filesystem::exists(folder_ / map)) << map;
  const auto small = render(scene, "small", "--integrator lightcuts --spp 1 --light-points 16 --maps --width 8 --height 8");
  ASSERT_EQ(small.exit_code, 0) << small.err;
  const auto mismatched = render(scene, "mismatched", "--integrator lightcuts --spp 1 --maps --cut-reference '" + (folder_ / "small.cut.pfm").string() + "'");
  EXPECT_EQ(mismatched.exit_code, 2);
  EXPECT_NE(mismatched.err.find("small.cut.pfm"), std::string::npos) << mismatched.err;
  EXPECT_NE(mismatched.err.find("8x8"), std::string::npos) << mismatched.err;
  EXPECT_FALSE(std::filesystem::exists(folder_ / "mismatched.pfm"));
  const auto without_maps = render(scene, "without", "--integrator lightcuts --spp 1 --cut-reference '" + (folder_ / "small.cut.pfm").string() + "'");
  EXPECT_EQ(without_maps.exit_code, 2);
  EXPECT_FALSE(std::filesystem::exists(folder_ / "without.pfm"));
  const auto stochastic = render(scene, "stochastic", "--integrator lightcuts --visibility stochastic --spp 1");
  EXPECT_EQ(stochastic.exit_code, 2);
  EXPECT_NE(stochastic.err.find("lightcuts"), std::string::npos) << stochastic.err;
}

// The shipped VPL scenes are described by the schema and render with virtual point
// lights: exact (packets and single rays give one image), occluder disks of a sphere set,
// the control variate with them; the stats say how many VPLs there were and what the clamp
// dropped, and are described by the schema. Bad VPL options get one line and no image.
TEST_F(CliRender, KnotRoomRendersWithVirtualPointLights) {
  const std::filesystem::path scenes = std::filesystem::path(VISPROXY_SOURCE_DIR) / "data/scenes";
  for (const char* name : {"knot-room.json", "armadillo-room.json", "menagerie-room.json"})
    testing::expect_described(json::parse(read_file(scenes / name)), "scene.schema.json");
  const std::filesystem::path knot = scenes / "knot-room.json";
  const std::string size = "--integrator vpl --vpls 48 --bounces 2 --spp 2 --width 24 --height 20 ";
  ASSERT_EQ(render(knot, "vpl-exact", size).exit_code, 0);
  const auto single = render(knot, "vpl-single", size + "--single-rays");
  ASSERT_EQ(single.exit_code, 0) << single.err;
  EXPECT_EQ(image("vpl-exact").pixels, image("vpl-single").pixels);
  const auto disks = render(knot, "vpl-disks", size + "--visibility spheres --proxy spheres:25 --self-shadow heuristic");
  ASSERT_EQ(disks.exit_code, 0) << disks.err;
  const auto cv = render(knot, "vpl-cv", size + "--visibility stochastic --estimator control-variate --probabilities learned --proxy spheres:25");
  ASSERT_EQ(cv.exit_code, 0) << cv.err;
  for (const char* name : {"vpl-exact", "vpl-single", "vpl-disks", "vpl-cv"}) {
    const json stats = json::parse(read_file(folder_ / (std::string(name) + ".stats.json")));
    testing::expect_described(stats, "render-stats.schema.json");
    EXPECT_EQ(stats.at("integrator"), "vpl") << name;
    EXPECT_GT(stats.at("stats").at("integrator").at("virtual_point_lights").get<int>(), 0) << name;
    EXPECT_GT(stats.at("stats").at("vpl_connections").get<std::uint64_t>(), 0u) << name;
    EXPECT_TRUE(all_finite(image(name))) << name;
  }
  EXPECT_GT(json::parse(read_file(folder_ / "vpl-disks.stats.json")).at("stats").at("disk_tests").get<std::uint64_t>(), 0u);
  // The correction scale defaults to 0.25 with VPLs (2 with the direct integrator), and a
  // given one is kept.
  EXPECT_EQ(json::parse(read_file(folder_ / "vpl-cv.stats.json")).at("correction_scale").get<double>(), 0.25);
  const auto given = render(knot, "vpl-cv-given", size + "--visibility stochastic --estimator control-variate --proxy spheres:25 "
                                                         "--correction-scale 3");
  ASSERT_EQ(given.exit_code, 0) << given.err;
  EXPECT_EQ(json::parse(read_file(folder_ / "vpl-cv-given.stats.json")).at("correction_scale").get<double>(), 3.0);
  const auto direct = render(knot, "direct-cv", "--spp 1 --width 8 --height 6 --visibility stochastic --estimator control-variate "
                                               "--proxy spheres:25");
  ASSERT_EQ(direct.exit_code, 0) << direct.err;
  EXPECT_EQ(json::parse(read_file(folder_ / "direct-cv.stats.json")).at("correction_scale").get<double>(), 2.0);
  EXPECT_NE(disks.out.find("VPLs ("), std::string::npos) << disks.out;
  const auto bad = render(knot, "vpl-bad", "--integrator vpl --vpls 0");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--vpls"), std::string::npos) << bad.err;
  EXPECT_FALSE(std::filesystem::exists(folder_ / "vpl-bad.pfm"));
}

// OpenEXR output holds the same linear image as the PFM (both store 32-bit floats).
TEST_F(CliRender, ExrOutputHoldsTheSameLinearImage) {
  const std::string options = "--spp 2 --seed 4 --width 12 --height 10";
  ASSERT_EQ(render(cornell(), "as-pfm", options).exit_code, 0);
  const auto exr = testing::run_visproxy("render '" + cornell().string() + "' -o '" + (folder_ / "as-exr.exr").string() + "' --cache '" +
                                         (folder_ / "cache").string() + "' " + options);
  ASSERT_EQ(exr.exit_code, 0) << exr.err;
  EXPECT_TRUE(std::filesystem::exists(folder_ / "as-exr.png"));
  const Image from_exr = read_exr(folder_ / "as-exr.exr");
  EXPECT_EQ(from_exr.width, 12);
  EXPECT_EQ(from_exr.height, 10);
  EXPECT_EQ(from_exr.pixels, image("as-pfm").pixels);
  // Not an image: one line naming the file.
  std::ofstream(folder_ / "bad.exr") << "not an image";
  EXPECT_THROW(read_exr(folder_ / "bad.exr"), InvalidInputError);
  const auto tiff = testing::run_visproxy("render '" + cornell().string() + "' -o '" + (folder_ / "out.tiff").string() + "' --spp 1");
  EXPECT_EQ(tiff.exit_code, 2);
  EXPECT_NE(tiff.err.find("out.tiff"), std::string::npos) << tiff.err;
  EXPECT_FALSE(std::filesystem::exists(folder_ / "out.tiff"));
}

TEST_F(CliRender, LearnedProbabilitiesNeedTheControlVariate) {
  const auto result = render(cornell(), "learned", "--visibility stochastic --probabilities learned --spp 1");
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.err.find("control-variate"), std::string::npos) << result.err;
  EXPECT_FALSE(std::filesystem::exists(folder_ / "learned.pfm"));
}

// `visproxy compare` on a small hairball: every mode in the table, its images and error
// maps, the convergence curve, and an efficiency ratio of 1 for exact.
TEST_F(CliRender, CompareWritesTheTableImagesAndConvergence) {
  const auto generated = testing::run_visproxy("generate hairball --triangles 4800 -o '" + (folder_ / "hairball").string() + "'");
  ASSERT_EQ(generated.exit_code, 0) << generated.err;
  const std::filesystem::path out = folder_ / "compare";
  const auto result = testing::run_visproxy("compare '" + (folder_ / "hairball" / "hairball.json").string() + "' -o '" + out.string() +
                                            "' --seconds 0.05 --rounds 4 --reference-spp 256 --convergence-points 2 --count-passes 1 "
                                            "--width 16 --height 12 --proxy hull:32 --cache '" + (folder_ / "cache").string() + "'");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const std::string table = read_file(out / "table.md");
  for (const char* mode : {"| exact |", "| bounds |", "| hull:32 eq8 equal |", "| hull:32 eq8 adaptive |",
                           "| hull:32 eq8 adaptive + cost heuristic |", "| hull:32 eq8 optimal |", "| hull:32 control variate equal |",
                           "| hull:32 control variate learned |"})
    EXPECT_NE(table.find(mode), std::string::npos) << mode << "\n" << table;
  const std::string csv = read_file(out / "table.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 9);  // header + 8 modes
  EXPECT_NE(csv.find("\"exact\",,"), std::string::npos) << csv;
  for (const char* file : {"reference.pfm", "exact.pfm", "exact.png", "exact.error.png", "bounds.error.png",
                           "hull-32-control-variate-learned.error.png", "convergence.csv", "convergence.svg"})
    EXPECT_TRUE(std::filesystem::exists(out / file)) << file;
  const std::string convergence = read_file(out / "convergence.csv");
  EXPECT_EQ(std::count(convergence.begin(), convergence.end(), '\n'), 1 + 8 * 2);
  EXPECT_NE(table.find("0.05 s per mode in 4 rounds"), std::string::npos) << table;
  // The curve is read from the table's own renders, at the end of rounds 2 and 4: per mode,
  // a point at half the budget with no more samples, then the table's samples per pixel.
  std::istringstream points(convergence), rows(csv);
  std::string point_line, row_line;
  std::getline(points, point_line), std::getline(rows, row_line);
  for (int mode = 0; mode < 8; ++mode) {
    std::string half, full;
    std::getline(points, half), std::getline(points, full), std::getline(rows, row_line);
    auto field = [](const std::string& line, std::size_t index) {  // mode names hold no comma
      std::vector<std::string> fields(1);
      for (const char c : line) {
        if (c == ',') fields.emplace_back();
        else fields.back().push_back(c);
      }
      return index < fields.size() ? fields[index] : std::string("?");
    };
    EXPECT_EQ(field(half, 1), "0.025") << half;
    EXPECT_EQ(field(full, 1), "0.05") << full;
    EXPECT_EQ(field(half, 0), field(full, 0));
    EXPECT_LE(std::stoi(field(half, 3)), std::stoi(field(full, 3))) << half << " / " << full;
    EXPECT_EQ(field(full, 3), field(row_line, 3)) << full << " / " << row_line;  // samples per pixel
  }
  // The exact row's efficiency ratio is 1 by definition.
  const std::size_t exact_row = csv.find("\"exact\"");
  const std::string row = csv.substr(exact_row, csv.find('\n', exact_row) - exact_row);
  EXPECT_EQ(row.substr(row.rfind(',') + 1), "1") << row;
}

// --equal samples: every mode renders the passes exact rendered in its first turn, so the
// modes' images share their samples: bounds, exact by proof, has exact's MSE to the digit.
// --mode keeps exact and the modes named; a name it does not know is refused in one line.
TEST_F(CliRender, CompareAtEqualSamplesSharesTheSamplesOfEveryMode) {
  const auto generated = testing::run_visproxy("generate hairball --triangles 2400 -o '" + (folder_ / "hairball").string() + "'");
  ASSERT_EQ(generated.exit_code, 0) << generated.err;
  const std::string base = "compare '" + (folder_ / "hairball" / "hairball.json").string() +
                           "' --seconds 0.06 --rounds 3 --reference-spp 64 --convergence-points 1 --no-count --width 24 "
                           "--height 18 --proxy hull:32 --cache '" + (folder_ / "cache").string() + "' ";
  const std::filesystem::path out = folder_ / "samples";
  const auto result = testing::run_visproxy(base + "-o '" + out.string() + "' --equal samples --mode bounds --mode 'control variate learned'");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  std::istringstream csv(read_file(out / "table.csv"));
  std::string line;
  std::getline(csv, line);
  std::vector<std::vector<std::string>> rows;
  while (std::getline(csv, line)) {
    rows.emplace_back(1);
    for (const char c : line) {
      if (c == ',') rows.back().emplace_back();
      else rows.back().back().push_back(c);
    }
  }
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0][0], "\"exact\"");
  EXPECT_EQ(rows[1][0], "\"bounds\"");
  EXPECT_EQ(rows[2][0], "\"hull:32 control variate learned\"");
  // header: mode,proxy,seconds,samples_per_pixel,...,pass_time_over_exact(9),low,high,mse(12),efficiency,efficiency_over_exact
  for (const auto& row : rows) {
    ASSERT_EQ(row.size(), 15u) << line;
    EXPECT_EQ(row[3], rows[0][3]) << row[0];  // the same passes
    EXPECT_LE(std::stod(row[10]), std::stod(row[9])) << row[0];
    EXPECT_GE(std::stod(row[11]), std::stod(row[9])) << row[0];
  }
  EXPECT_EQ(rows[0][9], "1");
  EXPECT_EQ(rows[1][12], rows[0][12]);  // bounds: exact's image, so exact's MSE
  EXPECT_NE(read_file(out / "table.md").find("equal samples per round"), std::string::npos);
  const auto refused = testing::run_visproxy(base + "-o '" + (folder_ / "refused").string() + "' --mode 'eq9 optimal'");
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.err.find("eq9 optimal"), std::string::npos) << refused.err;
  EXPECT_EQ(std::count(refused.err.begin(), refused.err.end(), '\n'), 1) << refused.err;
  EXPECT_FALSE(std::filesystem::exists(folder_ / "refused" / "table.csv"));
}

// The reference's own noise adds to every mode's MSE against it; compare estimates it from
// the reference's two halves and subtracts it. The estimate is checked against a second,
// independent reference (their MSE is the sum of their noises), given back with its
// REF.noise.json it is used again, without one it is said to be unknown (a scene file
// beside a reference of the same name is not taken for it), and a REF.noise.json edited to
// a negative noise is refused in one line naming it.
TEST_F(CliRender, CompareSubtractsTheReferencesOwnNoise) {
  const auto generated = testing::run_visproxy("generate hairball --triangles 2400 -o '" + (folder_ / "hairball").string() + "'");
  ASSERT_EQ(generated.exit_code, 0) << generated.err;
  const std::string scene = (folder_ / "hairball" / "hairball.json").string();
  auto compare = [&](const std::string& out, const std::string& extra) {
    return testing::run_visproxy("compare '" + scene + "' -o '" + (folder_ / out).string() +
                                 "' --seconds 0.02 --convergence-points 1 --no-count --width 24 --height 18 --proxy hull:32 --cache '" +
                                 (folder_ / "cache").string() + "' " + extra);
  };
  for (const char* out : {"first", "second"}) {
    const auto result = compare(out, std::string("--reference-spp 32 --seed ") + (out[0] == 'f' ? "1" : "2"));
    ASSERT_EQ(result.exit_code, 0) << result.err;
    EXPECT_NE(read_file(folder_ / out / "table.md").find("is subtracted from every MSE"), std::string::npos);
  }
  auto noise = [&](const char* out) {
    return nlohmann::json::parse(read_file(folder_ / out / "reference.noise.json")).at("noise_per_pixel").get<double>();
  };
  const double first = noise("first"), second = noise("second");
  EXPECT_GT(first, 0);
  const double between = mean_squared_error(read_linear_image(folder_ / "first" / "reference.pfm"),
                                            read_linear_image(folder_ / "second" / "reference.pfm"));
  EXPECT_NEAR(between / (first + second), 1.0, 0.3) << between << " against " << first << " + " << second;
  // Given back with its REF.json, and without.
  std::filesystem::copy_file(folder_ / "first" / "reference.pfm", folder_ / "bare.pfm");
  const auto with_noise = compare("again", "--reference '" + (folder_ / "first" / "reference.pfm").string() + "'");
  ASSERT_EQ(with_noise.exit_code, 0) << with_noise.err;
  EXPECT_NE(read_file(folder_ / "again" / "table.md").find("is subtracted from every MSE"), std::string::npos);
  std::ofstream(folder_ / "bare.json") << "{\"format\": \"visproxy-scene\"}";  // not the reference's noise
  const auto bare = compare("bare", "--reference '" + (folder_ / "bare.pfm").string() + "'");
  ASSERT_EQ(bare.exit_code, 0) << bare.err;
  EXPECT_NE(read_file(folder_ / "bare" / "table.md").find("is not known"), std::string::npos);
  std::ofstream(folder_ / "bare.noise.json") << "{\"noise_per_pixel\": -1}";
  const auto edited = compare("edited", "--reference '" + (folder_ / "bare.pfm").string() + "'");
  EXPECT_EQ(edited.exit_code, 2);
  EXPECT_EQ(edited.err.find('\n'), edited.err.size() - 1) << edited.err;
  EXPECT_NE(edited.err.find("bare.noise.json"), std::string::npos) << edited.err;
  EXPECT_FALSE(std::filesystem::exists(folder_ / "edited" / "table.md"));
}

TEST_F(CliRender, BadScenesGetOneLineNamingTheFile) {
  struct Case {
    std::string text, fragment;
  };
  const std::vector<Case> cases = {
      {"{", "not valid JSON"},
      {"{\"format\": \"visproxy-scene\", \"format_version\": 1}", "missing \"meshes\""},
      {"{\"format\": \"visproxy-scene\", \"format_version\": 1, \"meshes\": {\"m\": {\"file\": \"nowhere.off\"}}}", "nowhere.off"},
  };
  for (const Case& c : cases) {
    std::ofstream(folder_ / "bad.json") << c.text;
    const auto result = render(folder_ / "bad.json", "bad", "");
    EXPECT_EQ(result.exit_code, 2);
    EXPECT_EQ(result.err.find('\n'), result.err.size() - 1) << result.err;
    EXPECT_NE(result.err.find(c.fragment), std::string::npos) << result.err;
    EXPECT_FALSE(std::filesystem::exists(folder_ / "bad.pfm"));
  }
}

}  // namespace
}  // namespace visproxy
