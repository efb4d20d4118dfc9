// Exact point location and surface containment (CGAL, exact predicates on doubles).

#include "visproxy/verify/containment.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/FPU.h>
#include <CGAL/Interval_nt.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/convex_hull_3.h>
#include <CGAL/intersections.h>
#include <CGAL/squared_distance_3.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cassert>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <optional>
#include <variant>

#include "visproxy/core/errors.h"
#include "visproxy/core/random.h"

namespace visproxy {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using CgalSegment = Kernel::Segment_3;
using CgalTriangle = Kernel::Triangle_3;
using Triangles = std::vector<CgalTriangle>;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, Triangles::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;
using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::uint32_t>;

Point to_point(const Vertex& p) { return {p.x(), p.y(), p.z()}; }

Triangles triangles_of(const TriangleMesh& mesh) {
  Triangles triangles;
  triangles.reserve(mesh.triangles.size());
  for (const Triangle& t : mesh.triangles)
    triangles.emplace_back(to_point(mesh.positions[t[0]]), to_point(mesh.positions[t[1]]),
                           to_point(mesh.positions[t[2]]));
  return triangles;
}

void require_in_range(const TriangleMesh& mesh, const char* what) {
  if (const std::optional<std::size_t> vertex = first_vertex_out_of_range(mesh))
    throw InvalidInputError("", std::string(what) + " vertex " + std::to_string(*vertex) +
                                    " is not finite or beyond 1e100 in magnitude: exact containment cannot be decided");
}

// A triangle as the point set it is: a proper triangle, or (degenerate) a segment or a point.
using Shape = std::variant<CgalTriangle, CgalSegment, Point>;

Shape shape_of(const CgalTriangle& t) {
  if (!t.is_degenerate()) return t;
  const Point &a = t[0], &b = t[1], &c = t[2];
  if (a == b && b == c) return a;
  // Collinear: the segment between the two points that hold the third between them.
  if (CGAL::collinear_are_ordered_along_line(a, c, b) && a != b) return CgalSegment(a, b);
  if (CGAL::collinear_are_ordered_along_line(a, b, c) && a != c) return CgalSegment(a, c);
  return CgalSegment(b, c);
}

// Whether a proper (non-degenerate) triangle meets a shape, exactly.
bool meets(const CgalTriangle& proper, const Shape& shape) {
  if (const auto* t = std::get_if<CgalTriangle>(&shape)) return CGAL::do_intersect(proper, *t);
  if (const auto* s = std::get_if<CgalSegment>(&shape)) return CGAL::do_intersect(proper, *s);
  return proper.has_on(std::get<Point>(shape));
}

// What segment pq does at one triangle it meets: nothing (a degenerate triangle, which
// separates nothing), cross its interior leaving it from its inner side (+1) or entering
// (-1), start on it (p on the triangle), or meet an edge, a vertex or the plane along the
// way (degenerate: try another direction).
enum class Crossing { none, leaving, entering, starts_on, degenerate };

Crossing crossing_of(const CgalTriangle& t, const Point& p, const Point& q) {
  if (t.is_degenerate()) return Crossing::none;  // zero area: never separates inside from outside
  const CGAL::Orientation side = CGAL::orientation(t[0], t[1], t[2], p);
  if (side == CGAL::COPLANAR) {
    // p on the triangle's plane and pq meets the triangle: either p is on it, or the
    // segment runs in the plane (degenerate direction).
    return t.has_on(p) ? Crossing::starts_on : Crossing::degenerate;
  }
  if (CGAL::orientation(t[0], t[1], t[2], q) == CGAL::COPLANAR) return Crossing::degenerate;
  const CGAL::Orientation e0 = CGAL::orientation(p, q, t[0], t[1]);
  const CGAL::Orientation e1 = CGAL::orientation(p, q, t[1], t[2]);
  const CGAL::Orientation e2 = CGAL::orientation(p, q, t[2], t[0]);
  if (e0 == CGAL::COPLANAR || e1 == CGAL::COPLANAR || e2 == CGAL::COPLANAR) return Crossing::degenerate;
  // The segment crosses the interior: leaving through a face seen from its inner side
  // counts +1, entering through it -1.
  return side == CGAL::NEGATIVE ? Crossing::leaving : Crossing::entering;
}

// Signed crossings of segment pq with the triangles; nullopt when pq meets an edge or a
// vertex (try another direction); PointLocation::on_boundary via `on`.
std::optional<int> winding_along(const Tree& tree, const Point& p, const Point& q, bool& on) {
  std::vector<Tree::Primitive_id> hits;
  tree.all_intersected_primitives(CgalSegment(p, q), std::back_inserter(hits));
  int winding = 0;
  for (const auto& hit : hits) {
    switch (crossing_of(*hit, p, q)) {
      case Crossing::none: break;
      case Crossing::starts_on: on = true; return 0;
      case Crossing::degenerate: return std::nullopt;
      case Crossing::leaving: ++winding; break;
      case Crossing::entering: --winding; break;
    }
  }
  return winding;
}

// Which points lie beyond (on the outer side of) some triangle's plane, decided exactly:
// CGAL's positive side of the oriented plane. A convex polytope of m faces and n points
// would cost n * m orientation tests one by one; instead the points sit in a tree of boxes
// and each plane passes over the boxes wholly behind it (or wholly beyond it) at once, by
// the plane's orientation determinant evaluated in interval arithmetic over the box: an
// enclosure of the determinant at every point of the box, so that a box is passed only
// when the sign at each of its points is proved. Only the points of boxes the plane cuts
// meet the exact predicate. For a tight convex proxy that is about log n boxes and a few
// points per face.
class PlaneScan {
 public:
  PlaneScan(const Triangles& planes, const std::vector<Point>& points) : planes_(planes), points_(points) {
    if (brute_force()) return;
    order_.resize(points.size());
    std::iota(order_.begin(), order_.end(), std::uint32_t{0});
    nodes_.reserve(2 * points.size() / kLeaf + 2);
    build(0, static_cast<std::uint32_t>(points.size()));
  }

