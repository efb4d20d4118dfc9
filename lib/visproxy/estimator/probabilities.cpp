// Optimal probabilities of the stochastic visibility estimator: Billen, Lagae, Dutre,
// "Probabilistic visibility evaluation using geometry proxies", sections 3.2-4.2
// (eq. 14/16 for the variance, 22-24 for the cost heuristic; the closed forms here are
// written without the singularities of the printed ones, see probabilities.h).

#include "visproxy/estimator/probabilities.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "visproxy/estimator/golden_section.h"

namespace visproxy {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

bool needs_p2(ProxyKind kind) { return kind != ProxyKind::inside; }
bool needs_p3(ProxyKind kind) { return kind != ProxyKind::outside; }

double term(double weight, double probability) {
  if (weight == 0) return 0;
  return probability > 0 ? weight / probability : kInfinity;
}

// a / (a + b) for non-negative a, b, and 1 when both are 0.
double share(double a, double b) { return a + b > 0 ? a / (a + b) : 1.0; }

// Mixes the needed terms with a uniform choice among them so that each is at least `floor`.
Probabilities apply_floor(ProxyKind kind, Probabilities p, double floor) {
  if (floor <= 0) return p;
  const int needed = 1 + (needs_p2(kind) ? 1 : 0) + (needs_p3(kind) ? 1 : 0);
  floor = std::min(floor, 1.0 / needed);
  const double keep = 1.0 - needed * floor;
  p.p1 = keep * p.p1 + floor;
  p.p2 = needs_p2(kind) ? keep * p.p2 + floor : 0.0;
  p.p3 = needs_p3(kind) ? keep * p.p3 + floor : 0.0;
  return p;
}

}  // namespace

RayTypeFractions RayTypeFractions::from(const RayTypeCounts& counts) {
  RayTypeFractions fractions;
  const std::uint64_t total = counts.total();
  if (total == 0) return fractions;
  for (int i = 0; i < 4; ++i) fractions.f[i] = static_cast<double>(counts.counts[i]) / static_cast<double>(total);
  return fractions;
}

double RayTypeFractions::f_hit() const { return f[0] + f[1] > 0 ? f[0] / (f[0] + f[1]) : 1.0; }
double RayTypeFractions::f_miss() const { return f[2] + f[3] > 0 ? f[3] / (f[2] + f[3]) : 1.0; }

double estimator_variance(const RayTypeFractions& fractions, const Probabilities& p) {
  if (fractions.empty()) return 0;
  const auto& f = fractions.f;
  const double v = fractions.v_avg();
  const double second_moment = term(f[1] + f[3], p.p1) + term(f[2], p.p2) + term(f[1], p.p3);
  return std::isinf(second_moment) ? kInfinity : std::max(0.0, second_moment - v * v);
}

Probabilities equal_probabilities(ProxyKind kind) {
  switch (kind) {
    case ProxyKind::outside: return {0.5, 0.5, 0.0};
    case ProxyKind::inside: return {0.5, 0.0, 0.5};
    case ProxyKind::general: break;
  }
  return {1.0 / 3, 1.0 / 3, 1.0 / 3};
}

Probabilities optimal_probabilities(ProxyKind kind, const RayTypeFractions& fractions,
                                    const OptimalProbabilityOptions& options) {
  if (fractions.empty()) return equal_probabilities(kind);
  Probabilities p;
  switch (kind) {
    case ProxyKind::outside: {
      const double f_miss = fractions.f_miss();
      p.p1 = share(std::sqrt(f_miss), std::sqrt(1 - f_miss));
      p.p2 = 1 - p.p1;
      p.p3 = 0;
      break;
    }
    case ProxyKind::inside: {
      const double v = fractions.v_avg();
      const double f_hit = fractions.f_hit();
      const double s = 1 - f_hit * (1 - v);
      // (s - sqrt((1 - f_hit)(1 - V) s)) / V, rewritten with s - (1 - f_hit)(1 - V) = V.
      p.p1 = share(std::sqrt(s), std::sqrt(std::max(0.0, (1 - f_hit) * (1 - v))));
      p.p2 = 0;
      p.p3 = 1 - p.p1;
      break;
    }
    case ProxyKind::general: {
      const auto& f = fractions.f;
      const double a = std::sqrt(f[1] + f[3]), b = std::sqrt(f[2]), c = std::sqrt(f[1]);
      const double sum = a + b + c;
      if (sum == 0) {
        p = {1, 0, 0};
      } else {
        p.p2 = b / sum;
        p.p3 = c / sum;
        p.p1 = 1 - p.p2 - p.p3;
      }
      break;
    }
  }
  return apply_floor(kind, p, options.floor);
}

