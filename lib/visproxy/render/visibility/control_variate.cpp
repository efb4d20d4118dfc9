// Stochastic visibility with the proxy as a control variate: V' + (V - V') [u < q] / q, with
// q chosen by the proxy's answer (equal, adaptive from probe rays, or learned per pixel).

#include <optional>
#include <span>
#include <vector>

#include "visproxy/render/visibility/occluder_disks.h"
#include "visproxy/render/visibility/visibility.h"
#include "visproxy/render/world/query_costs.h"
#include "visproxy/render/world/sampling.h"

namespace visproxy {

ControlVariateSample control_variate_visibility(const RenderWorld& world, const Vertex& from, const Vertex& to, int own_instance,
                                                const CorrectionProbabilities& q, double u, bool split, RenderStats& stats,
                                                bool own_cannot_block) {
  ControlVariateSample sample;
  const ProxyAnswer answer = proxy_answer(world, from, to, own_instance, split, stats, own_cannot_block);
  if (answer.own_blocks) return sample;
  const InstanceFilter& rest = answer.rest;
  sample.proxy_traced = true;
  sample.proxy_blocked = answer.proxy_blocked;
  const double proxy = sample.proxy_blocked ? 0.0 : 1.0;
  sample.trace_probability = sample.proxy_blocked ? q.after_hit : q.after_miss;
  sample.visibility = proxy;
  if (!(u < sample.trace_probability)) return sample;
  ++(sample.proxy_blocked ? stats.control_variate.after_hit : stats.control_variate.after_miss);
  ++stats.exact_tests;
  sample.mesh_traced = true;
  sample.mesh_blocked = world.mesh_blocks(from, to, rest);
  sample.visibility = proxy + ((sample.mesh_blocked ? 0.0 : 1.0) - proxy) / sample.trace_probability;
  return sample;
}

bool control_variate_uses_disks(const VisibilityContext& context) {
  if (context.options.integrator != IntegratorKind::vpl) return false;
  for (std::size_t i = 0; i < context.scene.instances.size(); ++i)
    if (!context.world.occluder_spheres(i).empty()) return true;
  return false;
}

namespace {

class ControlVariateVisibility;

class ControlVariatePoint final : public PointVisibility {
 public:
  explicit ControlVariatePoint(ControlVariateVisibility& shared) : shared_(shared) {}
  void begin(const ShadingPoint& point) override;
  double to_light(const Vertex& end) override {
    if (disks_in_use_) return exact_light(end);
    if (settled()) return settled_answer(end);
    model_costs(end);
    const CorrectionProbabilities& q = light_corrections();
    return trace_exactly_ ? exact_answer(end) : answer(end, q);
  }
  double connection(const Vertex& end) override {
    return disks_in_use_ ? disk_answer(end, connection_corrections()) : answer(end, connection_corrections());
  }
  void connections(std::span<const Vertex> ends, std::span<const unsigned> end_shells, std::span<double> out) override;

