#include "visproxy/render/visibility/visibility.h"

namespace visproxy {

ProxyAnswer proxy_answer(const RenderWorld& world, const Vertex& from, const Vertex& to, int own_instance, bool split,
                         RenderStats& stats, bool own_cannot_block) {
  ProxyAnswer answer;
  if (!split) {
    ++stats.proxy_tests;
    answer.proxy_blocked = world.proxy_blocks(from, to);
    return answer;
  }
  const SplitAnswer split_answer = world.split_blocks(from, to, own_instance, !own_cannot_block, stats.exact_tests, stats.proxy_tests);
  answer.own_blocks = split_answer == SplitAnswer::own_blocks;
  answer.proxy_blocked = split_answer == SplitAnswer::proxy_blocks;
  answer.rest.skip = own_instance;
  return answer;
}

void ExactConnections::begin(const RenderWorld& world, const Vertex& from, unsigned bits) {
  world_ = &world;
  from_ = from;
  bits_ = bits;
  shells_known_ = false;
  own_hit_ = nullptr, own_bit_ = 0;
}

bool ExactConnections::blocked(const Vertex& end) const {
  return world_->mesh_blocks(from_, end, {.skip = -1, .only = -1, .bits = lane(end)});
}

void ExactConnections::blocked(std::span<const Vertex> ends, std::span<const unsigned> end_shells, std::span<std::uint8_t> blocked) {
  lanes_.resize(ends.size());
  for (std::size_t i = 0; i < ends.size(); ++i) lanes_[i] = lane(ends[i], end_shells.empty() ? nullptr : &end_shells[i]);
  world_->mesh_blocks(from_, ends, blocked, {}, lanes_);
}

std::vector<ProxyKind> stochastic_kinds(const VisibilityContext& context) {
  std::vector<ProxyKind> kinds;
  for (std::size_t i = 0; i < context.scene.instances.size(); ++i)
    kinds.push_back(context.world.stochastic_kind(context.options.split ? static_cast<int>(i) : -1));
  return kinds;
}

RayTypeCounts adaptive_probe_counts(const VisibilityContext& context, const ShadingPoint& point, RayTypeCounts* pixel_counts) {
  const RenderOptions& options = context.options;
  RayTypeCounts local;
  RayTypeCounts& counts = pixel_counts ? *pixel_counts : local;
  // Without area lights (VPLs given by the caller) there is nothing to probe: the counts
  // stay empty, and the probabilities from them equal.
  if (!context.lights.empty() && (options.probe_passes == 0 || point.pass < options.probe_passes)) {
    const int own = point.hit->instance;
    const InstanceFilter rest{.skip = options.split ? own : -1, .only = -1};
    const Vertex& x = point.position;
    for (int k = 0; k < options.probe_rays; ++k) {
      const LightSample y = context.lights.sample(*point.choices);
      if (point.hit->normal.dot(y.position - x) <= 0) continue;  // below the surface: never traced
      ++point.stats->probe_rays;
      const Vertex end = light_end(context.world, y, x);
      counts.add(context.world.mesh_blocks(x, end, rest), context.world.proxy_blocks(x, end, rest));
    }
  }
  return counts;
}

std::unique_ptr<Visibility> make_visibility(const VisibilityContext& context) {
  const RenderOptions& options = context.options;
  switch (options.visibility) {
    case VisibilityMode::exact: return make_exact_visibility(context);
    case VisibilityMode::bounds: return make_bounds_visibility(context);
    case VisibilityMode::spheres: return make_occluder_disk_visibility(context);
    case VisibilityMode::stochastic:
      return options.estimator == StochasticEstimator::control_variate ? make_control_variate_visibility(context)
                                                                       : make_term_choice_visibility(context);
  }
  return make_exact_visibility(context);
}

}  // namespace visproxy
