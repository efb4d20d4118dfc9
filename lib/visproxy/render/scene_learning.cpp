// What a render learns from the scene's own samples before its first pass
// (scene_learning.h).

#include "visproxy/render/scene_learning.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <span>

#include "visproxy/core/errors.h"
#include "visproxy/render/integrators/integrator.h"
#include "visproxy/render/renderer.h"
#include "visproxy/render/visibility/occluder_disks.h"

namespace visproxy {

// ProbabilityMode::optimal: eq. 8's optimal probabilities for each form of the rest of the
// scene, from the ray types of the scene's own shadow segments (20 000, seeded from the
// render's seed), each traced against the proxies and meshes of the instances its estimate
// would see (all but its own with visibility splitting), as the probe rays of adaptive are.
std::array<Probabilities, 3> scene_optimal_probabilities(const VisibilityContext& context) {
  const Scene& scene = context.scene;
  const RenderWorld& world = context.world;
  const RenderOptions& options = context.options;
  std::array<RayTypeCounts, 3> counts;
  const std::vector<bool> none(scene.instances.size(), false);
  const std::vector<ProxyKind> kinds = stochastic_kinds(context);
  for (const ShadowSegment& s : scene_shadow_segments(scene, world, 20000, options.seed ^ 0x6F7074696D616CULL, none)) {
    const InstanceFilter rest{.skip = options.split ? s.instance : -1, .only = -1};
    const bool mesh = world.mesh_blocks(s.from, s.to, rest), proxy = world.proxy_blocks(s.from, s.to, rest);
    counts[static_cast<std::size_t>(kinds[static_cast<std::size_t>(s.instance)])].add(mesh, proxy);
    if (kinds[static_cast<std::size_t>(s.instance)] != ProxyKind::general)
      counts[static_cast<std::size_t>(ProxyKind::general)].add(mesh, proxy);  // connections use the general form
  }
  std::array<Probabilities, 3> optimal;
  for (const ProxyKind kind : {ProxyKind::outside, ProxyKind::inside, ProxyKind::general})
    optimal[static_cast<std::size_t>(kind)] =
        optimal_probabilities(kind, RayTypeFractions::from(counts[static_cast<std::size_t>(kind)]), {.floor = options.probability_floor});
  return optimal;
}

// ProbabilityMode::learned with the control variate and direct light: per instance, the
// modelled costs of a segment from its points (render/world/query_costs.h, averaged over the
// segments of 4000 pairs of camera samples seeded from the render's seed; the camera ray's
// and shading's work shared among the sample's shadow rays), and the exact render's noise
// relative to a segment's squared contribution: within each pair (one pixel) the luminance
// difference of the two samples traced exactly, sum (x_a - x_b)^2 / 2 over sum (c_a^2 +
// c_b^2) / 2, c a segment's unoccluded contribution. The same segments, traced against the
// proxies the control variate would ask too, give each instance its prior: the share of its
// segments the proxy answers each way and how often wrongly, worth kPriorSegments of a
// pixel's own. An instance none of whose points was met gets what all of them had together.
// Empty when no sample found a lit segment.
constexpr double kPriorSegments = 16;

SceneCorrectionCosts scene_correction_costs(const VisibilityContext& context) {
  const Scene& scene = context.scene;
  const RenderWorld& world = context.world;
  const RenderOptions& options = context.options;
  const std::size_t n = scene.instances.size();
  const Vertex camera = CameraRays(scene.camera).origin();
  const double per_segment = 1.0 / std::max(options.shadow_rays, 1);  // a camera sample's share
  std::vector<SegmentQueryCosts> sums(n + 1);  // the last: every instance
  std::vector<double> counts(n + 1, 0.0);
  std::vector<CorrectionEvidence> evidence(n + 1);
  RenderStats uncounted;  // the proxy queries below are not the render's
  double noise = 0, squares = 0;
  auto luminance = [](const Color& c) { return c.mean(); };
  for (const std::array<CameraSample, 2>& pair : scene_sample_pairs(scene, world, 4000, options.seed ^ 0x636F737473ULL)) {
    std::array<double, 2> value{};
    for (std::size_t k = 0; k < 2; ++k) {
      const CameraSample& sample = pair[k];
      value[k] = luminance(sample.emitted);
      if (!sample.has_segment) continue;
      const ShadowSegment& s = sample.segment;
      const double c = luminance(sample.contribution);
      squares += c * c / 2;
      const SegmentQueryCosts q = segment_query_costs(world, camera, s.from, s.to, s.instance, options.split);
      // The exact answer: the own mesh (which the split answer traced exactly), else the rest.
      const ProxyAnswer answer = proxy_answer(world, s.from, s.to, s.instance, options.split, uncounted, false);
      const bool mesh = !answer.own_blocks && world.mesh_blocks(s.from, s.to, answer.rest);
      if (!answer.own_blocks && !mesh) value[k] += c;
      for (const std::size_t i : {static_cast<std::size_t>(s.instance), n}) {
        sums[i].camera += q.camera * per_segment, sums[i].exact += q.exact, sums[i].proxy += q.proxy;
        sums[i].correction += q.correction;
        counts[i] += 1;
        if (!answer.own_blocks) evidence[i].answer(answer.proxy_blocked), evidence[i].add(answer.proxy_blocked, mesh);
      }
    }
    noise += (value[0] - value[1]) * (value[0] - value[1]) / 2;
  }
  SceneCorrectionCosts result;
  if (!(counts[n] > 0) || !(squares > 0) || !(noise > 0)) return result;  // nothing to weigh: the cost-blind rule
  result.noise = noise / squares;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t from = counts[i] > 0 ? i : n;
    const double m = counts[from];
    result.priors.push_back(CorrectionPrior::from(evidence[from], kPriorSegments));
    const SegmentQueryCosts w{sums[from].camera / m, sums[from].exact / m, sums[from].proxy / m, sums[from].correction / m};
    result.work.push_back(w);
    result.costs.push_back({.base = w.camera + w.proxy, .correction = w.correction, .exact = w.camera + w.exact, .variance = result.noise});
  }
  return result;
}



