#include "visproxy/trace/convex_polytope.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>

#include "visproxy/mesh/mesh_topology.h"
#include "visproxy/trace/embree_support.h"

namespace visproxy {

std::optional<ConvexPolytope> ConvexPolytope::from_mesh(const TriangleMesh& mesh, std::size_t max_planes) {
  // A closed convex mesh of at most max_planes planes that is finely tessellated is rare;
  // the limit keeps big meshes from paying for the topology check.
  if (mesh.triangles.size() < 4 || mesh.triangles.size() > 64 * max_planes) return std::nullopt;
  const MeshTopology topology = analyze_topology(mesh);
  if (!topology.closed() || !topology.manifold() || !topology.consistently_oriented() || topology.components != 1)
    return std::nullopt;
  const double diagonal = bounding_box(mesh).diagonal();
  if (!(diagonal > 0)) return std::nullopt;
  const double tolerance = 1e-9 * diagonal;
  const std::vector<Vertex> points = used_positions(mesh);

  // Convex at every edge first (linear time): the neighbour's far vertex behind the plane.
  // It rejects most non-convex meshes before the quadratic work below.
  {
    std::vector<std::pair<std::uint64_t, std::uint32_t>> edges;  // (from << 32 | to, triangle)
    edges.reserve(3 * mesh.triangles.size());
    for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
      for (int k = 0; k < 3; ++k)
        edges.emplace_back((std::uint64_t{mesh.triangles[t][k]} << 32) | mesh.triangles[t][(k + 1) % 3], t);
    std::sort(edges.begin(), edges.end());
    for (const auto& [key, t] : edges) {
      const std::uint64_t twin = (key << 32) | (key >> 32);
      const auto it = std::lower_bound(edges.begin(), edges.end(), std::pair<std::uint64_t, std::uint32_t>(twin, 0));
      if (it == edges.end() || it->first != twin) return std::nullopt;
      const Triangle& a = mesh.triangles[t];
      const Vertex n = (mesh.positions[a[1]] - mesh.positions[a[0]]).cross(mesh.positions[a[2]] - mesh.positions[a[0]]);
      if (n.norm() <= 1e-12 * diagonal * diagonal) continue;
      for (const VertexIndex v : mesh.triangles[it->second])
        if (n.normalized().dot(mesh.positions[v] - mesh.positions[a[0]]) > tolerance) return std::nullopt;
    }
  }

  ConvexPolytope polytope;
  double signed_volume = 0;
  for (const Triangle& t : mesh.triangles) {
    const Vertex& a = mesh.positions[t[0]];
    const Vertex& b = mesh.positions[t[1]];
    const Vertex& c = mesh.positions[t[2]];
    signed_volume += a.dot(b.cross(c)) / 6;
    const Vertex n = (b - a).cross(c - a);
    if (n.norm() <= 1e-12 * diagonal * diagonal) continue;  // a sliver gives no reliable plane
    Plane plane{n.normalized(), 0};
    plane.offset = plane.normal.dot(a);
    // Coplanar faces share one plane.
    const bool known = std::any_of(polytope.planes_.begin(), polytope.planes_.end(), [&](const Plane& p) {
      return p.normal.dot(plane.normal) > 1 - 1e-12 && std::abs(p.offset - plane.offset) <= tolerance;
    });
    if (known) continue;
    if (polytope.planes_.size() == max_planes) return std::nullopt;
    polytope.planes_.push_back(plane);
  }
  if (!(signed_volume > 0) || polytope.planes_.size() < 4) return std::nullopt;
  // Convex: every vertex behind every face plane.
  for (Plane& plane : polytope.planes_) {
    double height = -std::numeric_limits<double>::infinity();
    for (const Vertex& v : points) height = std::max(height, plane.normal.dot(v) - plane.offset);
    if (height > tolerance) return std::nullopt;
    plane.offset += std::max(height, 0.0) + tolerance;
  }
  // The ball: around the box's centre, through the farthest vertex, grown by more than
  // the planes moved out (a vertex of the pushed-out solid moves by about tolerance over
  // the sine of the angle between its planes, which the factor covers for any sane mesh).
  const BoundingBox box = bounding_box(mesh);
  polytope.center_ = 0.5 * (box.min + box.max);
  for (const Vertex& v : points) polytope.radius_ = std::max(polytope.radius_, (v - polytope.center_).norm());
  polytope.radius_ += 1e3 * tolerance;
  polytope.pack();
  return polytope;
}

ConvexPolytope ConvexPolytope::transformed(const Eigen::Affine3d& transform) const {
  // x = A y + t; n . y <= d  <=>  (A^-T n) . x <= d + (A^-T n) . t.
  const Eigen::Matrix3d normal_matrix = transform.linear().inverse().transpose();
  ConvexPolytope result;
  result.center_ = transform * center_;
  result.radius_ = radius_ * Eigen::JacobiSVD<Eigen::Matrix3d>(transform.linear()).singularValues()(0) * (1 + 1e-12);
  for (const Plane& plane : planes_) {
    const Vertex n = normal_matrix * plane.normal;
    const double length = n.norm();
    result.planes_.push_back({n / length, (plane.offset + n.dot(transform.translation())) / length});
  }
  result.pack();
  return result;
}

ConvexPolytope ConvexPolytope::grown(double distance) const {
  ConvexPolytope result = *this;
  for (Plane& plane : result.planes_) plane.offset += distance;
  // A vertex moves by the distance over the sine of the angles between its planes; the
  // factor covers that for any sane mesh, as from_mesh's tolerance does.
  result.radius_ += 1e3 * distance;
  result.pack();
  return result;
}

double ConvexPolytope::inner_distance(const Vertex& point) const {
  double distance = std::numeric_limits<double>::infinity();
  for (const Plane& plane : planes_) distance = std::min(distance, plane.offset - plane.normal.dot(point));
  return distance;
}

void ConvexPolytope::pack() {
  const std::size_t blocks = (planes_.size() + 3) / 4;
  packed_.assign(16 * blocks, 0.0);
  for (std::size_t i = 0; i < 4 * blocks; ++i) {
    double* block = packed_.data() + 16 * (i / 4);
    const std::size_t k = i % 4;
    if (i < planes_.size()) {
      for (int a = 0; a < 3; ++a) block[4 * a + k] = planes_[i].normal[a];
      block[12 + k] = planes_[i].offset;
    } else {
      block[12 + k] = 1;  // 0 . x <= 1 everywhere
    }
  }
}

bool ConvexPolytope::meets_segment(const Vertex& from, const Vertex& to) const {
  const Vertex d = to - from;
  if (!segment_meets_ball({center_, radius_}, from, d, 0.0, 1.0)) return false;
  double enter = 0, leave = 1;
  bool parallel_outside = false;
  for (std::size_t block = 0; block < packed_.size(); block += 16) {
    const double* p = packed_.data() + block;
    for (int k = 0; k < 4; ++k) {
      const double along = p[k] * d.x() + p[4 + k] * d.y() + p[8 + k] * d.z();
      const double inside = p[12 + k] - (p[k] * from.x() + p[4 + k] * from.y() + p[8 + k] * from.z());
      const double t = inside / along;  // used only where along != 0
      enter = along < 0 ? std::max(enter, t) : enter;
      leave = along > 0 ? std::min(leave, t) : leave;
      parallel_outside = parallel_outside || (along == 0 && inside < 0);
    }
    if (enter > leave || parallel_outside) return false;
  }
  return true;
}

bool grow_convex_mesh(TriangleMesh& mesh, double distance, std::size_t max_planes) {
  const std::optional<ConvexPolytope> solid = ConvexPolytope::from_mesh(mesh, max_planes);
  if (!solid) return false;
  const std::vector<Vertex> points = used_positions(mesh);
  Vertex center = Vertex::Zero();
  for (const Vertex& v : points) center += v / static_cast<double>(points.size());
  const double inner = solid->inner_distance(center);
  if (!(inner > 0)) return false;
  const double scale = 1 + distance / inner;
  for (Vertex& v : mesh.positions) v = center + scale * (v - center);
  return true;
}

}  // namespace visproxy
