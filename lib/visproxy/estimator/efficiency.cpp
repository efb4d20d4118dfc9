// Predicted efficiency of a proxy's uses against the mesh alone (see efficiency.h for the
// model: variance and expected cost per ray of each use, from the ray-type fractions).

#include "visproxy/estimator/efficiency.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <vector>

#include "visproxy/core/random.h"
#include "visproxy/estimator/golden_section.h"

namespace visproxy {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// The minimum of f on [lo, hi]: the best of `cells` + 1 evenly spaced points, then a
// golden-section search between its neighbours (f need not be convex on the whole range).
double minimise(const std::function<double(double)>& f, double lo, double hi, int cells = 128) {
  if (!(hi > lo)) return lo;
  int best = 0;
  double best_value = kInfinity;
  for (int i = 0; i <= cells; ++i) {
    const double value = f(lo + (hi - lo) * i / cells);
    if (value < best_value) best_value = value, best = i;
  }
  const double x = golden_section(f, lo + (hi - lo) * std::max(0, best - 1) / cells,
                                  lo + (hi - lo) * std::min(cells, best + 1) / cells, 1e-12 * (hi - lo));
  return f(x) <= best_value ? x : lo + (hi - lo) * best / cells;
}

double relative_efficiency(double mesh_variance, double mesh_ns, double variance, double ns) {
  if (std::isinf(variance) || !(ns > 0)) return 0;
  if (variance <= 0) return mesh_variance <= 0 ? mesh_ns / ns : kInfinity;
  return mesh_variance * mesh_ns / (variance * ns);
}

// Standard normal and gamma variates from the seeded generator (Box-Muller; Marsaglia and
// Tsang, with the shape raised by one and U^(1/shape) for shapes below 1).
double normal(Random& random) {
  const double u = 1 - random.uniform(), v = random.uniform();
  return std::sqrt(-2 * std::log(u)) * std::cos(2 * std::numbers::pi * v);
}

double gamma(Random& random, double shape) {
  if (shape <= 0) return 0;
  if (shape < 1) return gamma(random, shape + 1) * std::pow(1 - random.uniform(), 1 / shape);
  const double d = shape - 1.0 / 3, c = 1 / std::sqrt(9 * d);
  for (;;) {
    double x, v;
    do {
      x = normal(random);
      v = 1 + c * x;
    } while (v <= 0);
    v = v * v * v;
    const double u = 1 - random.uniform();
    if (std::log(u) < 0.5 * x * x + d - d * v + d * std::log(v)) return d * v;
  }
}

}  // namespace

std::string_view use_name(ProxyUse use) {
  switch (use) {
    case ProxyUse::control_variate: return "control variate";
    case ProxyUse::term_choice: return "eq. 8";
    case ProxyUse::bounds: return "bounds";
  }
  return "?";
}

std::string_view use_key(ProxyUse use) {
  switch (use) {
    case ProxyUse::control_variate: return "control_variate";
    case ProxyUse::term_choice: return "eq8";
    case ProxyUse::bounds: return "bounds";
  }
  return "?";
}

UsePrediction predict_use_at(ProxyUse use, ProxyKind proved, const RayTypeFractions& fractions, const TraceCosts& costs,
                             const UseSetting& setting) {
  UsePrediction prediction;
  prediction.use = use, prediction.setting = setting;
  const auto& f = fractions.f;
  const double mesh_variance = fractions.v_avg() * (1 - fractions.v_avg());
  const double proxy_hit = f[0] + f[2], proxy_miss = f[1] + f[3];
  if (fractions.empty()) {
    prediction.usable = false, prediction.why_not = "no rays measured";
    return prediction;
  }
  if (!(costs.mesh_ns > 0) || !(costs.proxy_ns >= 0)) {
    prediction.usable = false, prediction.why_not = "cost per ray not measured";
    return prediction;
  }
  switch (use) {
    case ProxyUse::control_variate:
      prediction.variance = control_variate_variance(fractions, setting.correction);
      prediction.ns_per_ray =
          costs.proxy_ns + costs.mesh_ns * (setting.correction.after_miss * proxy_miss + setting.correction.after_hit * proxy_hit);
      break;
    case ProxyUse::term_choice:
      prediction.variance = estimator_variance(fractions, setting.term);
      prediction.ns_per_ray = costs.proxy_ns + costs.mesh_ns * (setting.term.p2 * proxy_hit + setting.term.p3 * proxy_miss);
      break;
    case ProxyUse::bounds:
      if (proved == ProxyKind::general) {
        prediction.usable = false, prediction.why_not = "bounds need a proved outside or inside proxy";
        return prediction;
      }
      prediction.variance = mesh_variance;
      prediction.ns_per_ray = costs.proxy_ns + costs.mesh_ns * (proved == ProxyKind::outside ? proxy_hit : proxy_miss);
      break;
  }
  prediction.efficiency = relative_efficiency(mesh_variance, costs.mesh_ns, prediction.variance, prediction.ns_per_ray);
  return prediction;
}

