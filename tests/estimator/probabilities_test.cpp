#include "visproxy/estimator/probabilities.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "visproxy/core/random.h"

namespace visproxy {
namespace {

// Fractions of the ray types a proxy of `kind` can produce, on a grid over
// (f_hit, f_miss, V_avg) that includes the edges 0 and 1.
std::vector<RayTypeFractions> grid(ProxyKind kind) {
  const double steps[] = {0.0, 0.01, 0.1, 0.3, 0.5, 0.7, 0.9, 0.99, 1.0};
  std::vector<RayTypeFractions> out;
  for (double f_hit : steps)
    for (double f_miss : steps)
      for (double v : steps) {
        if (kind == ProxyKind::outside && f_hit != 1.0) continue;
        if (kind == ProxyKind::inside && f_miss != 1.0) continue;
        RayTypeFractions fractions;
        fractions.f = {f_hit * (1 - v), (1 - f_hit) * (1 - v), (1 - f_miss) * v, f_miss * v};
        out.push_back(fractions);
      }
  return out;
}

TEST(EstimatorVariance, MatchesEquation16InTermsOfHitMissAndVisibility) {
  const double f_hit = 0.7, f_miss = 0.4, v = 0.35;
  RayTypeFractions fractions;
  fractions.f = {f_hit * (1 - v), (1 - f_hit) * (1 - v), (1 - f_miss) * v, f_miss * v};
  const Probabilities p{0.5, 0.3, 0.2};
  const double eq16 = (1 - v) * (1 - f_hit) * (p.p1 + p.p3) / (p.p1 * p.p3) + v * (1 - f_miss) / p.p2 +
                      v * f_miss / p.p1 - v * v;
  EXPECT_NEAR(estimator_variance(fractions, p), eq16, 1e-12);
}

// Mean and variance of an estimator over 2 000 000 rays of types 1..4 drawn with the
// fractions {0.3, 0.1, 0.2, 0.4} (V_avg = 0.6): `estimate(v_exact, v_proxy, pick)` with
// pick uniform in [0, 1).
struct Moments {
  double mean = 0, variance = 0;
};
constexpr int kSimulatedRays = 2'000'000;
RayTypeFractions simulated_fractions() {
  RayTypeFractions fractions;
  fractions.f = {0.3, 0.1, 0.2, 0.4};
  return fractions;
}
template <typename Estimate>
Moments simulate(std::uint64_t seed, Estimate estimate) {
  Random random(seed);
  double sum = 0, sum_squares = 0;
  for (int i = 0; i < kSimulatedRays; ++i) {
    const double u = random.uniform();
    const int type = u < 0.3 ? 1 : u < 0.4 ? 2 : u < 0.6 ? 3 : 4;
    const double v_exact = type >= 3 ? 1 : 0, v_proxy = (type == 2 || type == 4) ? 1 : 0;
    const double value = estimate(v_exact, v_proxy, random.uniform());
    sum += value;
    sum_squares += value * value;
  }
  const double mean = sum / kSimulatedRays;
  return {mean, sum_squares / kSimulatedRays - mean * mean};
}

// The variance formula is the second moment of the estimator minus V_avg^2: simulate it.
TEST(EstimatorVariance, AgreesWithSimulatedEstimator) {
  const Probabilities p{0.5, 0.25, 0.25};
  const Moments m = simulate(11, [&](double v_exact, double v_proxy, double pick) {
    return pick < p.p1 ? v_proxy / p.p1
           : pick < p.p1 + p.p2 ? (1 - v_proxy) * v_exact / p.p2
                                : -v_proxy * (1 - v_exact) / p.p3;
  });
  const double expected = estimator_variance(simulated_fractions(), p);
  // Mean: unbiased (V_avg = 0.6); standard error sqrt(Var / n) ~ 0.001, so 5 sigma.
  EXPECT_NEAR(m.mean, 0.6, 5 * std::sqrt(expected / kSimulatedRays));
  EXPECT_NEAR(m.variance, expected, 0.01 * expected);
}

TEST(EstimatorVariance, NeverChosenTermWithRaysIsInfiniteAndUnusedTermIsFree) {
  RayTypeFractions outside;
  outside.f = {0.5, 0.0, 0.2, 0.3};
  EXPECT_TRUE(std::isfinite(estimator_variance(outside, {0.5, 0.5, 0.0})));
  EXPECT_TRUE(std::isinf(estimator_variance(outside, {0.5, 0.0, 0.5})));
  EXPECT_EQ(estimator_variance(RayTypeFractions{}, {1, 0, 0}), 0.0);
}

class OptimalProbabilities : public ::testing::TestWithParam<ProxyKind> {};

TEST_P(OptimalProbabilities, ClosedFormsMatchNumericMinimisationOnAGrid) {
  const ProxyKind kind = GetParam();
  int compared = 0;
  for (const RayTypeFractions& fractions : grid(kind)) {
    const Probabilities closed = optimal_probabilities(kind, fractions);
    const Probabilities numeric = minimise_variance_numerically(kind, fractions);
    ASSERT_NEAR(closed.p1 + closed.p2 + closed.p3, 1.0, 1e-15);
    const double v_closed = estimator_variance(fractions, closed);
    const double v_numeric = estimator_variance(fractions, numeric);
    ASSERT_TRUE(std::isfinite(v_closed));
    // The closed form is never worse than the numeric minimum (up to its tolerance) ...
    EXPECT_LE(v_closed, v_numeric + 1e-9 * (1 + v_numeric)) << fractions.f[0] << " " << fractions.f[1] << " "
                                                            << fractions.f[2] << " " << fractions.f[3];
    // ... and where the minimiser is unique (every needed weight positive), it is the same point.
    const auto& f = fractions.f;
    const bool unique = f[1] + f[3] > 0 && (kind == ProxyKind::inside || f[2] > 0) && (kind == ProxyKind::outside || f[1] > 0);
    if (unique) {
      EXPECT_NEAR(closed.p1, numeric.p1, 1e-5);
      EXPECT_NEAR(closed.p2, numeric.p2, 1e-5);
      EXPECT_NEAR(closed.p3, numeric.p3, 1e-5);
      ++compared;
    }
  }
  EXPECT_GT(compared, 20);
}

TEST_P(OptimalProbabilities, AreNeverWorseThanEqualProbabilities) {
  const ProxyKind kind = GetParam();
  for (const RayTypeFractions& fractions : grid(kind))
    EXPECT_LE(estimator_variance(fractions, optimal_probabilities(kind, fractions)),
              estimator_variance(fractions, equal_probabilities(kind)) + 1e-12);
}

INSTANTIATE_TEST_SUITE_P(Kinds, OptimalProbabilities,
                         ::testing::Values(ProxyKind::outside, ProxyKind::inside, ProxyKind::general),
                         [](const auto& kind) { return std::string(kind_name(kind.param)); });

TEST(OptimalProbabilities, OutsideAndInsideMatchThePrintedFormulasAwayFromTheirSingularities) {
  for (double f_miss : {0.05, 0.3, 0.7, 0.95}) {
    RayTypeFractions fractions;
    const double v = 0.4;
    fractions.f = {1 - v, 0, (1 - f_miss) * v, f_miss * v};
    const double printed = (f_miss - std::sqrt(f_miss - f_miss * f_miss)) / (2 * f_miss - 1);
    EXPECT_NEAR(optimal_probabilities(ProxyKind::outside, fractions).p1, printed, 1e-12);
  }
  for (double f_hit : {0.05, 0.5, 0.95})
    for (double v : {0.1, 0.5, 0.9}) {
      RayTypeFractions fractions;
      fractions.f = {f_hit * (1 - v), (1 - f_hit) * (1 - v), 0, v};
      const double s = 1 - f_hit * (1 - v);
      const double spec = (s - std::sqrt((1 - f_hit) * (1 - v) * s)) / v;
      EXPECT_NEAR(optimal_probabilities(ProxyKind::inside, fractions).p1, spec, 1e-12);
    }
}

TEST(OptimalProbabilities, DegenerateCasesAreFiniteAndDocumented) {
  RayTypeFractions all_blocked;  // V_avg = 0, every ray of type 1
  all_blocked.f = {1, 0, 0, 0};
  RayTypeFractions all_free;  // V_avg = 1, every ray of type 4
  all_free.f = {0, 0, 0, 1};
  RayTypeFractions half;  // f_miss = 1/2: the printed outside form is 0/0 here
  half.f = {0.5, 0, 0.25, 0.25};
  RayTypeFractions inside_dark;  // V_avg = 0 with misses: the printed inside form is 0/0
  inside_dark.f = {0.6, 0.4, 0, 0};
  for (ProxyKind kind : {ProxyKind::outside, ProxyKind::inside, ProxyKind::general}) {
    EXPECT_EQ(optimal_probabilities(kind, all_blocked).p1, 1.0);
    EXPECT_EQ(optimal_probabilities(kind, all_free).p1, 1.0);
    const Probabilities empty = optimal_probabilities(kind, RayTypeFractions{});
    const Probabilities equal = equal_probabilities(kind);
    EXPECT_EQ(empty.p1, equal.p1);
    EXPECT_EQ(empty.p2, equal.p2);
    EXPECT_EQ(empty.p3, equal.p3);
  }
  EXPECT_DOUBLE_EQ(optimal_probabilities(ProxyKind::outside, half).p1, 0.5);
  EXPECT_DOUBLE_EQ(optimal_probabilities(ProxyKind::inside, inside_dark).p1, 0.5);
}

TEST(OptimalProbabilities, FloorKeepsEveryNeededTermAndTheSum) {
  RayTypeFractions fractions;
  fractions.f = {0, 0, 0, 1};
  const Probabilities p = optimal_probabilities(ProxyKind::general, fractions, {.floor = 0.05});
  EXPECT_NEAR(p.p1 + p.p2 + p.p3, 1.0, 1e-15);
  EXPECT_GE(p.p2, 0.05);
  EXPECT_GE(p.p3, 0.05);
  const Probabilities outside = optimal_probabilities(ProxyKind::outside, fractions, {.floor = 0.05});
  EXPECT_GE(outside.p2, 0.05);
  EXPECT_EQ(outside.p3, 0.0);
}

TEST(CostHeuristic, ShiftsProbabilityToTheProxyWhereProxyAndMeshAgree) {
  RayTypeFractions agreeing;
  agreeing.f = {0.6, 0.0, 0.01, 0.39};  // f1 + f4 = 0.99
  const Probabilities p = optimal_probabilities(ProxyKind::outside, agreeing);
  const Probabilities q = apply_cost_heuristic(ProxyKind::outside, p, agreeing);
  EXPECT_NEAR(q.p2, p.p2 * std::pow(0.01, 0.25), 1e-12);
  EXPECT_GT(q.p1, p.p1);
  EXPECT_NEAR(q.p1 + q.p2 + q.p3, 1.0, 1e-15);
  RayTypeFractions disagreeing;
  disagreeing.f = {0.0, 0.0, 0.5, 0.5};
  const Probabilities r = apply_cost_heuristic(ProxyKind::outside, p, disagreeing);
  EXPECT_NEAR(r.p2, p.p2 * std::pow(0.5, 0.25), 1e-12);
  RayTypeFractions all_agree;
  all_agree.f = {0.5, 0, 0, 0.5};
  EXPECT_EQ(apply_cost_heuristic(ProxyKind::outside, p, all_agree).p2, 0.0);
  EXPECT_GE(apply_cost_heuristic(ProxyKind::outside, p, all_agree, 0.05).p2, 0.05);
}

// The control variate's variance formula against a simulation of the estimator itself, and
// its mean against V_avg (unbiased), for probabilities below 1 on both sides.
TEST(ControlVariate, VarianceFormulaAgreesWithSimulatedEstimator) {
  const CorrectionProbabilities q{0.3, 0.6};
  const Moments m = simulate(12, [&](double v_exact, double v_proxy, double pick) {
    const double trace = v_proxy == 1 ? q.after_miss : q.after_hit;
    return pick < trace ? v_proxy + (v_exact - v_proxy) / trace : v_proxy;
  });
  const double expected = control_variate_variance(simulated_fractions(), q);
  EXPECT_NEAR(expected, 0.6 * 0.4 + 0.1 * (1 / 0.3 - 1) + 0.2 * (1 / 0.6 - 1), 1e-12);
  EXPECT_NEAR(m.mean, 0.6, 5 * std::sqrt(expected / kSimulatedRays));  // 5 sigma
  EXPECT_NEAR(m.variance, expected, 0.01 * expected);
}

// Eq. 8 draws (a) or (b) before the proxy answers; after a miss both cost the same and (b)
// returns 0, so the control variate (which returns the proxy's answer there) never does
// worse at the same probability of tracing the mesh after a hit.
TEST(ControlVariate, NeverNoisierThanEquation8AtTheSameExactWork) {
  for (ProxyKind kind : {ProxyKind::outside, ProxyKind::inside, ProxyKind::general})
    for (const RayTypeFractions& fractions : grid(kind)) {
      const Probabilities p = optimal_probabilities(kind, fractions, {.floor = 0.05});
      // Eq. 8 traces the mesh after a hit with p2 and after a miss with p3.
      const CorrectionProbabilities q{p.p3, p.p2};
      EXPECT_LE(control_variate_variance(fractions, q), estimator_variance(fractions, p) + 1e-12)
          << kind_name(kind) << " " << fractions.f[0] << " " << fractions.f[1] << " " << fractions.f[2] << " " << fractions.f[3];
    }
}

TEST(ControlVariate, SidesTheKindRulesOutAreNeverTracedAndCostNothing) {
  EXPECT_EQ(equal_correction_probabilities(ProxyKind::outside).after_miss, 0.0);
  EXPECT_EQ(equal_correction_probabilities(ProxyKind::outside).after_hit, 0.5);
  EXPECT_EQ(equal_correction_probabilities(ProxyKind::inside).after_hit, 0.0);
  EXPECT_EQ(equal_correction_probabilities(ProxyKind::general).after_miss, 0.5);
  RayTypeFractions outside;  // no type 2: an outside proxy's misses are free
  outside.f = {0.5, 0, 0.2, 0.3};
  EXPECT_TRUE(std::isfinite(control_variate_variance(outside, {0.0, 0.5})));
  EXPECT_TRUE(std::isinf(control_variate_variance(outside, {0.5, 0.0})));
  EXPECT_EQ(control_variate_variance(RayTypeFractions{}, {0, 0}), 0.0);
}

TEST(ControlVariate, ProbabilitiesFollowTheRootOfTheDisagreement) {
  CorrectionEvidence evidence;
  // No evidence: p = 1/2, q = min(1, 2 sqrt(1/2)) = 1 on every needed side.
  EXPECT_EQ(correction_probabilities(ProxyKind::general, evidence).after_miss, 1.0);
  EXPECT_EQ(correction_probabilities(ProxyKind::general, evidence).after_hit, 1.0);
  EXPECT_EQ(correction_probabilities(ProxyKind::outside, evidence).after_miss, 0.0);
  EXPECT_EQ(correction_probabilities(ProxyKind::inside, evidence).after_hit, 0.0);
  // 99 hits that all agreed (umbra): p = 0.5 / 100, q = 2 sqrt(0.005) = 0.141.
  for (int i = 0; i < 99; ++i) evidence.add(/*proxy_blocked=*/true, /*mesh_blocked=*/true);
  EXPECT_NEAR(correction_probabilities(ProxyKind::outside, evidence).after_hit, 2 * std::sqrt(0.005), 1e-12);
  EXPECT_NEAR(correction_probabilities(ProxyKind::outside, evidence, {.scale = 1, .floor = 0.2}).after_hit, 0.2, 1e-12);
  // Many disagreements (penumbra): always traced.
  for (int i = 0; i < 60; ++i) evidence.add(true, false);
  EXPECT_EQ(correction_probabilities(ProxyKind::outside, evidence).after_hit, 1.0);
  // From probe counts: types 1..4 = (mesh, proxy) blocked, (mesh), (proxy), neither.
  RayTypeCounts counts;
  counts.counts = {40, 3, 7, 50};
  const CorrectionEvidence from = CorrectionEvidence::from(counts);
  EXPECT_EQ(from.seen[0], 53u);  // the proxy let through types 2 and 4
  EXPECT_EQ(from.disagreed[0], 3u);
  EXPECT_EQ(from.seen[1], 47u);  // the proxy blocked types 1 and 3
  EXPECT_EQ(from.disagreed[1], 7u);
}

// The learned, cost-aware choice: the q it returns minimises variance x cost over the
// box [floor, 1]^2 (checked against a grid of 201 x 201 points, which it may not beat), with
// the evidence's estimates drawn towards the prior by its weight, and it traces exactly
// exactly when that minimum is not below kLearnedPaysBelow x exact's variance x cost.
TEST(ControlVariate, LearnedChoiceMinimisesVarianceTimesCostAndTracesExactlyWhenItDoesNotPay) {
  struct Case {
    ProxyKind kind;
    std::array<std::uint64_t, 2> answered, seen, disagreed;
    CorrectionCosts costs;
    CorrectionPrior prior = {};
  };
  const std::vector<Case> cases = {
      {ProxyKind::general, {300, 100}, {40, 60}, {4, 30}, {.base = 10, .correction = 12, .exact = 18, .variance = 0.3}},
      {ProxyKind::outside, {900, 100}, {0, 100}, {0, 2}, {.base = 6, .correction = 14, .exact = 18, .variance = 0.05}},
      {ProxyKind::inside, {50, 50}, {50, 0}, {25, 0}, {.base = 12, .correction = 12, .exact = 16, .variance = 0.02}},
      {ProxyKind::general, {0, 0}, {0, 0}, {0, 0}, {.base = 3, .correction = 20, .exact = 21, .variance = 1.5}},
      {ProxyKind::general, {10, 990}, {5, 600}, {0, 599}, {.base = 9, .correction = 9, .exact = 12, .variance = 0.01}},
      // A pixel with no evidence yet, and one with a little, start from an instance's prior.
      {ProxyKind::outside, {0, 0}, {0, 0}, {0, 0}, {.base = 6, .correction = 14, .exact = 18, .variance = 0.05},
       {.share = {0.9, 0.1}, .disagreeing = {0.001, 0.02}, .weight = 16}},
      {ProxyKind::general, {3, 1}, {3, 1}, {1, 1}, {.base = 10, .correction = 12, .exact = 18, .variance = 0.3},
       {.share = {0.7, 0.3}, .disagreeing = {0.01, 0.4}, .weight = 16}},
  };
  for (const Case& c : cases) {
    CorrectionEvidence evidence;
    evidence.answered = c.answered, evidence.seen = c.seen, evidence.disagreed = c.disagreed;
    const CorrectionOptions options{.scale = 2, .floor = 0.05};
    const LearnedChoice choice = learned_choice(c.kind, evidence, c.costs, options, c.prior);
    // The product as the documentation states it, from the evidence and the prior.
    const double n = static_cast<double>(c.answered[0] + c.answered[1]);
    auto product = [&](double q0, double q1) {
      double variance = c.costs.variance, cost = c.costs.base;
      const std::array<double, 2> q = {q0, q1};
      for (std::size_t i = 0; i < 2; ++i) {
        if (q[i] == 0) continue;
        const double w = c.prior.weight;
        const double s = (static_cast<double>(c.answered[i]) + w * c.prior.share[i]) / (n + w);
        const double p = (static_cast<double>(c.disagreed[i]) + w * c.prior.disagreeing[i]) / (static_cast<double>(c.seen[i]) + w);
        variance += s * p * (1 / q[i] - 1);
        cost += c.costs.correction * s * q[i];
      }
      return variance * cost;
    };
    EXPECT_EQ(choice.q.after_miss == 0, c.kind == ProxyKind::outside);
    EXPECT_EQ(choice.q.after_hit == 0, c.kind == ProxyKind::inside);
    const double chosen = product(choice.q.after_miss, choice.q.after_hit);
    double grid = std::numeric_limits<double>::infinity();
    for (int a = 0; a <= 200; ++a)
      for (int b = 0; b <= 200; ++b) {
        const double q0 = c.kind == ProxyKind::outside ? 0.0 : 0.05 + 0.95 * a / 200.0;
        const double q1 = c.kind == ProxyKind::inside ? 0.0 : 0.05 + 0.95 * b / 200.0;
        grid = std::min(grid, product(q0, q1));
      }
    EXPECT_LE(chosen, grid * (1 + 1e-12)) << "case " << (&c - cases.data());
    EXPECT_NEAR(choice.predicted_ratio, chosen / (c.costs.variance * c.costs.exact), 1e-12 * choice.predicted_ratio);
    EXPECT_EQ(choice.trace_exactly, !(choice.predicted_ratio < kLearnedPaysBelow));
    EXPECT_TRUE(choice.can_pay);  // every case's proxy query is cheaper than the exact one
  }
  // The prior decides a pixel with no evidence: the cheap outside proxy, rarely wrong,
  // pays; the same proxy said to block most segments, wrongly on 90 % of them, does not.
  const CorrectionCosts cheap{.base = 6, .correction = 14, .exact = 18, .variance = 0.05};
  EXPECT_FALSE(learned_choice(ProxyKind::outside, {}, cheap, {}, {.share = {0.9, 0.1}, .disagreeing = {0.001, 0.02}, .weight = 16})
                   .trace_exactly);
  EXPECT_TRUE(learned_choice(ProxyKind::outside, {}, cheap, {}, {.share = {0.2, 0.8}, .disagreeing = {0.001, 0.9}, .weight = 16})
                  .trace_exactly);
  // A proxy query that costs what the exact one does never pays, however well it agrees.
  CorrectionEvidence agreeing;
  agreeing.answered = {1000, 1000}, agreeing.seen = {1000, 1000};
  const LearnedChoice costly = learned_choice(ProxyKind::general, agreeing, {.base = 10, .correction = 8, .exact = 10, .variance = 0.2});
  EXPECT_TRUE(costly.trace_exactly);
  EXPECT_FALSE(costly.can_pay);  // nothing the pixel could learn would change that: no exploring
  // A cheap outside proxy that has never been wrong, in open light: the proxy alone.
  CorrectionEvidence open;
  open.answered = {1000, 0};
  const LearnedChoice free = learned_choice(ProxyKind::outside, open, {.base = 4, .correction = 8, .exact = 10, .variance = 0.2});
  EXPECT_FALSE(free.trace_exactly);
  EXPECT_TRUE(free.can_pay);
  EXPECT_LT(free.predicted_ratio, 0.45);
  // A predicted gain within the cost model's error is not taken.
  const LearnedChoice marginal = learned_choice(ProxyKind::outside, open, {.base = 9.5, .correction = 8, .exact = 10, .variance = 0.2});
  EXPECT_GT(marginal.predicted_ratio, kLearnedPaysBelow);
  EXPECT_LT(marginal.predicted_ratio, 1.0);
  EXPECT_TRUE(marginal.trace_exactly);
  // A cheap proxy that disagrees half the time where the render has little other noise.
  CorrectionEvidence wrong;
  wrong.answered = {500, 500}, wrong.seen = {500, 500}, wrong.disagreed = {250, 250};
  EXPECT_TRUE(learned_choice(ProxyKind::general, wrong, {.base = 2, .correction = 9, .exact = 10, .variance = 0.25}).trace_exactly);
  // Costs it cannot use (none modelled, or no noise measured): the cost-blind rule, never exact.
  for (const CorrectionCosts& unusable : {CorrectionCosts{}, CorrectionCosts{.base = 1, .correction = 1, .exact = 1, .variance = 0},
                                          CorrectionCosts{.base = std::nan(""), .correction = 1, .exact = 1, .variance = 1}}) {
    const LearnedChoice blind = learned_choice(ProxyKind::general, wrong, unusable);
    EXPECT_FALSE(blind.trace_exactly);
    EXPECT_EQ(blind.q.after_miss, correction_probabilities(ProxyKind::general, wrong).after_miss);
    EXPECT_EQ(blind.q.after_hit, correction_probabilities(ProxyKind::general, wrong).after_hit);
  }
}

}  // namespace
}  // namespace visproxy
