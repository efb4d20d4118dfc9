// Bounded convex hull by progressive half-space removal.
//
// The greedy order is that of S. Melax's convex hull simplification with containment by
// successive plane removal (as described by C. Bloom, "A Note on Convex Hull
// Simplification", 2011) and of A. Jacobson, "Progressive Convex Hull Simplification"
// (arXiv:2604.14468, 2026): remove the plane whose removal adds the least volume. Like Jacobson, the work is done in the
// dual: with the origin at a point strictly inside, the plane {x : p . x <= 1} is the
// dual point p, the polytope is the polar of the convex hull of the dual points, its
// faces are the dual hull's vertices and its corners the dual hull's triangles. Removing
// a plane is removing a dual vertex; only the triangles around it change (the hole is
// filled from the vertex's link alone, since removing a half-space never makes another
// one redundant), so each step and each cost update is local, and the whole run is
// O(H log H) with a heap.
//
// Every combinatorial decision (which triangles fill the hole, whether the region stays
// bounded) is an exact orientation test on the dual points as rounded to double, so the
// dual structure stays the exact hull of those points (up to how faces with more than
// three coplanar points are triangulated). The cost (the volume of the
// cap the removal adds) is computed in double and only orders the removals. The output's
// corners are computed in double; containment of the input is then checked exactly.

#include "visproxy/proxy/bounded_hull.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Exact_rational.h>

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <queue>
#include <stdexcept>
#include <string>
#include <tuple>

#include "visproxy/core/errors.h"
#include "visproxy/proxy/convex_hull.h"
#include "visproxy/proxy/detail/hull_facets.h"

