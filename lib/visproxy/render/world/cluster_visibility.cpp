#include "visproxy/render/world/cluster_visibility.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>

#include "visproxy/core/errors.h"

namespace visproxy {

Vertex box_corner(const BoundingBox& box, int k) {
  return Vertex(k & 1 ? box.max.x() : box.min.x(), k & 2 ? box.max.y() : box.min.y(), k & 4 ? box.max.z() : box.min.z());
}

namespace {

// The least of n . q over the box.
double box_min(const Vertex& n, const BoundingBox& box) {
  double s = 0;
  for (int i = 0; i < 3; ++i) s += std::min(n[i] * box.min[i], n[i] * box.max[i]);
  return s;
}

}  // namespace

Shaft::Shaft(const Vertex& apex, const BoundingBox& box) {
  points_[0] = apex;
  for (int k = 0; k < 8; ++k) points_[static_cast<std::size_t>(k) + 1] = box_corner(box, k);
  BoundingBox hull_box;
  for (const Vertex& p : points_) hull_box.extend(p);
  // A side plane through the apex and a silhouette edge: the other corners lie behind it
  // (by convexity, up to rounding of order 1e-16 of the coordinates, far below every margin
  // the separations are asked for).
  auto add = [&](const Vertex& n, const Vertex& c0, const Vertex& c1) {
    planes_[static_cast<std::size_t>(plane_count_++)] = {n, std::max({n.dot(apex), n.dot(c0), n.dot(c1)})};
  };
  for (int axis = 0; axis < 3; ++axis) {
    planes_[static_cast<std::size_t>(plane_count_++)] = {Vertex::Unit(axis), hull_box.max[axis]};
    planes_[static_cast<std::size_t>(plane_count_++)] = {-Vertex::Unit(axis), -hull_box.min[axis]};
  }
  // The hull's side faces: planes through the apex and each silhouette edge of the box, an
  // edge between a face turned towards the apex and one turned away. The offset is taken
  // over all nine points, so that the plane supports the hull whatever rounding did.
  auto faces_apex = [&](int axis, int side) {
    return side ? apex[axis] > box.max[axis] : apex[axis] < box.min[axis];
  };
  const Vertex centre = 0.5 * (box.min + box.max);
  for (int a = 0; a < 3; ++a) {
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    for (int sb = 0; sb < 2; ++sb)
      for (int sc = 0; sc < 2; ++sc) {
        if (faces_apex(b, sb) == faces_apex(c, sc)) continue;
        Vertex c0, c1;
        c0[b] = c1[b] = sb ? box.max[b] : box.min[b];
        c0[c] = c1[c] = sc ? box.max[c] : box.min[c];
        c0[a] = box.min[a], c1[a] = box.max[a];
        const Vertex edge = c1 - c0;
        Vertex n = edge.cross(c0 - apex);
        const double length = n.norm();
        if (!(length > 1e-12 * edge.norm() * (c0 - apex).norm()) || !(edge.norm() > 0)) continue;
        n /= length;
        if (n.dot(centre - apex) > 0) n = -n;
        add(n, c0, c1);
      }
  }
}

bool Shaft::separated_from(const BoundingBox& box, double margin) const {
  if (box.empty()) return true;
  for (int i = 0; i < plane_count_; ++i) {
    const auto& [n, offset] = planes_[static_cast<std::size_t>(i)];
    if (box_min(n, box) - offset > margin) return true;
  }
  return false;
}

bool Shaft::separated_from(const Vertex& a, const Vertex& b, const Vertex& c, double margin, double apex_margin) const {
  for (int i = 0; i < plane_count_; ++i) {
    const auto& [n, offset] = planes_[static_cast<std::size_t>(i)];
    if (std::min({n.dot(a), n.dot(b), n.dot(c)}) - offset > margin) return true;
  }
  Vertex m = (b - a).cross(c - a);
  const double length = m.norm();
  if (!(length > 0)) return false;
  m /= length;
  const double s0 = m.dot(points_[0] - a);
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (std::size_t k = 1; k < 9; ++k) {
    const double s = m.dot(points_[k] - a);
    lo = std::min(lo, s), hi = std::max(hi, s);
  }
  return (s0 > apex_margin && lo > margin) || (s0 < -apex_margin && hi < -margin);
}

bool Shaft::separated_from(const Sphere& ball, double margin) const {
  for (int i = 0; i < plane_count_; ++i) {
    const auto& [n, offset] = planes_[static_cast<std::size_t>(i)];
    if (n.dot(ball.center) - ball.radius - offset > margin) return true;
  }
  return false;
}

bool ball_blocks_box(const Vertex& apex, const Sphere& ball, const BoundingBox& box, double margin) {
  if (box.empty()) return false;
  const double r = ball.radius - margin;
  const Vertex axis_vector = ball.center - apex;
  const double t = axis_vector.norm();
  if (!(r > 0) || !(t > r)) return false;
  const Vertex axis = axis_vector / t;
  const double tangent = std::sqrt((t - r) * (t + r)), cos_gamma = tangent / t;
  // Every point of the box beyond the tangent length (plus the margin) ...
  const Vertex nearest = apex.cwiseMax(box.min).cwiseMin(box.max);
  if (!((nearest - apex).norm() > tangent + margin)) return false;
  // ... and inside the cone.
  for (int k = 0; k < 8; ++k) {
    const Vertex v = box_corner(box, k) - apex;
    if (!(axis.dot(v) > v.norm() * cos_gamma)) return false;
  }
  return true;
}

TriangleCone::TriangleCone(const Vertex& from, const Vertex& a, const Vertex& b, const Vertex& c) : apex(from), corner(a) {
  normal = (b - a).cross(c - a);
  const double length = normal.norm();
  if (!(length > 0)) return;
  normal /= length;
  apex_height = normal.dot(apex - a);
  if (apex_height < 0) normal = -normal, apex_height = -apex_height;
  if (!(apex_height > 0)) return;
  const std::array<Vertex, 3> v{a, b, c};
  for (int e = 0; e < 3; ++e) {
    const Vertex& p = v[static_cast<std::size_t>(e)];
    const Vertex& q = v[static_cast<std::size_t>((e + 1) % 3)];
    const Vertex& o = v[static_cast<std::size_t>((e + 2) % 3)];
    Vertex m = (p - apex).cross(q - apex);
    const double m_length = m.norm();
    if (!(m_length > 0)) return;
    m /= m_length;
    if (m.dot(o - apex) < 0) m = -m;
    sides[static_cast<std::size_t>(e)] = m;
  }
  valid = true;
}

bool TriangleCone::blocks(const BoundingBox& box, double margin) const {
  if (!valid || box.empty()) return false;
  for (int k = 0; k < 8; ++k) {
    const Vertex y = box_corner(box, k);
    const double depth = -normal.dot(y - corner);
    if (!(depth > margin)) return false;
    // The crossing point apex + s (y - apex), s = h / (h + depth), lies s m.(y - apex)
    // inside each edge's plane.
    const double along = apex_height / (apex_height + depth);
    const Vertex w = y - apex;
    for (const Vertex& m : sides)
      if (!(along * m.dot(w) > margin)) return false;
  }
  return true;
}

bool triangle_blocks_box(const Vertex& apex, const Vertex& a, const Vertex& b, const Vertex& c, const BoundingBox& box,
                         double margin) {
  return TriangleCone(apex, a, b, c).blocks(box, margin);
}

TriangleTree::TriangleTree(const TriangleMesh& mesh) {
  for (const Triangle& t : mesh.triangles) triangles_.push_back({mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]});
  if (triangles_.empty()) return;
  std::vector<std::uint32_t> order(triangles_.size());
  std::iota(order.begin(), order.end(), 0u);
  std::vector<Vertex> centroids;
  for (const auto& t : triangles_) centroids.push_back((t[0] + t[1] + t[2]) / 3);
  struct Task {
    std::uint32_t node, begin, end;
  };
  nodes_.push_back({});
  std::vector<Task> stack{{0, 0, static_cast<std::uint32_t>(order.size())}};
  while (!stack.empty()) {
    const Task task = stack.back();
    stack.pop_back();
    BoundingBox box, centres;
    for (std::uint32_t i = task.begin; i < task.end; ++i) {
      for (const Vertex& p : triangles_[order[i]]) box.extend(p);
      centres.extend(centroids[order[i]]);
    }
    nodes_[task.node].box = box;
    if (task.end - task.begin <= 4) {
      nodes_[task.node].first = task.begin, nodes_[task.node].count = task.end - task.begin;
      continue;
    }
    int axis = 0;
    (centres.max - centres.min).maxCoeff(&axis);
    const std::uint32_t middle = task.begin + (task.end - task.begin) / 2;
    std::nth_element(order.begin() + task.begin, order.begin() + middle, order.begin() + task.end,
                     [&](std::uint32_t l, std::uint32_t r) { return centroids[l][axis] < centroids[r][axis]; });
    const auto child = static_cast<std::uint32_t>(nodes_.size());
    nodes_[task.node].first = child, nodes_[task.node].count = 0;
    nodes_.push_back({}), nodes_.push_back({});
    stack.push_back({child, task.begin, middle});
    stack.push_back({child + 1, middle, task.end});
  }
  std::vector<std::array<Vertex, 3>> sorted;
  sorted.reserve(triangles_.size());
  for (const std::uint32_t i : order) sorted.push_back(triangles_[i]);
  triangles_ = std::move(sorted);
}

