#include "visproxy/measure/cost_model.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <vector>

#include "test_meshes.h"
#include "visproxy/core/random.h"
#include "visproxy/measure/random_lines.h"
#include "visproxy/mesh/sphere_set.h"

namespace visproxy {
namespace {

// Works spanning what a run sees: one box (few nodes, 12 triangles) to a big mesh.
std::vector<WorkPerRay> works() {
  return {{2, 6, 0},   {3, 9, 0}, {8, 14, 0}, {14, 20, 0},  {25, 30, 0},
          {60, 45, 0}, {4, 0, 5}, {9, 0, 12}, {120, 70, 0}, {310, 95, 0}};
}

TEST(FitCostModel, RecoversTheConstantsOfExactTimings) {
  const CostModel truth{.per_ray = 30, .per_node = 4.5, .per_triangle = 7, .per_ball = 11};
  std::vector<CostObservation> observations;
  for (const WorkPerRay& w : works()) observations.push_back({w, truth.predict(w)});
  const std::optional<CostModel> model = fit_cost_model(observations);
  ASSERT_TRUE(model);
  EXPECT_NEAR(model->per_ray, 30, 1e-6);
  EXPECT_NEAR(model->per_node, 4.5, 1e-7);
  EXPECT_NEAR(model->per_triangle, 7, 1e-7);
  EXPECT_NEAR(model->per_ball, 11, 1e-7);
  EXPECT_EQ(model->observations, works().size());
  EXPECT_NEAR(model->residual_low, 1, 1e-9);
  EXPECT_NEAR(model->residual_high, 1, 1e-9);
}

// A machine twice as slow in one run times everything twice as long: every predicted
// ratio must stay, or the recommendation would follow the machine's load.
TEST(FitCostModel, RatiosDoNotFollowAUniformChangeOfTheMachinesSpeed) {
  Random random(7);
  std::vector<CostObservation> observations;
  const CostModel truth{.per_ray = 25, .per_node = 3, .per_triangle = 9, .per_ball = 6};
  for (const WorkPerRay& w : works()) observations.push_back({w, truth.predict(w) * (0.9 + 0.2 * random.uniform())});
  std::vector<CostObservation> slower = observations;
  for (CostObservation& o : slower) o.ns_per_ray *= 2.3;
  const std::optional<CostModel> a = fit_cost_model(observations), b = fit_cost_model(slower);
  ASSERT_TRUE(a && b);
  const WorkPerRay mesh{310, 95, 0};
  for (const WorkPerRay& w : works())
    EXPECT_NEAR(a->predict(w) / a->predict(mesh), b->predict(w) / b->predict(mesh), 1e-9);
  EXPECT_NEAR(a->residual_low, b->residual_low, 1e-9);
  EXPECT_NEAR(a->residual_high, b->residual_high, 1e-9);
  EXPECT_LT(a->residual_low, 1);
  EXPECT_GT(a->residual_high, 1);
}

// Timings no non-negative model explains (the cost falls as the work grows): every
// constant stays non-negative and the residual range says how badly the model fits.
TEST(FitCostModel, KeepsConstantsNonNegativeAndReportsAMisfit) {
  std::vector<CostObservation> observations;
  for (const WorkPerRay& w : works()) observations.push_back({w, 1000 / (1 + w.nodes)});
  const std::optional<CostModel> model = fit_cost_model(observations);
  ASSERT_TRUE(model);
  EXPECT_GE(model->per_ray, 0);
  EXPECT_GE(model->per_node, 0);
  EXPECT_GE(model->per_triangle, 0);
  EXPECT_GE(model->per_ball, 0);
  EXPECT_GT(model->residual_high / model->residual_low, 10);
}

TEST(FitCostModel, RefusesTooFewOrUntimedObservations) {
  std::vector<CostObservation> observations;
  for (const WorkPerRay& w : works()) observations.push_back({w, 10 + w.nodes});
  observations.resize(kCostModelMinimumObservations - 1);
  EXPECT_FALSE(fit_cost_model(observations));
  // Untimed ones (0, NaN) do not count towards the minimum.
  observations.push_back({{5, 5, 0}, 0});
  observations.push_back({{5, 5, 0}, std::nan("")});
  EXPECT_FALSE(fit_cost_model(observations));
  observations.push_back({{7, 5, 0}, 17});
  EXPECT_TRUE(fit_cost_model(observations));
}

// The counts are the work of the rays, whatever the threads: summed one ray at a time
// they agree, and on one thread and on every thread they are the same numbers.
TEST(CountWork, IsTheSerialSumAndDoesNotDependOnThreads) {
  const TriangleMesh torus = testing::torus(1.0, 0.3, 64, 32);
  const std::vector<Segment> rays = isotropic_lines(bounding_sphere(torus), 20000, 3);
  const CountingBvh bvh(torus);
  TraversalCounts serial;
  for (std::size_t i = 0; i < 15000; ++i) bvh.segment_blocked(rays[i].from, rays[i].to, serial);
  WorkPerRay one, all = count_work(bvh, false, rays, 15000);
  {
    tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    one = count_work(bvh, false, rays, 15000);
  }
  EXPECT_EQ(one.nodes, all.nodes);
  EXPECT_EQ(one.triangles, all.triangles);
  EXPECT_DOUBLE_EQ(all.nodes, static_cast<double>(serial.nodes) / 15000);
  EXPECT_DOUBLE_EQ(all.triangles, static_cast<double>(serial.primitives) / 15000);
  EXPECT_EQ(all.balls, 0);
  EXPECT_GT(all.nodes, 1);
  // A limit beyond the rays counts them all; none counts nothing.
  const WorkPerRay every = count_work(bvh, false, rays, 1u << 30);
  EXPECT_GT(every.nodes, 0);
  EXPECT_EQ(count_work(bvh, false, rays, 0).nodes, 0);

  const std::vector<Sphere> balls{{Vertex(0, 0, 0), 0.5}, {Vertex(1, 0, 0), 0.25}};
  const WorkPerRay ball_work = count_work(CountingBvh(std::span<const Sphere>(balls)), true, rays, 15000);
  EXPECT_GT(ball_work.balls, 0);
  EXPECT_EQ(ball_work.triangles, 0);
}

}  // namespace
}  // namespace visproxy
