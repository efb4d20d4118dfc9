// The input of a conservative decimation (conservative_decimation.h): its exact geometry,
// the checks of the surface a decimation starts from, and the bounds it reports.

#include "visproxy/proxy/detail/exact_surface.h"

namespace visproxy::detail {

namespace {

// Checks of the starting surface and the reported distance bound.

// ConservativeInput::starts_conservative: the decimation's invariant starts from here, so
// it is checked, not assumed from how the start was made.
bool start_is_conservative(const TriangleMesh& wrap, const InputGeometry& input, InputSide side) {
  const MeshTopology topology = analyze_topology(wrap);
  if (!topology.closed() || !topology.manifold() || !topology.consistently_oriented()) return false;

  std::vector<TriangleCorners> corners(wrap.triangles.size());
  std::vector<CgalTriangle> triangles;
  triangles.reserve(wrap.triangles.size());
  std::vector<Box> boxes;
  boxes.reserve(wrap.triangles.size());
  for (std::size_t t = 0; t < wrap.triangles.size(); ++t) {
    for (std::size_t i = 0; i < 3; ++i) {
      corners[t].ids[i] = wrap.triangles[t][i];
      corners[t].points[i] = to_point(wrap.positions[wrap.triangles[t][i]]);
    }
    const auto& p = corners[t].points;
    if (CGAL::collinear(p[0], p[1], p[2])) return false;
    triangles.emplace_back(p[0], p[1], p[2]);
    boxes.emplace_back(p[0].bbox() + p[1].bbox() + p[2].bbox(), static_cast<std::uint32_t>(t));
  }
  bool self_intersecting = false;
  CGAL::box_self_intersection_d(boxes.begin(), boxes.end(), [&](const Box& a, const Box& b) {
    if (!self_intersecting) self_intersecting = triangles_meet_beyond_shared(corners[a.info()], corners[b.info()]);
  });
  if (self_intersecting) return false;

  // Orientation: outward, every component enclosing a positive volume (the input inside);
  // inward, the whole surface enclosing a negative volume (the input outside).
  std::size_t component_count = 0;
  const std::vector<std::uint32_t> component = triangle_components(wrap, &component_count);
  std::vector<double> volume(component_count, 0.0);
  for (std::size_t t = 0; t < wrap.triangles.size(); ++t) {
    const Triangle& triangle = wrap.triangles[t];
    volume[component[t]] += wrap.positions[triangle[0]].dot(
        wrap.positions[triangle[1]].cross(wrap.positions[triangle[2]]));
  }
  if (side == InputSide::inside && std::any_of(volume.begin(), volume.end(), [](double v) { return !(v > 0); }))
    return false;
  if (side == InputSide::outside && !(std::accumulate(volume.begin(), volume.end(), 0.0) < 0)) return false;

  for (const CgalTriangle& t : triangles)
    if (input.meets(t)) return false;

  TriangleTree tree(triangles.begin(), triangles.end());
  tree.build();
  const BoundingBox box = bounding_box(wrap);
  const Vertex centre = 0.5 * (box.min + box.max);
  Random directions(0x5eed0f11u);
  std::vector<TrianglePrimitive::Id> hits;
  for (const Vertex& p : input.representatives()) {
    const double reach = 2.0 * box.diagonal() + (p - centre).norm();
    const std::optional<bool> inside = inside_by_parity(
        to_point(p), reach, directions, [&](const Point& from, const Point& to) -> std::optional<std::size_t> {
          hits.clear();
          tree.all_intersected_primitives(CgalSegment(from, to), std::back_inserter(hits));
          std::size_t count = 0;
          for (const auto& id : hits) {
            const Crossing crossing = segment_crossing(from, to, *id);
            if (crossing == Crossing::degenerate) return std::nullopt;
            if (crossing == Crossing::proper) ++count;
          }
          return count;
        });
    if (!inside || *inside != (side == InputSide::inside)) return false;
  }
  return true;
}

// An upper bound of the distance from the surface `mesh` to the input. The distance to the
// input is 1-Lipschitz, so over a triangle split into steps² similar pieces it is at most the
// largest distance at the piece corners plus the pieces' longest side. Corners whose bound
// from nearer known distances cannot raise the result are not queried.
double distance_bound(const TriangleMesh& mesh, const InputGeometry& input, double resolution) {
  std::vector<double> vertex_distance(mesh.positions.size(), -1.0);
  auto distance_at_vertex = [&](VertexIndex v) {
    if (vertex_distance[v] < 0) vertex_distance[v] = input.distance(to_point(mesh.positions[v]));
    return vertex_distance[v];
  };
  double bound = 0;
  for (const Triangle& t : mesh.triangles) {
    const std::array<Vertex, 3> p = {mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]};
    const std::array<double, 3> d = {distance_at_vertex(t[0]), distance_at_vertex(t[1]), distance_at_vertex(t[2])};
    const double longest = std::max({(p[1] - p[0]).norm(), (p[2] - p[1]).norm(), (p[0] - p[2]).norm()});
    // Any point of the triangle is within `longest` of every corner.
    if (std::min({d[0], d[1], d[2]}) + longest <= bound) continue;
    const int steps = std::clamp(static_cast<int>(std::ceil(longest / resolution)), 1, 64);
    const double slack = longest / steps;
    double farthest = std::max({d[0], d[1], d[2]});
    for (int i = 0; i <= steps; ++i)
      for (int j = 0; i + j <= steps; ++j) {
        const double u = static_cast<double>(i) / steps;
        const double v = static_cast<double>(j) / steps;
        const Vertex x = p[0] + u * (p[1] - p[0]) + v * (p[2] - p[0]);
        double known = std::numeric_limits<double>::infinity();
        for (std::size_t k = 0; k < 3; ++k) known = std::min(known, d[k] + (x - p[k]).norm());
        if (known <= farthest || known + slack <= bound) continue;
        farthest = std::max(farthest, input.distance(to_point(x)));
      }
    bound = std::max(bound, farthest + slack);
  }
  return bound;
}

}  // namespace



