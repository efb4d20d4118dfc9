#pragma once
// Visibility strategies: how the renderer answers a shadow segment: traced exactly,
// estimated with a proxy (eq. 8 or the control variate), proved by bounds, or approximated
// by occluder disks. A strategy answers the segments of one shading point at a time, one
// by one or as a group that shares the point as origin; integrators choose the segments.

#include <array>
#include <cstddef>
#include <memory>
#include <span>
#include <vector>

#include "visproxy/estimator/probabilities.h"
#include "visproxy/render/options/render_options.h"
#include "visproxy/render/options/render_stats.h"
#include "visproxy/render/world/render_world.h"
#include "visproxy/render/world/sampling.h"

namespace visproxy {

/// A shading point as a visibility strategy sees it.
struct ShadingPoint {
  std::size_t pixel = 0;
  int pass = 0;
  const SurfaceHit* hit = nullptr;  ///< where the camera ray met the surface
  Vertex position;                  ///< the point the segments leave from: hit->position moved off the surface
  PixelRandom* choices = nullptr;   ///< the estimators' stream (terms, corrections, probes)
  RenderStats* stats = nullptr;
  /// stochastic: the pixel's running sum of the probability that a segment traces the
  /// proxy alone, and how many values it holds (RenderResult::p1_map)
  double* p1_sum = nullptr;
  double* p1_count = nullptr;
};

/// The answers of one thread, for the shading point begin() was last given. Values are
/// estimates of visibility (1 unoccluded, 0 occluded); stochastic strategies may return any
/// real number whose mean is the visibility.
class PointVisibility {
 public:
  virtual ~PointVisibility() = default;
  virtual void begin(const ShadingPoint& point) = 0;
  /// The segment from the point to `end`, a light sample moved off the light (light_end).
  virtual double to_light(const Vertex& end) = 0;
  /// A segment to a point that is not on a light (a virtual point light, moved off its
  /// surface by segment_end). Proofs that need one end on a light are not used for it.
  virtual double connection(const Vertex& end) = 0;
  /// connection() for a group of ends; out[i] answers ends[i]. `end_shells`, empty or one
  /// per end, holds RenderWorld::convex_shells_holding(ends[i]) when the caller knows it
  /// (fixed ends such as VPLs). Strategies that trace the group as packets of rays from the
  /// shared origin override it.
  virtual void connections(std::span<const Vertex> ends, std::span<const unsigned> end_shells, std::span<double> out) {
    (void)end_shells;
    for (std::size_t i = 0; i < ends.size(); ++i) out[i] = connection(ends[i]);
  }
  /// Whether the strategy asks integrators for contributions() (costs them a pass over the
  /// point's segments).
  virtual bool wants_contributions() const { return false; }
  /// What each segment answered since begin() adds to the luminance of the point's value
  /// when it is visible (answer 1), in the order the segments were asked: integrators
  /// report it before end() when wants_contributions().
  virtual void contributions(std::span<const double> luminance) { (void)luminance; }
  /// After the point's last segment.
  virtual void end() {}
};

/// One per render: holds what persists across a pixel's passes and makes each thread's
/// PointVisibility.
class Visibility {
 public:
  virtual ~Visibility() = default;
  virtual std::unique_ptr<PointVisibility> point_visibility() = 0;
};

struct VisibilityContext {
  const Scene& scene;
  const RenderWorld& world;
  const RenderOptions& options;
  const LightSampler& lights;
  std::size_t pixels = 0;
  /// ProbabilityMode::optimal: eq. 8's probabilities per form of the rest of the scene
  /// (indexed by ProxyKind: outside, inside, general), found before the render.
  std::array<Probabilities, 3> optimal = {};
  /// ProbabilityMode::learned with the control variate and direct light: per instance, what
  /// a segment from its points costs and the render's noise without proxies, modelled before
  /// the render (learned_choice()); empty otherwise (the cost-blind rule).
  std::vector<CorrectionCosts> correction_costs;
  /// With correction_costs: per instance, what its proxy showed on segments traced before the
  /// render (the pixels' evidence starts from it).
  std::vector<CorrectionPrior> correction_priors;
  /// Adaptive eq. 8's gate: per instance, 1 where the points of the instance trace every
  /// segment exactly (adaptive_eq8_ratios() not below kLearnedPaysBelow); empty: none do.
  std::vector<std::uint8_t> trace_exactly_from;
};

std::unique_ptr<Visibility> make_exact_visibility(const VisibilityContext& context);
std::unique_ptr<Visibility> make_term_choice_visibility(const VisibilityContext& context);
std::unique_ptr<Visibility> make_control_variate_visibility(const VisibilityContext& context);
/// Whether the control variate's V' is occluder disks: the VPL integrator, with some
/// instance's sphere set.
bool control_variate_uses_disks(const VisibilityContext& context);
std::unique_ptr<Visibility> make_bounds_visibility(const VisibilityContext& context);
std::unique_ptr<Visibility> make_occluder_disk_visibility(const VisibilityContext& context);
/// The strategy `context.options` asks for.
std::unique_ptr<Visibility> make_visibility(const VisibilityContext& context);

/// The stochastic visibility of one shadow segment, eq. 8 with the given probabilities;
/// `u` in [0, 1) chooses the term. Counts its queries into `stats`. With `split`, the own
/// instance is traced exactly first, unless `own_cannot_block` (SurfaceHit::own_mesh_clear_of),
/// and the rest of the scene stochastically.
double stochastic_visibility(const RenderWorld& world, const Vertex& from, const Vertex& to, int own_instance,
                             const Probabilities& probabilities, double u, bool split, RenderStats& stats,
                             bool own_cannot_block = false);

/// One shadow segment through the control-variate estimator: V' + (V - V') [u < q] / q.
struct ControlVariateSample {
  double visibility = 0;
  bool proxy_traced = false;  ///< false when the own instance blocked the segment first
  bool proxy_blocked = false;
  double trace_probability = 0;  ///< the q the proxy's answer chose
  bool mesh_traced = false;
  bool mesh_blocked = false;
};
ControlVariateSample control_variate_visibility(const RenderWorld& world, const Vertex& from, const Vertex& to, int own_instance,
                                                const CorrectionProbabilities& q, double u, bool split, RenderStats& stats,
                                                bool own_cannot_block = false);

/// The proxy's answer for a shadow segment, as eq. 8 and the control variate ask it: with
/// `split`, the own instance exactly (unless `own_cannot_block`) and the rest of the scene
/// through its proxies (RenderWorld::split_blocks); without, every instance's proxy.
struct ProxyAnswer {
  bool own_blocks = false;     ///< the own instance blocked the segment: V = 0, whatever the proxies answer
  bool proxy_blocked = false;  ///< V' of the rest of the scene (or of the whole scene without split)
  InstanceFilter rest;         ///< what the proxies stood for: the exact geometry a correction traces
};
ProxyAnswer proxy_answer(const RenderWorld& world, const Vertex& from, const Vertex& to, int own_instance, bool split,
                         RenderStats& stats, bool own_cannot_block);

}  // namespace visproxy

