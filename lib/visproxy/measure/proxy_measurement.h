#pragma once
// How well a proxy stands in for a mesh on a set of rays: ray types, f_hit, f_miss,
// V_avg, GSSA ratio, optimal probabilities, variance and cost (Billen et al., section 3;
// definitions in SPEC.md, "Errata and exact definitions").

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "visproxy/core/proxy_kind.h"
#include "visproxy/estimator/probabilities.h"
#include "visproxy/measure/proportion.h"
#include "visproxy/trace/ray_scene.h"

namespace visproxy {

struct TimingOptions {
  std::size_t rays = 100000;  ///< the first this many rays are timed (all if fewer); 0: no timing
  /// Timed passes: for a proxy, this many interleaved blocks, each one pass against the
  /// mesh and one against the proxy (in alternating order), so that both see the same
  /// state of the machine; for the mesh alone, this many passes.
  int blocks = 6;
};

/// Wall time per ray of segment_blocked on one thread, in nanoseconds: the cost of a
/// shadow ray against `scene` on one core. The median of options.blocks passes over
/// the first options.rays rays, after one untimed pass to warm caches. 0 for no rays.
double nanoseconds_per_ray(const RayScene& scene, std::span<const Segment> rays, const TimingOptions& options = {});

/// The median of `values` (the mean of the middle two for an even count); 0 for none.
double median(std::vector<double> values);

/// One timed pass of segment_blocked over `rays` on this thread, without a warm-up: ns per
/// ray (0 for no rays). For timings interleaved with other work.
double nanoseconds_per_ray_once(const RayScene& scene, std::span<const Segment> rays);

/// The cost of a proxy against the mesh's, timed in interleaved blocks on one thread.
struct PairedTiming {
  std::vector<double> mesh_ns, proxy_ns;  ///< per block, ns per ray
  double mesh_median() const;
  double proxy_median() const;
  /// The median, least and greatest over the blocks of proxy_ns / mesh_ns. A block's two
  /// passes run back to back, so a change of the machine's speed between blocks (other
  /// work, frequency) moves both and leaves their ratio; the range of 6 blocks holds the
  /// median ratio with probability 1 - 2^-5 (97 %) for any distribution of block ratios.
  double ratio_median() const;
  double ratio_low() const;
  double ratio_high() const;
};

/// Times `proxy` against `mesh` on the first options.rays of `rays`: one warm-up pass of
/// each, then options.blocks blocks of one pass each (mesh first in even blocks, proxy
/// first in odd ones). Empty when nothing is timed.
PairedTiming time_against_mesh(const RayScene& mesh, const RayScene& proxy, std::span<const Segment> rays,
                               const TimingOptions& options = {});

/// The rays and what the exact mesh does to them, computed once and shared by every proxy.
struct ReferenceRays {
  std::vector<Segment> rays;
  std::vector<std::uint8_t> mesh_blocked;  ///< 1 where the mesh blocks rays[i]
  double mesh_ns_per_ray = 0;
  /// The mesh's scene (it must outlive the reference), for timing proxies against it in
  /// the same blocks; without it a proxy is timed alone and compared to mesh_ns_per_ray.
  const RayScene* mesh = nullptr;
};
ReferenceRays trace_reference(const RayScene& mesh, std::vector<Segment> rays, const TimingOptions& timing = {});

struct ProxyMeasurement {
  RayTypeCounts counts;
  Proportion f_hit;   ///< type 1 among rays the mesh blocks
  Proportion f_miss;  ///< type 4 among rays the mesh lets through
  Proportion v_avg;   ///< rays the mesh lets through (types 3 and 4)
  /// (f1 + f3) / (f1 + f2): how often the proxy blocks a ray relative to the mesh; under
  /// isotropic lines the ratio of their generalised shadowing surface areas. 95 %
  /// interval by the delta method for a ratio of two multinomial proportions; 0 (and
  /// [0, +inf)) when no ray hits the mesh.
  double gssa_ratio = 0, gssa_ratio_lower = 0, gssa_ratio_upper = 0;
  /// The kind whose optimal probabilities were used: the proxy's own, or `general` when
  /// these rays contradict its claim (an outside proxy missed by a ray the mesh blocks,
  /// an inside proxy hit by a ray the mesh lets through), where the kind's form with its
  /// zero probability would be biased.
  ProxyKind probability_form = ProxyKind::general;
  std::uint64_t rays_contradicting_claim = 0;
  Probabilities optimal;
  double variance_optimal = 0;  ///< eq. 16 per ray at `optimal`
  double variance_equal = 0;    ///< eq. 16 per ray at equal_probabilities(probability_form)
  double proxy_ns_per_ray = 0;  ///< median ns per ray of the proxy on the timed rays
  double mesh_ns_per_ray = 0;   ///< same for the mesh, timed in the same blocks
  /// proxy_ns_per_ray / mesh_ns_per_ray as the blocks give it: the median block ratio and
  /// the least and greatest (all equal when the proxy was timed alone); 0 when not timed.
  double cost_ratio = 0, cost_ratio_low = 0, cost_ratio_high = 0;
  int timing_blocks = 0;  ///< blocks timed in pairs with the mesh; 0 when timed alone
  /// Expected cost per estimate in ns at `optimal`: the proxy is always traced, the mesh
  /// with probability p2 on rays that hit the proxy and p3 on rays that miss it.
  double estimator_ns_per_ray = 0;
};

/// Measures `proxy` (a proxy of `kind`) on the reference rays: every ray traced against
/// it in parallel, the cost timed on one thread on the same rays as the mesh, in blocks
/// interleaved with the mesh's (time_against_mesh) when the reference holds its scene.
ProxyMeasurement measure_proxy(const ReferenceRays& reference, const RayScene& proxy, ProxyKind kind,
                               const TimingOptions& timing = {});

/// The counting part of measure_proxy, for callers that trace themselves.
ProxyMeasurement measure_from_counts(const RayTypeCounts& counts, ProxyKind kind);

}  // namespace visproxy
