#pragma once
// How much cheaper than tracing the mesh a proxy makes a visibility estimate, in each of
// the three ways a renderer can use it, predicted from the ray types it was measured on
// and the measured cost of a ray against each.
//
// A renderer estimates the mean visibility of shadow rays drawn from some population; the
// mesh alone gives each ray's V exactly, a variance of Var(V) = V_avg (1 - V_avg) per ray
// at a cost of c_mesh. A use of the proxy gives an unbiased estimate per ray with variance
// Var >= Var(V) at an expected cost c. At equal error the use needs Var / Var(V) times as
// many rays, so it is
//     efficiency = (Var(V) c_mesh) / (Var c)
// times as cheap as the mesh (1 / (variance x cost), relative to the mesh's). The uses:
//   control variate: V' + (V - V') [u < q] / q (probabilities.h); the proxy is always traced,
//     the mesh with probability q_miss after V' = 1 and q_hit after V' = 0:
//       Var = Var(V) + f2 (1/q_miss - 1) + f3 (1/q_hit - 1),
//       c = c_proxy + c_mesh (q_miss (f2 + f4) + q_hit (f1 + f3));
//   eq. 8 (term choice, Billen et al.): the proxy is always traced, the mesh after term (b)
//     when the proxy was hit and after term (c) when it was missed:
//       Var = eq. 16,   c = c_proxy + c_mesh (p2 (f1 + f3) + p3 (f2 + f4));
//   bounds (the exact answer): a proved outside proxy's miss proves V = 1, a proved inside
//     proxy's hit V = 0, and only the other rays trace the mesh:
//       Var = Var(V),   c = c_proxy + c_mesh (f1 + f3) (outside) or (f2 + f4) (inside).
// Each use is set up as well as it can be: the probabilities minimise Var x c, each needed
// one at least `floor` (as the renderer's adaptive and learned probabilities are), and a
// zero only where the proved kind makes it unbiased.

#include <array>
#include <cstdint>
#include <string>
#include <string_view>

#include "visproxy/core/proxy_kind.h"
#include "visproxy/estimator/probabilities.h"

