// Stochastic visibility, eq. 8 of Billen et al.: a term drawn with p1, p2, p3, then traced;
// visibility splitting (eq. 27) traces the own instance exactly first.

#include <cstdint>
#include <span>
#include <vector>

#include "visproxy/render/visibility/visibility.h"

namespace visproxy {

double stochastic_visibility(const RenderWorld& world, const Vertex& from, const Vertex& to, int own_instance,
                             const Probabilities& p, double u, bool split, RenderStats& stats, bool own_cannot_block) {
  const ProxyAnswer answer = proxy_answer(world, from, to, own_instance, split, stats, own_cannot_block);
  if (answer.own_blocks) return 0.0;
  const bool proxy_free = !answer.proxy_blocked;
  const InstanceFilter& rest = answer.rest;
  if (u < p.p1) {
    ++stats.eq8.terms[0];
    return proxy_free ? 1.0 / p.p1 : 0.0;
  }
  if (u < p.p1 + p.p2) {
    ++stats.eq8.terms[1];
    if (proxy_free) return 0.0;
    ++stats.exact_tests;
    return world.mesh_blocks(from, to, rest) ? 0.0 : 1.0 / p.p2;
  }
  ++stats.eq8.terms[2];
  if (!proxy_free) return 0.0;
  ++stats.exact_tests;
  return world.mesh_blocks(from, to, rest) ? -1.0 / p.p3 : 0.0;
}

Eq8Probabilities eq8_point_probabilities(const VisibilityContext& context, ProxyKind kind, const ShadingPoint& point,
                                         RayTypeCounts* pixel_counts) {
  const RenderOptions& options = context.options;
  // Segments that do not end on a light prove nothing about outside or inside proxies that
  // are traced as surfaces: their estimate uses the general form.
  Eq8Probabilities p{equal_probabilities(kind), equal_probabilities(ProxyKind::general)};
  if (options.probabilities == ProbabilityMode::optimal) {
    p.to_light = context.optimal[static_cast<std::size_t>(kind)];
    p.connection = context.optimal[static_cast<std::size_t>(ProxyKind::general)];
  }
  if (options.probabilities == ProbabilityMode::adaptive) {
    const RayTypeFractions fractions = RayTypeFractions::from(adaptive_probe_counts(context, point, pixel_counts));
    p.to_light = optimal_probabilities(kind, fractions, {.floor = options.probability_floor});
    p.connection = optimal_probabilities(ProxyKind::general, fractions, {.floor = options.probability_floor});
    if (options.cost_heuristic) {
      p.to_light = apply_cost_heuristic(kind, p.to_light, fractions, options.probability_floor);
      p.connection = apply_cost_heuristic(ProxyKind::general, p.connection, fractions, options.probability_floor);
    }
  }
  return p;
}

namespace {

class TermChoiceVisibility;

class TermChoicePoint final : public PointVisibility {
 public:
  explicit TermChoicePoint(TermChoiceVisibility& shared) : shared_(shared) {}
  void begin(const ShadingPoint& point) override;
  double to_light(const Vertex& end) override;
  double connection(const Vertex& end) override;
  void connections(std::span<const Vertex> ends, std::span<const unsigned> end_shells, std::span<double> out) override;

 private:
  TermChoiceVisibility& shared_;
  ShadingPoint point_;
  Probabilities probabilities_, connection_probabilities_;
  bool exact_ = false;  // the gate traces this point's segments exactly
  ExactConnections connections_;  // with exact_ and grouped connections: as exact visibility traces them
  std::vector<std::uint8_t> blocked_;

  // A segment from a point the gate gave to exact visibility: the meshes' answer.
  double traced_exactly(const Vertex& end);
};

class TermChoiceVisibility final : public Visibility {
 public:
  explicit TermChoiceVisibility(const VisibilityContext& context)
      : context_(context), kinds_(stochastic_kinds(context)), pixel_probes_(context.options.probe_passes > 0 ? context.pixels : 0) {}
  std::unique_ptr<PointVisibility> point_visibility() override { return std::make_unique<TermChoicePoint>(*this); }

 private:
  friend class TermChoicePoint;
  VisibilityContext context_;
  std::vector<ProxyKind> kinds_;  // per instance: the estimator's form for the rest of the scene
  std::vector<RayTypeCounts> pixel_probes_;
};

double TermChoicePoint::traced_exactly(const Vertex& end) {
  ++point_.stats->exact_tests, ++point_.stats->eq8.traced_exactly;
  return shared_.context_.world.mesh_blocks(point_.position, end) ? 0.0 : 1.0;
}

void TermChoicePoint::begin(const ShadingPoint& point) {
  point_ = point;
  const std::vector<std::uint8_t>& gate = shared_.context_.trace_exactly_from;
  exact_ = !gate.empty() && gate[static_cast<std::size_t>(point.hit->instance)] != 0;
  if (exact_) {
    *point.p1_count += 1;  // the proxy alone never: p1 = 0
    if (shared_.context_.options.group_connections) connections_.begin(shared_.context_.world, point.position);
    return;
  }
  const ProxyKind kind = shared_.kinds_[static_cast<std::size_t>(point.hit->instance)];
  const Eq8Probabilities p =
      eq8_point_probabilities(shared_.context_, kind, point, shared_.pixel_probes_.empty() ? nullptr : &shared_.pixel_probes_[point.pixel]);
  probabilities_ = p.to_light, connection_probabilities_ = p.connection;
  *point.p1_sum += probabilities_.p1;
  *point.p1_count += 1;
}

double TermChoicePoint::to_light(const Vertex& end) {
  const RenderOptions& options = shared_.context_.options;
  if (exact_) return traced_exactly(end);
  return stochastic_visibility(shared_.context_.world, point_.position, end, point_.hit->instance, probabilities_,
                               point_.choices->uniform(), options.split, *point_.stats, point_.hit->own_mesh_clear_of(point_.position, end));
}

double TermChoicePoint::connection(const Vertex& end) {
  const RenderOptions& options = shared_.context_.options;
  if (exact_) return traced_exactly(end);
  return stochastic_visibility(shared_.context_.world, point_.position, end, point_.hit->instance, connection_probabilities_,
                               point_.choices->uniform(), options.split, *point_.stats, point_.hit->own_mesh_clear_of(point_.position, end));
}

// A point the gate gave to exact visibility traces its connections as exact visibility
// does: as packets from the point, when the options group them.
void TermChoicePoint::connections(std::span<const Vertex> ends, std::span<const unsigned> end_shells, std::span<double> out) {
  if (!exact_ || !shared_.context_.options.group_connections) return PointVisibility::connections(ends, end_shells, out);
  point_.stats->exact_tests += ends.size(), point_.stats->eq8.traced_exactly += ends.size();
  blocked_.resize(ends.size());
  connections_.blocked(ends, end_shells, blocked_);
  for (std::size_t i = 0; i < ends.size(); ++i) out[i] = blocked_[i] ? 0.0 : 1.0;
}

}  // namespace

std::unique_ptr<Visibility> make_term_choice_visibility(const VisibilityContext& context) {
  return std::make_unique<TermChoiceVisibility>(context);
}

}  // namespace visproxy