ConservativeInput::ConservativeInput(const TriangleMesh& input) : impl_(std::make_unique<Impl>(input)) {}
ConservativeInput::~ConservativeInput() = default;

const TriangleBoxTree& ConservativeInput::triangles() const { return impl_->geometry.triangles(); }
const SoupPrimitives& ConservativeInput::degenerate() const { return impl_->geometry.degenerate(); }

bool ConservativeInput::starts_conservative(const TriangleMesh& surface, InputSide side) const {
  return start_is_conservative(surface, impl_->geometry, side);
}

std::vector<std::size_t> ConservativeInput::triangles_meeting(const TriangleMesh& surface) const {
  std::vector<std::size_t> meeting;
  for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
    const Triangle& tri = surface.triangles[t];
    const Point a = to_point(surface.positions[tri[0]]);
    const Point b = to_point(surface.positions[tri[1]]);
    const Point c = to_point(surface.positions[tri[2]]);
    if (CGAL::collinear(a, b, c)) {  // tested as the segments it is
      if (impl_->geometry.meets_segment(CgalSegment(a, b)) || impl_->geometry.meets_segment(CgalSegment(b, c)) ||
          impl_->geometry.meets_segment(CgalSegment(c, a)))
        meeting.push_back(t);
    } else if (impl_->geometry.meets(CgalTriangle(a, b, c))) {
      meeting.push_back(t);
    }
  }
  return meeting;
}

double ConservativeInput::distance(const Vertex& p) const { return impl_->geometry.distance(to_point(p)); }

bool ConservativeInput::keeps_clear(const TriangleMesh& surface, double clearance) const {
  const InputGeometry& input = impl_->geometry;
  // surfaces_clear_by's allowance for the rounding of the distances, relative to the
  // coordinates involved, added to the clearance so that this test is at least as strict.
  const BoundingBox box = bounding_box(surface);
  const double limit =
      clearance + 0x1.0p-40 * (std::max(box.max.cwiseAbs().maxCoeff(), box.min.cwiseAbs().maxCoeff()) + input.magnitude());
  std::atomic<bool> clear{true};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, surface.triangles.size(), 8),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t i = range.begin(); i != range.end() && clear; ++i) {
                        const Triangle& t = surface.triangles[i];
                        const CgalTriangle triangle(to_point(surface.positions[t[0]]), to_point(surface.positions[t[1]]),
                                                    to_point(surface.positions[t[2]]));
                        if (triangle.is_degenerate() || input.meets(triangle) || input.comes_within(triangle, limit))
                          clear = false;
                      }
                    });
  return clear;
}

double ConservativeInput::distance_bound(const TriangleMesh& surface, double resolution) const {
  return visproxy::detail::distance_bound(surface, impl_->geometry, resolution);
}

}  // namespace visproxy::detail