// Whether the learned control variate's rule could give any instance's proxy to a pixel at
// the instance's average costs: learned_choice() at its modelled costs and prior says
// whether any evidence could make its proxy pay (can_pay: even corrected at the floor, the
// proxy's cost is below kLearnedPaysBelow x exact's). A pixel weighs its own first
// segments' costs with the instance's, so that where can_pay holds for no instance's
// average, it would hold for a pixel only where its own segments cost far less than the
// instance's do on average; the scene-level rule gives up those pixels.
bool any_proxy_can_pay(const VisibilityContext& context) {
  const std::vector<ProxyKind> kinds = stochastic_kinds(context);
  const CorrectionOptions options{.scale = context.options.correction_scale, .floor = context.options.probability_floor};
  for (std::size_t i = 0; i < context.correction_costs.size(); ++i)
    if (learned_choice(kinds[i], CorrectionEvidence{}, context.correction_costs[i], options, context.correction_priors[i]).can_pay)
      return true;
  return false;
}

double eq8_predicted_ratio(ProxyKind kind, const CorrectionPrior& prior, const SegmentQueryCosts& work, double noise,
                           double probes_per_segment, double floor, bool cost_heuristic) {
  // The ray types from the prior's rates; an outside proxy's misses and an inside proxy's
  // hits are right by proof (the prior's estimates are never exactly 0).
  const double free = prior.share[0], blocked = prior.share[1];
  const double wrong_free = kind == ProxyKind::outside ? 0.0 : prior.disagreeing[0];
  const double wrong_blocked = kind == ProxyKind::inside ? 0.0 : prior.disagreeing[1];
  RayTypeFractions fractions;
  fractions.f = {blocked * (1 - wrong_blocked), free * wrong_free, blocked * wrong_blocked, free * (1 - wrong_free)};
  Probabilities p = optimal_probabilities(kind, fractions, {.floor = floor});
  if (cost_heuristic) p = apply_cost_heuristic(kind, p, fractions, floor);
  const double v = fractions.v_avg();
  // What eq. 8 adds to a segment whose visibility is fixed: eq. 16 less V's own variance.
  const double added = std::max(0.0, estimator_variance(fractions, p) - v * (1 - v));
  const double eq8 = work.camera + work.proxy + work.correction * (p.p2 * blocked + p.p3 * free) +
                     probes_per_segment * (work.proxy + work.correction);
  const double exact = work.camera + work.exact;
  const double ratio = (noise + added) * eq8 / (noise * exact);
  return std::isfinite(ratio) && noise > 0 && exact > 0 ? ratio : std::numeric_limits<double>::infinity();
}

