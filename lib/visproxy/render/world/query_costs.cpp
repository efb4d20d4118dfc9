#include "visproxy/render/world/query_costs.h"

#include <cmath>
#include <vector>

#include "visproxy/render/world/box_tree.h"

namespace visproxy {
namespace {

// The instances whose world box the segment meets.
void instances_met(const RenderWorld& world, const Vertex& from, const Vertex& to, std::vector<std::size_t>& out) {
  out.clear();
  world.instances_where([&](const BoundingBox& box, const Sphere&) { return segment_meets_box(from, to, box); }, out);
}

double levels(std::size_t primitives) { return std::log2(2.0 + static_cast<double>(primitives)); }

}  // namespace

InstanceWork instance_work(const RenderWorld& world, std::size_t instance) {
  const RenderWorld::InstancePrimitives& p = world.instance_primitives(instance);
  return {.mesh = levels(p.mesh), .proxy = levels(p.proxy) + (p.proxy_triangles ? 0.0 : kOwnTestWork)};
}

SegmentQueryCosts segment_query_costs(const RenderWorld& world, const Vertex& camera, const Vertex& from, const Vertex& to, int own,
                                      bool split) {
  SegmentQueryCosts costs = shadow_segment_costs(world, from, to, own, split);
  costs.camera = camera_sample_work(world, camera, from);
  return costs;
}

double camera_sample_work(const RenderWorld& world, const Vertex& camera, const Vertex& from) {
  thread_local std::vector<std::size_t> met;
  double work = kQueryWork + kShadingWork;
  instances_met(world, camera, from, met);
  for (const std::size_t i : met) work += instance_work(world, i).mesh;
  return work;
}

SegmentQueryCosts shadow_segment_costs(const RenderWorld& world, const Vertex& from, const Vertex& to, int own, bool split) {
  thread_local std::vector<std::size_t> met;
  SegmentQueryCosts costs;
  costs.exact = costs.proxy = costs.correction = kQueryWork;
  instances_met(world, from, to, met);
  for (const std::size_t i : met) {
    const InstanceWork work = instance_work(world, i);
    costs.exact += work.mesh;
    if (split && static_cast<int>(i) == own) {
      costs.proxy += work.mesh;
    } else {
      costs.proxy += work.proxy;
      costs.correction += work.mesh;
    }
  }
  return costs;
}

}  // namespace visproxy
