#include "visproxy/measure/proxy_measurement.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

namespace visproxy {
namespace {

constexpr double kZ95 = 1.959964;

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

double nanoseconds_per_ray(const RayScene& scene, std::span<const Segment> rays, const TimingOptions& options) {
  const std::span<const Segment> timed = rays.first(std::min(rays.size(), options.rays));
  if (timed.empty()) return 0;
  volatile std::size_t sink = 0;  // keeps the loop from being optimised away
  auto pass = [&] {
    std::size_t blocked = 0;
    for (const Segment& ray : timed) blocked += scene.segment_blocked(ray) ? 1 : 0;
    sink = sink + blocked;
  };
  pass();  // warm-up
  double best = std::numeric_limits<double>::infinity();
  for (int repeat = 0; repeat < std::max(1, options.repeats); ++repeat) {
    const auto start = std::chrono::steady_clock::now();
    pass();
    best = std::min(best, seconds_since(start));
  }
  return best * 1e9 / static_cast<double>(timed.size());
}

ReferenceRays trace_reference(const RayScene& mesh, std::vector<Segment> rays, const TimingOptions& timing) {
  ReferenceRays reference;
  reference.mesh_blocked = mesh.segments_blocked(rays);
  reference.rays = std::move(rays);
  reference.mesh_ns_per_ray = nanoseconds_per_ray(mesh, reference.rays, timing);
  return reference;
}

ProxyMeasurement measure_from_counts(const RayTypeCounts& counts, ProxyKind kind) {
  ProxyMeasurement m;
  m.counts = counts;
  const auto& n = counts.counts;
  const std::uint64_t total = counts.total();
  m.f_hit = {n[0], n[0] + n[1]};
  m.f_miss = {n[3], n[2] + n[3]};
  m.v_avg = {n[2] + n[3], total};

  // GSSA ratio R = a / b with a = f1 + f3 (proxy blocks), b = f1 + f2 (mesh blocks).
  if (total > 0 && n[0] + n[1] > 0) {
    const double count = static_cast<double>(total);
    const double a = static_cast<double>(n[0] + n[2]) / count;
    const double b = static_cast<double>(n[0] + n[1]) / count;
    const double both = static_cast<double>(n[0]) / count;
    const double ratio = a / b;
    const double variance = (a * (1 - a) - 2 * ratio * (both - a * b) + ratio * ratio * b * (1 - b)) / (count * b * b);
    const double half_width = kZ95 * std::sqrt(std::max(0.0, variance));
    m.gssa_ratio = ratio;
    m.gssa_ratio_lower = std::max(0.0, ratio - half_width);
    m.gssa_ratio_upper = ratio + half_width;
  } else {
    m.gssa_ratio_upper = std::numeric_limits<double>::infinity();
  }

  m.rays_contradicting_claim = kind == ProxyKind::outside ? n[1] : kind == ProxyKind::inside ? n[2] : 0;
  m.probability_form = m.rays_contradicting_claim == 0 ? kind : ProxyKind::general;
  const RayTypeFractions fractions = RayTypeFractions::from(counts);
  m.optimal = optimal_probabilities(m.probability_form, fractions);
  m.variance_optimal = estimator_variance(fractions, m.optimal);
  m.variance_equal = estimator_variance(fractions, equal_probabilities(m.probability_form));
  return m;
}

ProxyMeasurement measure_proxy(const ReferenceRays& reference, const RayScene& proxy, ProxyKind kind,
                               const TimingOptions& timing) {
  const std::vector<std::uint8_t> proxy_blocked = proxy.segments_blocked(reference.rays);
  RayTypeCounts counts;
  for (std::size_t i = 0; i < proxy_blocked.size(); ++i) counts.add(reference.mesh_blocked[i] != 0, proxy_blocked[i] != 0);
  ProxyMeasurement m = measure_from_counts(counts, kind);
  m.proxy_ns_per_ray = nanoseconds_per_ray(proxy, reference.rays, timing);
  m.mesh_ns_per_ray = reference.mesh_ns_per_ray;
  const RayTypeFractions fractions = RayTypeFractions::from(counts);
  const double proxy_hit = fractions.f[0] + fractions.f[2];
  m.estimator_ns_per_ray =
      m.proxy_ns_per_ray + m.mesh_ns_per_ray * (m.optimal.p2 * proxy_hit + m.optimal.p3 * (1 - proxy_hit));
  return m;
}

}  // namespace visproxy