namespace visproxy {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using PlaneIndex = std::uint32_t;
using DualTriangle = std::array<PlaneIndex, 3>;

constexpr double infinite_cost = std::numeric_limits<double>::infinity();

[[noreturn]] void reject(const std::string& problem) { throw InvalidInputError("bounded hull", problem); }

Point cgal_point(const Vertex& p) { return {p.x(), p.y(), p.z()}; }

// A plane {x : normal . x <= offset} in coordinates centred at a point strictly inside,
// so offset > 0; its dual point is normal / offset.
struct Plane {
  Vertex normal;  // unit length
  double offset = 0.0;
  Vertex dual() const { return normal / offset; }
};

// The corner where the three planes with dual points a, b, c meet: the solution of
// a.x = b.x = c.x = 1.
Vertex meeting_point(const Vertex& a, const Vertex& b, const Vertex& c) {
  const double determinant = a.dot(b.cross(c));
  return (b.cross(c) + c.cross(a) + a.cross(b)) / determinant;
}

// meeting_point(a, b, c) + center computed in exact rational arithmetic, rounded once.
Vertex exact_meeting_point(const Vertex& a, const Vertex& b, const Vertex& c, const Vertex& center) {
  using Rational = CGAL::Exact_rational;
  using Vector = std::array<Rational, 3>;
  auto exact = [](const Vertex& v) { return Vector{Rational(v.x()), Rational(v.y()), Rational(v.z())}; };
  auto cross = [](const Vector& u, const Vector& v) {
    return Vector{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  };
  const Vector ea = exact(a), eb = exact(b), ec = exact(c);
  const Vector bc = cross(eb, ec), ca = cross(ec, ea), ab = cross(ea, eb);
  const Rational determinant = ea[0] * bc[0] + ea[1] * bc[1] + ea[2] * bc[2];
  assert(!CGAL::is_zero(determinant));
  Vertex point;
  for (int k = 0; k < 3; ++k) point[k] = CGAL::to_double((bc[k] + ca[k] + ab[k]) / determinant + Rational(center[k]));
  return point;
}

// Outward triangles seen as fans: next(center, from) is the vertex that follows `from`
// counter-clockwise around `center`.
class Fan {
 public:
  explicit Fan(const std::vector<DualTriangle>& triangles) {
    steps_.reserve(3 * triangles.size());
    for (const DualTriangle& t : triangles)
      for (int k = 0; k < 3; ++k) steps_.push_back({t[k], t[(k + 1) % 3], t[(k + 2) % 3]});
    std::sort(steps_.begin(), steps_.end());
  }
  PlaneIndex next(PlaneIndex center, PlaneIndex from) const {
    const auto found = std::lower_bound(steps_.begin(), steps_.end(), std::array<PlaneIndex, 3>{center, from, 0});
    assert(found != steps_.end() && (*found)[0] == center && (*found)[1] == from);
    return (*found)[2];
  }

 private:
  std::vector<std::array<PlaneIndex, 3>> steps_;
};

// The convex hull of the dual points as a triangulated sphere: for each live vertex, its
// neighbours in counter-clockwise order seen from outside, so that (v, ring[k],
// ring[k+1]) are the outward triangles around v.
class DualHull {
 public:
  DualHull(std::vector<Vertex> duals, const std::vector<DualTriangle>& triangles) : duals_(std::move(duals)) {
    points_.reserve(duals_.size());
    for (const Vertex& d : duals_) points_.push_back(cgal_point(d));
    rings_ = rings_from_triangles(duals_.size(), triangles);
    alive_.assign(duals_.size(), false);
    for (std::size_t v = 0; v < duals_.size(); ++v)
      if (!rings_[v].empty()) {
        alive_[v] = true;
        ++alive_count_;
      }
  }

  std::size_t vertex_count() const { return duals_.size(); }
  std::size_t alive_count() const { return alive_count_; }
  bool alive(PlaneIndex v) const { return alive_[v]; }
  const std::vector<PlaneIndex>& ring(PlaneIndex v) const { return rings_[v]; }
  const Vertex& dual(PlaneIndex v) const { return duals_[v]; }

  // The triangles that fill the hole left by removing v, each a facet of the hull of the
  // remaining points seen from v, found by clipping ears off v's link: an ear (a, b, c)
  // of consecutive link vertices is taken when no link vertex is beyond its plane and v
  // is not behind it. nullopt when the removal would leave the origin outside or on the
  // new hull (an unbounded polytope) or when no ear is found (a degenerate link).
  std::optional<std::vector<DualTriangle>> fill_hole(PlaneIndex v) const {
    const std::vector<PlaneIndex>& link = rings_[v];
    const std::size_t m = link.size();
    std::vector<std::size_t> next(m), previous(m);
    for (std::size_t i = 0; i < m; ++i) {
      next[i] = (i + 1) % m;
      previous[i] = (i + m - 1) % m;
    }
    const Point& removed = points_[v];
    const Point origin(0.0, 0.0, 0.0);
    auto is_ear = [&](std::size_t i) {
      const Point& a = points_[link[previous[i]]];
      const Point& b = points_[link[i]];
      const Point& c = points_[link[next[i]]];
      if (CGAL::collinear(a, b, c)) return false;
      if (CGAL::orientation(a, b, c, removed) == CGAL::NEGATIVE) return false;
      if (CGAL::orientation(a, b, c, origin) != CGAL::NEGATIVE) return false;
      for (std::size_t j = 0; j < m; ++j) {
        if (j == i || j == previous[i] || j == next[i]) continue;
        if (CGAL::orientation(a, b, c, points_[link[j]]) == CGAL::POSITIVE) return false;
      }
      return true;
    };

    std::vector<DualTriangle> filled;
    filled.reserve(m - 2);
    std::size_t remaining = m;
    std::size_t at = 0;
    std::size_t failures = 0;
    while (remaining > 3) {
      if (is_ear(at)) {
        filled.push_back({link[previous[at]], link[at], link[next[at]]});
        next[previous[at]] = next[at];
        previous[next[at]] = previous[at];
        --remaining;
        at = previous[at];
        failures = 0;
      } else {
        if (++failures > remaining) return std::nullopt;
        at = next[at];
      }
    }
    if (!is_ear(at)) return std::nullopt;
    filled.push_back({link[previous[at]], link[at], link[next[at]]});
    return filled;
  }

  // Removes v and puts `filled` (from fill_hole(v)) in its place.
  void remove(PlaneIndex v, const std::vector<DualTriangle>& filled) {
    const std::vector<PlaneIndex> link = rings_[v];
    const std::size_t m = link.size();
    const Fan fan(filled);
    for (std::size_t i = 0; i < m; ++i) {
      // Around link[i], counter-clockwise: link[i+1], v, link[i-1]. v gives way to the
      // filled triangles' vertices between link[i+1] and link[i-1].
      const PlaneIndex center = link[i];
      const PlaneIndex last = link[(i + m - 1) % m];
      std::vector<PlaneIndex> inserted;
      for (PlaneIndex at = fan.next(center, link[(i + 1) % m]); at != last; at = fan.next(center, at))
        inserted.push_back(at);
      std::vector<PlaneIndex>& ring = rings_[center];
      const auto position = std::find(ring.begin(), ring.end(), v);
      assert(position != ring.end());
      ring.insert(ring.erase(position), inserted.begin(), inserted.end());
    }
    rings_[v].clear();
    alive_[v] = false;
    --alive_count_;
  }

 private:
  static std::vector<std::vector<PlaneIndex>> rings_from_triangles(std::size_t vertex_count,
                                                                   const std::vector<DualTriangle>& triangles) {
    // successors[v] holds (from, to) for every triangle (v, from, to).
    std::vector<std::vector<std::pair<PlaneIndex, PlaneIndex>>> successors(vertex_count);
    for (const DualTriangle& t : triangles)
      for (int k = 0; k < 3; ++k) successors[t[k]].emplace_back(t[(k + 1) % 3], t[(k + 2) % 3]);
    std::vector<std::vector<PlaneIndex>> rings(vertex_count);
    for (std::size_t v = 0; v < vertex_count; ++v) {
      auto& pairs = successors[v];
      if (pairs.empty()) continue;
      std::sort(pairs.begin(), pairs.end());
      PlaneIndex at = pairs.front().first;
      for (std::size_t step = 0; step < pairs.size(); ++step) {
        rings[v].push_back(at);
        const auto found = std::lower_bound(pairs.begin(), pairs.end(), std::make_pair(at, PlaneIndex{0}));
        assert(found != pairs.end() && found->first == at);
        at = found->second;
      }
      assert(at == pairs.front().first);
    }
    return rings;
  }

  std::vector<Vertex> duals_;
  std::vector<Point> points_;
  std::vector<std::vector<PlaneIndex>> rings_;
  std::vector<bool> alive_;
  std::size_t alive_count_ = 0;
};

// Volume added to the polytope by removing plane v, whose hole `filled` fills: the cap
// bounded by v's plane and the planes of its link. Computed as cones from a point on v's
// face over the cap's faces on the link planes.
double cap_volume(const DualHull& hull, PlaneIndex v, const std::vector<DualTriangle>& filled) {
  const std::vector<PlaneIndex>& link = hull.ring(v);
  const std::size_t m = link.size();
  // Corners of v's face: star[i] is where v, link[i] and link[i+1] meet.
  std::vector<Vertex> star(m);
  Vertex apex = Vertex::Zero();
  for (std::size_t i = 0; i < m; ++i) {
    star[i] = meeting_point(hull.dual(v), hull.dual(link[i]), hull.dual(link[(i + 1) % m]));
    apex += star[i];
  }
  apex /= static_cast<double>(m);

  const Fan fan(filled);
  double volume = 0.0;
  std::vector<Vertex> polygon;
  for (std::size_t i = 0; i < m; ++i) {
    const PlaneIndex center = link[i];
    const PlaneIndex after = link[(i + 1) % m];
    const PlaneIndex before = link[(i + m - 1) % m];
    // The cap's face on center's plane: the old edge shared with v's face, then the new
    // corners around center from the `after` side to the `before` side.
    polygon.clear();
    polygon.push_back(star[(i + m - 1) % m]);
    polygon.push_back(star[i]);
    PlaneIndex from = after;
    while (from != before) {
      const PlaneIndex to = fan.next(center, from);
      polygon.push_back(meeting_point(hull.dual(center), hull.dual(from), hull.dual(to)));
      from = to;
    }
    Vertex area_vector = Vertex::Zero();
    for (std::size_t k = 0; k < polygon.size(); ++k)
      area_vector += (polygon[k] - apex).cross(polygon[(k + 1) % polygon.size()] - apex);
    const Vertex& dual = hull.dual(center);
    const double offset = 1.0 / dual.norm();
    const Vertex normal = dual * offset;
    const double height = std::max(0.0, offset - normal.dot(apex));
    volume += height * std::abs(0.5 * normal.dot(area_vector)) / 3.0;
  }
  // Corners computed from nearly dependent planes can overflow; such a removal is still
  // allowed (it keeps the region bounded) but is taken last.
  return std::isfinite(volume) ? volume : std::numeric_limits<double>::max();
}

// The outward triangles of the convex hull of `duals`, in plane indices. Dual points that
// are not corners of that hull (redundant planes) appear in no triangle. Throws
// std::logic_error when the origin is not strictly inside (the planes bound no region
// around it): the callers only pass plane sets that are known to be bounded.
std::vector<DualTriangle> dual_hull_triangles(const std::vector<Vertex>& duals) {
  const Point origin(0.0, 0.0, 0.0);
  std::vector<DualTriangle> triangles;
  for (const Triangle& t : hull_detail::exact_convex_hull(duals)) {
    if (CGAL::orientation(cgal_point(duals[t[0]]), cgal_point(duals[t[1]]), cgal_point(duals[t[2]]), origin) !=
        CGAL::NEGATIVE)
      throw std::logic_error("bounded hull: the planes do not enclose the centre strictly");
    triangles.push_back({t[0], t[1], t[2]});
  }
  return triangles;
}

// Greedy removal until at most `max_faces` planes are left or no removal keeps the region
// bounded.
void remove_planes(DualHull& hull, std::size_t max_faces) {
  using Entry = std::tuple<double, PlaneIndex, std::uint32_t>;  // cost, plane, version
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> heap;
  std::vector<std::uint32_t> version(hull.vertex_count(), 0);
  auto cost_of = [&](PlaneIndex v) {
    const auto filled = hull.fill_hole(v);
    return filled ? cap_volume(hull, v, *filled) : infinite_cost;
  };
  for (PlaneIndex v = 0; v < hull.vertex_count(); ++v)
    if (hull.alive(v)) heap.emplace(cost_of(v), v, 0);
  while (hull.alive_count() > max_faces && !heap.empty()) {
    const auto [cost, v, entry_version] = heap.top();
    heap.pop();
    if (!hull.alive(v) || entry_version != version[v]) continue;
    if (cost == infinite_cost) break;  // every remaining plane is needed to stay bounded
    const auto filled = hull.fill_hole(v);
    assert(filled);
    const std::vector<PlaneIndex> link = hull.ring(v);
    hull.remove(v, *filled);
    for (const PlaneIndex u : link) heap.emplace(cost_of(u), u, ++version[u]);
  }
}

// The polytope bounded by `planes` (coordinates centred at `center`) as a closed mesh in
// world coordinates, with the plane of each triangle.
struct Polytope {
  TriangleMesh mesh;
  std::vector<PlaneIndex> plane_of_triangle;
  std::size_t faces = 0;
};

Polytope polytope_of_planes(const std::vector<Plane>& planes, const Vertex& center) {
  std::vector<Vertex> duals;
  duals.reserve(planes.size());
  for (const Plane& plane : planes) duals.push_back(plane.dual());
  const std::vector<DualTriangle> triangles = dual_hull_triangles(duals);

  // Dual triangles in one plane (exactly) are one corner of the polytope, where more than
  // three planes meet.
  TriangleMesh dual_mesh;
  dual_mesh.positions = duals;
  dual_mesh.triangles.reserve(triangles.size());
  for (const DualTriangle& t : triangles) dual_mesh.triangles.push_back({t[0], t[1], t[2]});
  std::size_t corner_count = 0;
  const std::vector<std::uint32_t> corner_of_triangle = hull_detail::planar_facets(dual_mesh, corner_count);
  // Each corner exactly, from any triangle of its group (their planes all meet there),
  // then rounded once: no cancellation, no overflow, whatever the planes' angles.
  std::vector<Vertex> corners(corner_count);
  std::vector<bool> placed(corner_count, false);
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const std::uint32_t corner = corner_of_triangle[t];
    if (placed[corner]) continue;
    placed[corner] = true;
    corners[corner] = exact_meeting_point(duals[triangles[t][0]], duals[triangles[t][1]], duals[triangles[t][2]], center);
    if (!corners[corner].allFinite()) throw std::logic_error("bounded hull: a corner is beyond the range of double");
  }

  // Each plane's face: the corners of the dual triangles around it, counter-clockwise
  // seen from outside (polarity keeps the order), consecutive repeats merged.
  std::vector<std::vector<std::pair<PlaneIndex, std::uint32_t>>> around(planes.size());  // (from, triangle)
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) around[triangles[t][k]].emplace_back(triangles[t][(k + 1) % 3], static_cast<std::uint32_t>(t));
  const Fan fan(triangles);
  Polytope polytope;
  constexpr VertexIndex unused = ~VertexIndex{0};
  std::vector<VertexIndex> output_index(corner_count, unused);
  std::vector<std::uint32_t> face;
  for (PlaneIndex j = 0; j < planes.size(); ++j) {
    auto& steps = around[j];
    if (steps.empty()) continue;  // redundant plane
    std::sort(steps.begin(), steps.end());
    face.clear();
    PlaneIndex from = steps.front().first;
    for (std::size_t step = 0; step < steps.size(); ++step) {
      const auto found = std::lower_bound(steps.begin(), steps.end(), std::make_pair(from, std::uint32_t{0}));
      const std::uint32_t corner = corner_of_triangle[found->second];
      if (face.empty() || face.back() != corner) face.push_back(corner);
      from = fan.next(j, from);
    }
    while (face.size() > 1 && face.back() == face.front()) face.pop_back();
    if (face.size() < 3) continue;  // the plane touches the polytope in an edge or a corner only
    ++polytope.faces;
    for (const std::uint32_t corner : face)
      if (output_index[corner] == unused) {
        output_index[corner] = static_cast<VertexIndex>(polytope.mesh.positions.size());
        polytope.mesh.positions.push_back(corners[corner]);
      }
    for (std::size_t k = 1; k + 1 < face.size(); ++k) {
      polytope.mesh.triangles.push_back(
          {output_index[face[0]], output_index[face[k]], output_index[face[k + 1]]});
      polytope.plane_of_triangle.push_back(j);
    }
  }
  return polytope;
}

