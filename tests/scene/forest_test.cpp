// The procedural forest: trees of about the asked size, seeded, standing on the terrain they
// are placed on, and a scene file the reader takes that matches its schema.

#include "visproxy/scene/forest.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <nlohmann/json.hpp>

#include "schema_support.h"
#include "test_support.h"
#include "visproxy/core/files.h"
#include "visproxy/mesh/write_mesh.h"
#include "visproxy/scene/scene.h"

namespace visproxy {
namespace {

constexpr ForestOptions kSmall{.trees = 60, .species = 3, .seed = 4, .fewest_triangles = 3000, .most_triangles = 12000,
                               .spacing = 1.2, .terrain_cells = 24};

TEST(Tree, HasAboutTheTrianglesAskedAndStandsOnTheOrigin) {
  for (const std::size_t triangles : {std::size_t{5000}, std::size_t{60000}}) {
    for (const bool needles : {false, true}) {
      const TriangleMesh tree = make_tree({.seed = 3, .triangles = triangles, .needles = needles});
      EXPECT_NEAR(static_cast<double>(tree.triangles.size()), static_cast<double>(triangles), 0.02 * static_cast<double>(triangles));
      const BoundingBox box = bounding_box(tree);
      EXPECT_TRUE(box.min.allFinite() && box.max.allFinite());
      for (int k = 0; k < 6; ++k) EXPECT_EQ(tree.positions[static_cast<std::size_t>(k)].y(), 0.0);  // the trunk's base ring
      EXPECT_GT(box.min.y(), -0.15);            // low twigs may droop a little
      EXPECT_GT(box.max.y(), 0.7);              // about a unit tall
      EXPECT_LT(box.max.y(), 1.8);
      EXPECT_LT(std::max(-box.min.x(), box.max.x()), 1.2);  // a crown, not a line
      EXPECT_GT(box.max.x() - box.min.x(), 0.3);
    }
  }
  EXPECT_EQ(make_tree({.seed = 3, .triangles = 5000}).positions, make_tree({.seed = 3, .triangles = 5000}).positions);
  EXPECT_NE(make_tree({.seed = 3, .triangles = 5000}).positions, make_tree({.seed = 4, .triangles = 5000}).positions);
}

// The ground height of the terrain under (x, z), from its triangles: a vertical line.
double terrain_height(const TriangleMesh& terrain, double x, double z) {
  for (const Triangle& t : terrain.triangles) {
    const Vertex &a = terrain.positions[t[0]], &b = terrain.positions[t[1]], &c = terrain.positions[t[2]];
    const double d = (b.x() - a.x()) * (c.z() - a.z()) - (c.x() - a.x()) * (b.z() - a.z());
    const double u = ((x - a.x()) * (c.z() - a.z()) - (c.x() - a.x()) * (z - a.z())) / d;
    const double v = ((b.x() - a.x()) * (z - a.z()) - (x - a.x()) * (b.z() - a.z())) / d;
    if (u >= -1e-12 && v >= -1e-12 && u + v <= 1 + 1e-12) return a.y() + u * (b.y() - a.y()) + v * (c.y() - a.y());
  }
  return std::nan("");
}

TEST(Forest, TreesStandOnTheTerrainWithinItsExtent) {
  const Forest forest = make_forest(kSmall);
  ASSERT_EQ(forest.species.size(), 3u);
  EXPECT_LT(forest.species[0].triangles.size(), forest.species[2].triangles.size());
  EXPECT_EQ(forest.trees.size(), 60u);
  const double half = 0.5 * forest.extent;
  std::size_t total = forest.terrain.triangles.size();
  for (const TreePlacement& tree : forest.trees) {
    ASSERT_LT(tree.species, 3u);
    const Vertex base = tree.transform * Vertex::Zero();
    EXPECT_LT(std::abs(base.x()), half);
    EXPECT_LT(std::abs(base.z()), half);
    // Sunk by a hundredth of its height below the ground it stands on.
    const double scale = tree.transform.linear().col(0).norm();
    EXPECT_GE(scale, 0.8);
    EXPECT_LE(scale, 1.25);
    EXPECT_NEAR(base.y(), terrain_height(forest.terrain, base.x(), base.z()) - 0.01 * scale, 1e-9);
    total += forest.species[tree.species].triangles.size();
  }
  EXPECT_EQ(forest.instanced_triangles(), total);
  // Seeded.
  const Forest again = make_forest(kSmall);
  EXPECT_EQ(again.terrain, forest.terrain);
  EXPECT_TRUE(again.trees.back().transform.isApprox(forest.trees.back().transform, 0));
}

class ForestScene : public testing::ScratchFolder {};

TEST_F(ForestScene, IsReadAndMatchesItsSchema) {
  const Forest forest = make_forest(kSmall);
  ForestFiles files;
  for (std::size_t k = 0; k < forest.species.size(); ++k) {
    files.species.push_back("tree-" + std::to_string(k) + ".ply");
    files.proxy_folders.push_back("");
    write_mesh(folder_ / files.species.back(), forest.species[k]);
  }
  files.terrain = "terrain.ply";
  write_mesh(folder_ / files.terrain, forest.terrain);
  const std::string text = forest_scene_json(forest, files, kForestProxies, 64, 36, 4);
  testing::expect_described(nlohmann::json::parse(text), "scene.schema.json");
  write_file_atomically(folder_ / "forest.json", text);
  const Scene scene = load_scene(folder_ / "forest.json");
  ASSERT_EQ(scene.instances.size(), 61u);
  EXPECT_EQ(scene.instances[0].mesh, "terrain");
  EXPECT_EQ(scene.instances[1].proxies, kForestProxies);
  EXPECT_TRUE(scene.instances[5].transform.isApprox(forest.trees[4].transform, 1e-15));
  ASSERT_EQ(scene.lights.size(), 1u);
  EXPECT_GT(scene.lights[0].triangles[0][0].y(), 0.5 * forest.extent);  // high above every tree
  EXPECT_EQ(scene.camera.width, 64);
}

}  // namespace
}  // namespace visproxy