std::vector<double> adaptive_eq8_ratios(const VisibilityContext& context, const SceneCorrectionCosts& costs) {
  const RenderOptions& options = context.options;
  const std::vector<ProxyKind> kinds = stochastic_kinds(context);
  const double probe_share =
      options.probe_passes > 0 ? std::min(1.0, static_cast<double>(options.probe_passes) / std::max(options.spp, 1)) : 1.0;
  const double probes_per_segment = options.probe_rays * probe_share / std::max(options.shadow_rays, 1);
  std::vector<double> ratios;
  for (std::size_t i = 0; i < costs.work.size(); ++i)
    ratios.push_back(eq8_predicted_ratio(kinds[i], costs.priors[i], costs.work[i], costs.noise, probes_per_segment,
                                         options.probability_floor, options.cost_heuristic));
  return ratios;
}

namespace {

// The gates of the VPL integrator's estimators (scene_disk_gate, adaptive_eq8_vpl_ratios)
// weigh them on kGatePairs pairs of camera samples, each pair in one pixel of a
// kGateSide^2 grid over the image, shaded by the render's integrator with every segment
// answered exactly by a probe that records what the estimator would have seen.
constexpr std::size_t kGateSide = 12;
constexpr std::size_t kGatePairs = kGateSide * kGateSide;

struct GateSample {
  bool shaded = false;
  int instance = -1;                // of the shaded point
  std::size_t first = 0, last = 0;  // its records
  double camera_work = 0;           // its camera ray and shading (camera_sample_work)
  double own_work = 0;              // what the estimator spends on the point itself (Probe::point_work)
  double pair_noise = 0;            // (x_a - x_b)^2 / 2 over its pair: the exact render's variance there
};

// Shades the pairs with `probe` (a PointVisibility with records(), the records made so far,
// and point_work(), the last point's own work), the pixels and samples seeded from `seed`
// and the estimators' choices from the render's seed: two samples per pair,
// passes 0 and 1 of its pixel. `noise` gets the mean over pairs of (x_a - x_b)^2 / 2.
template <typename Probe>
std::vector<GateSample> shade_gate_pairs(const VisibilityContext& context, Probe& probe, std::uint64_t seed, double& noise) {
  const Scene& scene = context.scene;
  const RenderWorld& world = context.world;
  // An integrator of its own: integrators may keep per-pixel sums of what they shaded.
  const std::unique_ptr<Integrator> integrator = make_integrator(IntegratorContext{scene, world, context.options, context.lights});
  const CameraRays camera(scene.camera);
  const Vertex eye = camera.origin();
  std::vector<GateSample> samples(2 * kGatePairs);
  RenderStats stats;
  double p1_sum = 0, p1_count = 0, noise_sum = 0;
  PixelRandom random(seed, 0, 0);
  PixelRandom choices(context.options.seed ^ 0x63686F69636573ULL, 0, 0);
  const int width = scene.camera.width, height = scene.camera.height;
  for (std::size_t pair = 0; pair < kGatePairs; ++pair) {
    const double cx = static_cast<double>(pair % kGateSide), cy = static_cast<double>(pair / kGateSide);
    const int px = std::min(width - 1, static_cast<int>((cx + random.uniform()) / kGateSide * width));
    const int py = std::min(height - 1, static_cast<int>((cy + random.uniform()) / kGateSide * height));
    std::array<double, 2> value{};
    for (std::size_t k = 0; k < 2; ++k) {
      GateSample& sample = samples[2 * pair + k];
      const double jx = random.uniform(), jy = random.uniform();
      const std::optional<SurfaceHit> hit = world.intersect(eye, camera.direction(px + jx, py + jy));
      if (!hit) continue;
      if (hit->light >= 0) {
        const AreaLight& light = scene.lights[static_cast<std::size_t>(hit->light)];
        if (hit->light_front || light.two_sided) value[k] = light.radiance.mean();
        continue;
      }
      const Vertex position = hit->position + world.surface_offset(hit->position, hit->distance) * hit->normal;
      const ShadingPoint point{.pixel = static_cast<std::size_t>(py) * static_cast<std::size_t>(width) + static_cast<std::size_t>(px),
                               .pass = static_cast<int>(k),
                               .hit = &*hit,
                               .position = position,
                               .choices = &choices,
                               .stats = &stats,
                               .p1_sum = &p1_sum,
                               .p1_count = &p1_count};
      const Color brdf = scene.instances[static_cast<std::size_t>(hit->instance)].albedo / std::numbers::pi;
      sample.shaded = true;
      sample.instance = hit->instance;
      sample.first = probe.records();
      probe.begin(point);
      value[k] = integrator->shade(point, brdf, random, probe).mean();
      probe.end();
      sample.last = probe.records();
      sample.camera_work = camera_sample_work(world, eye, position);
      sample.own_work = probe.point_work();
    }
    const double n = (value[0] - value[1]) * (value[0] - value[1]) / 2;
    samples[2 * pair].pair_noise = samples[2 * pair + 1].pair_noise = n;
    noise_sum += n;
  }
  noise = noise_sum / kGatePairs;
  return samples;
}

// ProbabilityMode::learned with the control variate and occluder disks as V' (the VPL
// integrator with sphere sets): whether the control variate can pay on this scene at all.
// Its corrections are chosen per pixel from the pixel's evidence alone, blind to cost, so
// where the disks' set-up and tests cost more than the meshes they stand for, or the disks
// disagree with the meshes often, the control variate costs more than exact visibility.
// Before the render, kGatePairs pairs of camera samples (each pair in one pixel of a
// kGateSide^2 grid over the image, seeded from the render's seed) are shaded by the
// render's integrator with every segment traced exactly; each segment's disk answer, mesh
// answers, modelled work and contribution (PointVisibility::contributions) are kept, and
// segments to area lights are traced exactly, as the control variate traces them. Then:
// - T, the exact render's variance per camera sample: sum (x_a - x_b)^2 / 2 over the pairs;
// - the control variate's learning is replayed per pixel for min(spp, kDiskGatePasses)
//   passes, its two samples taking turns: a pass's segments are corrected with the
//   probabilities q the pixel's evidence gives when its point begins (as the render's
//   groups of connections are), and the corrections it draws join the evidence. A, the
//   variance the control variate adds per camera sample, is the mean over passes of the
//   sum over segments the disks answer wrongly of contribution^2 (1/q - 1);
// - modelled work (render/world/query_costs.h) per pass: exact, the camera sample plus each
//   segment's meshes; the control variate, the camera sample, the disks' set-up
//   (kDiskSetupWork a ball made) and tests (kDiskTestWork a comparison), the meshes traced
//   exactly (the own instance when splitting, segments to lights), and each segment's
//   correction times its q, at kDiskCorrectionWork times its meshes' modelled work (a
//   point's corrections go to Embree as packets of the few connections that drew one, not
//   as exact's full packets). The constants were fit to `visproxy-bench-vpl` on the
//   armadillo and menagerie rooms: the model puts disks alone at 0.06-0.27 of exact's time
//   (measured 0.09-0.36), the control variate at correction scale 0.25 at 0.48-0.73
//   (measured 0.36-0.71), and at scale 2 on the armadillo room at 1.17 (measured 1.12).
// The render traces every segment exactly when (T + A) x work_cv >= kLearnedPaysBelow x T x
// work_exact, the rule learned_choice() applies to direct light. Without noise in the
// pairs (T = 0), it keeps the control variate only where A = 0 and work_cv is below
// kLearnedPaysBelow x work_exact.
constexpr int kDiskGatePasses = 16;
constexpr double kDiskSetupWork = 1.5;
constexpr double kDiskTestWork = 0.035;
constexpr double kDiskCorrectionWork = 1.75;

struct DiskGateRecord {
  bool exact = false;  // traced exactly, as the control variate traces segments to lights
  bool traced_blocked = false, proxy_blocked = false, mesh_blocked = false;
  float exact_work = 0, correction_work = 0, disk_work = 0;
  float contribution = 0;  // luminance, when visible
};

// Answers exactly, recording what the control variate would see; a point's connections go
// to Embree as packets, as the render's do.
class DiskGateProbe final : public PointVisibility {
 public:
  DiskGateProbe(const VisibilityContext& context, const OccluderDiskIndex& index, std::vector<DiskGateRecord>& records)
      : context_(context), index_(index), records_(records) {}
  void begin(const ShadingPoint& point) override {
    point_ = point;
    first_ = records_.size();
    // As the control variate begins its points (ControlVariatePoint::begin).
    disk_bits_ = begin_point_disks(disks_, exact_part_, index_, context_.world, context_.options, *point.hit, point.position,
                                   context_.options.split)
                     .disks;
  }
  // As the control variate with disks answers them: segments to lights exactly.
  double to_light(const Vertex& end) override {
    DiskGateRecord r;
    r.exact = true;
    r.traced_blocked = context_.world.mesh_blocks(point_.position, end);
    r.exact_work = static_cast<float>(costs(end).exact);
    records_.push_back(r);
    return r.traced_blocked ? 0.0 : 1.0;
  }
  double connection(const Vertex& end) override {
    const Vertex ends[1] = {end};
    double out[1] = {0};
    connections(ends, {}, out);
    return out[0];
  }
  void connections(std::span<const Vertex> ends, std::span<const unsigned> end_shells, std::span<double> out) override {
    const std::size_t m = ends.size();
    // The exactly traced part: the own instance when splitting, instances without sphere sets.
    traced_.assign(m, 0);
    index_of_.clear(), lane_ends_.clear(), lanes_.clear();
    for (std::size_t i = 0; i < m; ++i)
      if (const unsigned lane = exact_part_.lane(ends[i], end_shells.empty() ? nullptr : &end_shells[i]); lane != 0)
        index_of_.push_back(i), lane_ends_.push_back(ends[i]), lanes_.push_back(lane);
    trace(traced_);
    // One segment at a time: the comparisons counted are those of the single-segment test,
    // which the disk work's constant was fit to.
    proxy_.resize(m);
    disk_work_.resize(m);
    for (std::size_t i = 0; i < m; ++i) {
      std::uint64_t tests = 0;
      proxy_[i] = disks_.occludes(ends[i], tests) ? 1 : 0;
      disk_work_[i] = static_cast<float>(kDiskTestWork * static_cast<double>(tests));
    }
    // The meshes the disks stand for, where the traced part let the segment through.
    mesh_.assign(m, 0);
    index_of_.clear(), lane_ends_.clear(), lanes_.clear();
    for (std::size_t i = 0; i < m; ++i)
      if (!traced_[i]) index_of_.push_back(i), lane_ends_.push_back(ends[i]), lanes_.push_back(disk_bits_);
    trace(mesh_);
    for (std::size_t i = 0; i < m; ++i) {
      DiskGateRecord r;
      r.traced_blocked = traced_[i] != 0, r.proxy_blocked = proxy_[i] != 0, r.mesh_blocked = mesh_[i] != 0;
      r.disk_work = disk_work_[i];
      const SegmentQueryCosts c = costs(ends[i]);
      r.exact_work = static_cast<float>(c.exact), r.correction_work = static_cast<float>(c.correction);
      records_.push_back(r);
      out[i] = r.traced_blocked || r.mesh_blocked ? 0.0 : 1.0;
    }
  }
  bool wants_contributions() const override { return true; }
  void contributions(std::span<const double> luminance) override {
    if (luminance.size() != records_.size() - first_) throw Error("render: an integrator reported contributions for other segments than it asked");
    for (std::size_t i = 0; i < luminance.size(); ++i) records_[first_ + i].contribution = static_cast<float>(luminance[i]);
  }
  std::size_t records() const { return records_.size(); }
  // The point's set-up: the disks it made (with a lazy index, those its segments asked for).
  double point_work() const { return kDiskSetupWork * static_cast<double>(disks_.size()); }