  /// Whether some point is strictly behind some plane (CGAL's negative side).
  bool strictly_behind_one() const { return strictly_; }

  /// Whether every point is behind or on every plane; stops at the first point beyond.
  bool none_beyond() {
    std::atomic<bool> beyond{false};
    run(
        [&](std::uint32_t, std::uint8_t mark) {
          if (mark == kBeyond) beyond.store(true, std::memory_order_relaxed);
        },
        &beyond);
    return !beyond;
  }

  static constexpr std::uint8_t kBeyond = 1, kOn = 2;
  /// For each point, kBeyond when it lies beyond at least one plane, kOn when it lies on
  /// at least one (both may be set).
  std::vector<std::uint8_t> classify() {
    const std::unique_ptr<std::atomic<std::uint8_t>[]> marks(new std::atomic<std::uint8_t>[points_.size()]);
    for (std::size_t i = 0; i < points_.size(); ++i) marks[i] = 0;
    run([&](std::uint32_t point, std::uint8_t mark) { marks[point].fetch_or(mark, std::memory_order_relaxed); }, nullptr);
    std::vector<std::uint8_t> result(points_.size());
    for (std::size_t i = 0; i < points_.size(); ++i) result[i] = marks[i];
    return result;
  }

  /// For each point, whether it lies beyond at least one plane.
  std::vector<std::uint8_t> beyond_some_plane() {
    std::vector<std::uint8_t> marks = classify();
    for (std::uint8_t& mark : marks) mark &= kBeyond;
    return marks;
  }

 private:
  static constexpr std::uint32_t kLeaf = 8;
  struct Node {
    std::array<double, 3> low, high;
    std::uint32_t begin, end;  ///< range of order_
    std::uint32_t second = 0;  ///< index of the second child (the first follows the node); 0 for a leaf
  };

  bool brute_force() const { return planes_.size() * points_.size() <= 4096; }

  std::uint32_t build(std::uint32_t begin, std::uint32_t end) {
    const auto index = static_cast<std::uint32_t>(nodes_.size());
    nodes_.push_back({});
    Node node;
    node.begin = begin, node.end = end;
    node.low.fill(std::numeric_limits<double>::infinity());
    node.high.fill(-std::numeric_limits<double>::infinity());
    for (std::uint32_t i = begin; i < end; ++i)
      for (int axis = 0; axis < 3; ++axis) {
        node.low[axis] = std::min(node.low[axis], points_[order_[i]][axis]);
        node.high[axis] = std::max(node.high[axis], points_[order_[i]][axis]);
      }
    if (end - begin > kLeaf) {
      int axis = 0;
      for (int a = 1; a < 3; ++a)
        if (node.high[a] - node.low[a] > node.high[axis] - node.low[axis]) axis = a;
      const std::uint32_t middle = begin + (end - begin) / 2;
      std::nth_element(order_.begin() + begin, order_.begin() + middle, order_.begin() + end,
                       [&](std::uint32_t a, std::uint32_t b) { return points_[a][axis] < points_[b][axis]; });
      build(begin, middle);
      node.second = build(middle, end);
    }
    nodes_[index] = node;
    return index;
  }

