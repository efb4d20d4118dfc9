#include "visproxy/estimator/efficiency.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "visproxy/core/random.h"

namespace visproxy {
namespace {

RayTypeFractions fractions_of(double f_hit, double f_miss, double v) {
  RayTypeFractions fractions;
  fractions.f = {f_hit * (1 - v), (1 - f_hit) * (1 - v), (1 - f_miss) * v, f_miss * v};
  return fractions;
}

constexpr TraceCosts kCosts{.proxy_ns = 40, .mesh_ns = 300};

TEST(Efficiency, BoundsOfAnOutsideProxyCostTheProxyPlusTheMeshOnRaysThatHitIt) {
  // Every ray the proxy misses is proved free; the others trace the mesh. The variance is
  // the mesh's own, so the efficiency is the ratio of the costs.
  const RayTypeFractions f = fractions_of(1.0, 0.6, 0.5);
  const UsePrediction p = predict_use(ProxyUse::bounds, ProxyKind::outside, f, kCosts);
  ASSERT_TRUE(p.usable);
  const double hit = f.f[0] + f.f[2];
  EXPECT_NEAR(p.ns_per_ray, 40 + 300 * hit, 1e-9);
  EXPECT_NEAR(p.variance, 0.25, 1e-12);
  EXPECT_NEAR(p.efficiency, 300 / (40 + 300 * hit), 1e-12);
  // The same for an inside proxy: its hits are proved blocked.
  const RayTypeFractions g = fractions_of(0.7, 1.0, 0.4);
  const UsePrediction q = predict_use(ProxyUse::bounds, ProxyKind::inside, g, kCosts);
  EXPECT_NEAR(q.ns_per_ray, 40 + 300 * (g.f[1] + g.f[3]), 1e-9);
  // A general proxy, or one whose claim was not proved, proves nothing.
  const UsePrediction r = predict_use(ProxyUse::bounds, ProxyKind::general, f, kCosts);
  EXPECT_FALSE(r.usable);
  EXPECT_EQ(r.efficiency, 0);
  EXPECT_FALSE(r.why_not.empty());
}

// The brute-force minimum of variance x cost over a fine grid of the use's parameters.
double grid_minimum(ProxyUse use, ProxyKind kind, const RayTypeFractions& f, double floor) {
  double best = INFINITY;
  const int n = 200;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) {
      const double a = floor + (1 - floor) * i / n, b = floor + (1 - floor) * j / n;
      UseSetting s;
      if (use == ProxyUse::control_variate) {
        s.correction = {kind == ProxyKind::outside ? 0.0 : a, kind == ProxyKind::inside ? 0.0 : b};
      } else {
        if (kind == ProxyKind::outside) s.term = {a, 1 - a, 0};
        else if (kind == ProxyKind::inside) s.term = {a, 0, 1 - a};
        else s.term = {a, b, 1 - a - b};
        if (s.term.p1 < floor || s.term.p2 < (kind == ProxyKind::inside ? 0 : floor) - 1e-12 ||
            s.term.p3 < (kind == ProxyKind::outside ? 0 : floor) - 1e-12 || s.term.p1 > 1 - floor + 1e-12)
          continue;
      }
      const UsePrediction p = predict_use_at(use, kind, f, kCosts, s);
      best = std::min(best, p.variance * p.ns_per_ray);
    }
  return best;
}

TEST(Efficiency, TheChosenSettingIsAtLeastAsGoodAsTheBestOfAFineGrid) {
  const double floor = 0.05;
  for (ProxyKind kind : {ProxyKind::outside, ProxyKind::inside, ProxyKind::general})
    for (ProxyUse use : {ProxyUse::control_variate, ProxyUse::term_choice})
      for (double f_hit : {0.3, 0.8, 0.97})
        for (double f_miss : {0.2, 0.6, 0.95})
          for (double v : {0.1, 0.5, 0.9}) {
            const RayTypeFractions f =
                fractions_of(kind == ProxyKind::outside ? 1.0 : f_hit, kind == ProxyKind::inside ? 1.0 : f_miss, v);
            const UsePrediction p = predict_use(use, kind, f, kCosts, {.floor = floor});
            const double grid = grid_minimum(use, kind, f, floor);
            SCOPED_TRACE(std::string(use_name(use)) + " " + std::string(kind_name(kind)) + " f_hit " +
                         std::to_string(f_hit) + " f_miss " + std::to_string(f_miss) + " v " + std::to_string(v));
            EXPECT_LE(p.variance * p.ns_per_ray, grid * (1 + 1e-6));
            EXPECT_GT(p.efficiency, 0);
            EXPECT_TRUE(std::isfinite(p.efficiency));
            // Every probability the kind needs is at least the floor.
            if (use == ProxyUse::control_variate) {
              if (kind != ProxyKind::outside) {
                EXPECT_GE(p.setting.correction.after_miss, floor);
              }
              if (kind != ProxyKind::inside) {
                EXPECT_GE(p.setting.correction.after_hit, floor);
              }
            } else {
              EXPECT_GE(p.setting.term.p1, floor - 1e-12);
              if (kind != ProxyKind::inside) {
                EXPECT_GE(p.setting.term.p2, floor - 1e-12);
              }
              if (kind != ProxyKind::outside) {
                EXPECT_GE(p.setting.term.p3, floor - 1e-12);
              }
              EXPECT_NEAR(p.setting.term.p1 + p.setting.term.p2 + p.setting.term.p3, 1, 1e-12);
            }
          }
}

// Simulates the estimators ray by ray on a population with known fractions and compares the
// sample variance and the mean cost with the prediction: the model, not just its algebra.
TEST(Efficiency, PredictedVarianceAndCostMatchASimulationOfEachEstimator) {
  const RayTypeFractions f = fractions_of(0.8, 0.7, 0.45);
  const std::size_t n = 400000;
  for (ProxyUse use : {ProxyUse::control_variate, ProxyUse::term_choice, ProxyUse::bounds}) {
    const ProxyKind kind = use == ProxyUse::bounds ? ProxyKind::inside : ProxyKind::general;
    const RayTypeFractions g = use == ProxyUse::bounds ? fractions_of(0.8, 1.0, 0.45) : f;
    const UsePrediction p = predict_use(use, kind, g, kCosts);
    Random random(7 + static_cast<std::uint64_t>(use));
    double sum = 0, sum2 = 0, sum4 = 0, cost = 0;
    std::vector<double> samples(n);
    for (std::size_t i = 0; i < n; ++i) {
      const double u = random.uniform();
      const int type = u < g.f[0] ? 0 : u < g.f[0] + g.f[1] ? 1 : u < g.f[0] + g.f[1] + g.f[2] ? 2 : 3;
      const double v = type >= 2 ? 1 : 0, v_proxy = type == 1 || type == 3 ? 1 : 0;
      double estimate = 0, c = kCosts.proxy_ns;
      if (use == ProxyUse::control_variate) {
        const double q = v_proxy == 1 ? p.setting.correction.after_miss : p.setting.correction.after_hit;
        estimate = v_proxy;
        if (random.uniform() < q) estimate += (v - v_proxy) / q, c += kCosts.mesh_ns;
      } else if (use == ProxyUse::term_choice) {
        const double w = random.uniform();
        if (w < p.setting.term.p1) {
          estimate = v_proxy / p.setting.term.p1;
        } else if (w < p.setting.term.p1 + p.setting.term.p2) {
          if (v_proxy == 0) estimate = v / p.setting.term.p2, c += kCosts.mesh_ns;
        } else if (v_proxy == 1) {
          estimate = -(1 - v) / p.setting.term.p3, c += kCosts.mesh_ns;
        }
      } else {
        estimate = v_proxy == 0 ? 0 : v;  // an inside proxy's hit proves V = 0
        if (v_proxy == 1) c += kCosts.mesh_ns;
      }
      samples[i] = estimate, sum += estimate, cost += c;
    }
    const double mean = sum / n;
    for (double s : samples) sum2 += (s - mean) * (s - mean), sum4 += std::pow(s - mean, 4);
    const double variance = sum2 / (n - 1);
    // Standard error of the sample variance: sqrt((m4 - s^4) / n). 5 of them: a false
    // alarm once in 3.5 million runs under a normal approximation.
    const double error = std::sqrt((sum4 / n - variance * variance) / n);
    SCOPED_TRACE(std::string(use_name(use)));
    EXPECT_NEAR(mean, g.v_avg(), 5 * std::sqrt(variance / n));  // unbiased
    EXPECT_NEAR(variance, p.variance, 5 * error);
    // Cost: a mean of at most two values, c_proxy and c_proxy + c_mesh.
    EXPECT_NEAR(cost / n, p.ns_per_ray, 5 * kCosts.mesh_ns * 0.5 / std::sqrt(static_cast<double>(n)));
  }
}

TEST(Efficiency, AnExactProxyOfAllFreeRaysIsComparedByCostAlone) {
  RayTypeFractions f;
  f.f = {0, 0, 0, 1};  // every ray free, and the proxy lets every one through
  const UsePrediction p = predict_use(ProxyUse::control_variate, ProxyKind::outside, f, kCosts);
  EXPECT_EQ(p.variance, 0);
  EXPECT_NEAR(p.efficiency, 300.0 / 40.0, 1e-12);
  // A proxy that blocks a fifth of them: the control variate traces the mesh after every
  // proxy hit (q = 1, no variance) and after the floor's share of its misses, so it is still
  // compared by cost; eq. 8 cannot avoid variance where the mesh has none, so it is worth 0.
  f.f = {0, 0, 0.2, 0.8};
  const UsePrediction cv = predict_use(ProxyUse::control_variate, ProxyKind::general, f, kCosts);
  EXPECT_EQ(cv.setting.correction.after_hit, 1.0);
  EXPECT_EQ(cv.variance, 0);
  EXPECT_NEAR(cv.efficiency, 300.0 / (40 + 300 * (0.05 * 0.8 + 0.2)), 1e-9);
  const UsePrediction eq8 = predict_use(ProxyUse::term_choice, ProxyKind::general, f, kCosts);
  EXPECT_GT(eq8.variance, 0.79);  // at least (sqrt(0.8) + sqrt(0.2))^2 - 1 = 0.8
  EXPECT_EQ(eq8.efficiency, 0);
  // No rays: nothing to predict, and no NaN.
  const UsePrediction none = predict_use(ProxyUse::term_choice, ProxyKind::general, RayTypeFractions{}, kCosts);
  EXPECT_FALSE(none.usable);
  EXPECT_EQ(none.efficiency, 0);
  // Costs not measured.
  const UsePrediction untimed = predict_use(ProxyUse::bounds, ProxyKind::outside, fractions_of(1, 0.5, 0.5), {});
  EXPECT_FALSE(untimed.usable);
}

RayTypeCounts draw_counts(const RayTypeFractions& f, std::uint64_t n, Random& random) {
  RayTypeCounts counts;
  for (std::uint64_t i = 0; i < n; ++i) {
    const double u = random.uniform();
    counts.counts[u < f.f[0] ? 0 : u < f.f[0] + f.f[1] ? 1 : u < f.f[0] + f.f[1] + f.f[2] ? 2 : 3]++;
  }
  return counts;
}

TEST(Efficiency, TheIntervalCoversTheTrueEfficiencyAtItsStatedRate) {
  // 200 measurements of 2000 rays each from a known population; the 95 % interval must hold
  // the true efficiency (at the same setting) in about 190 of them. Fewer than 180 has
  // probability 3e-4 if the coverage is 95 %; a coverage of 85 % would give fewer than 180
  // with probability 0.8.
  for (ProxyUse use : {ProxyUse::control_variate, ProxyUse::term_choice, ProxyUse::bounds}) {
    const ProxyKind kind = use == ProxyUse::bounds ? ProxyKind::outside : ProxyKind::general;
    const RayTypeFractions truth = use == ProxyUse::bounds ? fractions_of(1.0, 0.6, 0.4) : fractions_of(0.85, 0.75, 0.4);
    const UseSetting setting = predict_use(use, kind, truth, kCosts).setting;
    const double true_efficiency = predict_use_at(use, kind, truth, kCosts, setting).efficiency;
    Random random(11);
    int covered = 0;
    for (int trial = 0; trial < 200; ++trial) {
      const RayTypeCounts counts = draw_counts(truth, 2000, random);
      const Interval interval = efficiency_interval(use, kind, counts, kCosts, setting, 1000 + trial, 1000);
      EXPECT_LE(interval.lower, interval.upper);
      covered += interval.lower <= true_efficiency && true_efficiency <= interval.upper ? 1 : 0;
    }
    SCOPED_TRACE(std::string(use_name(use)));
    EXPECT_GE(covered, 180);
  }
}

TEST(Efficiency, TheIntervalNarrowsWithMoreRaysAndIsReproducible) {
  const RayTypeFractions truth = fractions_of(0.9, 0.8, 0.5);
  const UseSetting setting = predict_use(ProxyUse::control_variate, ProxyKind::general, truth, kCosts).setting;
  RayTypeCounts small, large;
  for (std::size_t i = 0; i < 4; ++i) {
    small.counts[i] = static_cast<std::uint64_t>(std::llround(truth.f[i] * 1e3));
    large.counts[i] = static_cast<std::uint64_t>(std::llround(truth.f[i] * 1e6));
  }
  const Interval a = efficiency_interval(ProxyUse::control_variate, ProxyKind::general, small, kCosts, setting, 3);
  const Interval b = efficiency_interval(ProxyUse::control_variate, ProxyKind::general, large, kCosts, setting, 3);
  const double value = predict_use_at(ProxyUse::control_variate, ProxyKind::general, truth, kCosts, setting).efficiency;
  EXPECT_LT(a.lower, value);
  EXPECT_GT(a.upper, value);
  EXPECT_LE(b.lower, value);
  EXPECT_GE(b.upper, value);
  // The width shrinks as 1/sqrt(n): 1000 times the rays, about 1/31 of the width.
  EXPECT_LT((b.upper - b.lower) * 15, a.upper - a.lower);
  const Interval again = efficiency_interval(ProxyUse::control_variate, ProxyKind::general, small, kCosts, setting, 3);
  EXPECT_EQ(again.lower, a.lower);
  EXPECT_EQ(again.upper, a.upper);
}

TEST(RenderEfficiency, IsAmdahlsLawWithTheVarianceRatio) {
  EXPECT_DOUBLE_EQ(render_efficiency(2.0, 1.0, 1.0), 2.0);           // all of a sample is the mesh's shadow test
  EXPECT_DOUBLE_EQ(render_efficiency(2.0, 1.0, 0.5), 1 / (0.5 + 0.25));  // bounds: Amdahl
  EXPECT_DOUBLE_EQ(render_efficiency(2.0, 1.0, 0.0), 1.0);           // shadow tests cost nothing: no gain
  EXPECT_DOUBLE_EQ(render_efficiency(2.0, 1.5, 0.0), 1 / 1.5);       // ... and the noise still grows
  EXPECT_DOUBLE_EQ(render_efficiency(0.5, 1.0, 0.2), 1 / (0.8 + 0.4));
  EXPECT_DOUBLE_EQ(render_efficiency(2.0, 1.0, 7.0), 2.0);  // a share is clamped to [0, 1]
  EXPECT_EQ(render_efficiency(0.0, 1.0, 0.5), 0.0);
  EXPECT_EQ(render_efficiency(2.0, std::numeric_limits<double>::infinity(), 0.5), 0.0);
  EXPECT_DOUBLE_EQ(render_efficiency(std::numeric_limits<double>::infinity(), 1.0, 0.25), 1 / 0.75);
  // A use that pays per ray pays less over the render, and more as the share grows.
  double previous = render_efficiency(3.0, 1.2, 0.0);
  EXPECT_LT(previous, 1.0);
  for (double share = 0.1; share <= 1.0; share += 0.1) {
    const double e = render_efficiency(3.0, 1.2, share);
    EXPECT_GT(e, previous - 1e-12);
    EXPECT_LE(e, 3.0 + 1e-12);
    previous = e;
  }
}

// The variance each use adds per ray type, weighted by the type fractions and added to
// Var(V), is the use's whole variance (eq. 14 for eq. 8, the control variate's formula), on
// random fractions and probabilities; a type the setting cannot estimate adds +infinity,
// and a render whose changed segments carry no weight keeps its noise.
TEST(RenderNoise, TheVarianceAddedPerRayTypeSumsToTheEstimatorsVariance) {
  Random random(41);
  for (int trial = 0; trial < 200; ++trial) {
    RayTypeFractions fractions;
    double total = 0;
    for (double& f : fractions.f) total += (f = random.uniform());
    for (double& f : fractions.f) f /= total;
    const double v = fractions.v_avg();
    UseSetting setting;
    const double a = 0.05 + 0.9 * random.uniform(), b = 0.05 + (0.95 - a) * random.uniform();
    setting.term = {a, b, 1 - a - b};
    setting.correction = {0.05 + 0.95 * random.uniform(), 0.05 + 0.95 * random.uniform()};
    for (const ProxyUse use : {ProxyUse::term_choice, ProxyUse::control_variate, ProxyUse::bounds}) {
      const std::array<double, 4> added = added_variance_by_type(use, setting);
      double sum = v * (1 - v);
      for (std::size_t t = 0; t < 4; ++t) sum += fractions.f[t] * added[t];
      const double expected = use == ProxyUse::term_choice       ? estimator_variance(fractions, setting.term)
                              : use == ProxyUse::control_variate ? control_variate_variance(fractions, setting.correction)
                                                                 : v * (1 - v);
      EXPECT_NEAR(sum, expected, 1e-9 * (1 + expected)) << use_name(use) << " trial " << trial;
    }
  }
  UseSetting outside;
  outside.term = equal_probabilities(ProxyKind::outside);  // p3 = 0: type 2 cannot be estimated
  outside.correction = equal_correction_probabilities(ProxyKind::outside);
  EXPECT_TRUE(std::isinf(added_variance_by_type(ProxyUse::term_choice, outside)[1]));
  EXPECT_TRUE(std::isinf(added_variance_by_type(ProxyUse::control_variate, outside)[1]));
  // ... which a proved outside proxy never meets: its weight is 0 and it adds nothing.
  const std::array<double, 4> no_type_2 = {0.2, 0, 0.1, 0.3};
  const double ratio = render_variance_ratio(no_type_2, added_variance_by_type(ProxyUse::term_choice, outside), 0.5);
  EXPECT_DOUBLE_EQ(ratio, 1 + (0.1 * (2 - 1) + 0.3 * (2 - 1)) / 0.5);
  EXPECT_EQ(render_variance_ratio({0, 0, 0, 0}, added_variance_by_type(ProxyUse::term_choice, outside), 0.0), 1.0);
  EXPECT_TRUE(std::isinf(render_variance_ratio(no_type_2, added_variance_by_type(ProxyUse::term_choice, outside), 0.0)));
  // Amdahl's law on the time, the render's own ratio on the noise.
  EXPECT_DOUBLE_EQ(render_efficiency_of(0.5, 1.0, 0.4), 1 / (0.6 + 0.2));
  EXPECT_DOUBLE_EQ(render_efficiency_of(0.5, 2.0, 0.4), 1 / (2 * (0.6 + 0.2)));
  EXPECT_EQ(render_efficiency_of(0.5, std::numeric_limits<double>::infinity(), 0.4), 0.0);
}

// A simulated render: each sample's value is X V, with X the rest of the sample's noise
// (light sampling, 1 without any), V the visibility of its shadow ray, and its time the
// rest of the sample plus the shadow test. With the control variate, V is replaced by its
// unbiased estimate and the test by the use's cost. The render's measured efficiency
// equals the prediction when visibility is the only noise, and is at least the prediction
// when there is other noise (the stated lower bound), within the simulation's error.
TEST(RenderEfficiency, MatchesASimulatedRenderAndBoundsOneWithOtherNoise) {
  const RayTypeFractions f = fractions_of(0.7, 0.6, 0.55);
  const UseSetting setting{{}, {.after_miss = 0.3, .after_hit = 0.4}};
  const UsePrediction use = predict_use_at(ProxyUse::control_variate, ProxyKind::general, f, kCosts, setting);
  const double mesh_variance = f.v_avg() * (1 - f.v_avg());
  const double other_ns = 600;  // the rest of a sample
  const double share = kCosts.mesh_ns / (other_ns + kCosts.mesh_ns);
  const double predicted = render_efficiency(use.efficiency, use.variance / mesh_variance, share);
  for (const bool other_noise : {false, true}) {
    Random random(other_noise ? 11 : 12);
    const int n = 400000;
    double sum_exact = 0, sum2_exact = 0, sum_use = 0, sum2_use = 0;
    for (int i = 0; i < n; ++i) {
      const double x = other_noise ? 2 * random.uniform() : 1.0;
      const double u = random.uniform();
      const int type = u < f.f[0] ? 0 : u < f.f[0] + f.f[1] ? 1 : u < f.f[0] + f.f[1] + f.f[2] ? 2 : 3;
      const double v = type >= 2 ? 1 : 0, proxy = type == 1 || type == 3 ? 1 : 0;
      const double q = proxy == 1 ? setting.correction.after_miss : setting.correction.after_hit;
      const double estimate = proxy + (random.uniform() < q ? (v - proxy) / q : 0.0);
      sum_exact += x * v, sum2_exact += x * x * v * v;
      sum_use += x * estimate, sum2_use += x * x * estimate * estimate;
    }
    const double var_exact = sum2_exact / n - (sum_exact / n) * (sum_exact / n);
    const double var_use = sum2_use / n - (sum_use / n) * (sum_use / n);
    const double measured = (var_exact * (other_ns + kCosts.mesh_ns)) / (var_use * (other_ns + use.ns_per_ray));
    // Sampling error of a variance ratio at n = 4e5: a few per cent at most (4 sigma).
    if (other_noise)
      EXPECT_GT(measured, predicted * 0.97) << "the prediction is a lower bound";
    else
      EXPECT_NEAR(measured / predicted, 1.0, 0.03);
  }
}

}  // namespace
}  // namespace visproxy