 private:
  SegmentQueryCosts costs(const Vertex& end) const {
    return shadow_segment_costs(context_.world, point_.position, end, point_.hit->instance, context_.options.split);
  }
  // answers[index_of_[k]] for the segments to lane_ends_[k] against the instances of lanes_[k].
  void trace(std::vector<std::uint8_t>& answers) {
    if (lane_ends_.empty()) return;
    blocked_.resize(lane_ends_.size());
    context_.world.mesh_blocks(point_.position, lane_ends_, blocked_, {}, lanes_);
    for (std::size_t k = 0; k < lane_ends_.size(); ++k) answers[index_of_[k]] = blocked_[k];
  }

  const VisibilityContext& context_;
  const OccluderDiskIndex& index_;
  std::vector<DiskGateRecord>& records_;
  std::size_t first_ = 0;
  ShadingPoint point_;
  PointDisks disks_;
  ExactConnections exact_part_;
  unsigned disk_bits_ = 0;
  std::vector<std::uint8_t> traced_, proxy_, mesh_, blocked_;
  std::vector<float> disk_work_;
  std::vector<std::size_t> index_of_;
  std::vector<Vertex> lane_ends_;
  std::vector<unsigned> lanes_;
};

}  // namespace

nlohmann::json DiskGate::to_json() const {
  return {{"pairs", kGatePairs},     {"passes", passes},
          {"weighed", weighed},          {"noise_per_sample", noise},
          {"added_variance_per_sample", added}, {"variance_ratio", variance_ratio},
          {"work_ratio", work_ratio},    {"mean_correction_probability", corrections},
          {"traced_exactly_everywhere", trace_exactly}};
}