 private:
  double answer(const Vertex& end, const CorrectionProbabilities& q);
  // With occluder disks, a segment to an area light: traced exactly. A point's light sample
  // carries as much light as many VPLs together, and a wrong disk answer corrected at
  // probability q adds (1/q - 1) x its squared contribution to the variance; on the
  // armadillo and menagerie rooms these segments gave 99.9 % of the variance the control
  // variate added, for one segment in 180-460 of a point's.
  double exact_light(const Vertex& end);
  // Where the learned choice says the proxy does not pay: the meshes alone, as exact
  // visibility traces them; while the pixel has little evidence and evidence could make the
  // proxy pay, one segment in kLearnedExploreOneIn traces proxy and meshes both (an exact answer
  // too) to keep learning.
  double exact_answer(const Vertex& end);
  // With occluder disks as V': the exactly traced part first, then the disks, corrected by
  // the meshes of the instances the disks stand for.
  double disk_answer(const Vertex& end, const CorrectionProbabilities& q);
  void learn(bool proxy_blocked, bool mesh_blocked);
  void evidence_changed();  // learned: the pixel's corrections and cached choice are recomputed when next asked
  // Learned with costs: the modelled costs of the pixel's first kCostSegments light
  // segments from one instance, which its choice weighs, with the instance's average, once
  // they are all in.
  void model_costs(const Vertex& end);
  // Learned with costs: the pixel traces this instance's segments exactly and has nothing
  // left to learn (no exploring, its costs modelled): answered touching one int per pixel.
  bool settled() const;
  double settled_answer(const Vertex& end);
  CorrectionCosts pixel_costs(int instance) const;
  // The probabilities for segments to a light (the kind of the rest of the scene) and for
  // other segments (general), brought up to date with the pixel's evidence when it grew.
  const CorrectionProbabilities& light_corrections();
  const CorrectionProbabilities& connection_corrections();
  bool disks_in_use_ = false;
  PointDisks disks_;
  ExactConnections exact_part_;  // traced exactly: the own instance when splitting, instances without sphere sets
  InstanceFilter disk_part_;     // the instances the disks stand for
  bool any_exact_ = false;
  // connections(): per end, the lanes' filters and answers (kept to reuse their memory)
  std::vector<Vertex> traced_ends_;
  std::vector<unsigned> traced_lanes_;
  std::vector<std::size_t> traced_index_;
  std::vector<std::uint8_t> blocked_, hidden_, proxy_;
  std::vector<double> trace_probability_;
  ControlVariateVisibility& shared_;
  ShadingPoint point_;
  ProxyKind kind_ = ProxyKind::general;
  CorrectionProbabilities corrections_, connection_corrections_;
  bool corrections_stale_ = false, connection_corrections_stale_ = false;  // learned: evidence added since computed
  bool trace_exactly_ = false;  // learned with costs: light segments traced exactly (light_corrections())
  bool explore_ = false;        // and some of them explored (the proxy could pay)
};

class ControlVariateVisibility final : public Visibility {
 public:
  explicit ControlVariateVisibility(const VisibilityContext& context)
      : context_(context),
        options_{.scale = context.options.correction_scale, .floor = context.options.probability_floor},
        pixel_probes_(context.options.probe_passes > 0 ? context.pixels : 0),
        pixel_evidence_(context.options.probabilities == ProbabilityMode::learned ? context.pixels : 0),
        costs_(context.correction_costs),
        priors_(context.correction_priors),
        pixel_choice_(costs_.empty() ? 0 : context.pixels),
        pixel_costs_(costs_.empty() ? 0 : context.pixels),
        pixel_settled_(costs_.empty() ? 0 : context.pixels, -1),
        camera_(CameraRays(context.scene.camera).origin()) {
    kinds_ = stochastic_kinds(context);
    disks_ = control_variate_uses_disks(context);
    if (disks_) disk_index_.emplace(context.world, context.scene.instances.size(), context.options.disk_lazy_from);
  }
  std::unique_ptr<PointVisibility> point_visibility() override { return std::make_unique<ControlVariatePoint>(*this); }

