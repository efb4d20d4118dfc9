#include "visproxy/proxy/merge_spheres.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/core/random.h"

namespace visproxy {
namespace {

std::vector<Sphere> random_spheres(std::size_t count, std::uint64_t seed) {
  Random random(seed);
  std::vector<Sphere> spheres;
  for (std::size_t i = 0; i < count; ++i)
    spheres.push_back({Vertex(random.uniform(), random.uniform(), random.uniform()) * 10.0,
                       0.05 + random.uniform() * random.uniform() * 2.0});
  return spheres;
}

std::vector<Sphere> sorted(std::vector<Sphere> spheres) {
  const auto key = [](const Sphere& s) { return std::tuple(s.center.x(), s.center.y(), s.center.z(), s.radius); };
  std::sort(spheres.begin(), spheres.end(), [&](const Sphere& a, const Sphere& b) { return key(a) < key(b); });
  return spheres;
}

// The same greedy done the slow way: every step scans all pairs for the smallest distance
// and merges it into the slot of the larger sphere, as merge_spheres does.
std::vector<Sphere> merge_by_scanning(std::vector<Sphere> spheres, std::size_t target, PairDistance measure) {
  std::vector<bool> alive(spheres.size(), true);
  std::size_t live = spheres.size();
  auto distance = [&](const Sphere& a, const Sphere& b) {
    const double d = (a.center - b.center).norm();
    return measure == PairDistance::d1 ? d : d - std::abs(a.radius - b.radius);
  };
  while (live > target) {
    double best = std::numeric_limits<double>::infinity();
    std::size_t best_a = 0, best_b = 0;
    for (std::size_t a = 0; a < spheres.size(); ++a)
      for (std::size_t b = a + 1; b < spheres.size(); ++b)
        if (alive[a] && alive[b] && distance(spheres[a], spheres[b]) < best) {
          best = distance(spheres[a], spheres[b]);
          best_a = a;
          best_b = b;
        }
    const Sphere merged = merge_two_spheres(spheres[best_a], spheres[best_b]);
    const bool keep_a = spheres[best_a].radius >= spheres[best_b].radius;
    spheres[keep_a ? best_a : best_b] = merged;
    alive[keep_a ? best_b : best_a] = false;
    --live;
  }
  std::vector<Sphere> result;
  for (std::size_t i = 0; i < spheres.size(); ++i)
    if (alive[i]) result.push_back(spheres[i]);
  return result;
}

class MergeSpheresAgainstScan : public ::testing::TestWithParam<PairDistance> {};

TEST_P(MergeSpheresAgainstScan, SameSetsAsMergingTheClosestPairByScanning) {
  const std::vector<Sphere> spheres = random_spheres(120, 3);
  const std::vector<std::size_t> targets = {60, 17, 1};
  const auto levels = merge_spheres(spheres, targets, {.pair_distance = GetParam()});
  ASSERT_EQ(levels.size(), 3u);
  for (std::size_t k = 0; k < targets.size(); ++k) {
    SCOPED_TRACE(targets[k]);
    ASSERT_EQ(levels[k].size(), targets[k]);
    EXPECT_EQ(sorted(levels[k]), sorted(merge_by_scanning(spheres, targets[k], GetParam())));
  }
}

INSTANTIATE_TEST_SUITE_P(PairDistances, MergeSpheresAgainstScan, ::testing::Values(PairDistance::d1, PairDistance::d2),
                         [](const auto& test) { return std::string(pair_distance_name(test.param)); });

TEST(MergeSpheres, ExactCountsAnyTargetOrderAndDeterministic) {
  const std::vector<Sphere> spheres = random_spheres(3000, 9);
  const std::vector<std::size_t> targets = {10, 1000, 250, 2999, 3000, 10};
  const auto levels = merge_spheres(spheres, targets);
  for (std::size_t k = 0; k < targets.size(); ++k) EXPECT_EQ(levels[k].size(), targets[k]);
  EXPECT_EQ(levels[0], levels[5]);
  EXPECT_EQ(sorted(levels[4]), sorted(spheres));
  EXPECT_EQ(merge_spheres(spheres, targets), levels);
  for (const auto& level : levels)
    for (const Sphere& s : level) {
      EXPECT_TRUE(s.center.allFinite());
      EXPECT_GT(s.radius, 0);
    }
}

TEST(MergeSpheres, HeldSpheresVanishFirstUnderD2) {
  // Small balls inside a large one are absorbed without changing it (D2 < 0 comes first);
  // a far ball stays.
  std::vector<Sphere> spheres = {{{0, 0, 0}, 5}, {{1, 0, 0}, 1}, {{0, 2, 0}, 0.5}, {{-2, -1, 0}, 2}, {{100, 0, 0}, 1}};
  const auto levels = merge_spheres(spheres, std::vector<std::size_t>{2});
  EXPECT_EQ(sorted(levels[0]), sorted({spheres[0], spheres[4]}));
}

// One huge ball holding 10 000 small ones: each is absorbed without changing it, so no
// merge may send the others searching again (that made the merging quadratic: 5e7 queue
// entries here). The searches and queue operations must stay linear in the spheres.
TEST(MergeSpheres, OneHugeSphereAmongManySmallOnesStaysLinear) {
  constexpr std::size_t small = 10000;
  Random random(17);
  std::vector<Sphere> spheres = {{{0, 0, 0}, 1000}};
  for (std::size_t i = 0; i < small; ++i)
    spheres.push_back({Vertex(random.uniform() - 0.5, random.uniform() - 0.5, random.uniform() - 0.5) * 100.0,
                       0.01 + 0.1 * random.uniform()});
  MergeSpheresStatistics statistics;
  const auto levels = merge_spheres(spheres, std::vector<std::size_t>{1000, 1}, {}, &statistics);
  EXPECT_EQ(levels[1], std::vector<Sphere>{spheres[0]});  // the huge one, unchanged
  EXPECT_EQ(levels[0].size(), 1000u);
  EXPECT_LE(statistics.queue_entries, 3 * spheres.size()) << statistics.queue_entries;
  EXPECT_LE(statistics.queue_pops, 3 * spheres.size());
  EXPECT_LE(statistics.partner_searches, 3 * spheres.size());
  EXPECT_GE(statistics.partner_searches, spheres.size());  // the first search of every sphere
  // The same holds under D1, where small pairs merge among themselves first.
  MergeSpheresStatistics d1;
  merge_spheres(spheres, std::vector<std::size_t>{1}, {.pair_distance = PairDistance::d1}, &d1);
  EXPECT_LE(d1.queue_entries, 6 * spheres.size()) << d1.queue_entries;
  EXPECT_LE(d1.partner_searches, 4 * spheres.size()) << d1.partner_searches;
}

TEST(MergeSpheres, BadTargetsAndSpheresAreRejected) {
  const std::vector<Sphere> spheres = random_spheres(10, 1);
  EXPECT_THROW(merge_spheres(spheres, std::vector<std::size_t>{0}), InvalidInputError);
  EXPECT_THROW(merge_spheres(spheres, std::vector<std::size_t>{11}), InvalidInputError);
  std::vector<Sphere> bad = spheres;
  bad[3].radius = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(merge_spheres(bad, std::vector<std::size_t>{5}), InvalidInputError);
  EXPECT_EQ(merge_spheres(spheres, std::vector<std::size_t>{}).size(), 0u);
  const std::vector<Sphere> one = {{{1, 2, 3}, 4}};
  EXPECT_EQ(merge_spheres(one, std::vector<std::size_t>{1})[0], one);
}

}  // namespace
}  // namespace visproxy
