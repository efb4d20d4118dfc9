#include "visproxy/evaluate/batch.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <set>
#include <string>
#include <unistd.h>

#include "visproxy/core/errors.h"
#include "visproxy/core/files.h"
#include "visproxy/mesh/write_mesh.h"
#include "schema_support.h"
#include "test_meshes.h"

namespace visproxy {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

class Batch : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("visproxy-batch-test-" + std::to_string(::getpid()) + "-" +
                                         ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    fs::create_directories(root_ / "assets");
    write_mesh(root_ / "assets" / "cube.obj", testing::unit_cube());
    write_mesh(root_ / "assets" / "tetra.ply", testing::tetrahedron());
    write_file_atomically(root_ / "assets" / "broken.obj", "v 0 0 0\nv 1 0 0\nf 1 2 7\n");
  }
  void TearDown() override { fs::remove_all(root_); }
  fs::path root_;
  // Cheap proxies and few rays: the pipeline, not the figures, is under test.
  BatchOptions options_{.proxies = {"aabb", "hull"}, .seed = 3, .rays = 4000, .timed_rays = 500, .hausdorff_samples = 500,
                        .gssa_lines = 1000};
};

TEST_F(Batch, ListFileSkipsCommentsAndResolvesRelativePaths) {
  write_file_atomically(root_ / "assets" / "list.txt", "# my assets\n\ncube.obj\n  tetra.ply  \n/abs/path.off\n");
  const std::vector<fs::path> assets = read_asset_list(root_ / "assets" / "list.txt");
  ASSERT_EQ(assets.size(), 3u);
  EXPECT_EQ(assets[0], root_ / "assets" / "cube.obj");
  EXPECT_EQ(assets[1], root_ / "assets" / "tetra.ply");
  EXPECT_EQ(assets[2], fs::path("/abs/path.off"));
}

TEST_F(Batch, FolderListsMeshFilesRecursivelySorted) {
  fs::create_directories(root_ / "assets" / "sub");
  write_file_atomically(root_ / "assets" / "sub" / "a.STL", "solid a\nendsolid a\n");  // listed by its extension, read later
  write_file_atomically(root_ / "assets" / "notes.txt", "not a mesh");
  const std::vector<fs::path> assets = read_asset_list(root_ / "assets");
  const std::vector<fs::path> expected{root_ / "assets" / "broken.obj", root_ / "assets" / "cube.obj",
                                       root_ / "assets" / "sub" / "a.STL", root_ / "assets" / "tetra.ply"};
  EXPECT_EQ(assets, expected);
}

TEST_F(Batch, EmptyOrMissingListsAreRefusedNamingThem) {
  write_file_atomically(root_ / "empty.txt", "# nothing\n\n");
  try {
    read_asset_list(root_ / "empty.txt");
    FAIL() << "accepted an empty list";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("empty.txt"), std::string::npos) << e.what();
  }
  EXPECT_THROW(read_asset_list(root_ / "missing.txt"), IOError);
  fs::create_directories(root_ / "no-meshes");
  EXPECT_THROW(read_asset_list(root_ / "no-meshes"), InvalidInputError);
}

TEST_F(Batch, ShardsPartitionTheListForEveryCount) {
  std::vector<fs::path> assets;
  for (int i = 0; i < 11; ++i) assets.push_back("asset" + std::to_string(i) + ".obj");
  for (std::size_t count = 1; count <= 5; ++count) {
    std::multiset<fs::path> seen;
    for (std::size_t index = 0; index < count; ++index) {
      const auto shard = shard_assets(assets, index, count);
      EXPECT_EQ(shard, shard_assets(assets, index, count));  // deterministic
      seen.insert(shard.begin(), shard.end());
    }
    EXPECT_EQ(seen, std::multiset<fs::path>(assets.begin(), assets.end())) << count << " shards";
  }
  EXPECT_EQ(parse_shard("0/1"), std::make_pair(std::size_t{0}, std::size_t{1}));
  EXPECT_EQ(parse_shard("3/4"), std::make_pair(std::size_t{3}, std::size_t{4}));
  for (const char* bad : {"4/4", "1", "-1/2", "1/0", "a/2", "1/2/3", "", "1/ 2", "99999999999/99999999999"})
    EXPECT_THROW(parse_shard(bad), InvalidInputError) << bad;
  EXPECT_THROW(shard_assets(assets, 2, 2), InvalidInputError);
}