bool TriangleTree::shaft_misses(const Shaft& shaft, double margin, double apex_margin) const {
  if (nodes_.empty()) return true;
  std::uint32_t stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (shaft.separated_from(node.box, margin)) continue;
    if (node.count > 0) {
      for (std::uint32_t i = node.first; i < node.first + node.count; ++i) {
        const auto& t = triangles_[i];
        if (!shaft.separated_from(t[0], t[1], t[2], margin, apex_margin)) return false;
      }
      continue;
    }
    if (top + 2 > 128) return false;  // deeper than any balanced tree of 2^64 triangles: refuse, not guess
    stack[top++] = node.first, stack[top++] = node.first + 1;
  }
  return true;
}

ClusterProofs::ClusterProofs(const RenderWorld& world, std::size_t instances) : world_(&world), instances_(instances) {
  if (!world.keeps_solids()) throw Error("lightcuts: visibility bounds need a render world made with keep_solids");
  for (std::size_t i = 0; i < instances; ++i) {
    const InstanceSolids& solids = world.instance_solids(i);
    mesh_trees_.emplace_back(solids.mesh);
    outside_trees_.push_back(solids.outside_is_mesh ? TriangleTree() : TriangleTree(solids.outside));
  }
}

void ClusterProofs::Point::begin(const Vertex& x, const SurfaceHit& hit, double offset, const BoundingBox& lights,
                                 const BoundingBox& on_lights) {
  x_ = x;
  hit_ = &hit;
  // The point lies `offset` off its surface, up to Embree's rounding of the hit distance
  // (an eighth of the offset at most): a quarter of it is kept from the own triangles' planes.
  apex_margin_ = offset / 4;
  lights_ = lights, on_lights_ = on_lights;
  lower_ready_ = upper_ready_ = false;
  last_ball_ = last_face_ = last_blocker_ = -1;
}