Probabilities minimise_variance_numerically(ProxyKind kind, const RayTypeFractions& fractions) {
  if (fractions.empty()) return equal_probabilities(kind);
  constexpr double lo = 1e-12, hi = 1 - 1e-12;
  switch (kind) {
    case ProxyKind::outside: {
      const double p1 = golden_section(
          [&](double x) { return estimator_variance(fractions, {x, 1 - x, 0}); }, lo, hi);
      return {p1, 1 - p1, 0};
    }
    case ProxyKind::inside: {
      const double p1 = golden_section(
          [&](double x) { return estimator_variance(fractions, {x, 0, 1 - x}); }, lo, hi);
      return {p1, 0, 1 - p1};
    }
    case ProxyKind::general: break;
  }
  // min over p1 of (min over p2 of Var(p1, p2, 1 - p1 - p2)): both convex.
  auto best_p2 = [&](double p1) {
    return golden_section([&](double x) { return estimator_variance(fractions, {p1, x, 1 - p1 - x}); }, lo * (1 - p1),
                          (1 - p1) * hi);
  };
  const double p1 = golden_section(
      [&](double x) {
        const double p2 = best_p2(x);
        return estimator_variance(fractions, {x, p2, 1 - x - p2});
      },
      lo, hi);
  const double p2 = best_p2(p1);
  return {p1, p2, 1 - p1 - p2};
}

Probabilities apply_cost_heuristic(ProxyKind kind, const Probabilities& probabilities,
                                   const RayTypeFractions& fractions, double floor) {
  if (fractions.empty()) return probabilities;
  const double agreeing = fractions.f[0] + fractions.f[3];
  const double scale = std::pow(std::max(0.0, 1 - agreeing), 0.25);
  Probabilities p = probabilities;
  p.p2 *= scale;
  p.p3 *= scale;
  p.p1 = 1 - p.p2 - p.p3;
  return apply_floor(kind, p, floor);
}

double control_variate_variance(const RayTypeFractions& fractions, const CorrectionProbabilities& q) {
  if (fractions.empty()) return 0;
  const auto& f = fractions.f;
  const double v = fractions.v_avg();
  auto roulette = [](double weight, double probability) {  // weight (1/q - 1)
    if (weight == 0) return 0.0;
    return probability > 0 ? weight * (1 / probability - 1) : kInfinity;
  };
  const double extra = roulette(f[1], q.after_miss) + roulette(f[2], q.after_hit);
  return std::isinf(extra) ? kInfinity : v * (1 - v) + extra;
}

CorrectionProbabilities equal_correction_probabilities(ProxyKind kind) {
  return {kind == ProxyKind::outside ? 0.0 : 0.5, kind == ProxyKind::inside ? 0.0 : 0.5};
}

CorrectionEvidence CorrectionEvidence::from(const RayTypeCounts& counts) {
  const auto& c = counts.counts;  // types 1..4: (V, V') = (0, 0), (0, 1), (1, 0), (1, 1)
  CorrectionEvidence evidence;
  evidence.seen = {c[1] + c[3], c[0] + c[2]};
  evidence.disagreed = {c[1], c[2]};
  return evidence;
}

CorrectionProbabilities correction_probabilities(ProxyKind kind, const CorrectionEvidence& evidence,
                                                 const CorrectionOptions& options) {
  auto side = [&](int i) {
    const double p = (static_cast<double>(evidence.disagreed[static_cast<std::size_t>(i)]) + 0.5) /
                     (static_cast<double>(evidence.seen[static_cast<std::size_t>(i)]) + 1.0);
    return std::clamp(options.scale * std::sqrt(p), std::clamp(options.floor, 0.0, 1.0), 1.0);
  };
  return {kind == ProxyKind::outside ? 0.0 : side(0), kind == ProxyKind::inside ? 0.0 : side(1)};
}