// Planes of the triangles that some point is not strictly inside of (outside, or on the
// plane), decided exactly. Strictly: a point on a plane would let the input's triangles
// touch the output, which the corners' rounding keeps from being exactly convex, and then
// no exact check could prove the input contained. Degenerate (collinear) triangles bound
// nothing and are skipped.
std::vector<PlaneIndex> planes_not_strictly_holding(const Polytope& polytope, const std::vector<Point>& points) {
  std::vector<PlaneIndex> planes;
  for (std::size_t t = 0; t < polytope.mesh.triangles.size(); ++t) {
    const Triangle& triangle = polytope.mesh.triangles[t];
    const Point a = cgal_point(polytope.mesh.positions[triangle[0]]);
    const Point b = cgal_point(polytope.mesh.positions[triangle[1]]);
    const Point c = cgal_point(polytope.mesh.positions[triangle[2]]);
    if (CGAL::collinear(a, b, c)) continue;
    for (const Point& p : points)
      if (CGAL::orientation(a, b, c, p) != CGAL::NEGATIVE) {
        planes.push_back(polytope.plane_of_triangle[t]);
        break;
      }
  }
  std::sort(planes.begin(), planes.end());
  planes.erase(std::unique(planes.begin(), planes.end()), planes.end());
  return planes;
}

