#pragma once
// The unbiased stochastic visibility estimator's probabilities and variance
// (Billen, Lagae, Dutre: "Probabilistic visibility evaluation using geometry proxies").
//
// A shadow ray xy falls in one of four types by the exact visibility V (mesh P) and the
// proxy's visibility V' (proxy P'), V = 1 meaning unoccluded:
//   type 1: V = 0, V' = 0    type 2: V = 0, V' = 1    type 3: V = 1, V' = 0    type 4: V = 1, V' = 1
// The estimator (eq. 8) picks one of three terms with probabilities p1 + p2 + p3 = 1:
//   (a) V' / p1   (b) (1 - V') V / p2   (c) -V' (1 - V) / p3
// Its variance over a population of rays with type fractions f1..f4 is (eq. 14, 16)
//   Var = w1 / p1 + w2 / p2 + w3 / p3 - V_avg^2,   w1 = f2 + f4,  w2 = f3,  w3 = f2,
// with V_avg = f3 + f4. Every term with a non-zero weight needs a non-zero probability:
// a term that is never chosen while its rays exist makes the estimate biased.

#include <array>
#include <cstdint>

#include "visproxy/core/proxy_kind.h"

namespace visproxy {

/// How many rays of each type were seen: counts[0] is type 1, ..., counts[3] is type 4.
struct RayTypeCounts {
  std::array<std::uint64_t, 4> counts{};

  std::uint64_t total() const { return counts[0] + counts[1] + counts[2] + counts[3]; }
  void add(bool mesh_blocked, bool proxy_blocked) {
    ++counts[mesh_blocked ? (proxy_blocked ? 0 : 1) : (proxy_blocked ? 2 : 3)];
  }
};

/// Fractions f1..f4 of the ray types; they sum to 1 unless no ray was seen (all 0).
struct RayTypeFractions {
  std::array<double, 4> f{};

