#include "visproxy/measure/proxy_measurement.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <vector>

namespace visproxy {
namespace {

constexpr double kZ95 = 1.959964;

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

double median(std::vector<double> values) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

namespace {

std::vector<double> ratios(const PairedTiming& timing) {
  std::vector<double> r;
  for (std::size_t k = 0; k < timing.mesh_ns.size(); ++k)
    if (timing.mesh_ns[k] > 0) r.push_back(timing.proxy_ns[k] / timing.mesh_ns[k]);
  return r;
}

// One timed pass: seconds per ray of segment_blocked over `rays` on this thread.
double seconds_per_ray(const RayScene& scene, std::span<const Segment> rays) {
  const auto start = std::chrono::steady_clock::now();
  std::size_t blocked = 0;
  for (const Segment& ray : rays) blocked += scene.segment_blocked(ray) ? 1 : 0;
  volatile std::size_t sink = blocked;  // keeps the loop from being optimised away
  static_cast<void>(sink);
  return seconds_since(start) / static_cast<double>(rays.size());
}

}  // namespace

double PairedTiming::mesh_median() const { return median(mesh_ns); }
double PairedTiming::proxy_median() const { return median(proxy_ns); }
double PairedTiming::ratio_median() const { return median(ratios(*this)); }
double PairedTiming::ratio_low() const {
  const std::vector<double> r = ratios(*this);
  return r.empty() ? 0 : *std::min_element(r.begin(), r.end());
}
double PairedTiming::ratio_high() const {
  const std::vector<double> r = ratios(*this);
  return r.empty() ? 0 : *std::max_element(r.begin(), r.end());
}

double nanoseconds_per_ray_once(const RayScene& scene, std::span<const Segment> rays) {
  return rays.empty() ? 0 : 1e9 * seconds_per_ray(scene, rays);
}

double nanoseconds_per_ray(const RayScene& scene, std::span<const Segment> rays, const TimingOptions& options) {
  const std::span<const Segment> timed = rays.first(std::min(rays.size(), options.rays));
  if (timed.empty() || options.blocks < 1) return 0;
  seconds_per_ray(scene, timed);  // warm-up
  std::vector<double> passes;
  for (int block = 0; block < options.blocks; ++block) passes.push_back(1e9 * seconds_per_ray(scene, timed));
  return median(passes);
}

PairedTiming time_against_mesh(const RayScene& mesh, const RayScene& proxy, std::span<const Segment> rays,
                               const TimingOptions& options) {
  PairedTiming timing;
  const std::span<const Segment> timed = rays.first(std::min(rays.size(), options.rays));
  if (timed.empty() || options.blocks < 1) return timing;
  seconds_per_ray(mesh, timed), seconds_per_ray(proxy, timed);  // warm-up
  for (int block = 0; block < options.blocks; ++block) {
    double mesh_ns = 0, proxy_ns = 0;
    if (block % 2 == 0) {
      mesh_ns = 1e9 * seconds_per_ray(mesh, timed);
      proxy_ns = 1e9 * seconds_per_ray(proxy, timed);
    } else {
      proxy_ns = 1e9 * seconds_per_ray(proxy, timed);
      mesh_ns = 1e9 * seconds_per_ray(mesh, timed);
    }
    timing.mesh_ns.push_back(mesh_ns);
    timing.proxy_ns.push_back(proxy_ns);
  }
  return timing;
}

ReferenceRays trace_reference(const RayScene& mesh, std::vector<Segment> rays, const TimingOptions& timing) {
  ReferenceRays reference;
  reference.mesh_blocked = mesh.segments_blocked(rays);
  reference.rays = std::move(rays);
  reference.mesh_ns_per_ray = nanoseconds_per_ray(mesh, reference.rays, timing);
  reference.mesh = &mesh;
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
  if (reference.mesh) {
    const PairedTiming paired = time_against_mesh(*reference.mesh, proxy, reference.rays, timing);
    if (!paired.mesh_ns.empty()) {
      m.proxy_ns_per_ray = paired.proxy_median();
      m.mesh_ns_per_ray = paired.mesh_median();
      m.cost_ratio = paired.ratio_median();
      m.cost_ratio_low = paired.ratio_low();
      m.cost_ratio_high = paired.ratio_high();
      m.timing_blocks = static_cast<int>(paired.mesh_ns.size());
    }
  } else {
    m.proxy_ns_per_ray = nanoseconds_per_ray(proxy, reference.rays, timing);
    m.mesh_ns_per_ray = reference.mesh_ns_per_ray;
    m.cost_ratio = m.cost_ratio_low = m.cost_ratio_high = m.mesh_ns_per_ray > 0 ? m.proxy_ns_per_ray / m.mesh_ns_per_ray : 0;
  }
  const RayTypeFractions fractions = RayTypeFractions::from(counts);
  const double proxy_hit = fractions.f[0] + fractions.f[2];
  m.estimator_ns_per_ray =
      m.proxy_ns_per_ray + m.mesh_ns_per_ray * (m.optimal.p2 * proxy_hit + m.optimal.p3 * (1 - proxy_hit));
  return m;
}

}  // namespace visproxy