UsePrediction predict_use(ProxyUse use, ProxyKind proved, const RayTypeFractions& fractions, const TraceCosts& costs,
                          const UseOptions& options) {
  const double floor = std::clamp(options.floor, 0.0, 1.0 / 3);
  auto product = [&](const UseSetting& setting) {
    const UsePrediction p = predict_use_at(use, proved, fractions, costs, setting);
    return p.usable ? p.variance * p.ns_per_ray : kInfinity;
  };
  UseSetting setting;
  const auto& f = fractions.f;
  switch (use) {
    case ProxyUse::control_variate: {
      // At the minimum of Var x c, d/dq = 0 gives q = kappa sqrt(disagreeing fraction of
      // the side) with one kappa = sqrt(c / (c_mesh Var)) for both sides (a side clamped
      // to the floor or to 1 satisfies its bound's condition instead): a search along kappa.
      const bool miss_side = proved != ProxyKind::outside, hit_side = proved != ProxyKind::inside;
      const double miss_disagree = f[1] + f[3] > 0 ? f[1] / (f[1] + f[3]) : 0;
      const double hit_disagree = f[0] + f[2] > 0 ? f[2] / (f[0] + f[2]) : 0;
      auto at = [&](double log_kappa) {
        const double kappa = std::exp(log_kappa);
        UseSetting s;
        s.correction.after_miss = miss_side ? std::clamp(kappa * std::sqrt(miss_disagree), floor, 1.0) : 0.0;
        s.correction.after_hit = hit_side ? std::clamp(kappa * std::sqrt(hit_disagree), floor, 1.0) : 0.0;
        return s;
      };
      setting = at(minimise([&](double x) { return product(at(x)); }, std::log(1e-4), std::log(1e4), 256));
      break;
    }
    case ProxyUse::term_choice: {
      if (proved == ProxyKind::general) {
        // p1 and p2 each at least the floor and p3 = 1 - p1 - p2 too: nested searches.
        auto best_p2 = [&](double p1) {
          return minimise([&](double p2) { return product({{p1, p2, 1 - p1 - p2}, {}}); }, floor, 1 - p1 - floor, 64);
        };
        const double p1 = minimise(
            [&](double x) {
              const double p2 = best_p2(x);
              return product({{x, p2, 1 - x - p2}, {}});
            },
            floor, 1 - 2 * floor, 64);
        const double p2 = best_p2(p1);
        setting.term = {p1, p2, 1 - p1 - p2};
      } else {
        const bool outside = proved == ProxyKind::outside;
        auto at = [&](double p1) {
          return UseSetting{outside ? Probabilities{p1, 1 - p1, 0} : Probabilities{p1, 0, 1 - p1}, {}};
        };
        setting = at(minimise([&](double x) { return product(at(x)); }, floor, 1 - floor, 256));
      }
      break;
    }
    case ProxyUse::bounds: break;
  }
  return predict_use_at(use, proved, fractions, costs, setting);
}

