#pragma once
// Golden-section search: the minimum of a unimodal function on an interval, for the
// estimator's numeric minimisations (probabilities.cpp, efficiency.cpp).

#include <cmath>

namespace visproxy {

/// The minimiser of `f` on [lo, hi], for f unimodal there: the bracket shrinks by the golden
/// ratio until it is narrower than `tolerance` (at most 200 steps); its midpoint is returned.
template <typename F>
double golden_section(F f, double lo, double hi, double tolerance = 1e-13) {
  const double ratio = (std::sqrt(5.0) - 1) / 2;
  double a = lo, b = hi;
  double c = b - ratio * (b - a), d = a + ratio * (b - a);
  double fc = f(c), fd = f(d);
  for (int i = 0; i < 200 && b - a > tolerance; ++i) {
    if (fc <= fd) {
      b = d, d = c, fd = fc;
      c = b - ratio * (b - a), fc = f(c);
    } else {
      a = c, c = d, fc = fd;
      d = a + ratio * (b - a), fd = f(d);
    }
  }
  return (a + b) / 2;
}

}  // namespace visproxy