// Volume centroid of a closed outward mesh: strictly inside when the volume is positive.
Vertex volume_centroid(const TriangleMesh& mesh) {
  const Vertex& origin = mesh.positions.front();
  Vertex weighted = Vertex::Zero();
  double six_volume = 0.0;
  for (const Triangle& triangle : mesh.triangles) {
    const Vertex a = mesh.positions[triangle[0]] - origin;
    const Vertex b = mesh.positions[triangle[1]] - origin;
    const Vertex c = mesh.positions[triangle[2]] - origin;
    const double determinant = a.dot(b.cross(c));
    six_volume += determinant;
    weighted += determinant * (a + b + c);
  }
  return origin + weighted / (4.0 * six_volume);
}

// One plane per planar facet of the exact hull, in coordinates centred at `center`. The
// normal comes from the facet's triangles in input coordinates (exact for axis-aligned
// facets with small integer coordinates), the offset from its corners.
std::vector<Plane> facet_planes(const ConvexHullResult& hull, const Vertex& center) {
  std::size_t facet_count = 0;
  const std::vector<std::uint32_t> facet_of_triangle = hull_detail::planar_facets(hull.mesh, facet_count);
  std::vector<Vertex> area_normal(facet_count, Vertex::Zero());
  for (std::size_t t = 0; t < hull.mesh.triangles.size(); ++t) {
    const Triangle& triangle = hull.mesh.triangles[t];
    const Vertex& a = hull.mesh.positions[triangle[0]];
    area_normal[facet_of_triangle[t]] += (hull.mesh.positions[triangle[1]] - a).cross(hull.mesh.positions[triangle[2]] - a);
  }
  std::vector<Plane> planes(facet_count);
  for (std::size_t f = 0; f < facet_count; ++f) planes[f].normal = area_normal[f].normalized();
  std::vector<double> support(facet_count, -std::numeric_limits<double>::infinity());
  for (std::size_t t = 0; t < hull.mesh.triangles.size(); ++t)
    for (const VertexIndex corner : hull.mesh.triangles[t]) {
      const std::uint32_t f = facet_of_triangle[t];
      support[f] = std::max(support[f], planes[f].normal.dot(hull.mesh.positions[corner]));
    }
  // A sliver facet (nearly collinear corners: points along an edge of the input turned
  // off their line by rounding) has no plane double precision can give. It bounds next to
  // nothing: it is left out, which only grows the polytope (containment is checked exactly
  // at the end). A facet of real area without a plane means the hull itself is too thin.
  const double diagonal = bounding_box(hull.mesh).diagonal();
  std::vector<Plane> kept;
  for (std::size_t f = 0; f < facet_count; ++f) {
    planes[f].offset = support[f] - planes[f].normal.dot(center);
    if (planes[f].normal.allFinite() && planes[f].offset > 0.0) {
      kept.push_back(planes[f]);
      continue;
    }
    if (!(0.5 * area_normal[f].norm() <= 1e-12 * diagonal * diagonal))
      reject("the convex hull is too thin for its facet planes to be computed in double precision");
  }
  if (kept.size() < 4) reject("the convex hull is too thin for its facet planes to be computed in double precision");
  return kept;
}

}  // namespace