 private:
  friend class ControlVariatePoint;
  VisibilityContext context_;
  CorrectionOptions options_;
  std::vector<ProxyKind> kinds_;
  std::vector<RayTypeCounts> pixel_probes_;        // adaptive with probe_passes > 0
  std::vector<CorrectionEvidence> pixel_evidence_;  // learned: what each pixel's corrections showed so far
  std::vector<CorrectionCosts> costs_;              // learned, direct light: per instance (learned_choice)
  std::vector<CorrectionPrior> priors_;             // and what each instance's proxy showed before the render
  // With costs: each pixel's last choice and the instance it was made for (-1: none, or the
  // pixel's evidence changed since), so that a pixel whose evidence stands still (traced
  // exactly, not exploring) does not weigh it again at every sample.
  struct CachedChoice {
    LearnedChoice choice;
    int instance = -1;
  };
  std::vector<CachedChoice> pixel_choice_;
  struct PixelCosts {
    SegmentQueryCosts sum;  // camera: each segment's share
    int instance = -1;      // the instance the segments start on (the pixel's first)
    int segments = 0;
  };
  static constexpr int kCostSegments = 4;
  std::vector<PixelCosts> pixel_costs_;
  std::vector<int> pixel_settled_;  // the instance whose segments the pixel traces exactly, with nothing to learn (-1: none)
  Vertex camera_ = Vertex::Zero();
  bool disks_ = false;  // the VPL integrator with sphere-set proxies: occluder disks are V'
  std::optional<OccluderDiskIndex> disk_index_;
};

void ControlVariatePoint::begin(const ShadingPoint& point) {
  point_ = point;
  const RenderOptions& options = shared_.context_.options;
  kind_ = shared_.kinds_[static_cast<std::size_t>(point.hit->instance)];
  corrections_ = equal_correction_probabilities(kind_);
  // Segments that do not end on a light: the general form (see TermChoicePoint::begin).
  connection_corrections_ = equal_correction_probabilities(ProxyKind::general);
  if (options.probabilities == ProbabilityMode::adaptive) {
    const CorrectionEvidence evidence = CorrectionEvidence::from(
        adaptive_probe_counts(shared_.context_, point, shared_.pixel_probes_.empty() ? nullptr : &shared_.pixel_probes_[point.pixel]));
    corrections_ = correction_probabilities(kind_, evidence, shared_.options_);
    connection_corrections_ = correction_probabilities(ProxyKind::general, evidence, shared_.options_);
  }
  // learned: computed when first asked (an integrator asks for one of the two kinds of segment).
  corrections_stale_ = connection_corrections_stale_ = options.probabilities == ProbabilityMode::learned;
  trace_exactly_ = explore_ = false;
  disks_in_use_ = shared_.disks_;
  if (!disks_in_use_) return;
  // Traced exactly: the own instance when splitting, and every instance without a sphere
  // set. The disks stand for the others.
  const DiskPartition partition = begin_point_disks(disks_, exact_part_, *shared_.disk_index_, shared_.context_.world, options,
                                                    *point.hit, point.position, options.split);
  disk_part_ = {.skip = -1, .only = -1, .bits = partition.disks};
  any_exact_ = partition.traced != 0;
}

// A group of connections with disks as V': the same estimate per connection as
// disk_answer(), with the exact parts and the corrections traced as packets. The
// probabilities are those the point began with (learned ones are updated after the group
// from every correction it traced): they depend only on draws made before the group, so
// each estimate stays unbiased.
void ControlVariatePoint::connections(std::span<const Vertex> ends, std::span<const unsigned> end_shells, std::span<double> out) {
  if (!disks_in_use_ || !shared_.context_.options.group_connections) return PointVisibility::connections(ends, end_shells, out);
  const RenderWorld& world = shared_.context_.world;
  RenderStats& stats = *point_.stats;
  const std::size_t m = ends.size();
  const CorrectionProbabilities q = connection_corrections();
  // 1. The exactly traced part (own instance, instances without sphere sets), where no
  //    convex shell clears it.
  blocked_.assign(m, 0);
  if (any_exact_) {
    traced_ends_.clear(), traced_lanes_.clear(), traced_index_.clear();
    for (std::size_t i = 0; i < m; ++i) {
      const unsigned lane = exact_part_.lane(ends[i], end_shells.empty() ? nullptr : &end_shells[i]);
      if (lane != 0) traced_ends_.push_back(ends[i]), traced_lanes_.push_back(lane), traced_index_.push_back(i);
    }
    if (!traced_ends_.empty()) {
      stats.exact_tests += traced_ends_.size();
      std::vector<std::uint8_t>& answers = hidden_;
      answers.resize(traced_ends_.size());
      world.mesh_blocks(point_.position, traced_ends_, answers, {}, traced_lanes_);
      for (std::size_t k = 0; k < traced_ends_.size(); ++k) blocked_[traced_index_[k]] = answers[k];
    }
  }
  // 2. V' from the disks, all ends at once.
  std::vector<std::uint8_t>& proxy = proxy_;
  proxy.resize(m);
  disks_.occludes(ends, proxy, stats.disks.tests, &stats.disks.clusters);
  // 3. The corrections each connection draws, traced as packets.
  traced_ends_.clear(), traced_lanes_.clear(), traced_index_.clear();
  trace_probability_.assign(m, 0);
  for (std::size_t i = 0; i < m; ++i) {
    const double u = point_.choices->uniform();  // drawn for every connection, as disk_answer() does
    out[i] = 0;
    if (blocked_[i]) continue;
    ++stats.proxy_tests;
    const double p = proxy[i] ? q.after_hit : q.after_miss;
    trace_probability_[i] = p;
    *point_.p1_sum += 1 - p;
    *point_.p1_count += 1;
    out[i] = proxy[i] ? 0.0 : 1.0;
    if (u < p) {
      ++(proxy[i] ? stats.control_variate.after_hit : stats.control_variate.after_miss);
      traced_ends_.push_back(ends[i]), traced_lanes_.push_back(disk_part_.bits), traced_index_.push_back(i);
    }
  }
  if (traced_ends_.empty()) return;
  stats.exact_tests += traced_ends_.size();
  hidden_.resize(traced_ends_.size());
  world.mesh_blocks(point_.position, traced_ends_, hidden_, {}, traced_lanes_);
  for (std::size_t k = 0; k < traced_ends_.size(); ++k) {
    const std::size_t i = traced_index_[k];
    const double v = proxy[i] ? 0.0 : 1.0;
    out[i] = v + ((hidden_[k] ? 0.0 : 1.0) - v) / trace_probability_[i];
    learn(proxy[i] != 0, hidden_[k] != 0);
  }
}

void ControlVariatePoint::learn(bool proxy_blocked, bool mesh_blocked) {
  if (shared_.pixel_evidence_.empty()) return;
  CorrectionEvidence& evidence = shared_.pixel_evidence_[point_.pixel];
  evidence.add(proxy_blocked, mesh_blocked);
  evidence_changed();
}

void ControlVariatePoint::model_costs(const Vertex& end) {
  if (shared_.pixel_costs_.empty()) return;
  ControlVariateVisibility::PixelCosts& c = shared_.pixel_costs_[point_.pixel];
  const int instance = point_.hit->instance;
  if (c.segments >= ControlVariateVisibility::kCostSegments || (c.segments > 0 && c.instance != instance)) return;
  const RenderOptions& options = shared_.context_.options;
  const SegmentQueryCosts q =
      segment_query_costs(shared_.context_.world, shared_.camera_, point_.position, end, instance, options.split);
  c.sum.camera += q.camera / std::max(options.shadow_rays, 1);
  c.sum.exact += q.exact, c.sum.proxy += q.proxy, c.sum.correction += q.correction;
  c.instance = instance;
  // The choice is weighed again once the pixel's costs are in (until then, the instance's).
  if (++c.segments == ControlVariateVisibility::kCostSegments) evidence_changed();
}

// The instance's average from before the render counts as one segment among the pixel's.
CorrectionCosts ControlVariatePoint::pixel_costs(int instance) const {
  const CorrectionCosts& average = shared_.costs_[static_cast<std::size_t>(instance)];
  const ControlVariateVisibility::PixelCosts& c = shared_.pixel_costs_[point_.pixel];
  if (c.segments < ControlVariateVisibility::kCostSegments || c.instance != instance) return average;
  const double n = c.segments + 1.0;
  return {.base = (c.sum.camera + c.sum.proxy + average.base) / n,
          .correction = (c.sum.correction + average.correction) / n,
          .exact = (c.sum.camera + c.sum.exact + average.exact) / n,
          .variance = average.variance};
}

void ControlVariatePoint::evidence_changed() {
  corrections_stale_ = connection_corrections_stale_ = true;
  if (!shared_.pixel_choice_.empty()) shared_.pixel_choice_[point_.pixel].instance = shared_.pixel_settled_[point_.pixel] = -1;
}

bool ControlVariatePoint::settled() const {
  return !shared_.pixel_settled_.empty() && shared_.pixel_settled_[point_.pixel] == point_.hit->instance;
}

double ControlVariatePoint::settled_answer(const Vertex& end) {
  RenderStats& stats = *point_.stats;
  ++stats.control_variate.traced_exactly;
  ++stats.exact_tests;
  *point_.p1_count += 1;  // the proxy alone: never
  return shared_.context_.world.mesh_blocks(point_.position, end) ? 0 : 1;
}

const CorrectionProbabilities& ControlVariatePoint::light_corrections() {
  if (corrections_stale_) {
    const CorrectionEvidence& evidence = shared_.pixel_evidence_[point_.pixel];
    if (shared_.costs_.empty()) {
      corrections_ = correction_probabilities(kind_, evidence, shared_.options_);
    } else {
      ControlVariateVisibility::CachedChoice& cached = shared_.pixel_choice_[point_.pixel];
      const int instance = point_.hit->instance;
      if (cached.instance != instance) {
        cached.choice =
            learned_choice(kind_, evidence, pixel_costs(instance), shared_.options_, shared_.priors_[static_cast<std::size_t>(instance)]);
        cached.instance = instance;
      }
      const LearnedChoice& choice = cached.choice;
      corrections_ = choice.q;
      trace_exactly_ = choice.trace_exactly;
      explore_ = choice.can_pay;
    }
    corrections_stale_ = false;
  }
  return corrections_;
}

double ControlVariatePoint::exact_answer(const Vertex& end) {
  const RenderWorld& world = shared_.context_.world;
  RenderStats& stats = *point_.stats;
  CorrectionEvidence& evidence = shared_.pixel_evidence_[point_.pixel];
  // Drawn whether or not it explores, as answer() draws one uniform per segment.
  const double u = point_.choices->uniform();
  ++stats.control_variate.traced_exactly;
  *point_.p1_count += 1;  // the proxy alone: never
  const bool learning = learned_keeps_exploring(explore_, evidence);
  if (!(learning && u * kLearnedExploreOneIn < 1)) {
    const ControlVariateVisibility::PixelCosts& c = shared_.pixel_costs_[point_.pixel];
    if (!learning && (c.segments >= ControlVariateVisibility::kCostSegments || c.instance != point_.hit->instance))
      shared_.pixel_settled_[point_.pixel] = point_.hit->instance;
    ++stats.exact_tests;
    return world.mesh_blocks(point_.position, end) ? 0 : 1;
  }
  ++stats.control_variate.explored;
  const ControlVariateSample sample =
      control_variate_visibility(world, point_.position, end, point_.hit->instance, {.after_miss = 1, .after_hit = 1}, 0.0,
                                 shared_.context_.options.split, stats, point_.hit->own_mesh_clear_of(point_.position, end));
  if (sample.proxy_traced) evidence.answer(sample.proxy_blocked), evidence_changed();
  if (sample.mesh_traced) learn(sample.proxy_blocked, sample.mesh_blocked);
  return sample.visibility;
}

const CorrectionProbabilities& ControlVariatePoint::connection_corrections() {
  if (connection_corrections_stale_) {
    connection_corrections_ = correction_probabilities(ProxyKind::general, shared_.pixel_evidence_[point_.pixel], shared_.options_);
    connection_corrections_stale_ = false;
  }
  return connection_corrections_;
}

double ControlVariatePoint::disk_answer(const Vertex& end, const CorrectionProbabilities& q) {
  const RenderWorld& world = shared_.context_.world;
  RenderStats& stats = *point_.stats;
  const double u = point_.choices->uniform();
  if (any_exact_) {
    // Instances whose convex shell holds both ends cannot block.
    const unsigned lane = exact_part_.lane(end);
    if (lane != 0) {
      ++stats.exact_tests;
      if (world.mesh_blocks(point_.position, end, {.skip = -1, .only = -1, .bits = lane})) return 0;
    }
  }
  ++stats.proxy_tests;
  const bool proxy_blocked = disks_.occludes(end, stats.disks.tests, &stats.disks.clusters);
  const double proxy = proxy_blocked ? 0.0 : 1.0;
  const double trace_probability = proxy_blocked ? q.after_hit : q.after_miss;
  *point_.p1_sum += 1 - trace_probability;
  *point_.p1_count += 1;
  if (!(u < trace_probability)) return proxy;
  ++(proxy_blocked ? stats.control_variate.after_hit : stats.control_variate.after_miss);
  ++stats.exact_tests;
  const bool mesh_blocked = world.mesh_blocks(point_.position, end, disk_part_);
  learn(proxy_blocked, mesh_blocked);
  return proxy + ((mesh_blocked ? 0.0 : 1.0) - proxy) / trace_probability;
}

double ControlVariatePoint::exact_light(const Vertex& end) {
  ++point_.stats->exact_tests;
  return shared_.context_.world.mesh_blocks(point_.position, end) ? 0 : 1;
}

double ControlVariatePoint::answer(const Vertex& end, const CorrectionProbabilities& q) {
  const RenderOptions& options = shared_.context_.options;
  const ControlVariateSample sample = control_variate_visibility(shared_.context_.world, point_.position, end, point_.hit->instance, q,
                                                                 point_.choices->uniform(), options.split, *point_.stats,
                                                                 point_.hit->own_mesh_clear_of(point_.position, end));
  if (sample.proxy_traced) {
    *point_.p1_sum += 1 - sample.trace_probability;
    *point_.p1_count += 1;
    if (!shared_.pixel_choice_.empty()) {  // the cost-aware choice weighs the share of each answer
      shared_.pixel_evidence_[point_.pixel].answer(sample.proxy_blocked);
      evidence_changed();
    }
  }
  if (sample.mesh_traced) learn(sample.proxy_blocked, sample.mesh_blocked);
  return sample.visibility;
}

}  // namespace

std::unique_ptr<Visibility> make_control_variate_visibility(const VisibilityContext& context) {
  return std::make_unique<ControlVariateVisibility>(context);
}

}  // namespace visproxy