  // Calls found(point, kBeyond) for every point beyond some plane and found(point, kOn)
  // for every point on one (possibly more than once, from several threads); stops early
  // once *stop is set.
  template <class Found>
  void run(const Found& found, const std::atomic<bool>* stop) {
    std::atomic<bool> strictly{false};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, planes_.size(), brute_force() ? std::max<std::size_t>(planes_.size(), 1) : 64),
                      [&](const tbb::blocked_range<std::size_t>& range) {
      bool local_strictly = false;
      std::vector<std::uint32_t> stack;
      std::vector<std::pair<std::uint32_t, std::uint32_t>> cut;  // ranges of order_ to test exactly
      for (std::size_t f = range.begin(); f != range.end(); ++f) {
        if (stop && stop->load(std::memory_order_relaxed)) return;
        const CgalTriangle& t = planes_[f];
        auto exact = [&](std::uint32_t point) {
          const CGAL::Orientation side = CGAL::orientation(t[0], t[1], t[2], points_[point]);
          if (side == CGAL::POSITIVE) found(point, kBeyond);
          else if (side == CGAL::ZERO) found(point, kOn);
          local_strictly = local_strictly || side == CGAL::NEGATIVE;
        };
        if (brute_force()) {
          for (std::uint32_t p = 0; p < points_.size(); ++p) exact(p);
          continue;
        }
        cut.clear();
        {
          using I = CGAL::Interval_nt<false>;
          const CGAL::Protect_FPU_rounding<true> upward;
          const I ox(t[0].x()), oy(t[0].y()), oz(t[0].z());
          const I ax = I(t[1].x()) - ox, ay = I(t[1].y()) - oy, az = I(t[1].z()) - oz;
          const I bx = I(t[2].x()) - ox, by = I(t[2].y()) - oy, bz = I(t[2].z()) - oz;
          const I nx = ay * bz - az * by, ny = az * bx - ax * bz, nz = ax * by - ay * bx;
          stack.assign(1, 0);
          while (!stack.empty()) {
            const Node& node = nodes_[stack.back()];
            const std::uint32_t at = stack.back();
            stack.pop_back();
            const I determinant = nx * (I(node.low[0], node.high[0]) - ox) + ny * (I(node.low[1], node.high[1]) - oy) +
                                  nz * (I(node.low[2], node.high[2]) - oz);
            if (determinant.sup() < 0) {
              local_strictly = true;  // the whole box strictly behind
            } else if (determinant.inf() > 0) {
              for (std::uint32_t i = node.begin; i < node.end; ++i) cut.emplace_back(i, i + 1);  // all beyond; reported below
            } else if (node.second == 0) {
              cut.emplace_back(node.begin, node.end);
            } else {
              stack.push_back(node.second);
              stack.push_back(at + 1);
            }
          }
        }
        for (const auto& [begin, end] : cut)
          for (std::uint32_t i = begin; i < end; ++i) exact(order_[i]);
      }
      if (local_strictly) strictly.store(true, std::memory_order_relaxed);
    });
    strictly_ = strictly;
  }

  const Triangles& planes_;
  const std::vector<Point>& points_;
  std::vector<std::uint32_t> order_;
  std::vector<Node> nodes_;
  bool strictly_ = false;
};

// Whether every point lies behind or on the plane of every triangle (its inner side:
// CGAL's negative side of the oriented plane), exactly; `strictly_behind_one` tells
// whether some point lies strictly behind some plane (only meaningful when true is returned).
bool behind_or_on_every_plane(const Triangles& planes, const std::vector<Point>& points, bool* strictly_behind_one = nullptr) {
  PlaneScan scan(planes, points);
  const bool held = scan.none_beyond();
  if (strictly_behind_one) *strictly_behind_one = scan.strictly_behind_one();
  return held;
}

// The points that can be farthest out along any direction: the vertices of their convex
// hull (all of them when there are few). A convex set holds the points when it holds these.
std::vector<Point> extreme_points(std::vector<Point> points) {
  std::sort(points.begin(), points.end());
  points.erase(std::unique(points.begin(), points.end()), points.end());
  if (points.size() <= 64) return points;
  std::vector<Point> extreme;
  CGAL::extreme_points_3(points, std::back_inserter(extreme));
  return extreme;
}

// The connected components of a container with the non-degenerate triangles of each (its
// face planes), its bounding box and, once asked, whether it is convex: its own vertices
// behind or on all of its planes and at least one strictly behind one (not flat).
class ConvexParts {
 public:
  ConvexParts(const TriangleMesh& mesh, const Triangles& triangles) : mesh_(mesh), triangles_(triangles) {
    std::size_t count = 0;
    component_of_triangle_ = triangle_components(mesh, &count);
    parts_.resize(count);
    for (std::size_t t = 0; t < triangles.size(); ++t) {
      Part& part = parts_[component_of_triangle_[t]];
      part.triangles.push_back(static_cast<std::uint32_t>(t));
      for (const VertexIndex v : mesh.triangles[t]) part.box.extend(mesh.positions[v]);
    }
  }
  std::size_t count() const { return parts_.size(); }
  std::uint32_t part_of_triangle(std::uint32_t t) const { return component_of_triangle_[t]; }
  const BoundingBox& box(std::size_t part) const { return parts_[part].box; }

