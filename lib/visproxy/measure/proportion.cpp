#include "visproxy/measure/proportion.h"

#include <algorithm>
#include <cmath>

namespace visproxy {
namespace {

struct Interval {
  double lower, upper;
};

Interval wilson(std::uint64_t successes, std::uint64_t trials, double z) {
  if (trials == 0) return {0.0, 1.0};
  const double n = static_cast<double>(trials);
  const double p = static_cast<double>(successes) / n;
  const double z2 = z * z;
  const double centre = (p + z2 / (2 * n)) / (1 + z2 / n);
  const double half = z / (1 + z2 / n) * std::sqrt(p * (1 - p) / n + z2 / (4 * n * n));
  return {std::max(0.0, centre - half), std::min(1.0, centre + half)};
}

}  // namespace

double Proportion::fraction() const {
  return trials == 0 ? 0.0 : static_cast<double>(successes) / static_cast<double>(trials);
}
double Proportion::lower(double z) const { return wilson(successes, trials, z).lower; }
double Proportion::upper(double z) const { return wilson(successes, trials, z).upper; }

}  // namespace visproxy
