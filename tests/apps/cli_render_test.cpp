// `visproxy render` and `generate` as a user runs them: the shipped Cornell box and a
// generated hairball render, `bounds` gives the bit-identical image of `exact`, no mode
// (including adaptive probabilities with a zero floor) produces NaN or infinity, and bad
// scenes get one line naming the file.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "apps/cli_test_support.h"
#include "core/files.h"
#include "render/image.h"
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
};

std::filesystem::path cornell() { return std::filesystem::path(VISPROXY_SOURCE_DIR) / "data/scenes/cornell.json"; }

void expect_bounds_identical_and_finite(CliRender& test, const std::filesystem::path& scene, const std::string& size) {
  for (const char* mode : {"exact", "bounds", "stochastic"}) {
    const auto result = test.render(scene, mode, std::string("--visibility ") + mode + " --spp 3 --shadow-rays 2 --seed 9 " + size);
    ASSERT_EQ(result.exit_code, 0) << mode << ": " << result.err;
  }
  const auto adaptive = test.render(scene, "adaptive",
                                    "--visibility stochastic --probabilities adaptive --cost-heuristic --probability-floor 0 "
                                    "--probe-rays 4 --spp 2 --maps " + size);
  ASSERT_EQ(adaptive.exit_code, 0) << adaptive.err;
  const Image exact = test.image("exact");
  EXPECT_EQ(exact.pixels, test.image("bounds").pixels);  // bit-identical
  double brightest = 0;
  for (const Color& c : exact.pixels) brightest = std::max(brightest, c.maxCoeff());
  EXPECT_GT(brightest, 0.0);
  for (const char* name : {"exact", "stochastic", "adaptive"}) EXPECT_TRUE(all_finite(test.image(name))) << name;
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

TEST_F(CliRender, GeneratedHairballBoundsMatchesExact) {
  const auto generated = testing::run_visproxy("generate hairball --triangles 20000 -o '" + (folder_ / "hairball").string() + "'");
  ASSERT_EQ(generated.exit_code, 0) << generated.err;
  EXPECT_TRUE(std::filesystem::exists(folder_ / "hairball" / "proxies" / "manifest.json"));
  expect_bounds_identical_and_finite(*this, folder_ / "hairball" / "hairball.json", "--width 40 --height 30");
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