DiskGate scene_disk_gate(const VisibilityContext& context) {
  const RenderOptions& options = context.options;
  const OccluderDiskIndex index(context.world, context.scene.instances.size(), options.disk_lazy_from);
  std::vector<DiskGateRecord> records;
  DiskGateProbe probe(context, index, records);
  double noise = 0;
  const std::vector<GateSample> samples = shade_gate_pairs(context, probe, options.seed ^ 0x6469736B67617465ULL, noise);
  DiskGate gate;
  if (records.empty()) return gate;  // no segment to weigh
  const CorrectionOptions correction{.scale = options.correction_scale, .floor = options.probability_floor};
  const int passes = std::clamp(options.spp, 1, kDiskGatePasses);
  double work_exact = 0, work_cv = 0, added = 0, probability_sum = 0, probability_count = 0;
  PixelRandom draws(options.seed ^ 0x7265706C6179ULL, 0, 0);
  for (std::size_t pair = 0; pair < kGatePairs; ++pair) {
    CorrectionEvidence evidence;  // the pixel's, as the render starts it
    for (int pass = 0; pass < passes; ++pass) {
      const GateSample& sample = samples[2 * pair + static_cast<std::size_t>(pass % 2)];
      if (!sample.shaded) continue;
      const CorrectionProbabilities q = correction_probabilities(ProxyKind::general, evidence, correction);
      work_exact += sample.camera_work;
      work_cv += sample.camera_work + sample.own_work;
      for (std::size_t r = sample.first; r < sample.last; ++r) {
        const DiskGateRecord& record = records[r];
        work_exact += record.exact_work;
        if (record.exact) {
          work_cv += record.exact_work;
          continue;
        }
        work_cv += record.exact_work - record.correction_work + record.disk_work;
        if (record.traced_blocked) continue;
        const double p = record.proxy_blocked ? q.after_hit : q.after_miss;
        work_cv += p * kDiskCorrectionWork * record.correction_work;
        probability_sum += p, probability_count += 1;
        if (record.proxy_blocked != record.mesh_blocked) added += record.contribution * record.contribution * (1 / p - 1);
        if (draws.uniform() < p) evidence.add(record.proxy_blocked, record.mesh_blocked);
      }
    }
  }
  gate.passes = passes;
  gate.noise = noise;
  gate.added = added / (static_cast<double>(kGatePairs) * passes);
  gate.work_ratio = work_cv / work_exact;
  gate.corrections = probability_count > 0 ? probability_sum / probability_count : 0.0;
  gate.weighed = gate.noise > 0;
  if (gate.weighed) {
    gate.variance_ratio = (gate.noise + gate.added) / gate.noise;
    gate.trace_exactly = !(gate.variance_ratio * gate.work_ratio < kLearnedPaysBelow);
  } else {
    // Exact answers without noise: the control variate only where it adds none and costs
    // less (variance_ratio stays 1: no ratio to take).
    gate.trace_exactly = gate.added > 0 || !(gate.work_ratio < kLearnedPaysBelow);
  }
  return gate;
}

}  // namespace visproxy

