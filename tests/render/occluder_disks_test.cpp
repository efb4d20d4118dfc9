// The occluder-disk test agrees with a brute-force evaluation of its definition (cos delta
// > cos gamma and t < z) on random configurations, its vectorised and scalar loops agree,
// and its disagreement with exact ball intersection is measured.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <cstdio>

#include "visproxy/core/random.h"
#include "visproxy/mesh/sphere_set.h"
#include "visproxy/render/visibility/occluder_disks.h"
#include "visproxy/trace/embree_support.h"

namespace visproxy {
namespace {

Vertex random_unit(Random& random) {
  for (;;) {
    const Vertex v(2 * random.uniform() - 1, 2 * random.uniform() - 1, 2 * random.uniform() - 1);
    if (v.squaredNorm() > 1e-6 && v.squaredNorm() <= 1) return v.normalized();
  }
}

// The single-precision disk test errs by at most OccluderDisks::kDiskTestError (in units of
// |w|, cos delta against cos gamma), the bound that the clusters' widened cones rest on:
// 3000 balls from 1e-5 to nearly 1 of their distance wide (the point close to the surface),
// at 0.01 to 3000 units, half of them 1e5 units from the origin, and segments whose exact
// cos delta lies within 2 kDiskTestError of cos gamma on either side. No answer lies beyond
// the bound, and the test does err (some hidden segments lie outside the exact cone), so
// the bound is what keeps the clusters' answers those of every disk.
TEST(OccluderDisks, TheSinglePrecisionTestErrsWithinItsBound) {
  Random random(4242);
  constexpr double e = OccluderDisks::kDiskTestError;
  std::uint64_t segments = 0, outside_hidden = 0, beyond = 0, tests = 0;
  double largest = 0;  // the largest error seen, over e
  for (int p = 0; p < 3000; ++p) {
    const Vertex x = (p % 2 == 0 ? Vertex(1e5, -7e4, 3e4) : Vertex::Zero()) + Vertex(random.uniform(), random.uniform(), random.uniform());
    const Vertex axis = random_unit(random);
    const double t = 0.01 * std::pow(10.0, 5.5 * random.uniform());
    const double share = p % 5 == 0 ? 1 - std::pow(10.0, -4 * random.uniform()) : std::pow(10.0, -5 * random.uniform());
    const Sphere ball{x + t * axis, share * t};
    Vertex n = random_unit(random);
    if (n.dot(axis) < 0) n = -n;
    OccluderDisks disks;
    disks.reset(x, n);
    disks.add({ball}, false);
    disks.finish();
    const Vertex v = ball.center - x;
    const double t_exact = v.norm(), cos_gamma = std::sqrt((t_exact - ball.radius) * (t_exact + ball.radius)) / t_exact;
    const Vertex u = v / t_exact;
    for (int k = 0; k < 64; ++k) {
      const double excess = 2 * e * (2 * random.uniform() - 1) * std::pow(10.0, -2 * random.uniform());
      const double cos_delta = std::clamp(cos_gamma - excess, -1.0, 1.0);
      Vertex side = random_unit(random);
      side = (side - side.dot(u) * u).normalized();
      const double sin_delta = std::sqrt(std::max(0.0, 1 - cos_delta * cos_delta));
      const Vertex end = x + t_exact * (1.5 + random.uniform()) * (cos_delta * u + sin_delta * side);
      const Vertex w = end - x;
      const double error = cos_gamma - v.dot(w) / (t_exact * w.norm());  // > 0: outside the exact cone
      const bool hidden = disks.occludes(end, tests);
      ++segments;
      if (hidden && error > 0) ++outside_hidden, largest = std::max(largest, error / e);
      if (!hidden && error < 0) largest = std::max(largest, -error / e);
      if ((hidden && error > e) || (!hidden && error < -e)) ++beyond;
    }
  }
  std::printf("single-precision disk test: %llu segments, %llu hidden outside the exact cone, largest error %.3f of the bound\n",
              static_cast<unsigned long long>(segments), static_cast<unsigned long long>(outside_hidden), largest);
  EXPECT_EQ(beyond, 0u);
  EXPECT_GT(outside_hidden, 0u);
  EXPECT_GT(largest, 0.01);
}

// The group form of occludes() of each of `disks` gives `answers` for `ends`.
void expect_group_answers(std::initializer_list<const OccluderDisks*> disks, const std::vector<Vertex>& ends,
                          const std::vector<std::uint8_t>& answers, int point) {
  for (const OccluderDisks* d : disks) {
    std::vector<std::uint8_t> grouped(ends.size());
    std::uint64_t tests = 0;
    d->occludes(ends, grouped, tests);
    EXPECT_EQ(grouped, answers) << "point " << point;
  }
}

// 2000 shading points, each with 1 to 24 balls of radius 0.01 to 0.2 within 3 units and
// 64 segment ends in front of the tangent plane, some inside balls' cones and beyond them.
// The float test must give the double definition's answer except where the configuration
// lies within float rounding of a boundary (|cos delta - cos gamma| or |t - z| / z below
// 1e-5): no disagreement elsewhere, and those near-boundary cases are rare. The grid over
// the projected hemisphere gives the linear loop's answer every time.
TEST(OccluderDisks, AgreeWithTheDefinitionOnRandomConfigurations) {
  Random random(2024);
  std::uint64_t checks = 0, occluded = 0, near_boundary = 0, tests = 0;
  std::uint64_t disk_vs_ball = 0, ball_hits = 0;
  for (int p = 0; p < 2000; ++p) {
    const Vertex x(4 * random.uniform() - 2, 4 * random.uniform() - 2, 4 * random.uniform() - 2);
    const Vertex n = random_unit(random);
    std::vector<Sphere> balls;
    const int count = 1 + static_cast<int>(random.below(24));
    for (int b = 0; b < count; ++b) balls.push_back({x + 3 * random.uniform() * random_unit(random), 0.01 + 0.19 * random.uniform()});
    OccluderDisks disks, grid;
    disks.reset(x, n);
    disks.add(balls, false);
    disks.finish();
    grid.reset(x, n);
    grid.add(balls, false);
    grid.finish(true);
    std::vector<Vertex> ends;
    std::vector<std::uint8_t> answers;
    for (int e = 0; e < 64; ++e) {
      Vertex direction = random_unit(random);
      if (direction.dot(n) < 0) direction -= 2 * direction.dot(n) * n;
      // Half the ends aimed at a ball, so that occluded answers are common.
      if (e % 2 == 0) {
        const Sphere& target = balls[random.below(balls.size())];
        const Vertex to = target.center + target.radius * random.uniform() * random_unit(random) - x;
        if (to.dot(n) > 0) direction = to.normalized();
      }
      const Vertex end = x + (0.2 + 4 * random.uniform()) * direction;
      bool reference = false, close = false, ball = false;
      for (const Sphere& s : balls) {
        if (n.dot(s.center - x) <= -s.radius) continue;  // behind the plane: hides nothing in front
        reference = reference || disk_occludes_reference(x, s, end);
        ball = ball || segment_meets_ball(s, x, end - x, 0.0, 1.0);
        const Vertex v = s.center - x, w = end - x;
        const double t = v.norm(), z = w.norm();
        if (t > s.radius) {
          const double cos_gamma = std::sqrt(t * t - s.radius * s.radius) / t, cos_delta = v.dot(w) / (t * z);
          close = close || std::abs(cos_delta - cos_gamma) < 1e-5;
        }
        close = close || std::abs(t - z) < 1e-5 * z || std::abs(t - s.radius) < 1e-5 * t;
      }
      const bool answer = disks.occludes(end, tests);
      ends.push_back(end), answers.push_back(answer ? 1 : 0);
      ++checks;
      occluded += answer ? 1 : 0;
      if (answer != reference) {
        ++near_boundary;
        EXPECT_TRUE(close) << "point " << p << " end " << e;
      }
      ball_hits += ball ? 1 : 0;
      disk_vs_ball += answer != ball ? 1 : 0;
    }
    // The group forms, with and without the grid, give the single segments' answers: the
    // grid only narrows the disks compared.
    expect_group_answers({&disks, &grid}, ends, answers, p);
  }
  EXPECT_GT(occluded, checks / 5);
  EXPECT_LT(occluded, checks * 4 / 5);
  EXPECT_LT(near_boundary, checks / 10000 + 1);
  const auto percent = [](std::uint64_t part, std::uint64_t whole) {
    return 100.0 * static_cast<double>(part) / static_cast<double>(std::max<std::uint64_t>(whole, 1));
  };
  std::printf("occluder disks: %llu segments, %.1f %% occluded; disagree with exact ball intersection on %.2f %% (%.1f %% of "
              "those the balls meet); %llu within rounding of the definition's boundary\n",
              static_cast<unsigned long long>(checks), percent(occluded, checks), percent(disk_vs_ball, checks),
              percent(disk_vs_ball, ball_hits), static_cast<unsigned long long>(near_boundary));
  // The disks are not the balls: they differ where a ball straddles the light's distance
  // (its centre beyond the light but its front before it, or the reverse), and only there.
  EXPECT_GT(disk_vs_ball, 0u);
}

// The grid against the linear loop where its projection is stretched: balls up to 1.5
// units wide within 2 units (caps near a hemisphere wide, caps holding -n, balls holding x
// or straddling the tangent plane), ends grazing the plane, and ends behind it (which an
// API user may ask about; integrators never do).
TEST(OccluderDisks, GridAgreesWithTheLinearLoopForWideAndGrazingCaps) {
  Random random(31337);
  std::uint64_t tests = 0, occluded = 0, checks = 0;
  for (int p = 0; p < 3000; ++p) {
    const Vertex x = Vertex::Zero(), n = random_unit(random);
    std::vector<Sphere> balls;
    const int count = 1 + static_cast<int>(random.below(40));
    for (int b = 0; b < count; ++b) balls.push_back({2 * random.uniform() * random_unit(random), 0.01 + 1.5 * random.uniform() * random.uniform()});
    OccluderDisks linear, grid;
    linear.reset(x, n), grid.reset(x, n);
    linear.add(balls, false), grid.add(balls, false);
    linear.finish(), grid.finish(true);
    std::vector<Vertex> ends;
    std::vector<std::uint8_t> answers;
    for (int e = 0; e < 64; ++e) {
      Vertex direction = random_unit(random);
      if (direction.dot(n) < 0) direction -= 2 * direction.dot(n) * n;
      if (e % 4 == 0) direction = (direction - 0.999 * direction.dot(n) * n).normalized();  // grazing
      if (e % 16 == 1) direction = -n;  // behind the plane: outside the projection's reach
      if (e % 16 == 2) direction = (-(0.8 + 0.199 * random.uniform()) * n + 0.5 * random_unit(random)).normalized();
      ends.push_back((0.1 + 5 * random.uniform()) * direction);
      answers.push_back(linear.occludes(ends.back(), tests) ? 1 : 0);
      occluded += answers.back();
      ++checks;
    }
    std::vector<std::uint8_t> grouped(ends.size());
    grid.occludes(ends, grouped, tests);
    ASSERT_EQ(grouped, answers) << "point " << p;
  }
  EXPECT_GT(occluded, checks / 10);
  EXPECT_LT(occluded, checks * 9 / 10);
}

// The two loops compute the same comparisons; they may differ only by the rounding of the
// dot product (contracted to fused multiply-adds in the vectorised clone), never beyond it.
TEST(OccluderDisks, VectorisedAndScalarLoopsAgree) {
  Random random(99);
  int differ = 0, total = 0, hidden = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const std::size_t n = OccluderDisks::kDiskBlock * (1 + random.below(8));
    std::vector<float> ux(n), uy(n), uz(n), c(n), t(n);
    for (std::size_t j = 0; j < n; ++j) {
      const Vertex u = random_unit(random);
      ux[j] = static_cast<float>(u.x()), uy[j] = static_cast<float>(u.y()), uz[j] = static_cast<float>(u.z());
      c[j] = static_cast<float>(0.9 + 0.1 * random.uniform());
      t[j] = static_cast<float>(3 * random.uniform());
    }
    const float z = static_cast<float>(3 * random.uniform());
    const Vertex w = random_unit(random) * z;
    const bool a = any_disk_occludes(ux.data(), uy.data(), uz.data(), c.data(), t.data(), n, float(w.x()), float(w.y()), float(w.z()), z);
    const bool b = any_disk_occludes_scalar(ux.data(), uy.data(), uz.data(), c.data(), t.data(), n, float(w.x()), float(w.y()), float(w.z()), z);
    differ += a != b ? 1 : 0;
    hidden += a ? 1 : 0;
    ++total;
  }
  EXPECT_GT(hidden, total / 10);
  EXPECT_LT(hidden, total * 9 / 10);
  EXPECT_LE(differ, total / 10000);
}

// Balls behind the tangent plane are left out, a ball holding the point hides every
// segment longer than its centre's distance, and the self-shadowing heuristic skips balls
// closer than twice their radius.
TEST(OccluderDisks, EdgeCases) {
  std::uint64_t tests = 0;
  OccluderDisks disks;
  const Vertex x = Vertex::Zero(), n = Vertex::UnitZ();
  disks.reset(x, n);
  disks.add({{{0, 0, -1}, 0.5}}, false);  // behind the plane
  disks.finish();
  EXPECT_EQ(disks.size(), 0u);
  EXPECT_FALSE(disks.occludes({0, 0, 5}, tests));
  disks.reset(x, n);
  disks.add({{{0, 0, 0.1}, 0.5}}, false);  // holds x
  disks.finish();
  EXPECT_EQ(disks.size(), 1u);
  EXPECT_TRUE(disks.occludes({3, 0, 0.5}, tests));   // any direction, beyond t
  EXPECT_FALSE(disks.occludes({0, 0, 0.05}, tests)); // shorter than t
  disks.reset(x, n);
  disks.add({{{0, 0, 0.7}, 0.4}}, true);  // t = 0.7 < 2R: skipped
  disks.add({{{0, 0, 0.9}, 0.4}}, true);  // t = 0.9 > 2R: kept
  disks.finish();
  EXPECT_EQ(disks.size(), 1u);
  EXPECT_TRUE(disks.occludes({0, 0, 2}, tests));
  EXPECT_FALSE(disks.occludes({0, 0, 0.85}, tests));  // the light before the kept ball's centre
}

// The clusters' bounds only skip work: with them (one level, or clusters headed a few at a
// time), every segment gets the answer of testing every disk, one at a time and in groups.
// The balls are made to defeat a careless bound:
// balls touching the inside of their cluster's bound (so that their cones touch the bound's
// cone), ends aimed within 1e-6 radians of those balls' silhouettes, points inside a bound
// and inside a ball, the self-shadowing heuristic, and everything 10^4 units from the origin.
TEST(OccluderDisks, ClustersGiveTheAnswersOfEveryDisk) {
  Random random(4242);
  std::uint64_t checks = 0, occluded = 0, flat_tests = 0, clustered_tests = 0, grazing = 0;
  std::size_t most_groups = 0;
  for (int p = 0; p < 1500; ++p) {
    const Vertex offset = (p % 3 == 0) ? Vertex(1e4, -1e4, 1e4) : Vertex::Zero();
    const Vertex x = offset + Vertex(random.uniform() - 0.5, random.uniform() - 0.5, random.uniform() - 0.5);
    const Vertex n = random_unit(random);
    std::vector<Sphere> balls;
    const int shells = 1 + static_cast<int>(random.below(6));
    for (int s = 0; s < shells; ++s) {
      // A shell: balls inside a sphere (C, R), a third of them touching it from inside.
      const Vertex centre = offset + 3 * random.uniform() * random_unit(random);
      const double big = 0.1 + 0.6 * random.uniform();
      const int count = 2 + static_cast<int>(random.below(40));
      for (int b = 0; b < count; ++b) {
        const double r = big * (0.05 + 0.4 * random.uniform());
        const double reach = (b % 3 == 0) ? big - r : (big - r) * random.uniform();
        balls.push_back({centre + reach * random_unit(random), r});
      }
    }
    if (p % 7 == 0) balls.push_back({x + 0.01 * random_unit(random), 0.05});  // holds x
    const bool heuristic = p % 4 == 1;
    const std::size_t leaf = 1 + random.below(24), group = p % 2 == 0 ? 0 : 2 + random.below(4);
    std::vector<Sphere> ordered = balls;
    const std::vector<SphereCluster> clusters = cluster_spheres(ordered, leaf, group);
    OccluderDisks flat, clustered;
    flat.reset(x, n), clustered.reset(x, n);
    flat.add(balls, heuristic), clustered.add(ordered, clusters, heuristic);
    flat.finish(), clustered.finish();
    ASSERT_EQ(flat.size(), clustered.size()) << "point " << p;
    most_groups = std::max(most_groups, clustered.groups());
    std::vector<Vertex> ends;
    std::vector<std::uint8_t> answers;
    for (int e = 0; e < 96; ++e) {
      Vertex direction = random_unit(random);
      double length = 0.1 + 6 * random.uniform();
      if (e % 2 == 0) {
        // Along a ball's silhouette, jittered by up to 1e-6 radians, beyond the ball.
        const Sphere& ball = balls[random.below(balls.size())];
        const Vertex v = ball.center - x;
        const double t = v.norm();
        if (t > ball.radius) {
          const Vertex u = v / t;
          Vertex side = random_unit(random);
          side = (side - side.dot(u) * u).normalized();
          const double gamma = std::asin(ball.radius / t) + 1e-6 * (2 * random.uniform() - 1);
          direction = std::cos(gamma) * u + std::sin(gamma) * side;
          length = t + ball.radius * (0.5 + 2 * random.uniform());
          ++grazing;
        }
      }
      if (direction.dot(n) < 0 && e % 8 != 1) direction -= 2 * direction.dot(n) * n;
      ends.push_back(x + length * direction);
      const bool answer = flat.occludes(ends.back(), flat_tests);
      ASSERT_EQ(clustered.occludes(ends.back(), clustered_tests), answer) << "point " << p << " end " << e;
      answers.push_back(answer ? 1 : 0);
      occluded += answer ? 1 : 0;
      ++checks;
    }
    expect_group_answers({&flat, &clustered}, ends, answers, p);
  }
  EXPECT_GT(occluded, checks / 5);
  EXPECT_LT(occluded, checks * 4 / 5);
  EXPECT_GT(grazing, checks / 3);
  EXPECT_GE(most_groups, 10u);
  // The bounds reject: fewer comparisons than testing every disk.
  EXPECT_LT(clustered_tests, flat_tests * 3 / 4);
}

// Small balls far away: radii 1e-4 to 1e-2 at 200 to 3000 units, so that each cone is
// under 0.01 radians wide and the float test of a disk errs by far more than 2^-16 radians
// near its edge (about 1e-7 / sin gamma, up to 5e-4 radians for the smallest). Ends are
// aimed within 2e-3 radians of a ball's axis or silhouette. A bound's cone widened by a
// fixed 2^-16 of its distance rejected segments its balls' own float tests hid (2 % of
// those near silhouettes at distance 2000); widened by the float test's error bound, every
// answer is every disk's, in the scalar, group and lazily made forms.
TEST(OccluderDisks, ClustersGiveTheAnswersOfEveryDiskForSmallBallsFarAway) {
  Random random(777);
  std::uint64_t checks = 0, occluded = 0, mismatches = 0;
  for (int p = 0; p < 600; ++p) {
    const Vertex offset = p % 2 == 0 ? Vertex(5e3, -2e3, 1e3) : Vertex::Zero();
    const Vertex x = offset + Vertex(random.uniform(), random.uniform(), random.uniform());
    const Vertex n = random_unit(random);
    const double distance = 200 + 2800 * random.uniform();
    const Vertex direction = (random_unit(random) + 1.5 * n).normalized();
    const Vertex centre = x + distance * direction;
    std::vector<Sphere> balls;
    const int count = 1 + static_cast<int>(random.below(48));
    const double spread = std::pow(10.0, -3 + 2 * random.uniform());
    for (int b = 0; b < count; ++b) balls.push_back({centre + spread * random.uniform() * random_unit(random), std::pow(10.0, -4 + 2 * random.uniform())});
    const std::size_t leaf = 1 + random.below(8), group = p % 3 == 0 ? 0 : 2 + random.below(3);
    std::vector<Sphere> ordered = balls;
    const std::vector<SphereCluster> clusters = cluster_spheres(ordered, leaf, group);
    OccluderDisks flat, clustered;
    flat.reset(x, n), clustered.reset(x, n);
    flat.add(ordered, false), clustered.add(ordered, clusters, false);
    flat.finish(), clustered.finish();
    std::vector<Vertex> ends;
    std::vector<std::uint8_t> answers;
    std::uint64_t tests = 0;
    for (int e = 0; e < 64; ++e) {
      const Sphere& ball = ordered[random.below(ordered.size())];
      const Vertex v = ball.center - x;
      const double t = v.norm();
      const Vertex u = v / t;
      Vertex side = random_unit(random);
      side = (side - side.dot(u) * u).normalized();
      const double angle = (e % 2 == 0 ? std::asin(ball.radius / t) : 0.0) + 2e-3 * (2 * random.uniform() - 1) * std::pow(10.0, -3 * random.uniform());
      ends.push_back(x + (t + 1 + 5 * random.uniform()) * (std::cos(angle) * u + std::sin(angle) * side));
      const bool answer = flat.occludes(ends.back(), tests);
      answers.push_back(answer ? 1 : 0);
      occluded += answer ? 1 : 0;
      mismatches += clustered.occludes(ends.back(), tests) != answer ? 1 : 0;
      ++checks;
    }
    std::vector<std::uint8_t> grouped(ends.size());
    clustered.occludes(ends, grouped, tests);
    for (std::size_t k = 0; k < ends.size(); ++k) mismatches += grouped[k] != answers[k] ? 1 : 0;
  }
  EXPECT_EQ(mismatches, 0u) << "of " << 2 * checks << " answers";
  EXPECT_GT(occluded, checks / 10);  // the ends do reach the disks' edges
  EXPECT_LT(occluded, checks * 9 / 10);
}

}  // namespace
}  // namespace visproxy