namespace visproxy {

enum class ProxyUse { control_variate, term_choice, bounds };

/// "control variate", "eq. 8", "bounds".
std::string_view use_name(ProxyUse use);
/// "control_variate", "eq8", "bounds": the keys of the JSON that records them.
std::string_view use_key(ProxyUse use);

/// Wall time of one shadow ray, in nanoseconds on one core.
struct TraceCosts {
  double proxy_ns = 0;
  double mesh_ns = 0;
  /// How far the proxy's cost may lie from proxy_ns, relative to mesh_ns, by the spread
  /// of its timing (PairedTiming's least and greatest block ratio times mesh_ns); negative
  /// for "as measured" (proxy_ns). Only efficiency_interval reads them.
  double proxy_ns_low = -1;
  double proxy_ns_high = -1;
};

/// A use's free parameters: eq. 8's term probabilities, the control variate's correction
/// probabilities (the other is left at its default and unused).
struct UseSetting {
  Probabilities term;
  CorrectionProbabilities correction;
};

struct UsePrediction {
  ProxyUse use = ProxyUse::control_variate;
  /// Bounds needs a proved outside or inside proxy; the other uses are always possible.
  bool usable = true;
  std::string why_not;  ///< when not usable
  UseSetting setting;
  double variance = 0;    ///< per ray
  double ns_per_ray = 0;  ///< expected cost of one estimate
  double efficiency = 0;  ///< (Var(V) c_mesh) / (variance ns_per_ray); 0 when not usable
};

struct UseOptions {
  /// Least probability of every term (eq. 8) or correction (control variate) that the
  /// proved kind does not make unnecessary. The renderer's default is the same.
  double floor = 0.05;
};

/// The use at `setting` on rays of `fractions`. `proved` is the kind the proxy's claim is
/// proved for: outside or inside when `visproxy verify` found it to hold, general otherwise.
/// Efficiency when both variances are 0 (every ray blocked, or every ray free, and the
/// proxy exact on them): c_mesh / c; when only the mesh's is 0: 0.
UsePrediction predict_use_at(ProxyUse use, ProxyKind proved, const RayTypeFractions& fractions, const TraceCosts& costs,
                             const UseSetting& setting);

/// The use at its most efficient setting (minimum of variance x cost over the allowed
/// probabilities: exact along the one-parameter family the optimum lies on for the control
/// variate, golden-section search on a grid's best cell for eq. 8).
UsePrediction predict_use(ProxyUse use, ProxyKind proved, const RayTypeFractions& fractions, const TraceCosts& costs,
                          const UseOptions& options = {});

/// A use's efficiency over a whole render rather than over its shadow rays (Amdahl): when
/// testing shadow rays against the mesh takes the share `share` of a sample's time and
/// the use makes them `ray_efficiency` times as efficient with a variance
/// `variance_ratio` = Var / Var(V) times the mesh's (1 for bounds),
///     render = 1 / (variance_ratio (1 - share) + share / ray_efficiency).
/// The render's noise is taken to grow by the whole variance ratio: the most it can when
/// the ratio is at least 1 (visibility the render's only noise); any other noise (light
/// sampling, the integrator's) dilutes it, so the figure is a lower bound in that respect.
/// At share 1 it is ray_efficiency; at share 0, 1 / variance_ratio. 0 when ray_efficiency
/// is 0 or the variance ratio unbounded.
double render_efficiency(double ray_efficiency, double variance_ratio, double share);

/// The variance a use adds, over the exact answer, to the estimate of a shadow segment of
/// each ray type (index 0 is type 1, ..., 3 is type 4): E[V_est^2 | type] - V^2 under the
/// use's setting:
///   eq. 8:            {0, 1/p1 + 1/p3, 1/p2 - 1, 1/p1 - 1}
///   control variate:  {0, 1/q_miss - 1, 1/q_hit - 1, 0}
///   bounds:           {0, 0, 0, 0}
/// +infinity where the type needs a probability that is 0 (the estimate would be biased
/// for it; a proved kind rules such types out). Weighted by the type fractions and added
/// to Var(V), it gives eq. 14 and the control variate's variance.
std::array<double, 4> added_variance_by_type(ProxyUse use, const UseSetting& setting);

/// The render's noise with a use over the exact render's: 1 + sum_t weighted[t] added[t] /
/// exact, where weighted[t] is the mean, over a render's camera samples, of the squared
/// contribution (per colour channel) of the samples whose shadow segment has type t, and
/// `exact` the mean variance of one camera sample of the exact render within its pixel.
/// Types without weight add nothing whatever their `added`; 1 when nothing is added.
/// +infinity when something is added to a render without noise.
double render_variance_ratio(const std::array<double, 4>& weighted, const std::array<double, 4>& added, double exact);

/// A use's efficiency over a whole render from what it does to the render's time and noise:
///     1 / (render_variance_ratio ((1 - share) + share cost_ratio)),
/// `cost_ratio` being the use's cost per shadow ray over the mesh's and `share` the share
/// of a sample's time the mesh's shadow tests take. 0 for an unbounded variance ratio.
double render_efficiency_of(double cost_ratio, double render_variance_ratio, double share);

/// The render's efficiency over exact's from the render's own time with the use over
/// exact's (a pass's, timed against exact's) and its variance ratio: 1 / (variance ratio x
/// time ratio). 0 for an infinite or non-positive variance ratio or a non-positive time.
double render_efficiency_timed(double time_ratio, double render_variance_ratio);

struct Interval {
  double lower = 0;
  double upper = 0;
};

/// A 95 % interval for predict_use_at's efficiency over the sampling of the rays: the
/// central 95 % of the efficiency under `draws` draws of the fractions from their posterior
/// (Dirichlet with the counts plus 1/2 on every type the proved kind allows; an outside
/// proxy's type 2 and an inside proxy's type 3 are impossible, not just unseen), seeded. The
/// timing's spread is in it too: the lower end is the 2.5 % quantile with the proxy at its
/// dearest (costs.proxy_ns_high), the upper the 97.5 % quantile at its cheapest
/// (costs.proxy_ns_low), on the same draws; efficiency falls as the proxy's cost rises.
Interval efficiency_interval(ProxyUse use, ProxyKind proved, const RayTypeCounts& counts, const TraceCosts& costs,
                             const UseSetting& setting, std::uint64_t seed, int draws = 2000);

}  // namespace visproxy
