#include "visproxy/trace/triangle_distance.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

#include "visproxy/trace/embree_support.h"

namespace visproxy {

namespace {

Vertex segment_nearest_point(const Vertex& p, const Vertex& a, const Vertex& b) {
  const Vertex ab = b - a;
  const double length2 = ab.squaredNorm();
  if (!(length2 > 0)) return a;
  const double t = std::clamp((p - a).dot(ab) / length2, 0.0, 1.0);
  return a + t * ab;
}

// Of the candidate points, the one nearest to p (the first among equals).
template <std::size_t N>
Vertex nearest_of(const Vertex& p, const std::array<Vertex, N>& candidates) {
  std::size_t best = 0;
  double best_distance = (p - candidates[0]).squaredNorm();
  for (std::size_t i = 1; i < N; ++i) {
    const double distance = (p - candidates[i]).squaredNorm();
    if (distance < best_distance) best = i, best_distance = distance;
  }
  return candidates[best];
}

}  // namespace

Vertex point_triangle_nearest_point(const Vertex& p, const Vertex& a, const Vertex& b, const Vertex& c) {
  // The nearest point by the region of the triangle's plane p projects into: a corner, a
  // side, or the inside (barycentric coordinates from the dot products of the sides).
  const Vertex ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vertex bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const Vertex cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return segment_nearest_point(p, a, b);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return segment_nearest_point(p, a, c);
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) return segment_nearest_point(p, b, c);
  const std::array<Vertex, 3> sides = {segment_nearest_point(p, a, b), segment_nearest_point(p, b, c),
                                       segment_nearest_point(p, a, c)};
  const double sum = va + vb + vc;
  // Collinear corners (no area): the segments they span.
  if (!(std::abs(sum) > 0) || !std::isfinite(sum)) return nearest_of(p, sides);
  // Rounding can put a nearly degenerate triangle's "inside" point off it: never farther
  // than the sides.
  const double v = vb / sum, w = vc / sum;
  return nearest_of(p, std::array<Vertex, 4>{a + v * ab + w * ac, sides[0], sides[1], sides[2]});
}

double point_triangle_squared_distance(const Vertex& p, const Vertex& a, const Vertex& b, const Vertex& c) {
  return (p - point_triangle_nearest_point(p, a, b, c)).squaredNorm();
}

struct TriangleDistance::Impl {
  EmbreeDevice device;
  RTCScene scene = nullptr;
  const TriangleMesh* mesh = nullptr;
  std::vector<std::uint32_t> triangles;
  // The BVH holds the triangles moved by -centre (the centre of their box), so that single
  // precision resolves them wherever they lie.
  Vertex centre = Vertex::Zero();
  double extent = 0;     // largest absolute coordinate of the moved triangles
  double magnitude = 0;  // largest absolute coordinate of the triangles where they lie

  // The search radius's slack for a query at p: 2^-18 of the moved coordinates' magnitude
  // (single-precision boxes and query point) plus 2^-40 of the absolute one (the move's
  // double-precision rounding).
  double slack(const Vertex& p) const {
    return 0x1.0p-18 * std::max(extent, (p - centre).cwiseAbs().maxCoeff()) +
           0x1.0p-40 * std::max(magnitude, p.cwiseAbs().maxCoeff());
  }

  std::array<Vertex, 3> corners(unsigned prim) const {
    const Triangle& t = mesh->triangles[triangles[prim]];
    return {mesh->positions[t[0]], mesh->positions[t[1]], mesh->positions[t[2]]};
  }
};