  bool convex(std::size_t index) {
    Part& part = parts_[index];
    if (!part.convex) {
      std::vector<Point> vertices;
      for (const std::uint32_t t : part.triangles) {
        if (!triangles_[t].is_degenerate()) part.planes.push_back(triangles_[t]);
        for (const VertexIndex v : mesh_.triangles[t]) vertices.push_back(to_point(mesh_.positions[v]));
      }
      bool not_flat = false;
      part.convex = !part.planes.empty() && behind_or_on_every_plane(part.planes, extreme_points(std::move(vertices)), &not_flat) && not_flat;
    }
    return *part.convex;
  }
  /// Whether the part is convex and holds every point behind or on its planes.
  bool holds(std::size_t index, const std::vector<Point>& points) {
    return convex(index) && behind_or_on_every_plane(parts_[index].planes, points);
  }
  /// The part's non-degenerate triangles (filled by convex()).
  const Triangles& planes(std::size_t index) const { return parts_[index].planes; }
  /// For each point, whether it lies beyond some plane of the part (which must be convex).
  std::vector<std::uint8_t> beyond(std::size_t index, const std::vector<Point>& points) {
    return PlaneScan(parts_[index].planes, points).beyond_some_plane();
  }

 private:
  struct Part {
    std::vector<std::uint32_t> triangles;
    BoundingBox box;
    Triangles planes;
    std::optional<bool> convex;
  };
  const TriangleMesh& mesh_;
  const Triangles& triangles_;
  std::vector<std::uint32_t> component_of_triangle_;
  std::vector<Part> parts_;
};

bool box_holds(const BoundingBox& outer, const BoundingBox& inner) {
  return (outer.min.array() <= inner.min.array()).all() && (inner.max.array() <= outer.max.array()).all();
}

// The triangles of `touching` (contents triangles, each with the container triangles it
// meets) that lie in no convex part of the container (`parts`): first, for each part a
// triangle touches first, all such triangles' corners at once (their extreme points); then,
// for those left, each triangle's corners against every convex part whose box holds it.
std::vector<std::pair<std::uint32_t, std::uint32_t>> outside_convex_parts(
    ConvexParts& parts, const TriangleMesh& contents, const std::vector<std::pair<std::uint32_t, std::uint32_t>>& crossings,
    std::size_t& proved) {
  // Contents triangle -> first container triangle it meets (crossings are sorted by
  // container triangle, so take the lowest per contents triangle).
  std::vector<std::pair<std::uint32_t, std::uint32_t>> first;  // (contents, container)
  for (const auto& [a, b] : crossings) first.emplace_back(b, a);
  std::sort(first.begin(), first.end());
  first.erase(std::unique(first.begin(), first.end(), [](const auto& x, const auto& y) { return x.first == y.first; }),
              first.end());
  auto corners = [&](std::uint32_t t) {
    std::vector<Point> points;
    for (const VertexIndex v : contents.triangles[t]) points.push_back(to_point(contents.positions[v]));
    return points;
  };
  // Group by the part of the first container triangle met.
  std::vector<std::vector<std::uint32_t>> by_part(parts.count());
  for (const auto& [t, a] : first) by_part[parts.part_of_triangle(a)].push_back(t);
  std::vector<std::uint32_t> left;
  for (std::size_t part = 0; part < by_part.size(); ++part) {
    if (by_part[part].empty()) continue;
    std::vector<Point> points;
    for (const std::uint32_t t : by_part[part])
      for (const Point& p : corners(t)) points.push_back(p);
    if (parts.holds(part, extreme_points(std::move(points))))
      proved += by_part[part].size();
    else
      left.insert(left.end(), by_part[part].begin(), by_part[part].end());
  }
  // The triangles left, each against every convex part whose box holds it: for each part,
  // the corners of all its candidates in one scan of its planes.
  std::sort(left.begin(), left.end());
  std::vector<BoundingBox> boxes(left.size());
  for (std::size_t k = 0; k < left.size(); ++k)
    for (const VertexIndex v : contents.triangles[left[k]]) boxes[k].extend(contents.positions[v]);
  std::vector<std::uint8_t> held(left.size(), 0);
  for (std::size_t part = 0; part < parts.count(); ++part) {
    std::vector<std::size_t> candidates;
    for (std::size_t k = 0; k < left.size(); ++k)
      if (!held[k] && box_holds(parts.box(part), boxes[k])) candidates.push_back(k);
    if (candidates.empty() || !parts.convex(part)) continue;
    std::vector<Point> points;
    for (const std::size_t k : candidates)
      for (const Point& p : corners(left[k])) points.push_back(p);
    const std::vector<std::uint8_t> beyond = parts.beyond(part, points);
    for (std::size_t c = 0; c < candidates.size(); ++c)
      held[candidates[c]] = !beyond[3 * c] && !beyond[3 * c + 1] && !beyond[3 * c + 2];
  }
  std::vector<std::pair<std::uint32_t, std::uint32_t>> unproved;
  for (std::size_t k = 0; k < left.size(); ++k) {
    if (held[k]) {
      ++proved;
    } else {
      const auto it = std::lower_bound(first.begin(), first.end(), std::pair<std::uint32_t, std::uint32_t>(left[k], 0));
      unproved.emplace_back(it->second, left[k]);
    }
  }
  std::sort(unproved.begin(), unproved.end());
  return unproved;
}