// What the lower bound needs of the point: the instances the shaft to every light may meet,
// the point's convex shells, and whether it lies outside each convex outside solid. Made on
// the first proof, so that points whose cuts need none pay nothing.
void ClusterProofs::Point::prepare_lower() {
  const RenderWorld& world = *proofs_->world_;
  lower_ready_ = true;
  x_shells_ = world.convex_shells_holding(x_);
  near_.clear(), x_outside_.assign(proofs_->instances_, false);
  const Shaft all(x_, lights_);
  for (std::size_t i = 0; i < proofs_->instances_; ++i) {
    if (static_cast<int>(i) != hit_->instance && all.separated_from(world.instance_bounds(i), 0.0)) continue;
    near_.push_back(i);
    for (const auto& [n, d] : world.instance_solids(i).outside_planes)
      if (n.dot(x_) - d > world.instance_solids(i).pad) x_outside_[i] = true;
  }
}

// What the upper bound needs: the inside balls and inside triangles the shaft to the lights'
// points may meet, the largest as seen from the point first (at most 64 of each).
void ClusterProofs::Point::prepare_upper() {
  const RenderWorld& world = *proofs_->world_;
  upper_ready_ = true;
  balls_.clear(), faces_.clear();
  if (on_lights_.empty()) return;
  const Shaft all(x_, on_lights_);
  for (std::size_t i = 0; i < proofs_->instances_; ++i) {
    const InstanceSolids& solids = world.instance_solids(i);
    if (solids.inside_spheres.empty() && solids.inside.triangles.empty()) continue;
    if (all.separated_from(world.instance_bounds(i), 0.0)) continue;
    for (const Sphere& ball : solids.inside_spheres)
      if ((ball.center - x_).norm() > ball.radius + solids.pad && !all.separated_from(ball, 0.0)) balls_.emplace_back(ball, solids.pad);
    for (const Triangle& t : solids.inside.triangles) {
      const Vertex& a = solids.inside.positions[t[0]];
      const Vertex& b = solids.inside.positions[t[1]];
      const Vertex& c = solids.inside.positions[t[2]];
      if (all.separated_from(a, b, c, 0.0, 0.0)) continue;
      // Only faces with some light beyond their plane (seen from the point) can block a
      // cluster.
      const TriangleCone cone(x_, a, b, c);
      if (!cone.valid) continue;
      bool beyond = false;
      for (int k = 0; k < 8 && !beyond; ++k) beyond = cone.normal.dot(box_corner(on_lights_, k) - a) < -solids.pad;
      if (!beyond) continue;
      const double size = (b - a).cross(c - a).norm() / std::max(((a + b + c) / 3 - x_).squaredNorm(), 1e-300);
      faces_.push_back({cone, solids.pad, size});
    }
  }
  auto ball_size = [&](const std::pair<Sphere, double>& b) { return b.first.radius / (b.first.center - x_).norm(); };
  std::sort(balls_.begin(), balls_.end(), [&](const auto& l, const auto& r) { return ball_size(l) > ball_size(r); });
  if (balls_.size() > 64) balls_.resize(64);
  std::sort(faces_.begin(), faces_.end(), [&](const Face& l, const Face& r) { return l.size > r.size; });
  if (faces_.size() > 64) faces_.resize(64);
}