namespace visproxy {

/// Connections traced exactly, as the exact strategy traces them (bounds traces its
/// connections the same way, so that its image stays exact's): instances whose convex
/// shell holds both ends are skipped (RenderWorld::convex_shells_holding); a group goes to
/// Embree as packets.
class ExactConnections {
 public:
  /// Segments from `from` against the instances of `bits` (instance_bit()s; all by default).
  void begin(const RenderWorld& world, const Vertex& from, unsigned bits = 0x7FFFFFFFu);
  /// The instances a segment to `end` must still be traced against: those of `bits` whose
  /// convex shell does not hold both ends. `end_shells`, if known, is
  /// convex_shells_holding(end).
  unsigned lane(const Vertex& end, const unsigned* end_shells = nullptr) const {
    if (!shells_known_) from_shells_ = world_->convex_shells_holding(from_), shells_known_ = true;
    unsigned bits = bits_ & ~(from_shells_ & (end_shells ? *end_shells : world_->convex_shells_holding(end)));
    if ((bits & own_bit_) != 0 && own_hit_->own_mesh_clear_of(from_, end)) bits &= ~own_bit_;
    return bits;
  }
  /// Leaves out `own_bit` (the bit of `hit`'s instance, carried by no other instance the
  /// connections trace) from the segments that certainly miss that instance's mesh
  /// (SurfaceHit::own_mesh_clear_of from the begin() point). Until the next begin().
  void skip_own_where_clear(const SurfaceHit& hit, unsigned own_bit) { own_hit_ = &hit, own_bit_ = own_bit; }
  bool blocked(const Vertex& end) const;
  /// blocked[i] for ends[i]; `end_shells` as in PointVisibility::connections.
  void blocked(std::span<const Vertex> ends, std::span<const unsigned> end_shells, std::span<std::uint8_t> blocked);

 private:
  const RenderWorld* world_ = nullptr;
  Vertex from_ = Vertex::Zero();
  unsigned bits_ = 0x7FFFFFFFu;
  // The convex shells holding `from_`, found when a first connection asks (a point whose
  // integrator traces only segments to lights never does).
  mutable unsigned from_shells_ = 0;
  mutable bool shells_known_ = false;
  const SurfaceHit* own_hit_ = nullptr;
  unsigned own_bit_ = 0;
  std::vector<unsigned> lanes_;
};

/// Per instance: the kind of the rest of the scene's stochastic proxies that its shading
/// points see (RenderWorld::stochastic_kind, the own instance left out when splitting).
std::vector<ProxyKind> stochastic_kinds(const VisibilityContext& context);

/// adaptive probabilities: the ray types seen by K probe segments from the point to the
/// lights (rest of the scene: the own instance left out when splitting). With
/// probe_passes > 0 the counts of the pixel's first passes are kept in `pixel_counts` and
/// returned in later passes without probing. A scene without area lights (VPLs given by
/// the caller) has nothing to probe: the counts stay empty.
RayTypeCounts adaptive_probe_counts(const VisibilityContext& context, const ShadingPoint& point, RayTypeCounts* pixel_counts);

/// Eq. 8's probabilities at a shading point whose rest of the scene has proxies of `kind`,
/// as the options choose them (equal, optimal, or adaptive from the point's probe segments,
/// counted as adaptive_probe_counts() counts them): for segments to lights, and for
/// connections, which use the general form.
struct Eq8Probabilities {
  Probabilities to_light, connection;
};
Eq8Probabilities eq8_point_probabilities(const VisibilityContext& context, ProxyKind kind, const ShadingPoint& point,
                                         RayTypeCounts* pixel_counts);

}  // namespace visproxy