// Squared distance between two shapes in double precision (accurate to rounding). Two
// disjoint convex sets are closest at a feature of one's boundary: a segment and a
// triangle at an endpoint or at one of the triangle's edges.
double squared_between(const Shape& x, const Shape& y) {
  struct Visitor {
    double operator()(const CgalTriangle& t, const CgalSegment& s) const {
      double best = std::min(CGAL::squared_distance(s.source(), t), CGAL::squared_distance(s.target(), t));
      for (int k = 0; k < 3; ++k) best = std::min(best, CGAL::squared_distance(s, CgalSegment(t[k], t[(k + 1) % 3])));
      return best;
    }
    double operator()(const CgalSegment& s, const CgalTriangle& t) const { return (*this)(t, s); }
    double operator()(const CgalTriangle& a, const CgalTriangle& b) const { return CGAL::squared_distance(a, b); }
    double operator()(const CgalTriangle& t, const Point& p) const { return CGAL::squared_distance(p, t); }
    double operator()(const Point& p, const CgalTriangle& t) const { return CGAL::squared_distance(p, t); }
    double operator()(const CgalSegment& a, const CgalSegment& b) const { return CGAL::squared_distance(a, b); }
    double operator()(const CgalSegment& s, const Point& p) const { return CGAL::squared_distance(p, s); }
    double operator()(const Point& p, const CgalSegment& s) const { return CGAL::squared_distance(p, s); }
    double operator()(const Point& p, const Point& q) const { return CGAL::squared_distance(p, q); }
  };
  return std::visit(Visitor{}, x, y);
}

std::vector<Box> boxes_of(const Triangles& triangles, double grow = 0) {
  std::vector<Box> boxes;
  boxes.reserve(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    CGAL::Bbox_3 b = triangles[t].bbox();
    if (grow > 0) b = CGAL::Bbox_3(b.xmin() - grow, b.ymin() - grow, b.zmin() - grow, b.xmax() + grow, b.ymax() + grow, b.zmax() + grow);
    boxes.emplace_back(b, static_cast<std::uint32_t>(t));
  }
  return boxes;
}

// One pass over the triangles instead of a tree: the points binned on a grid in the plane
// across the direction, each triangle tested exactly against the segments of the points in
// the cells its shadow on that plane covers. Bins and shadows are computed in double and
// padded far beyond their rounding, so no segment that meets a triangle is missed.
template <class SegmentEnd>
void scan_first_rays(const TriangleMesh& container, std::span<const Vertex> points, const std::vector<std::uint32_t>& active,
                     const Vertex& direction, const BoundingBox& box, double reach, const SegmentEnd& segment_end,
                     std::vector<PointLocation>& locations, std::vector<std::size_t>& retry) {
  const Vertex across_u = direction.cross(std::abs(direction.x()) < 0.9 ? Vertex(1, 0, 0) : Vertex(0, 1, 0)).normalized();
  const Vertex across_v = direction.cross(across_u);
  const double magnitude = std::max({box.min.cwiseAbs().maxCoeff(), box.max.cwiseAbs().maxCoeff(), 1e-300});
  const double pad = 1e-9 * (magnitude + 3 * reach);
  std::vector<Point> starts(active.size()), ends(active.size());
  std::vector<double> u(active.size()), v(active.size()), along(active.size());
  double u_min = std::numeric_limits<double>::infinity(), u_max = -u_min, v_min = u_min, v_max = -u_min;
  for (std::size_t k = 0; k < active.size(); ++k) {
    const Vertex& p = points[active[k]];
    starts[k] = to_point(p);
    ends[k] = to_point(segment_end(p, direction));
    u[k] = p.dot(across_u), v[k] = p.dot(across_v), along[k] = p.dot(direction);
    u_min = std::min(u_min, u[k]), u_max = std::max(u_max, u[k]), v_min = std::min(v_min, v[k]), v_max = std::max(v_max, v[k]);
  }
  const std::size_t side = std::clamp<std::size_t>(static_cast<std::size_t>(std::sqrt(static_cast<double>(active.size()) / 2.0)), 1, 2048);
  const double cell_u = std::max((u_max - u_min) / static_cast<double>(side), 1e-300);
  const double cell_v = std::max((v_max - v_min) / static_cast<double>(side), 1e-300);
  auto cell_of = [&](double value, double low, double cell) {
    return static_cast<std::size_t>(std::clamp((value - low) / cell, 0.0, static_cast<double>(side - 1)));
  };
  std::vector<std::uint32_t> cell_start(side * side + 1, 0), in_cell(active.size());
  for (std::size_t k = 0; k < active.size(); ++k) ++cell_start[cell_of(u[k], u_min, cell_u) * side + cell_of(v[k], v_min, cell_v) + 1];
  for (std::size_t c = 0; c < side * side; ++c) cell_start[c + 1] += cell_start[c];
  {
    std::vector<std::uint32_t> fill(cell_start.begin(), cell_start.end() - 1);
    for (std::size_t k = 0; k < active.size(); ++k)
      in_cell[fill[cell_of(u[k], u_min, cell_u) * side + cell_of(v[k], v_min, cell_v)]++] = static_cast<std::uint32_t>(k);
  }
  const std::unique_ptr<std::atomic<int>[]> winding(new std::atomic<int>[active.size()]);
  const std::unique_ptr<std::atomic<std::uint8_t>[]> state(new std::atomic<std::uint8_t>[active.size()]);  // 1 on, 2 degenerate
  for (std::size_t k = 0; k < active.size(); ++k) winding[k] = 0, state[k] = 0;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, container.triangles.size(), 1024), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t t = range.begin(); t != range.end(); ++t) {
      const Triangle& corners = container.triangles[t];
      double tu_lo = std::numeric_limits<double>::infinity(), tu_hi = -tu_lo, tv_lo = tu_lo, tv_hi = -tu_lo, ta_hi = -tu_lo;
      for (const VertexIndex c : corners) {
        const Vertex& x = container.positions[c];
        const double xu = x.dot(across_u), xv = x.dot(across_v), xa = x.dot(direction);
        tu_lo = std::min(tu_lo, xu), tu_hi = std::max(tu_hi, xu), tv_lo = std::min(tv_lo, xv), tv_hi = std::max(tv_hi, xv);
        ta_hi = std::max(ta_hi, xa);
      }
      tu_lo -= pad, tu_hi += pad, tv_lo -= pad, tv_hi += pad, ta_hi += pad;
      if (tu_hi < u_min || tu_lo > u_max || tv_hi < v_min || tv_lo > v_max) continue;
      std::optional<CgalTriangle> triangle;
      const std::size_t cu_lo = cell_of(tu_lo, u_min, cell_u), cu_hi = cell_of(tu_hi, u_min, cell_u);
      const std::size_t cv_lo = cell_of(tv_lo, v_min, cell_v), cv_hi = cell_of(tv_hi, v_min, cell_v);
      for (std::size_t cu = cu_lo; cu <= cu_hi; ++cu)
        for (std::size_t cv = cv_lo; cv <= cv_hi; ++cv)
          for (std::uint32_t at = cell_start[cu * side + cv]; at < cell_start[cu * side + cv + 1]; ++at) {
            const std::uint32_t k = in_cell[at];
            if (u[k] < tu_lo || u[k] > tu_hi || v[k] < tv_lo || v[k] > tv_hi || ta_hi < along[k]) continue;
            if (!triangle)
              triangle.emplace(to_point(container.positions[corners[0]]), to_point(container.positions[corners[1]]),
                               to_point(container.positions[corners[2]]));
            if (!CGAL::do_intersect(CgalSegment(starts[k], ends[k]), *triangle)) continue;
            switch (crossing_of(*triangle, starts[k], ends[k])) {
              case Crossing::none: break;
              case Crossing::starts_on: state[k].fetch_or(1); break;
              case Crossing::degenerate: state[k].fetch_or(2); break;
              case Crossing::leaving: winding[k].fetch_add(1); break;
              case Crossing::entering: winding[k].fetch_sub(1); break;
            }
          }
    }
  });

  for (std::size_t k = 0; k < active.size(); ++k) {
    if (state[k] & 1) locations[active[k]] = PointLocation::on_boundary;
    else if (state[k] & 2) retry.push_back(k);
    else locations[active[k]] = winding[k] != 0 ? PointLocation::inside : PointLocation::outside;
  }
}

}  // namespace