namespace {

void triangle_bounds(const RTCBoundsFunctionArguments* args) {
  const auto& impl = *static_cast<const TriangleDistance::Impl*>(args->geometryUserPtr);
  const Triangle& t = impl.mesh->triangles[impl.triangles[args->primID]];
  const Vertex a = impl.mesh->positions[t[0]] - impl.centre;
  const Vertex b = impl.mesh->positions[t[1]] - impl.centre;
  const Vertex c = impl.mesh->positions[t[2]] - impl.centre;
  RTCBounds* bounds = args->bounds_o;
  bounds->lower_x = round_down(std::min({a.x(), b.x(), c.x()}));
  bounds->lower_y = round_down(std::min({a.y(), b.y(), c.y()}));
  bounds->lower_z = round_down(std::min({a.z(), b.z(), c.z()}));
  bounds->upper_x = round_up(std::max({a.x(), b.x(), c.x()}));
  bounds->upper_y = round_up(std::max({a.y(), b.y(), c.y()}));
  bounds->upper_z = round_up(std::max({a.z(), b.z(), c.z()}));
}

// One query: the point, the nearest squared distance so far (or, for within(), the
// squared radius to stop below), and the slack added to the single-precision search radius.
struct Query {
  const TriangleDistance::Impl* impl;
  Vertex p;
  double best;        // squared distance found so far (squared_distance) or asked (within)
  double slack;
  bool stop_at_first;
  bool found = false;
};

bool visit_triangle(RTCPointQueryFunctionArguments* args) {
  auto& query = *static_cast<Query*>(args->userPtr);
  const std::array<Vertex, 3> c = query.impl->corners(args->primID);
  const double d = point_triangle_squared_distance(query.p, c[0], c[1], c[2]);
  if (!(d < query.best)) return false;
  query.found = true;
  if (query.stop_at_first) {
    args->query->radius = 0;
    return true;
  }
  query.best = d;
  args->query->radius = std::min(args->query->radius, round_up(std::sqrt(d) + query.slack));
  return true;
}

}  // namespace

TriangleDistance::TriangleDistance(const TriangleMesh& mesh, std::vector<std::uint32_t> triangles)
    : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.mesh = &mesh;
  s.triangles = std::move(triangles);
  BoundingBox box;
  for (const std::uint32_t t : s.triangles)
    for (const VertexIndex v : mesh.triangles[t]) box.extend(mesh.positions[v]);
  if (!s.triangles.empty()) {
    s.centre = 0.5 * (box.min + box.max);
    s.extent = (0.5 * (box.max - box.min)).maxCoeff();
    s.magnitude = std::max(box.min.cwiseAbs().maxCoeff(), box.max.cwiseAbs().maxCoeff());
  }
  s.scene = rtcNewScene(s.device.get());
  rtcSetSceneBuildQuality(s.scene, RTC_BUILD_QUALITY_MEDIUM);
  rtcSetSceneFlags(s.scene, RTC_SCENE_FLAG_COMPACT);
  if (!s.triangles.empty()) {
    RTCGeometry geometry = rtcNewGeometry(s.device.get(), RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(geometry, static_cast<unsigned>(s.triangles.size()));
    rtcSetGeometryUserData(geometry, &s);
    rtcSetGeometryBoundsFunction(geometry, triangle_bounds, &s);
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(s.scene, geometry);
    rtcReleaseGeometry(geometry);
  }
  rtcCommitScene(s.scene);
  s.device.throw_if_failed();
}

TriangleDistance::~TriangleDistance() {
  if (impl_ && impl_->scene) rtcReleaseScene(impl_->scene);
}

std::size_t TriangleDistance::size() const { return impl_->triangles.size(); }

const std::vector<std::uint32_t>& TriangleDistance::triangles() const { return impl_->triangles; }

namespace {

double search(const TriangleDistance::Impl& impl, Query& query, double radius) {
  RTCPointQuery point{};
  const Vertex moved = query.p - impl.centre;
  point.x = static_cast<float>(moved.x());
  point.y = static_cast<float>(moved.y());
  point.z = static_cast<float>(moved.z());
  point.time = 0;
  point.radius = std::isfinite(radius) ? round_up(radius) : std::numeric_limits<float>::infinity();
  RTCPointQueryContext context;
  rtcInitPointQueryContext(&context);
  rtcPointQuery(impl.scene, &point, &context, visit_triangle, &query);
  return query.best;
}

}  // namespace

double TriangleDistance::squared_distance(const Vertex& p) const {
  Query query{impl_.get(), p, std::numeric_limits<double>::infinity(), impl_->slack(p), false};
  return search(*impl_, query, std::numeric_limits<double>::infinity());
}

bool TriangleDistance::within(const Vertex& p, double squared_radius) const {
  if (!(squared_radius > 0)) return false;
  Query query{impl_.get(), p, squared_radius, impl_->slack(p), true};
  search(*impl_, query, std::sqrt(squared_radius) + query.slack);
  return query.found;
}

}  // namespace visproxy