  static RayTypeFractions from(const RayTypeCounts& counts);
  bool empty() const { return f[0] + f[1] + f[2] + f[3] == 0; }
  double v_avg() const { return f[2] + f[3]; }
  /// f_hit = f1 / (f1 + f2): how often the proxy blocks a ray the mesh blocks; 1 when
  /// no ray is blocked by the mesh (nothing to miss).
  double f_hit() const;
  /// f_miss = f4 / (f3 + f4): how often the proxy lets through a ray the mesh lets
  /// through; 1 when every ray is blocked by the mesh.
  double f_miss() const;
};

struct Probabilities {
  double p1 = 1.0 / 3;  ///< trace the proxy only
  double p2 = 1.0 / 3;  ///< trace the proxy, and the mesh when the proxy was hit
  double p3 = 1.0 / 3;  ///< trace the proxy, and the mesh when the proxy was missed
};

/// The estimator's variance per ray (eq. 14/16) for rays with `fractions` drawn with
/// `probabilities`. A term with weight 0 costs nothing whatever its probability; a term
/// with positive weight and probability 0 gives +infinity (the estimate would be biased).
/// 0 for an empty population.
double estimator_variance(const RayTypeFractions& fractions, const Probabilities& probabilities);

/// Equal probabilities among the terms the kind needs: outside {1/2, 1/2, 0}, inside
/// {1/2, 0, 1/2}, general {1/3, 1/3, 1/3}.
Probabilities equal_probabilities(ProxyKind kind);

struct OptimalProbabilityOptions {
  /// Lower bound of every probability the kind needs (p1 always; p2 unless inside; p3
  /// unless outside), so that rays of a type the probe rays did not see still have a
  /// term that accounts for them. 0 gives the exact minimiser of eq. 16; a renderer that
  /// chooses probabilities from a few probe rays needs a positive floor to stay unbiased.
  double floor = 0;
};

/// The probabilities that minimise eq. 16 among those the kind allows.
///   outside (p3 = 0): p1 = sqrt(f_miss) / (sqrt(f_miss) + sqrt(1 - f_miss));
///   inside (p2 = 0), s = 1 - f_hit (1 - V_avg): p1 = (s - sqrt((1 - f_hit)(1 - V_avg) s)) / V_avg;
///   general: eq. 14 is a sum of w_i / p_i, minimised on the simplex by p_i = sqrt(w_i) / sum_j sqrt(w_j).
/// The outside and inside forms are that same rule with w3 = 0 or w2 = 0, evaluated in a
/// way that has no singularity (the paper's outside form divides 0 by 0 at f_miss = 1/2,
/// its inside form at V_avg = 0). When every needed weight is 0 (all rays of type 1, or
/// all of type 4) any choice has zero variance and p1 = 1 (cheapest). An empty population
/// gives equal_probabilities(kind). The result is always finite and sums to 1.
Probabilities optimal_probabilities(ProxyKind kind, const RayTypeFractions& fractions,
                                    const OptimalProbabilityOptions& options = {});

/// Minimises eq. 16 numerically over the probabilities the kind allows (golden-section
/// search along p1 for outside and inside; nested golden-section search over (p1, p2) for
/// general). Slower than optimal_probabilities and independent of its closed forms: the
/// two are checked against each other.
Probabilities minimise_variance_numerically(ProxyKind kind, const RayTypeFractions& fractions);

/// The cost heuristic (eq. 22-24): p2 and p3 scaled by (1 - (f1 + f4))^(1/4), p1 takes
/// the rest, so that rays where proxy and mesh agree mostly trace the proxy alone. The
/// scaled p2 and p3 are then raised to `floor` if the kind needs them (see
/// OptimalProbabilityOptions::floor).
Probabilities apply_cost_heuristic(ProxyKind kind, const Probabilities& probabilities,
                                   const RayTypeFractions& fractions, double floor = 0);

/// The proxy as a control variate, an alternative to eq. 8 that always traces the proxy
/// and corrects its answer V' with the exact geometry under Russian roulette:
///   estimate = V' + (V - V') [u < q] / q,   q = after_miss when V' = 1, after_hit when V' = 0.
/// Its mean is V for any q > 0, and for q = 0 on the side where V cannot differ from V'
/// (an outside proxy's misses, an inside proxy's hits: the claims `visproxy verify` proves).
/// Eq. 8 draws its term before the proxy answers; here the proxy's answer picks the
/// probability, so a ray that misses an outside proxy is 1 at no cost and without the
/// noise of eq. 8's (a) term (Rao-Blackwellisation over the terms whose cost is the same).
struct CorrectionProbabilities {
  double after_miss = 0.5;  ///< trace the mesh when the proxy lets the ray through (V' = 1)
  double after_hit = 0.5;   ///< trace the mesh when the proxy blocks it (V' = 0)
};

/// Variance per ray of the control-variate estimator: Var(V) + f2 (1/after_miss - 1) +
/// f3 (1/after_hit - 1), with Var(V) = V_avg (1 - V_avg). +infinity when a side with
/// disagreeing rays is never traced; 0 for an empty population.
double control_variate_variance(const RayTypeFractions& fractions, const CorrectionProbabilities& q);

/// 1/2 on each side the kind needs: outside {0, 1/2}, inside {1/2, 0}, general {1/2, 1/2}.
CorrectionProbabilities equal_correction_probabilities(ProxyKind kind);

/// What is known of the rays on each side of the proxy's answer: how many were seen with
/// the mesh traced, and on how many the mesh disagreed with the proxy. Index 0: the proxy
/// let the ray through (V' = 1); 1: the proxy blocked it (V' = 0).
struct CorrectionEvidence {
  std::array<std::uint64_t, 2> seen{}, disagreed{};

  /// From probe rays, each of which traced both.
  static CorrectionEvidence from(const RayTypeCounts& counts);
  /// How many segments the proxy answered on each side, traced or not (the learned,
  /// cost-aware rule weighs its sides by them; correction_probabilities() does not use them).
  std::array<std::uint64_t, 2> answered{};