namespace visproxy {
namespace {

// Adaptive eq. 8 with VPLs (adaptive_eq8_vpl_gate): a shadow ray that eq. 8 answers alone
// costs this much more, per unit of modelled work, than one of a point's connections that
// exact visibility traces in packets: `visproxy-bench-vpl` puts single rays at 1.2-1.6x
// the packets' time on the armadillo and menagerie rooms.
constexpr double kSingleRayWork = 1.4;

struct Eq8GateRecord {
  bool connection = false;  // a connection (packets for exact visibility), else a segment to a light
  bool own_blocked = false;
  std::uint8_t type = 0;     // RayTypeCounts' index: mesh and proxy of the rest blocked, ...
  std::uint32_t point = 0;   // the probabilities of its point (Eq8GateProbe::probabilities)
  float exact_work = 0, proxy_work = 0, correction_work = 0;
  float contribution = 0;  // luminance, when visible
};

// Answers exactly, recording what eq. 8 would have seen: each segment's ray type against the
// rest of the scene, its point's probabilities (drawn as the render draws them, probes
// included), its modelled work and its contribution.
class Eq8GateProbe final : public PointVisibility {
 public:
  Eq8GateProbe(const VisibilityContext& context, std::vector<Eq8GateRecord>& records)
      : context_(context), kinds_(stochastic_kinds(context)), records_(records) {}
  void begin(const ShadingPoint& point) override {
    point_ = point;
    first_ = records_.size();
    if (point.pixel != pixel_) pixel_probes_ = RayTypeCounts{}, pixel_ = point.pixel;  // a new pair's pixel
    const std::uint64_t probes_before = point.stats->probe_rays;
    const ProxyKind kind = kinds_[static_cast<std::size_t>(point.hit->instance)];
    probabilities.push_back(
        eq8_point_probabilities(context_, kind, point, context_.options.probe_passes > 0 ? &pixel_probes_ : nullptr));
    probes_ = static_cast<double>(point.stats->probe_rays - probes_before);
  }
  double to_light(const Vertex& end) override { return record(end, false); }
  double connection(const Vertex& end) override { return record(end, true); }
  bool wants_contributions() const override { return true; }
  void contributions(std::span<const double> luminance) override {
    if (luminance.size() != records_.size() - first_) throw Error("render: an integrator reported contributions for other segments than it asked");
    for (std::size_t i = 0; i < luminance.size(); ++i) records_[first_ + i].contribution = static_cast<float>(luminance[i]);
  }
  void end() override {
    // The probes' work: each a proxy query and a mesh query of the rest of the scene, as
    // single rays, costed as the point's segments to lights are on average (its connections
    // where it has none).
    double sum = 0, count = 0;
    for (const bool connections : {false, true}) {
      for (std::size_t r = first_; r < records_.size(); ++r)
        if (records_[r].connection == connections) sum += records_[r].proxy_work + records_[r].correction_work, count += 1;
      if (count > 0) break;
    }
    const double per_probe = count > 0 ? sum / count : 2 * kQueryWork;
    point_work_ = kSingleRayWork * probes_ * per_probe;
  }
  std::size_t records() const { return records_.size(); }
  double point_work() const { return point_work_; }

