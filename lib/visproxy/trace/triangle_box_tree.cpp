#include "visproxy/trace/triangle_box_tree.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>
#include <utility>

#include "visproxy/trace/embree_support.h"
#include "visproxy/trace/triangle_distance.h"

namespace visproxy {

struct TriangleBoxTree::Impl {
  EmbreeDevice device;
  RTCBVH bvh = nullptr;
  const BinaryBvhNode* root = nullptr;
  const TriangleMesh* mesh = nullptr;
  std::vector<std::uint32_t> triangles;
  Vertex centre = Vertex::Zero();  // the tree holds the boxes moved by -centre
  double margin = 0;               // added on each side of a box moved back

  ~Impl() {
    if (bvh) rtcReleaseBVH(bvh);
  }

  BoundingBox child_box(const BinaryBvhNode& node, int child) const {
    BoundingBox box;
    for (int k = 0; k < 3; ++k) {
      box.min[k] = (centre[k] + static_cast<double>(node.lower[child][k])) - margin;
      box.max[k] = (centre[k] + static_cast<double>(node.upper[child][k])) + margin;
    }
    return box;
  }
};

TriangleBoxTree::TriangleBoxTree(const TriangleMesh& mesh, std::vector<std::uint32_t> triangles)
    : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.mesh = &mesh;
  s.triangles = std::move(triangles);
  if (s.triangles.empty()) return;
  BoundingBox all;
  for (const std::uint32_t t : s.triangles)
    for (const VertexIndex v : mesh.triangles[t]) all.extend(mesh.positions[v]);
  s.centre = 0.5 * (all.min + all.max);
  s.margin = 0x1.0p-40 * std::max(all.min.cwiseAbs().maxCoeff(), all.max.cwiseAbs().maxCoeff());

  std::vector<RTCBuildPrimitive> primitives(s.triangles.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, s.triangles.size(), 4096),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t i = range.begin(); i < range.end(); ++i) {
                        const Triangle& t = mesh.triangles[s.triangles[i]];
                        const Vertex a = mesh.positions[t[0]] - s.centre;
                        const Vertex b = mesh.positions[t[1]] - s.centre;
                        const Vertex c = mesh.positions[t[2]] - s.centre;
                        const Vertex lower = a.cwiseMin(b).cwiseMin(c), upper = a.cwiseMax(b).cwiseMax(c);
                        RTCBuildPrimitive& p = primitives[i];
                        p.lower_x = round_down(lower.x()), p.lower_y = round_down(lower.y());
                        p.lower_z = round_down(lower.z());
                        p.upper_x = round_up(upper.x()), p.upper_y = round_up(upper.y()), p.upper_z = round_up(upper.z());
                        p.geomID = 0;
                        p.primID = static_cast<unsigned>(i);
                      }
                    });
  s.bvh = rtcNewBVH(s.device.get());
  // Morton-code build: at 4.8 M triangles, about a third of the binned SAH build's time,
  // which outweighs the slower queries of an alpha wrap or a conservative decimation.
  s.root = build_binary_bvh(s.device, s.bvh, std::move(primitives), RTC_BUILD_QUALITY_LOW);
}

TriangleBoxTree::~TriangleBoxTree() = default;

std::size_t TriangleBoxTree::size() const { return impl_->triangles.size(); }

bool TriangleBoxTree::any(const std::function<bool(const BoundingBox&)>& may_meet,
                          const std::function<bool(std::uint32_t)>& test) const {
  const Impl& s = *impl_;
  if (!s.root) return false;
  // A root that is a leaf (a few triangles) has no boxes of its own: its triangles are tested.
  const BinaryBvhNode* stack[128];
  int top = 0;
  stack[top++] = s.root;
  while (top > 0) {
    const BinaryBvhNode* node = stack[--top];
    if (node->leaf) {
      for (std::uint32_t i = 0; i < node->count; ++i)
        if (test(s.triangles[node->ids[i]])) return true;
      continue;
    }
    for (int child = 1; child >= 0; --child)
      if (node->children[child] && may_meet(s.child_box(*node, child))) stack[top++] = node->children[child];
  }
  return false;
}

namespace {

double box_squared_distance(const Vertex& p, const BoundingBox& box) {
  return (box.min - p).cwiseMax(p - box.max).cwiseMax(0.0).squaredNorm();
}

}  // namespace

TriangleBoxTree::Nearest TriangleBoxTree::nearest(const Vertex& p) const {
  const Impl& s = *impl_;
  Nearest best{Vertex::Zero(), 0, std::numeric_limits<double>::infinity()};
  const auto visit_leaf = [&](const BinaryBvhNode& leaf) {
    for (std::uint32_t i = 0; i < leaf.count; ++i) {
      const std::uint32_t index = s.triangles[leaf.ids[i]];
      const Triangle& t = s.mesh->triangles[index];
      const Vertex q = point_triangle_nearest_point(p, s.mesh->positions[t[0]], s.mesh->positions[t[1]],
                                                    s.mesh->positions[t[2]]);
      const double d = (p - q).squaredNorm();
      if (d < best.squared_distance || (d == best.squared_distance && index < best.triangle)) best = {q, index, d};
    }
  };
  if (!s.root) return best;
  // A node waits on the stack with the squared distance of its box; it is skipped when the
  // box is further than the nearest triangle found since. Equal distances are not skipped,
  // for the tie rule.
  std::pair<const BinaryBvhNode*, double> stack[128];
  int top = 0;
  stack[top++] = {s.root, 0.0};
  while (top > 0) {
    const auto [node, distance] = stack[--top];
    if (distance > best.squared_distance) continue;
    if (node->leaf) {
      visit_leaf(*node);
      continue;
    }
    const double d0 = box_squared_distance(p, s.child_box(*node, 0));
    const double d1 = box_squared_distance(p, s.child_box(*node, 1));
    // The nearer child is pushed last, so it is visited first.
    if (d0 <= d1) {
      stack[top++] = {node->children[1], d1};
      stack[top++] = {node->children[0], d0};
    } else {
      stack[top++] = {node->children[0], d0};
      stack[top++] = {node->children[1], d1};
    }
  }
  return best;
}

}  // namespace visproxy