TEST_F(Batch, KeyFollowsTheBytesTheOptionsAndNotThePathAlone) {
  const fs::path cube = root_ / "assets" / "cube.obj";
  const std::string name = asset_folder_name(cube, options_);
  EXPECT_EQ(name.rfind("cube-", 0), 0u) << name;
  EXPECT_EQ(name.size(), 5u + 16u);
  EXPECT_EQ(name, asset_folder_name(cube, options_));
  BatchOptions other = options_;
  other.seed = 4;
  EXPECT_NE(name, asset_folder_name(cube, other));
  // The same bytes under another path and name: the same key, its own stem.
  fs::copy_file(cube, root_ / "assets" / "copy.obj");
  EXPECT_EQ(asset_folder_name(root_ / "assets" / "copy.obj", options_).substr(5), name.substr(5));
  // One byte changed: a new key.
  write_file_atomically(cube, read_file(cube) + "\n");
  EXPECT_NE(name, asset_folder_name(cube, options_));
}

TEST_F(Batch, AnAssetIsBuiltVerifiedMeasuredAndThenResumed) {
  const fs::path out = root_ / "out";
  const json record = process_asset(root_ / "assets" / "cube.obj", out, options_);
  EXPECT_EQ(record["status"], "ok") << record.dump();
  EXPECT_FALSE(record["resumed"].get<bool>());
  EXPECT_EQ(record["proxies"], 2);
  EXPECT_EQ(record["claims_holding"], 2);
  EXPECT_EQ(record["triangles"], 12);
  const fs::path folder = out / record["folder"].get<std::string>();
  for (const char* file : {"manifest.json", "report.html", "recommendation.json", "pictures/aabb-overlay.png",
                           "pictures/hull-difference.png", "asset.json", "aabb.ply", "hull.ply"})
    EXPECT_TRUE(fs::exists(folder / file)) << file;
  const json manifest = json::parse(read_file(folder / "manifest.json"));
  for (const json& entry : manifest["proxies"]) {
    EXPECT_TRUE(entry["verify"]["holds"].get<bool>());
    EXPECT_EQ(entry["measure"]["rays"]["count"], 4000);
  }
  // Nothing left half-written.
  EXPECT_TRUE(fs::is_empty(out / ".partial"));
  // Again: not processed, the same record.
  const auto written = fs::last_write_time(folder / "manifest.json");
  const json again = process_asset(root_ / "assets" / "cube.obj", out, options_);
  EXPECT_TRUE(again["resumed"].get<bool>());
  EXPECT_EQ(again["folder"], record["folder"]);
  EXPECT_EQ(fs::last_write_time(folder / "manifest.json"), written);
}

TEST_F(Batch, AMalformedAssetIsRecordedWithItsErrorAndNotRetriedUnlessAsked) {
  const fs::path out = root_ / "out";
  const fs::path broken = root_ / "assets" / "broken.obj";
  const json record = process_asset(broken, out, options_);
  EXPECT_EQ(record["status"], "failed");
  const std::string error = record["error"].get<std::string>();
  EXPECT_NE(error.find("broken.obj"), std::string::npos) << error;
  EXPECT_EQ(error.find('\n'), std::string::npos) << error;
  EXPECT_TRUE(record["folder"].is_null());
  const std::string name = asset_folder_name(broken, options_);
  EXPECT_TRUE(fs::exists(out / (name + ".failed.json")));
  EXPECT_FALSE(fs::exists(out / name));
  EXPECT_TRUE(fs::is_empty(out / ".partial"));
  EXPECT_TRUE(process_asset(broken, out, options_)["resumed"].get<bool>());
  const json retried = process_asset(broken, out, options_, true);
  EXPECT_FALSE(retried["resumed"].get<bool>());
  EXPECT_EQ(retried["status"], "failed");
  // A missing file fails the same way, naming it.
  const json missing = process_asset(root_ / "assets" / "gone.obj", out, options_);
  EXPECT_EQ(missing["status"], "failed");
  EXPECT_NE(missing["error"].get<std::string>().find("gone.obj"), std::string::npos);
}