BoundedHullResult build_bounded_hull(const TriangleMesh& mesh, const BoundedHullOptions& options) {
  if (options.max_faces < 4)
    reject("max_faces is " + std::to_string(options.max_faces) + "; a bounded polytope has at least 4 faces");
  ConvexHullResult exact = build_convex_hull(mesh);
  BoundedHullResult result;
  result.exact_hull_volume = exact.volume;
  if (exact.faces == 2) {  // flat: a two-sided polygon
    const std::size_t edges = exact.mesh.positions.size();
    if (edges > options.max_faces)
      reject("the input is flat and its convex polygon has " + std::to_string(edges) + " edges, more than max_faces (" +
             std::to_string(options.max_faces) + ")");
  }
  if (exact.faces <= options.max_faces || exact.faces == 2) {
    result.mesh = std::move(exact.mesh);
    result.faces = exact.faces;
    result.volume = exact.volume;
    return result;
  }

  const Vertex center = volume_centroid(exact.mesh);
  std::vector<Plane> planes = facet_planes(exact, center);
  std::vector<Vertex> duals;
  duals.reserve(planes.size());
  for (const Plane& plane : planes) duals.push_back(plane.dual());
  DualHull dual_hull(duals, dual_hull_triangles(duals));
  remove_planes(dual_hull, options.max_faces);
  if (dual_hull.alive_count() > options.max_faces)
    reject("no plane of the remaining " + std::to_string(dual_hull.alive_count()) +
           " can be removed without leaving an unbounded region; max_faces " + std::to_string(options.max_faces) +
           " is out of reach by removing planes");

  // The kept planes, each moved to touch the hull's vertices (rounding may have left a
  // vertex slightly outside its own facet's plane).
  std::vector<Plane> kept;
  for (PlaneIndex j = 0; j < dual_hull.vertex_count(); ++j)
    if (dual_hull.alive(j)) kept.push_back(planes[j]);
  for (Plane& plane : kept) {
    double support = -std::numeric_limits<double>::infinity();
    for (const Vertex& p : exact.mesh.positions) support = std::max(support, plane.normal.dot(p));
    plane.offset = support - plane.normal.dot(center);
  }

  // Build, check exactly, push the planes that leave a vertex outside or on them, repeat.
  std::vector<Point> hull_points;
  hull_points.reserve(exact.mesh.positions.size());
  for (const Vertex& p : exact.mesh.positions) hull_points.push_back(cgal_point(p));
  // A few units in the last place of the coordinates, doubled each round.
  const BoundingBox box = bounding_box(exact.mesh);
  double push = 8.0 * std::numeric_limits<double>::epsilon() *
                (box.diagonal() + std::max(box.min.cwiseAbs().maxCoeff(), box.max.cwiseAbs().maxCoeff()));
  for (int round = 0;; ++round) {
    Polytope polytope = polytope_of_planes(kept, center);
    const std::vector<PlaneIndex> outside = planes_not_strictly_holding(polytope, hull_points);
    if (outside.empty()) {
      result.mesh = std::move(polytope.mesh);
      result.faces = polytope.faces;
      break;
    }
    if (round == 64) throw std::logic_error("bounded hull: containment not reached after 64 rounds of pushing planes");
    for (const PlaneIndex j : outside) kept[j].offset += push;
    push *= 2.0;
  }
  result.volume = hull_detail::enclosed_volume(result.mesh);
  return result;
}

}  // namespace visproxy