std::vector<PointLocation> locate_points(const TriangleMesh& container, std::span<const Vertex> points) {
  std::vector<PointLocation> locations(points.size(), PointLocation::outside);
  if (container.triangles.empty() || points.empty()) return locations;
  require_in_range(container, "container");
  for (std::size_t i = 0; i < points.size(); ++i)
    if (!within_coordinate_range(points[i]))
      throw InvalidInputError("", "point " + std::to_string(i) + " to locate is not finite or beyond 1e100 in magnitude");
  const BoundingBox box = bounding_box(container);
  const double reach = 4.0 * box.diagonal() + 1.0;
  // The segment from each point in the box, along a fixed generic direction, to a point
  // beyond the box; retries (below) draw seeded directions.
  const Vertex direction = Vertex(0.5773502691896258, 0.4472135954999579, 0.6831300510639732).normalized();
  auto segment_end = [&](const Vertex& v, const Vertex& d) { return v + (reach + (v - box.min).norm() + (v - box.max).norm()) * d; };
  std::vector<std::uint32_t> active;  // points in the box (the rest are outside)
  for (std::size_t i = 0; i < points.size(); ++i)
    if (!((points[i].array() < box.min.array()).any() || (points[i].array() > box.max.array()).any()))
      active.push_back(static_cast<std::uint32_t>(i));
  if (active.empty()) return locations;
  std::vector<std::size_t> retry;  // positions in `active` of the points to trace one by one
  if (container.triangles.size() * 8 < active.size()) {
    // Few triangles for many points (a box around a mesh's vertices): each point's ray
    // through a tree, in parallel over the points.
    retry.resize(active.size());
    std::iota(retry.begin(), retry.end(), std::size_t{0});
  } else {
    scan_first_rays(container, points, active, direction, box, reach, segment_end, locations, retry);
  }
  if (retry.empty()) return locations;
  const Triangles triangles = triangles_of(container);
  Tree tree(triangles.begin(), triangles.end());
  tree.build();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, retry.size(), 64), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t r = range.begin(); r != range.end(); ++r) {
      const std::size_t i = active[retry[r]];
      const Vertex& point = points[i];
      // The points the scan left (their first ray in special position) start from the
      // seeded directions; the others from the fixed one.
      const bool scanned = container.triangles.size() * 8 >= active.size();
      Random random(0x5EED0000u + i);
      Vertex d = scanned ? random.unit_vector() : direction;
      for (int attempt = scanned ? 1 : 0;; ++attempt) {
        bool on = false;
        const std::optional<int> count = winding_along(tree, to_point(point), to_point(segment_end(point, d)), on);
        if (on) {
          locations[i] = PointLocation::on_boundary;
          break;
        }
        if (count) {
          locations[i] = *count != 0 ? PointLocation::inside : PointLocation::outside;
          break;
        }
        if (attempt == 1000) throw Error("point location: no ray in general position after 1000 tries");
        d = random.unit_vector();
      }
    }
  });
  return locations;
}