double render_efficiency(double ray_efficiency, double variance_ratio, double share) {
  if (!(ray_efficiency > 0) || !(variance_ratio >= 0) || std::isinf(variance_ratio)) return 0;
  const double s = std::clamp(share, 0.0, 1.0);
  const double time_and_noise = variance_ratio * (1 - s) + (std::isinf(ray_efficiency) ? 0.0 : s / ray_efficiency);
  return time_and_noise > 0 ? 1 / time_and_noise : kInfinity;
}

std::array<double, 4> added_variance_by_type(ProxyUse use, const UseSetting& setting) {
  const auto inverse = [](double p) { return p > 0 ? 1 / p : kInfinity; };
  switch (use) {
    case ProxyUse::term_choice: {
      const Probabilities& p = setting.term;
      return {0, inverse(p.p1) + inverse(p.p3), inverse(p.p2) - 1, inverse(p.p1) - 1};
    }
    case ProxyUse::control_variate: {
      const CorrectionProbabilities& q = setting.correction;
      return {0, inverse(q.after_miss) - 1, inverse(q.after_hit) - 1, 0};
    }
    case ProxyUse::bounds:
      break;
  }
  return {0, 0, 0, 0};
}

double render_variance_ratio(const std::array<double, 4>& weighted, const std::array<double, 4>& added, double exact) {
  double sum = 0;
  for (std::size_t t = 0; t < 4; ++t)
    if (weighted[t] > 0) sum += weighted[t] * added[t];
  if (!(sum > 0)) return 1;
  return exact > 0 ? 1 + sum / exact : kInfinity;
}

double render_efficiency_of(double cost_ratio, double render_variance_ratio, double share) {
  if (!(render_variance_ratio > 0) || std::isinf(render_variance_ratio) || !(cost_ratio >= 0)) return 0;
  const double s = std::clamp(share, 0.0, 1.0);
  const double time = (1 - s) + s * cost_ratio;
  return time > 0 ? 1 / (render_variance_ratio * time) : kInfinity;
}

Interval efficiency_interval(ProxyUse use, ProxyKind proved, const RayTypeCounts& counts, const TraceCosts& costs,
                             const UseSetting& setting, std::uint64_t seed, int draws) {
  Random random(seed);
  TraceCosts dearest = costs, cheapest = costs;
  dearest.proxy_ns = costs.proxy_ns_high >= 0 ? std::max(costs.proxy_ns, costs.proxy_ns_high) : costs.proxy_ns;
  cheapest.proxy_ns = costs.proxy_ns_low >= 0 ? std::min(costs.proxy_ns, costs.proxy_ns_low) : costs.proxy_ns;
  std::vector<double> low_values, high_values;
  low_values.reserve(static_cast<std::size_t>(std::max(draws, 1)));
  high_values.reserve(static_cast<std::size_t>(std::max(draws, 1)));
  for (int draw = 0; draw < std::max(draws, 1); ++draw) {
    RayTypeFractions fractions;
    double total = 0;
    for (std::size_t i = 0; i < 4; ++i) {
      const bool impossible = (proved == ProxyKind::outside && i == 1) || (proved == ProxyKind::inside && i == 2);
      fractions.f[i] = impossible ? 0 : gamma(random, static_cast<double>(counts.counts[i]) + 0.5);
      total += fractions.f[i];
    }
    for (double& value : fractions.f) value /= total;
    low_values.push_back(predict_use_at(use, proved, fractions, dearest, setting).efficiency);
    high_values.push_back(predict_use_at(use, proved, fractions, cheapest, setting).efficiency);
  }
  std::sort(low_values.begin(), low_values.end());
  std::sort(high_values.begin(), high_values.end());
  const std::size_t n = low_values.size();
  const std::size_t lower = static_cast<std::size_t>(std::floor(0.025 * static_cast<double>(n)));
  const std::size_t upper = std::min(n - 1, static_cast<std::size_t>(std::ceil(0.975 * static_cast<double>(n))) - 1);
  return {low_values[lower], high_values[upper]};
}

double render_efficiency_timed(double time_ratio, double render_variance_ratio) {
  if (!(render_variance_ratio > 0) || std::isinf(render_variance_ratio) || !(time_ratio > 0)) return 0;
  return 1 / (render_variance_ratio * time_ratio);
}

}  // namespace visproxy
