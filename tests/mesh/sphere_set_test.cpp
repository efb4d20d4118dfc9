#include "visproxy/mesh/sphere_set.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <tuple>
#include <numbers>

#include "visproxy/core/errors.h"
#include "visproxy/core/random.h"
#include "visproxy/core/files.h"
#include "visproxy/mesh/mesh_topology.h"
#include "test_support.h"

namespace visproxy {
namespace {

using SphereSetFile = testing::ScratchFolder;

TEST_F(SphereSetFile, RoundTripsEveryDoubleExactly) {
  const std::vector<Sphere> spheres = {{{0.1, 1.0 / 3.0, -7.5e200}, 2.5e-300}, {{-1, 0, 1}, 0.0}, {{1e-7, 3, 4}, 1.0 / 7.0}};
  const auto path = folder_ / "spheres.json";
  write_sphere_set(path, spheres);
  EXPECT_EQ(read_sphere_set(path), spheres);
  write_sphere_set(path, {});
  EXPECT_TRUE(read_sphere_set(path).empty());
}

TEST_F(SphereSetFile, RejectsMalformedFilesNamingTheProblem) {
  const auto path = folder_ / "bad.json";
  const std::pair<const char*, const char*> cases[] = {
      {"{\"spheres\": [", ":1: not valid JSON"},
      {"[1, 2]", "bad.json: expected an object with a \"spheres\" array"},
      {"{\"spheres\": {}}", "bad.json: spheres: expected an array of spheres"},
      {"{\"spheres\": [{\"center\": [0, 0], \"radius\": 1}]}",
       "bad.json: spheres[0].center: expected an array of 3 numbers"},
      {"{\"spheres\": [{\"center\": [0, 0, 0], \"radius\": 1}, {\"center\": [0, 0, 0]}]}",
       "bad.json: spheres[1]: missing \"radius\""},
      {"{\"spheres\": [{\"center\": [0, 0, \"x\"], \"radius\": 1}]}",
       "bad.json: spheres[0].center: expected an array of 3 numbers"},
      {"{\"spheres\": [{\"center\": [0, 0, 0], \"radius\": \"1\"}]}", "bad.json: spheres[0].radius: expected a number"},
      {"{\"spheres\": [{\"center\": [0, 0, 0], \"radius\": -1}]}", "bad.json: spheres[0].radius: must not be negative"},
      {"{\"spheres\": [{\"center\": [0, 0, 0], \"radius\": 1e999}]}", "bad.json: not valid JSON"},  // overflows
      {"{\"spheres\": [7]}", "bad.json: spheres[0]: expected an object"},
  };
  for (const auto& [text, problem] : cases) {
    write_file_atomically(path, text);
    try {
      read_sphere_set(path);
      ADD_FAILURE() << "accepted " << text;
    } catch (const InvalidInputError& error) {
      EXPECT_NE(std::string(error.what()).find(problem), std::string::npos) << error.what();
      EXPECT_NE(std::string(error.what()).find("bad.json"), std::string::npos) << error.what();
    }
  }
}

TEST(SphereSetMesh, IsClosedOutwardAndOnTheSpheres) {
  const std::vector<Sphere> spheres = {{{1, 2, 3}, 0.5}, {{-4, 0, 0}, 2.0}};
  const TriangleMesh mesh = sphere_set_mesh(spheres, 2);
  ASSERT_EQ(mesh.triangles.size(), 2u * 20 * 16);
  const MeshTopology topology = analyze_topology(mesh);
  EXPECT_TRUE(topology.closed());
  EXPECT_EQ(topology.components, 2u);
  // Each half lies on its sphere and encloses a positive volume a little below the ball's.
  const std::size_t per_sphere = mesh.positions.size() / 2;
  for (std::size_t s = 0; s < 2; ++s) {
    double volume = 0;
    for (std::size_t t = s * 320; t < (s + 1) * 320; ++t) {
      const Triangle& tri = mesh.triangles[t];
      volume += mesh.positions[tri[0]].dot(mesh.positions[tri[1]].cross(mesh.positions[tri[2]])) / 6.0;
    }
    const double ball = 4.0 / 3.0 * std::numbers::pi * std::pow(spheres[s].radius, 3);
    EXPECT_GT(volume, 0.9 * ball);
    EXPECT_LT(volume, ball);
    for (std::size_t v = s * per_sphere; v < (s + 1) * per_sphere; ++v)
      EXPECT_NEAR((mesh.positions[v] - spheres[s].center).norm(), spheres[s].radius, 1e-12);
  }
}

TEST(SphereUnionBoundaryMesh, DropsTrianglesBuriedInOtherBalls) {
  const std::vector<Sphere> one = {{{0, 0, 0}, 1.0}};
  EXPECT_EQ(sphere_union_boundary_mesh(one, 2), sphere_set_mesh(one, 2));
  // Two overlapping balls and a small one wholly inside the first.
  const std::vector<Sphere> spheres = {{{0, 0, 0}, 1.0}, {{1.2, 0, 0}, 1.0}, {{-0.2, 0.1, 0}, 0.3}};
  const TriangleMesh all = sphere_set_mesh(spheres, 2), boundary = sphere_union_boundary_mesh(spheres, 2);
  EXPECT_LT(boundary.triangles.size(), all.triangles.size());
  std::size_t from_small = 0;
  for (const Triangle& t : boundary.triangles) {
    from_small += t[0] >= 2 * all.positions.size() / 3 ? 1 : 0;
    // No kept triangle has all three corners strictly inside another ball.
    bool all_buried = true;
    for (VertexIndex v : t) {
      const std::size_t own = v / (all.positions.size() / 3);
      bool buried = false;
      for (std::size_t other = 0; other < 3; ++other)
        buried = buried || (other != own && (all.positions[v] - spheres[other].center).norm() < spheres[other].radius * (1 - 1e-9));
      all_buried = all_buried && buried;
    }
    EXPECT_FALSE(all_buried);
  }
  EXPECT_EQ(from_small, 0u);  // the buried ball leaves nothing
  // Each big ball keeps the part of its surface outside the other: most of it.
  EXPECT_GT(boundary.triangles.size(), all.triangles.size() / 2);
}

// Clusters partition the set into runs of at most `leaf`, each bound holds its balls (also
// far from the origin, with equal balls and with balls of radius 0), heads cover the runs of
// the clusters they head, and the order is the same on every call.
TEST(ClusterSpheres, PartitionsTheSetAndBoundsHoldTheirBalls) {
  Random random(77);
  for (int trial = 0; trial < 200; ++trial) {
    const double far = trial % 2 == 0 ? 1e7 : 0;
    std::vector<Sphere> balls;
    const int count = static_cast<int>(random.below(300));
    for (int b = 0; b < count; ++b) {
      const Vertex c = Vertex::Constant(far) + Vertex(random.uniform(), random.uniform(), random.uniform()) * 10;
      balls.push_back({trial % 5 == 0 ? Vertex::Constant(far) : c, trial % 7 == 0 ? 0.0 : random.uniform()});
    }
    const std::size_t leaf = 1 + random.below(40), group = trial % 3 == 0 ? 0 : 2 + random.below(5);
    std::vector<Sphere> ordered = balls, again = balls;
    const std::vector<SphereCluster> clusters = cluster_spheres(ordered, leaf, group);
    EXPECT_EQ(cluster_spheres(again, leaf, group).size(), clusters.size());
    EXPECT_EQ(again, ordered);
    std::uint32_t next = 0;
    std::size_t heads = 0;
    for (std::size_t c = 0; c < clusters.size(); ++c) {
      const SphereCluster& cluster = clusters[c];
      if (cluster.children > 0) {
        // A head: followed by its clusters, whose runs make up its own.
        ++heads;
        ASSERT_LE(c + cluster.children, clusters.size() - 1);
        EXPECT_LE(cluster.children, group);
        EXPECT_EQ(cluster.begin, clusters[c + 1].begin);
        EXPECT_EQ(cluster.end, clusters[c + cluster.children].end);
        for (std::size_t k = 1; k <= cluster.children; ++k) EXPECT_EQ(clusters[c + k].children, 0u);
      } else {
        EXPECT_EQ(cluster.begin, next);
        EXPECT_GT(cluster.end, cluster.begin);
        EXPECT_LE(cluster.end - cluster.begin, leaf);
        next = cluster.end;
      }
      for (std::uint32_t i = cluster.begin; i < cluster.end; ++i) {
        // Checked in long double, finer than the double the bound was computed in.
        const auto d = [](double a, double b) { return static_cast<long double>(a) - static_cast<long double>(b); };
        const Vertex& centre = ordered[i].center;
        const long double dx = d(centre.x(), cluster.bound.center.x()), dy = d(centre.y(), cluster.bound.center.y()),
                          dz = d(centre.z(), cluster.bound.center.z());
        EXPECT_LE(std::sqrt(dx * dx + dy * dy + dz * dz) + ordered[i].radius, static_cast<long double>(cluster.bound.radius));
      }
    }
    EXPECT_EQ(next, ordered.size());
    if (group < 2) {
      EXPECT_EQ(heads, 0u);
    } else if (!ordered.empty()) {
      EXPECT_GT(heads, 0u);
    }
    // The same balls, reordered.
    auto less = [](const Sphere& a, const Sphere& b) {
      return std::tie(a.center.x(), a.center.y(), a.center.z(), a.radius) < std::tie(b.center.x(), b.center.y(), b.center.z(), b.radius);
    };
    std::sort(balls.begin(), balls.end(), less), std::sort(ordered.begin(), ordered.end(), less);
    EXPECT_EQ(balls, ordered);
  }
}

}  // namespace
}  // namespace visproxy