bool ClusterProofs::Point::instance_clear(std::size_t i, const Shaft& shaft, bool on_lights) const {
  const InstanceSolids& solids = proofs_->world_->instance_solids(i);
  if (static_cast<int>(i) == hit_->instance) {
    // The own mesh behind the hit triangle's exact plane, the point and the box in front of
    // it (every segment of the shaft then is).
    if (hit_->own_mesh_behind) {
      bool front = true;
      for (std::size_t k = 1; k < 9 && front; ++k) front = hit_->own_mesh_clear_of(shaft.apex(), shaft.points()[k]);
      if (front) return true;
    }
    return proofs_->mesh_trees_[i].shaft_misses(shaft, solids.pad, apex_margin_);
  }
  // A convex outside solid beside the shaft: one of its planes has every point beyond it.
  for (const auto& [n, d] : solids.outside_planes) {
    bool beyond = true;
    for (const Vertex& p : shaft.points())
      if (!(n.dot(p) - d > solids.pad)) {
        beyond = false;
        break;
      }
    if (beyond) return true;
  }
  if (!solids.outside_is_mesh) {
    // Missing every face of the solid proves the shaft outside it only with a point of the
    // shaft known to lie outside.
    const bool point_outside = x_outside_[i] || (on_lights && solids.lights_outside_outside);
    if (point_outside && proofs_->outside_trees_[i].shaft_misses(shaft, solids.pad, solids.pad)) return true;
  }
  return proofs_->mesh_trees_[i].shaft_misses(shaft, solids.pad, solids.pad);
}

bool ClusterProofs::Point::unoccluded(const BoundingBox& box, bool on_lights) {
  const RenderWorld& world = *proofs_->world_;
  if (!lower_ready_) prepare_lower();
  unsigned shells = x_shells_;
  for (int k = 0; k < 8 && shells != 0; ++k) shells &= world.convex_shells_holding(box_corner(box, k));
  std::optional<Shaft> shaft;  // made once an instance needs it
  auto clear = [&](std::size_t i) {
    if (shells & instance_bit(i)) return true;
    if (!shaft) shaft.emplace(x_, box);
    if (static_cast<int>(i) != hit_->instance && shaft->separated_from(world.instance_bounds(i), 0.0)) return true;
    return instance_clear(i, *shaft, on_lights);
  };
  // The instance that stopped the last proof first: a child cluster of a cluster it blocked
  // usually fails on it too, and then fails at once.
  if (last_blocker_ >= 0 && !clear(static_cast<std::size_t>(last_blocker_))) return false;
  for (const std::size_t i : near_) {
    if (static_cast<int>(i) == last_blocker_) continue;
    if (!clear(i)) {
      last_blocker_ = static_cast<int>(i);
      return false;
    }
  }
  return true;
}

bool ClusterProofs::Point::occluded(const BoundingBox& box, bool on_lights) {
  if (!on_lights) return false;
  if (!upper_ready_) prepare_upper();
  auto ball = [&](int k) {
    const auto& [sphere, pad] = balls_[static_cast<std::size_t>(k)];
    return ball_blocks_box(x_, sphere, box, pad);
  };
  auto face = [&](int k) {
    const Face& f = faces_[static_cast<std::size_t>(k)];
    return f.cone.blocks(box, f.pad);
  };
  if (last_ball_ >= 0 && ball(last_ball_)) return true;
  if (last_face_ >= 0 && face(last_face_)) return true;
  for (int k = 0; k < static_cast<int>(balls_.size()); ++k)
    if (k != last_ball_ && ball(k)) return last_ball_ = k, true;
  for (int k = 0; k < static_cast<int>(faces_.size()); ++k)
    if (k != last_face_ && face(k)) return last_face_ = k, true;
  return false;
}

}  // namespace visproxy