std::vector<std::uint8_t> beyond_face_planes(const TriangleMesh& mesh, std::span<const Vertex> points) {
  require_in_range(mesh, "plane");
  std::vector<Point> located;
  located.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!within_coordinate_range(points[i]))
      throw InvalidInputError("", "point " + std::to_string(i) + " to test is not finite or beyond 1e100 in magnitude");
    located.push_back(to_point(points[i]));
  }
  Triangles planes;
  for (const CgalTriangle& t : triangles_of(mesh))
    if (!t.is_degenerate()) planes.push_back(t);
  return PlaneScan(planes, located).beyond_some_plane();
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> find_crossing_triangles(const TriangleMesh& container,
                                                                              const TriangleMesh& contents) {
  const Triangles a = triangles_of(container);
  const Triangles b = triangles_of(contents);
  std::vector<Box> a_boxes = boxes_of(a);
  std::vector<Box> b_boxes = boxes_of(b);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> crossings;
  CGAL::box_intersection_d(a_boxes.begin(), a_boxes.end(), b_boxes.begin(), b_boxes.end(),
                           [&](const Box& x, const Box& y) {
                             const CgalTriangle& ta = a[x.info()];
                             if (!ta.is_degenerate() && meets(ta, shape_of(b[y.info()])))
                               crossings.emplace_back(x.info(), y.info());
                           });
  std::sort(crossings.begin(), crossings.end());
  return crossings;
}

