#pragma once
// A bounding volume hierarchy over the world bounds of a scene's instances (boxes, and balls
// around them): queries over thousands of instances visit only those a segment or a light
// shaft may meet, where a list would test every one.

#include <cstdint>
#include <vector>

#include "visproxy/mesh/sphere_set.h"
#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

class BoxTree {
 public:
  BoxTree() = default;
  /// Items i with box `boxes[i]` and ball `balls[i]` (each holding the item; `balls` may be
  /// empty). Every node's box holds its items' boxes and its ball their balls, grown by
  /// 2^-40 of their magnitude, so a test that is monotone in the box and the ball (false
  /// for a node means false for all it holds) prunes no item it would keep. Deterministic.
  BoxTree(const std::vector<BoundingBox>& boxes, const std::vector<Sphere>& balls);

  bool empty() const { return nodes_.empty(); }

  /// Calls visit(item) for every item in a leaf reached through nodes for which
  /// may_meet(box, ball) holds (the caller tests each item itself). Stops when visit returns
  /// true, and returns whether it did.
  template <class MayMeet, class Visit>
  bool any(MayMeet&& may_meet, Visit&& visit) const {
    return any_along(Vertex::Zero(), may_meet, visit);
  }
  /// any(), visiting at each node first the child whose items lie further back along
  /// `direction` (the child of smaller centres where direction[axis] >= 0): for a segment
  /// leaving along it, the leaves near its start come first (a leaf's few items in no
  /// order), so an early stop comes early.
  template <class MayMeet, class Visit>
  bool any_along(const Vertex& direction, MayMeet&& may_meet, Visit&& visit) const {
    if (nodes_.empty()) return false;
    std::uint32_t stack[64];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& node = nodes_[stack[--top]];
      if (!may_meet(node.box, node.ball)) continue;
      if (node.count > 0) {
        for (std::uint32_t k = node.first; k < node.first + node.count; ++k)
          if (visit(order_[k])) return true;
      } else {
        const bool left_first = direction[node.axis] >= 0;  // popped last, visited first
        stack[top++] = left_first ? node.first + 1 : node.first;
        stack[top++] = left_first ? node.first : node.first + 1;
      }
    }
    return false;
  }

 private:
  struct Node {
    BoundingBox box;
    Sphere ball;
    std::uint32_t first = 0;  ///< a leaf's first item in order_, or an inner node's left child
    std::uint32_t count = 0;  ///< items of a leaf; 0 for an inner node
    int axis = 0;             ///< an inner node's split: its left child has the smaller centres along it
  };
  std::vector<Node> nodes_;
  std::vector<std::uint32_t> order_;
};

/// Whether the closed segment from `from` to `to` meets `box` (slab test).
bool segment_meets_box(const Vertex& from, const Vertex& to, const BoundingBox& box);

}  // namespace visproxy