  std::vector<Eq8Probabilities> probabilities;  // per point begun

 private:
  double record(const Vertex& end, bool connection) {
    RenderStats uncounted;
    const ProxyAnswer answer = proxy_answer(context_.world, point_.position, end, point_.hit->instance, context_.options.split,
                                            uncounted, point_.hit->own_mesh_clear_of(point_.position, end));
    const bool mesh = !answer.own_blocks && context_.world.mesh_blocks(point_.position, end, answer.rest);
    const SegmentQueryCosts c =
        shadow_segment_costs(context_.world, point_.position, end, point_.hit->instance, context_.options.split);
    Eq8GateRecord r;
    r.connection = connection;
    r.own_blocked = answer.own_blocks;
    r.type = static_cast<std::uint8_t>(mesh ? (answer.proxy_blocked ? 0 : 1) : (answer.proxy_blocked ? 2 : 3));
    r.point = static_cast<std::uint32_t>(probabilities.size() - 1);
    r.exact_work = static_cast<float>(c.exact), r.proxy_work = static_cast<float>(c.proxy),
    r.correction_work = static_cast<float>(c.correction);
    records_.push_back(r);
    return answer.own_blocks || mesh ? 0.0 : 1.0;
  }

  const VisibilityContext& context_;
  std::vector<ProxyKind> kinds_;
  std::vector<Eq8GateRecord>& records_;
  std::size_t first_ = 0;
  ShadingPoint point_;
  RayTypeCounts pixel_probes_;  // the probes' counts in the pixel of pixel_, as the render keeps them
  std::size_t pixel_ = std::numeric_limits<std::size_t>::max();
  double probes_ = 0, point_work_ = 0;
};

}  // namespace

nlohmann::json Eq8Gate::to_json() const {
  nlohmann::json rows = nlohmann::json::array();
  for (std::size_t i = 0; i < instances.size(); ++i) {
    const Instance& g = instances[i];
    rows.push_back({{"instance", i},
                    {"samples", g.samples},
                    {"noise", g.noise},
                    {"added_variance", g.added},
                    {"work_ratio", g.work_exact > 0 ? nlohmann::json(g.work_eq8 / g.work_exact) : nlohmann::json(nullptr)},
                    {"predicted_ratio", std::isfinite(g.ratio) ? nlohmann::json(g.ratio) : nlohmann::json(nullptr)}});
  }
  return {{"pairs", kGatePairs}, {"instances", rows}};
}

std::vector<double> Eq8Gate::ratios() const {
  std::vector<double> r;
  for (const Instance& g : instances) r.push_back(g.ratio);
  return r;
}

Eq8Gate adaptive_eq8_vpl_gate(const VisibilityContext& context) {
  const RenderOptions& options = context.options;
  std::vector<Eq8GateRecord> records;
  Eq8GateProbe probe(context, records);
  double noise = 0;
  const std::vector<GateSample> samples = shade_gate_pairs(context, probe, options.seed ^ 0x6571386761746573ULL, noise);
  // With probe_passes > 0 the render probes in its first passes only, the pairs in their
  // first samples (passes 0 and 1).
  const double render_share = options.probe_passes > 0 ? std::min(1.0, static_cast<double>(options.probe_passes) / std::max(options.spp, 1)) : 1.0;
  const double pair_share = options.probe_passes > 0 ? std::min(1.0, static_cast<double>(options.probe_passes) / 2) : 1.0;
  Eq8Gate gate;
  gate.instances.resize(context.scene.instances.size());
  for (const GateSample& sample : samples) {
    if (!sample.shaded) continue;
    Eq8Gate::Instance& g = gate.instances[static_cast<std::size_t>(sample.instance)];
    g.samples += 1;
    g.noise += sample.pair_noise;
    g.work_exact += sample.camera_work;
    g.work_eq8 += sample.camera_work + sample.own_work * render_share / pair_share;
    for (std::size_t r = sample.first; r < sample.last; ++r) {
      const Eq8GateRecord& record = records[r];
      g.work_exact += record.exact_work;
      const bool single = record.connection && options.group_connections;  // exact traces it in a packet
      const double factor = single ? kSingleRayWork : 1.0;
      if (record.own_blocked) {
        g.work_eq8 += factor * record.proxy_work;
        continue;
      }
      const Eq8Probabilities& point = probe.probabilities[record.point];
      const Probabilities& p = record.connection ? point.connection : point.to_light;
      const bool proxy_blocked = record.type == 0 || record.type == 2;
      g.work_eq8 += factor * (record.proxy_work + (proxy_blocked ? p.p2 : p.p3) * record.correction_work);
      RayTypeFractions one;
      one.f[record.type] = 1;
      g.added += static_cast<double>(record.contribution) * record.contribution * estimator_variance(one, p);
    }
  }
  for (Eq8Gate::Instance& g : gate.instances) {
    if (g.samples == 0 || !(g.work_exact > 0)) continue;  // nothing seen: +infinity, traced exactly
    if (g.noise > 0)
      g.ratio = (g.noise + g.added) * g.work_eq8 / (g.noise * g.work_exact);
    else if (g.added == 0)
      g.ratio = g.work_eq8 / g.work_exact;  // no noise either way: the work alone
    if (!std::isfinite(g.ratio)) g.ratio = std::numeric_limits<double>::infinity();
  }
  return gate;
}

}  // namespace visproxy