Containment check_containment(const TriangleMesh& container, const TriangleMesh& contents,
                              const ContainmentOptions& options) {
  Containment result;
  result.container_edges = check_edge_balance(container);
  if (container.triangles.empty()) result.container_edges.unbalanced_edges = std::max<std::size_t>(result.container_edges.unbalanced_edges, 1);
  if (!result.container_edges.balanced()) return result;
  if (options.contents_solid) {
    result.contents_edges = check_edge_balance(contents);
    if (!result.contents_edges.balanced()) return result;
  }
  require_in_range(contents, "contents");

  std::vector<std::uint8_t> used(contents.positions.size(), 0);
  for (const Triangle& t : contents.triangles)
    for (VertexIndex v : t) used[v] = 1;
  std::vector<Vertex> points;
  std::vector<VertexIndex> point_vertex;
  for (std::size_t v = 0; v < used.size(); ++v)
    if (used[v]) {
      points.push_back(contents.positions[v]);
      point_vertex.push_back(static_cast<VertexIndex>(v));
    }
  result.vertices_checked = points.size();

  // A container of one closed convex part (convexity tested): its solid is the
  // intersection of its faces' inner half-spaces (ConvexParts), so a point is located by
  // its side of every face plane, and a contents triangle whose corners are all in it lies
  // in it; a triangle meets the surface exactly when a corner lies on it. One scan of the
  // planes over the points, no ray and no pair of triangles.
  // The container's parts, made once for this and for the general path's convex parts.
  const Triangles container_triangles = options.contents_solid ? Triangles{} : triangles_of(container);
  std::optional<ConvexParts> parts;
  if (!options.contents_solid) {
    parts.emplace(container, container_triangles);
    if (parts->count() == 1 && parts->convex(0)) {
      std::vector<Point> located;
      located.reserve(points.size());
      for (const Vertex& p : points) located.push_back(to_point(p));
      const std::vector<std::uint8_t> marks = PlaneScan(parts->planes(0), located).classify();
      const bool all_held = std::none_of(marks.begin(), marks.end(), [](std::uint8_t m) { return m & PlaneScan::kBeyond; });
      // A vertex outside: the general path below finds it again, with the triangles that
      // cross the surface and a pair to show (a failed proof may take longer).
      if (all_held) {
        result.convex_container = true;
        std::vector<std::uint8_t> on_surface(contents.positions.size(), 0);
        for (std::size_t i = 0; i < marks.size(); ++i)
          if (marks[i] & PlaneScan::kOn) ++result.vertices_on_boundary, on_surface[point_vertex[i]] = 1;
        if (!options.check_surface) return result;
        result.surface_checked = true;
        for (const Triangle& t : contents.triangles)
          if (on_surface[t[0]] || on_surface[t[1]] || on_surface[t[2]]) ++result.triangles_touching;
        result.triangles_in_convex_parts = result.triangles_touching;
        return result;
      }
    }
  }

  const std::vector<PointLocation> locations = locate_points(container, points);
  for (std::size_t i = 0; i < locations.size(); ++i) {
    if (locations[i] == PointLocation::outside && result.vertices_outside++ == 0) result.first_vertex_outside = point_vertex[i];
    if (locations[i] == PointLocation::on_boundary) ++result.vertices_on_boundary;
  }
  if (!options.check_surface) return result;

  result.surface_checked = true;
  const auto crossings = find_crossing_triangles(container, contents);
  {
    std::vector<std::uint32_t> touching;
    for (const auto& pair : crossings) touching.push_back(pair.second);
    std::sort(touching.begin(), touching.end());
    result.triangles_touching = static_cast<std::size_t>(std::unique(touching.begin(), touching.end()) - touching.begin());
  }
  if (options.contents_solid) {
    // No touching allowed; and no container vertex inside the contents' solid.
    result.triangles_unproved = result.triangles_touching;
    if (!crossings.empty()) result.first_unproved = crossings.front();
    std::vector<Vertex> container_points;
    std::vector<VertexIndex> container_vertex;
    std::vector<std::uint8_t> container_used(container.positions.size(), 0);
    for (const Triangle& t : container.triangles)
      for (VertexIndex v : t) container_used[v] = 1;
    for (std::size_t v = 0; v < container_used.size(); ++v)
      if (container_used[v]) container_points.push_back(container.positions[v]), container_vertex.push_back(static_cast<VertexIndex>(v));
    const std::vector<PointLocation> in_contents = locate_points(contents, container_points);
    for (std::size_t i = 0; i < in_contents.size(); ++i)
      if (in_contents[i] != PointLocation::outside && result.container_vertices_inside_contents++ == 0)
        result.first_container_vertex_inside = container_vertex[i];
    return result;
  }
  if (!crossings.empty()) {
    const std::vector<std::pair<std::uint32_t, std::uint32_t>> unproved =
        outside_convex_parts(*parts, contents, crossings, result.triangles_in_convex_parts);
    result.triangles_unproved = unproved.size();
    if (!unproved.empty()) result.first_unproved = unproved.front();
  }
  return result;
}

ClosestDistance closest_distance_to_surface(const TriangleMesh& mesh, std::span<const Vertex> points) {
  ClosestDistance closest{std::numeric_limits<double>::infinity(), 0};
  if (mesh.triangles.empty() || points.empty()) return closest;
  const Triangles triangles = triangles_of(mesh);
  Tree tree(triangles.begin(), triangles.end());
  tree.build();
  tree.accelerate_distance_queries();
  std::vector<double> squared(points.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 1024), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) squared[i] = tree.squared_distance(to_point(points[i]));
  });
  const auto smallest = std::min_element(squared.begin(), squared.end());
  closest.distance = std::sqrt(*smallest);
  closest.point = static_cast<std::size_t>(smallest - squared.begin());
  return closest;
}

bool surfaces_clear_by(const TriangleMesh& a, const TriangleMesh& b, double distance) {
  if (a.triangles.empty() || b.triangles.empty()) return true;
  require_in_range(a, "first surface");
  require_in_range(b, "second surface");
  const Triangles ta = triangles_of(a), tb = triangles_of(b);
  const double magnitude = std::max(bounding_box(a).max.cwiseAbs().maxCoeff(), bounding_box(a).min.cwiseAbs().maxCoeff()) +
                           std::max(bounding_box(b).max.cwiseAbs().maxCoeff(), bounding_box(b).min.cwiseAbs().maxCoeff());
  // Rounding of the distances computed in double: relative to the coordinates involved.
  const double required = distance * (1 + 1e-9) + 0x1.0p-40 * magnitude;
  std::vector<Box> a_boxes = boxes_of(ta, required), b_boxes = boxes_of(tb);
  bool clear = true;
  CGAL::box_intersection_d(a_boxes.begin(), a_boxes.end(), b_boxes.begin(), b_boxes.end(), [&](const Box& x, const Box& y) {
    if (!clear) return;
    const Shape u = shape_of(ta[x.info()]), v = shape_of(tb[y.info()]);
    const auto* proper_u = std::get_if<CgalTriangle>(&u);
    const auto* proper_v = std::get_if<CgalTriangle>(&v);
    if ((proper_u && meets(*proper_u, v)) || (proper_v && meets(*proper_v, u))) {
      clear = false;
      return;
    }
    if (!proper_u && !proper_v && squared_between(u, v) == 0) {
      clear = false;
      return;
    }
    if (squared_between(u, v) <= required * required) clear = false;
  });
  return clear;
}

}  // namespace visproxy
