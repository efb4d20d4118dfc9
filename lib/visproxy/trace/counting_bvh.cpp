#include "visproxy/trace/counting_bvh.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/trace/embree_support.h"

namespace visproxy {
namespace {

using Node = BinaryBvhNode;

// Entry parameter of the segment o + t d into the box over (tnear, tfar), or +inf.
double box_entry(const float lower[3], const float upper[3], const Vertex& o, const Vertex& inverse, double tfar) {
  double t0 = 0, t1 = tfar;
  for (int a = 0; a < 3; ++a) {
    double near = (lower[a] - o[a]) * inverse[a], far = (upper[a] - o[a]) * inverse[a];
    if (std::isnan(near)) near = -std::numeric_limits<double>::infinity();  // 0 * inf: ray in the slab's plane
    if (std::isnan(far)) far = std::numeric_limits<double>::infinity();
    if (near > far) std::swap(near, far);
    t0 = std::max(t0, near);
    t1 = std::min(t1, far);
  }
  return t0 <= t1 ? t0 : std::numeric_limits<double>::infinity();
}

}  // namespace

struct CountingBvh::Impl {
  EmbreeDevice device;
  RTCBVH bvh = nullptr;
  const Node* root = nullptr;
  TriangleMesh mesh;
  std::vector<Sphere> spheres;
  BoundingBox bounds;

  ~Impl() {
    if (bvh) rtcReleaseBVH(bvh);
  }

  void build(std::vector<RTCBuildPrimitive> primitives) {
    if (primitives.empty()) return;
    bvh = rtcNewBVH(device.get());
    root = build_binary_bvh(device, bvh, std::move(primitives), RTC_BUILD_QUALITY_MEDIUM);
  }

  bool primitive_blocks(std::uint32_t id, const Vertex& o, const Vertex& d) const {
    if (!spheres.empty()) return segment_meets_ball(spheres[id], o, d, 0.0, 1.0);
    const Triangle& t = mesh.triangles[id];
    const Vertex p0 = mesh.positions[t[0]], e1 = mesh.positions[t[1]] - p0, e2 = mesh.positions[t[2]] - p0;
    const Vertex h = d.cross(e2);
    const double det = e1.dot(h);
    if (det == 0) return false;
    const Vertex s = o - p0, q = s.cross(e1);
    const double u = s.dot(h) / det, v = d.dot(q) / det, time = e2.dot(q) / det;
    return u >= 0 && v >= 0 && u + v <= 1 && time > 0 && time < 1;
  }
};

CountingBvh::CountingBvh(const TriangleMesh& mesh) : impl_(std::make_unique<Impl>()) {
  impl_->mesh = mesh;
  std::vector<RTCBuildPrimitive> primitives;
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    BoundingBox box;
    for (VertexIndex v : mesh.triangles[i]) box.extend(mesh.positions[v]);
    impl_->bounds.extend(box.min), impl_->bounds.extend(box.max);
    RTCBuildPrimitive p{};
    p.lower_x = round_down(box.min.x()), p.lower_y = round_down(box.min.y()), p.lower_z = round_down(box.min.z());
    p.upper_x = round_up(box.max.x()), p.upper_y = round_up(box.max.y()), p.upper_z = round_up(box.max.z());
    p.primID = static_cast<unsigned>(i);
    primitives.push_back(p);
  }
  impl_->build(std::move(primitives));
}

CountingBvh::CountingBvh(std::span<const Sphere> spheres) : impl_(std::make_unique<Impl>()) {
  impl_->spheres.assign(spheres.begin(), spheres.end());
  std::vector<RTCBuildPrimitive> primitives;
  for (std::size_t i = 0; i < spheres.size(); ++i) {
    const Vertex r = Vertex::Constant(spheres[i].radius);
    impl_->bounds.extend(spheres[i].center - r), impl_->bounds.extend(spheres[i].center + r);
    RTCBuildPrimitive p{};
    const Vertex lo = spheres[i].center - r, hi = spheres[i].center + r;
    p.lower_x = round_down(lo.x()), p.lower_y = round_down(lo.y()), p.lower_z = round_down(lo.z());
    p.upper_x = round_up(hi.x()), p.upper_y = round_up(hi.y()), p.upper_z = round_up(hi.z());
    p.primID = static_cast<unsigned>(i);
    primitives.push_back(p);
  }
  impl_->build(std::move(primitives));
}

CountingBvh::~CountingBvh() = default;

const BoundingBox& CountingBvh::bounds() const { return impl_->bounds; }

bool CountingBvh::segment_blocked(const Vertex& from, const Vertex& to, TraversalCounts& counts) const {
  const Node* root = impl_->root;
  if (!root) return false;
  const Vertex d = to - from;
  const Vertex inverse = d.cwiseInverse();
  const Node* stack[64];
  int top = 0;
  stack[top++] = root;
  while (top > 0) {
    const Node* node = stack[--top];
    if (node->leaf) {
      for (std::uint32_t i = 0; i < node->count; ++i) {
        ++counts.primitives;
        if (impl_->primitive_blocks(node->ids[i], from, d)) return true;
      }
      continue;
    }
    counts.nodes += 1;
    const double t0 = box_entry(node->lower[0], node->upper[0], from, inverse, 1.0);
    const double t1 = box_entry(node->lower[1], node->upper[1], from, inverse, 1.0);
    const bool hit0 = std::isfinite(t0), hit1 = std::isfinite(t1);
    // Push the farther child first so the nearer one is visited next.
    if (hit0 && hit1) {
      stack[top++] = t0 <= t1 ? node->children[1] : node->children[0];
      stack[top++] = t0 <= t1 ? node->children[0] : node->children[1];
    } else if (hit0) {
      stack[top++] = node->children[0];
    } else if (hit1) {
      stack[top++] = node->children[1];
    }
  }
  return false;
}

}  // namespace visproxy