CorrectionPrior CorrectionPrior::from(const CorrectionEvidence& evidence, double weight) {
  CorrectionPrior prior{.weight = weight};
  const double answered = static_cast<double>(evidence.answered[0] + evidence.answered[1]);
  for (std::size_t side = 0; side < 2; ++side) {
    prior.share[side] = (static_cast<double>(evidence.answered[side]) + 0.5) / (answered + 1);
    prior.disagreeing[side] = (static_cast<double>(evidence.disagreed[side]) + 0.5) / (static_cast<double>(evidence.seen[side]) + 1);
  }
  return prior;
}

LearnedChoice learned_choice(ProxyKind kind, const CorrectionEvidence& evidence, const CorrectionCosts& costs,
                             const CorrectionOptions& options, const CorrectionPrior& prior) {
  LearnedChoice choice;
  const bool usable = std::isfinite(costs.base) && std::isfinite(costs.correction) && std::isfinite(costs.exact) &&
                      std::isfinite(costs.variance) && costs.base > 0 && costs.correction > 0 && costs.exact > 0 &&
                      costs.variance > 0;
  if (!usable) {
    choice.q = correction_probabilities(kind, evidence, options);
    return choice;
  }
  const std::array<bool, 2> needed = {kind != ProxyKind::outside, kind != ProxyKind::inside};
  const double answered = static_cast<double>(evidence.answered[0] + evidence.answered[1]);
  std::array<double, 2> s{}, p{};
  double disagreeing = 0;  // sum_i s_i p_i
  for (std::size_t i = 0; i < 2; ++i) {
    s[i] = (static_cast<double>(evidence.answered[i]) + prior.weight * prior.share[i]) / (answered + prior.weight);
    p[i] = needed[i] ? (static_cast<double>(evidence.disagreed[i]) + prior.weight * prior.disagreeing[i]) /
                           (static_cast<double>(evidence.seen[i]) + prior.weight)
                     : 0.0;
    disagreeing += s[i] * p[i];
  }
  const double floor = std::clamp(options.floor, 1e-6, 1.0);
  const double factor = 0.5 * options.scale;
  auto product = [&](const std::array<double, 2>& q) {  // variance x cost
    double variance = costs.variance - disagreeing, cost = costs.base;
    for (std::size_t i = 0; i < 2; ++i)
      if (needed[i]) variance += s[i] * p[i] / q[i], cost += costs.correction * s[i] * q[i];
    return variance * cost;
  };
  // The optimum with both sides free is q_i = sqrt(p_i base / (correction (T - sum s p))); a
  // side held at the floor or at 1 moves its terms into those constants. Every choice of
  // held sides is tried and the least product kept.
  double best = kInfinity;
  std::array<double, 2> best_q{};
  for (int held0 = 0; held0 < 3; ++held0)
    for (int held1 = 0; held1 < 3; ++held1) {
      const std::array<int, 2> held = {held0, held1};  // 0 free, 1 at the floor, 2 at 1
      std::array<double, 2> q{};
      double rest = costs.variance - disagreeing, base = costs.base;
      for (std::size_t i = 0; i < 2; ++i)
        if (needed[i] && held[i] != 0) {
          q[i] = held[i] == 1 ? floor : 1.0;
          rest += s[i] * p[i] / q[i], base += costs.correction * s[i] * q[i];
        }
      const double t = rest > 0 ? factor * std::sqrt(base / (costs.correction * rest)) : kInfinity;
      for (std::size_t i = 0; i < 2; ++i)
        if (needed[i] && held[i] == 0) q[i] = std::clamp(t * std::sqrt(p[i]), floor, 1.0);
      const double value = product(q);
      if (value < best) best = value, best_q = q;
    }
  choice.q = {best_q[0], best_q[1]};
  choice.predicted_ratio = best / (costs.variance * costs.exact);
  // The control variate's variance is never below T (q <= 1), and its cost never below the
  // proxy query with every needed side corrected at the floor: if that is not below
  // kLearnedPaysBelow x exact's cost, no evidence can make the proxy pay.
  double least_cost = costs.base;
  for (std::size_t i = 0; i < 2; ++i)
    if (needed[i]) least_cost += costs.correction * s[i] * floor;
  choice.can_pay = least_cost < kLearnedPaysBelow * costs.exact;
  choice.trace_exactly = !(choice.predicted_ratio < kLearnedPaysBelow);
  return choice;
}

}  // namespace visproxy
