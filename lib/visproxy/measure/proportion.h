#pragma once
// Fractions measured by counting, with their confidence intervals.

#include <cstdint>

namespace visproxy {

/// successes / trials with a Wilson score interval. An empty count (trials == 0) has
/// fraction 0 and the uninformative interval [0, 1], never NaN.
struct Proportion {
  std::uint64_t successes = 0;
  std::uint64_t trials = 0;
  double fraction() const;
  /// Wilson score interval for confidence level given by the normal quantile z
  /// (1.959964 for 95 %, 3.290527 for 99.9 %).
  double lower(double z = 1.959964) const;
  double upper(double z = 1.959964) const;
};

}  // namespace visproxy
