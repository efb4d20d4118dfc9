// GSSA of two balls and their merge. The three overestimates and the centre weights are
// those of L. Szecsi, L. Szirmay-Kalos, "Efficient approximate visibility testing using
// occluding spheres", WSCG 2004, section 3.3 (formulas as corrected in SPEC.md). The exact
// value replaces the paper's Monte-Carlo fit: by Cauchy's formula the measure of lines
// hitting a body K is the mean area of K's shadow over directions (times a constant), and
// the shadow of two balls is two discs, whose union has a closed-form area.

#include "visproxy/proxy/two_sphere_gssa.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <numbers>
#include <tuple>

namespace visproxy {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr int kNodes = 24;

struct GaussLegendre {
  std::array<double, kNodes> nodes{};    // on [0, 1]
  std::array<double, kNodes> weights{};  // sum to 1
};

// Nodes and weights by Newton's method on the Legendre polynomial P_n.
GaussLegendre make_gauss_legendre() {
  GaussLegendre rule;
  for (int i = 0; i < kNodes; ++i) {
    double x = std::cos(kPi * (i + 0.75) / (kNodes + 0.5));
    double derivative = 0;
    for (int iteration = 0; iteration < 100; ++iteration) {
      double p0 = 1, p1 = x;
      for (int k = 2; k <= kNodes; ++k) {
        const double p2 = ((2.0 * k - 1) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      derivative = kNodes * (x * p1 - p0) / (x * x - 1);
      const double step = p1 / derivative;
      x -= step;
      if (std::abs(step) < 1e-16) break;
    }
    rule.nodes[static_cast<std::size_t>(i)] = 0.5 * (1 - x);
    rule.weights[static_cast<std::size_t>(i)] = 1.0 / ((1 - x * x) * derivative * derivative);  // 2/(..) on [-1,1], halved
  }
  return rule;
}

const GaussLegendre& gauss_legendre() {
  static const GaussLegendre rule = make_gauss_legendre();
  return rule;
}

// Area of the intersection of two discs of radii R >= r whose centres are s apart.
double lens_area(double R, double r, double s) {
  if (s >= R + r) return 0;
  if (s <= R - r) return kPi * r * r;
  const double cos_small = std::clamp((s * s + r * r - R * R) / (2 * s * r), -1.0, 1.0);
  const double cos_large = std::clamp((s * s + R * R - r * r) / (2 * s * R), -1.0, 1.0);
  const double kite = (-s + r + R) * (s + r - R) * (s - r + R) * (s + r + R);
  return r * r * std::acos(cos_small) + R * R * std::acos(cos_large) - 0.5 * std::sqrt(std::max(0.0, kite));
}

// (R, r) with R >= r.
std::pair<double, double> ordered(double a, double b) { return a >= b ? std::pair{a, b} : std::pair{b, a}; }

}  // namespace

double two_sphere_area_sum(double R, double r, double /*d*/) { return 4 * kPi * (R * R + r * r); }

double two_sphere_union_area(double R, double r, double d) {
  std::tie(R, r) = ordered(R, r);
  if (d >= R + r) return two_sphere_area_sum(R, r, d);
  if (d <= R - r) return 4 * kPi * R * R;
  // a, b: signed distances from each centre to the plane of the intersection circle.
  const double a = (R * R - r * r + d * d) / (2 * d);
  const double b = (r * r - R * R + d * d) / (2 * d);
  return 2 * kPi * R * (R + a) + 2 * kPi * r * (r + b);
}

double two_sphere_hull_area(double R, double r, double d) {
  std::tie(R, r) = ordered(R, r);
  if (d <= R - r) return 4 * kPi * R * R;
  const double cos_alpha = (R - r) / d;
  const double l = std::sqrt(std::max(0.0, d * d - (R - r) * (R - r)));
  const double sin_alpha = l / d;
  return 2 * kPi * R * R * (1 + cos_alpha) + 2 * kPi * r * r * (1 - cos_alpha) + kPi * l * (R + r) * sin_alpha;
}

double two_sphere_gssa_analytic(double R, double r, double d) {
  return std::min({two_sphere_area_sum(R, r, d), two_sphere_union_area(R, r, d), two_sphere_hull_area(R, r, d)});
}

double two_sphere_gssa_exact(double R, double r, double d) {
  std::tie(R, r) = ordered(R, r);
  if (r <= 0 || d <= R - r) return 4 * kPi * R * R;
  // The shadows' centres are s(t) = d sqrt(1 - t^2) apart, t = |cos theta| uniform in [0, 1].
  // For t >= t_in the small disc lies inside the large one; for t <= t_out they are apart.
  const double t_in = std::sqrt(std::max(0.0, 1 - ((R - r) / d) * ((R - r) / d)));
  const double t_out = d > R + r ? std::sqrt(std::max(0.0, 1 - ((R + r) / d) * ((R + r) / d))) : 0.0;
  double overlap = kPi * r * r * (1 - t_in);
  const double width = t_in - t_out;
  if (width > 0) {
    // t = t_out + width * (3u^2 - 2u^3): the lens's (t - t_end)^(3/2) ends (and the square
    // root of s at t = 1 when R = r) become smooth in u, so Gauss-Legendre converges fast.
    const GaussLegendre& rule = gauss_legendre();
    double sum = 0;
    for (std::size_t i = 0; i < rule.nodes.size(); ++i) {
      const double u = rule.nodes[i];
      const double t = t_out + width * u * u * (3 - 2 * u);
      const double dt_du = width * 6 * u * (1 - u);
      const double s = d * std::sqrt(std::max(0.0, 1 - t * t));
      sum += rule.weights[i] * lens_area(R, r, s) * dt_du;
    }
    overlap += sum;
  }
  return 4 * kPi * (R * R + r * r) - 4 * overlap;
}

Sphere merge_two_spheres(const Sphere& a, const Sphere& b, MergeRadius rule) {
  // A canonical order makes the result bit-identical for (a, b) and (b, a).
  const auto key = [](const Sphere& s) { return std::tuple(s.radius, s.center.x(), s.center.y(), s.center.z()); };
  const bool a_first = key(a) >= key(b);
  const Sphere& large = a_first ? a : b;
  const Sphere& small = a_first ? b : a;
  const double R = large.radius, r = small.radius;
  const double d = (large.center - small.center).norm();
  if (d <= R - r) return large;
  const double area = rule == MergeRadius::exact ? two_sphere_gssa_exact(R, r, d) : two_sphere_gssa_analytic(R, r, d);
  const double cos_alpha = std::clamp((R - r) / d, -1.0, 1.0);
  const double weight_large = 2 * kPi * R * R * (1 + cos_alpha);
  const double weight_small = 2 * kPi * r * r * (1 - cos_alpha);
  Sphere merged;
  merged.center = (weight_large * large.center + weight_small * small.center) / (weight_large + weight_small);
  merged.radius = std::sqrt(area / (4 * kPi));
  return merged;
}

}  // namespace visproxy