TEST_F(Batch, AKilledRunsLeftoversAreNeverTakenForAFinishedAsset) {
  const fs::path out = root_ / "out";
  const fs::path cube = root_ / "assets" / "cube.obj";
  const std::string name = asset_folder_name(cube, options_);
  // A killed worker's partial folder, and a folder in place whose record was cut short or
  // edited by hand: neither is a finished asset.
  fs::create_directories(out / ".partial" / (name + ".12345"));
  write_file_atomically(out / ".partial" / (name + ".12345") / "manifest.json", "{");
  fs::create_directories(out / name);
  write_file_atomically(out / name / "asset.json", "{\"format\": \"visproxy-batch-asset\", \"stat");
  EXPECT_TRUE(find_asset_record(out, name).is_null());
  const json record = process_asset(cube, out, options_);
  EXPECT_EQ(record["status"], "ok") << record.dump();
  EXPECT_FALSE(record["resumed"].get<bool>());
  EXPECT_EQ(find_asset_record(out, name)["status"], "ok");
  EXPECT_TRUE(fs::exists(out / name / "manifest.json"));
}

TEST_F(Batch, MergeSummarisesEveryRecordSortedWithFailuresListed) {
  const fs::path out = root_ / "out";
  for (const char* asset : {"tetra.ply", "broken.obj", "cube.obj"}) process_asset(root_ / "assets" / asset, out, options_);
  const json summary = batch_merge(out);
  EXPECT_EQ(summary["assets"], 3);
  EXPECT_EQ(summary["ok"], 2);
  EXPECT_EQ(summary["failed"], 1);
  EXPECT_EQ(summary["proxies"], 4);
  ASSERT_EQ(summary["rows"].size(), 4u);
  std::vector<std::string> order;
  for (const json& row : summary["rows"]) order.push_back(row["asset"].get<std::string>() + " " + row["proxy"].get<std::string>());
  EXPECT_TRUE(std::is_sorted(order.begin(), order.end()));
  for (const json& row : summary["rows"]) {
    EXPECT_TRUE(row["holds"].get<bool>());
    EXPECT_GT(row["f_hit"].get<double>(), 0.5);  // box and hull of a convex solid block what it blocks
    // Each asset's report predicted every use of its proved outside proxies.
    for (const char* use : {"efficiency_control_variate", "efficiency_eq8", "efficiency_bounds"})
      EXPECT_GT(row[use].get<double>(), 0.0) << use;
  }
  // A damaged recommendation.json leaves its asset's efficiencies out, nothing else.
  const std::string first = summary["rows"][0]["folder"].get<std::string>();
  write_file_atomically(out / first / "recommendation.json", "{\"proxies\": [");
  const json damaged = batch_merge(out);
  for (const json& row : damaged["rows"])
    EXPECT_EQ(row["efficiency_bounds"].is_null(), row["folder"] == first) << row["proxy"];
  const std::string csv = read_file(out / "summary.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 4 + 1);
  EXPECT_NE(csv.find(",failed,"), std::string::npos);
  const std::string html = read_file(out / "summary.html");
  EXPECT_NE(html.find("/report.html\">"), std::string::npos);
  EXPECT_NE(html.find("broken.obj"), std::string::npos);
  EXPECT_NE(html.find("Failed assets"), std::string::npos);
  // Merging again gives the same summary.
  EXPECT_EQ(batch_merge(out), damaged);
  // The files as their schemas describe them.
  const json summary_schema = testing::read_schema("batch-summary.schema.json");
  testing::expect_described(json::parse(read_file(out / "summary.json")), summary_schema, summary_schema, "summary.json");
  const json record_schema = testing::read_schema("batch-asset.schema.json");
  for (const json& record : summary["records"]) testing::expect_described(record, record_schema, record_schema, "record");
}

}  // namespace
}  // namespace visproxy