  void add(bool proxy_blocked, bool mesh_blocked) {
    ++seen[proxy_blocked ? 1 : 0];
    disagreed[proxy_blocked ? 1 : 0] += proxy_blocked != mesh_blocked ? 1 : 0;
  }
  void answer(bool proxy_blocked) { ++answered[proxy_blocked ? 1 : 0]; }
};

struct CorrectionOptions {
  /// kappa: q = kappa sqrt(p) on a side whose rays disagree with probability p.
  double scale = 2;
  double floor = 0.05;  ///< least q on each side the kind needs
};

/// The probability of tracing the mesh on each side the kind needs:
///   q = clamp(scale * sqrt(p), floor, 1),  p = (disagreed + 1/2) / (seen + 1)
/// (the Krichevsky-Trofimov estimate of the disagreeing fraction: a side with no evidence
/// gets p = 1/2, one whose rays all agreed so far a small but positive p). The root is the
/// minimiser of one side's added variance p (1/q - 1) plus lambda q, its cost in exact
/// queries, with scale = 1 / sqrt(lambda): rays where proxy and mesh always agree (umbrae,
/// open space) are rarely traced, those where they often disagree (penumbrae) always.
/// Sides the kind does not need (an outside proxy's misses, an inside proxy's hits) get 0.
CorrectionProbabilities correction_probabilities(ProxyKind kind, const CorrectionEvidence& evidence,
                                                 const CorrectionOptions& options = {});

/// What a segment costs a render, in one unit of modelled work (RenderWorld's query model,
/// render/world/query_costs.h), and how noisy the render is without the proxy: what the
/// learned control variate weighs its corrections and its proxy against.
struct CorrectionCosts {
  double base = 0;        ///< the sample's share of camera ray and shading, plus the proxy query
  double correction = 0;  ///< one correction: the exact geometry the proxy stood for
  double exact = 0;       ///< the sample's share of camera ray and shading, plus the exact query
  /// The exact render's variance per segment, relative to the mean squared unoccluded
  /// contribution of a segment: the noise every segment carries before a proxy adds any.
  double variance = 0;
};

/// What learned_choice() assumes of a pixel before its own evidence: the share of segments
/// the proxy answers each way (let through, blocked) and the fraction of each it answers
/// wrongly, worth `weight` segments of the pixel's own. The default, half and half worth one
/// segment, is the Krichevsky-Trofimov estimate; a render gives each instance the rates of
/// its segments traced before the render.
struct CorrectionPrior {
  std::array<double, 2> share = {0.5, 0.5};
  std::array<double, 2> disagreeing = {0.5, 0.5};
  double weight = 1;
  /// The rates of `evidence` (Krichevsky-Trofimov estimates: never exactly 0 or 1), worth `weight`.
  static CorrectionPrior from(const CorrectionEvidence& evidence, double weight);
};

/// learned_choice() gives the control variate a pixel only where its predicted variance x
/// cost is below this fraction of exact's: the modelled costs (render/world/query_costs.h)
/// put the shadow queries' share of a sample's time above what renders of the bench scenes
/// measure (by up to 1.5x on cow-field), so a smaller predicted gain may be none.
inline constexpr double kLearnedPaysBelow = 0.9;

/// A segment the learned choice traces exactly also traces the proxy, to keep learning,
/// while the proxy could pay (LearnedChoice::can_pay) and the evidence holds fewer than
/// kLearnedExploreUntil answers (learned_keeps_exploring()): one such segment in
/// kLearnedExploreOneIn. Its answer is exact either way.
inline constexpr std::uint64_t kLearnedExploreUntil = 16;
inline constexpr int kLearnedExploreOneIn = 8;
inline bool learned_keeps_exploring(bool can_pay, const CorrectionEvidence& evidence) {
  return can_pay && evidence.answered[0] + evidence.answered[1] < kLearnedExploreUntil;
}

/// The learned, cost-aware choice for one segment: whether to trace the mesh exactly, and
/// if not, the control variate's probabilities.
struct LearnedChoice {
  bool trace_exactly = false;
  CorrectionProbabilities q;
  double predicted_ratio = 1;  ///< (variance x cost) of the control variate over exact's: >= 1 chooses exact
  /// Whether any evidence could make the proxy pay: its query, with every needed side
  /// corrected at the floor, costs less than kLearnedPaysBelow x the exact query (false:
  /// nothing to learn).
  bool can_pay = true;
};

/// From the evidence (answered[i]: the share s_i of each side; seen/disagreed: the
/// disagreeing fraction p_i, each with the prior's pseudo-segments added) and the costs, the q that
/// minimises the control variate's variance x cost,
///   (T + sum_i s_i p_i (1/q_i - 1)) x (base + correction sum_i s_i q_i),   T = costs.variance,
/// over q_i in [floor, 1]: with both sides free, q_i = sqrt(p_i base / (correction (T - sum_i
/// s_i p_i))) (1 when the bracket is not positive); a side held at the floor or at 1 moves
/// its terms into those constants, and the least product over the choices of held sides is
/// kept. options.scale / 2 multiplies the free sides' q (the default 2: the optimum).
/// trace_exactly when that product is not below kLearnedPaysBelow x T x exact (exact's
/// variance x cost): the control variate would not pay for this pixel. Sides the kind does not need get q = 0 and
/// p = 0. Costs that are not all positive and finite, or T not positive, give the
/// cost-blind correction_probabilities() and never trace exactly.
LearnedChoice learned_choice(ProxyKind kind, const CorrectionEvidence& evidence, const CorrectionCosts& costs,
                             const CorrectionOptions& options = {}, const CorrectionPrior& prior = {});

}  // namespace visproxy
