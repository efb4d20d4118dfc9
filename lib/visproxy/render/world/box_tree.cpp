#include "visproxy/render/world/box_tree.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <numeric>

namespace visproxy {

bool segment_meets_box(const Vertex& from, const Vertex& to, const BoundingBox& box) {
  double t0 = 0, t1 = 1;
  const Vertex d = to - from;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0) {
      if (from[a] < box.min[a] || from[a] > box.max[a]) return false;
      continue;
    }
    double near = (box.min[a] - from[a]) / d[a], far = (box.max[a] - from[a]) / d[a];
    if (near > far) std::swap(near, far);
    t0 = std::max(t0, near), t1 = std::min(t1, far);
  }
  return t0 <= t1;
}

BoxTree::BoxTree(const std::vector<BoundingBox>& boxes, const std::vector<Sphere>& balls) {
  for (std::uint32_t i = 0; i < boxes.size(); ++i)
    if (!boxes[i].empty()) order_.push_back(i);  // an empty box holds nothing to meet
  if (order_.empty()) return;
  std::vector<Vertex> centers(boxes.size(), Vertex::Zero());
  for (const std::uint32_t i : order_) centers[i] = 0.5 * (boxes[i].min + boxes[i].max);
  nodes_.reserve(2 * order_.size());
  nodes_.emplace_back();
  std::function<void(std::uint32_t, std::uint32_t, std::uint32_t)> build = [&](std::uint32_t at, std::uint32_t first,
                                                                               std::uint32_t count) {
    BoundingBox box, middles;
    for (std::uint32_t k = first; k < first + count; ++k) {
      box.extend(boxes[order_[k]].min), box.extend(boxes[order_[k]].max);
      middles.extend(centers[order_[k]]);
    }
    const Vertex center = 0.5 * (box.min + box.max);
    double radius = 0;
    for (std::uint32_t k = first; k < first + count; ++k) {
      const std::uint32_t i = order_[k];
      radius = balls.empty() ? std::max(radius, (boxes[i].max - center).cwiseMax(center - boxes[i].min).norm())
                             : std::max(radius, (balls[i].center - center).norm() + balls[i].radius);
    }
    const double pad = 0x1.0p-40 * std::max({box.min.cwiseAbs().maxCoeff(), box.max.cwiseAbs().maxCoeff(), radius});
    box.min.array() -= pad, box.max.array() += pad;
    Node node{box, {center, radius + pad}, first, count, 0};
    if (count > 4) {
      int axis = 0;
      (middles.max - middles.min).maxCoeff(&axis);
      const std::uint32_t mid = first + count / 2;
      std::nth_element(order_.begin() + first, order_.begin() + mid, order_.begin() + first + count,
                       [&](std::uint32_t a, std::uint32_t b) {
                         return centers[a][axis] != centers[b][axis] ? centers[a][axis] < centers[b][axis] : a < b;
                       });
      const auto left = static_cast<std::uint32_t>(nodes_.size());
      nodes_.emplace_back();
      nodes_.emplace_back();
      node.first = left, node.count = 0, node.axis = axis;
      nodes_[at] = node;
      build(left, first, mid - first);
      build(left + 1, mid, first + count - mid);
      return;
    }
    nodes_[at] = node;
  };
  build(0, 0, static_cast<std::uint32_t>(order_.size()));
}

}  // namespace visproxy
