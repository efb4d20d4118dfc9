#include "visproxy/render/world/query_costs.h"

#include <vector>

#include "visproxy/render/world/box_tree.h"

namespace visproxy {
namespace {

// The instances whose world box the segment meets.
void instances_met(const RenderWorld& world, const Vertex& from, const Vertex& to, std::vector<std::size_t>& out) {
  out.clear();
  world.instances_where([&](const BoundingBox& box, const Sphere&) { return segment_meets_box(from, to, box); }, out);
}

}  // namespace

SegmentQueryCosts segment_query_costs(const RenderWorld& world, const Vertex& camera, const Vertex& from, const Vertex& to, int own,
                                      bool split) {
  thread_local std::vector<std::size_t> met;
  SegmentQueryCosts costs;
  costs.camera = kQueryWork + kShadingWork;
  instances_met(world, camera, from, met);
  for (const std::size_t i : met) costs.camera += world.instance_work(i).mesh;
  costs.exact = costs.proxy = costs.correction = kQueryWork;
  instances_met(world, from, to, met);
  for (const std::size_t i : met) {
    const RenderWorld::InstanceWork& work = world.instance_work(i);
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
