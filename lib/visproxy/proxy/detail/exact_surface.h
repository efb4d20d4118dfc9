#pragma once
// Private to lib/visproxy/proxy/detail: the exact geometry the conservative decimation
// (conservative_decimation.cpp) and its checks (conservative_input.cpp) share: CGAL's
// kernel with exact predicates, triangle-triangle and segment-triangle tests that allow
// what triangles share by index, ray parity, and the input as those tests see it
// (InputGeometry: its triangles' trees, one point per component, distances). Included by
// those two CGAL translation units only.



#include <CGAL/AABB_segment_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/intersections.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <numeric>
#include <optional>
#include <queue>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/core/random.h"
#include "visproxy/mesh/mesh_topology.h"
#include "visproxy/proxy/detail/plane_quadric.h"
#include "visproxy/proxy/detail/triangle_soup.h"
#include "visproxy/trace/triangle_box_tree.h"
#include "visproxy/proxy/detail/conservative_decimation.h"

namespace visproxy::detail {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using CgalTriangle = Kernel::Triangle_3;
using CgalSegment = Kernel::Segment_3;
using TrianglePrimitive = CGAL::AABB_triangle_primitive<Kernel, std::vector<CgalTriangle>::const_iterator>;
using TriangleTree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, TrianglePrimitive>>;  // over a surface's triangles
using SegmentPrimitive = CGAL::AABB_segment_primitive<Kernel, std::vector<CgalSegment>::const_iterator>;
using SegmentTree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, SegmentPrimitive>>;
using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::uint32_t>;

inline Point to_point(const Vertex& p) { return {p.x(), p.y(), p.z()}; }

inline bool boxes_overlap(const BoundingBox& a, const BoundingBox& b) {
  return (a.min.array() <= b.max.array()).all() && (b.min.array() <= a.max.array()).all();
}

// The slab between two planes parallel to a triangle's that holds the triangle, for pruning
// tree nodes: a box wholly outside the slab cannot meet the triangle. The normal is the
// rounded cross product of two sides, but any vector would do: the triangle's projections
// onto it lie between those of its corners, and both ranges, the triangle's and the box's,
// are widened by 1e-12 of |normal|_1 x the coordinates' magnitude, far beyond the rounding
// of a three-term dot product and of the box's centre and half extent (a few units in the
// last place of that product).
class TriangleSlab {
 public:
  explicit TriangleSlab(const CgalTriangle& t) {
    std::array<Vertex, 3> corner;
    for (int i = 0; i < 3; ++i) corner[static_cast<std::size_t>(i)] = {t.vertex(i).x(), t.vertex(i).y(), t.vertex(i).z()};
    normal_ = (corner[1] - corner[0]).cross(corner[2] - corner[0]);
    abs_normal_ = normal_.cwiseAbs();
    norm1_ = abs_normal_.sum();
    magnitude_ = std::max({corner[0].cwiseAbs().maxCoeff(), corner[1].cwiseAbs().maxCoeff(), corner[2].cwiseAbs().maxCoeff()});
    // Not finite (NaN included), zero, or products so small that they could lose digits to
    // underflow, which the allowance does not cover: never prune.
    usable_ = std::isfinite(norm1_ * magnitude_) && norm1_ * magnitude_ > 1e-250;
    if (!usable_) return;
    low_ = high_ = normal_.dot(corner[0]);
    for (std::size_t i = 1; i < 3; ++i) {
      const double projection = normal_.dot(corner[i]);
      low_ = std::min(low_, projection);
      high_ = std::max(high_, projection);
    }
  }

  bool misses(const BoundingBox& box) const {
    if (!usable_) return false;
    const Vertex centre = 0.5 * (box.min + box.max);
    const Vertex half = 0.5 * (box.max - box.min);
    const double at_centre = normal_.dot(centre);
    const double reach = abs_normal_.dot(half);
    const double magnitude = std::max({magnitude_, box.min.cwiseAbs().maxCoeff(), box.max.cwiseAbs().maxCoeff()});
    const double allowance = 1e-12 * norm1_ * magnitude;
    if (!(std::isfinite(at_centre) && std::isfinite(reach) && std::isfinite(allowance))) return false;
    return at_centre - reach > high_ + allowance || at_centre + reach < low_ - allowance;
  }

 private:
  Vertex normal_ = Vertex::Zero();
  Vertex abs_normal_ = Vertex::Zero();  // |normal_| componentwise, for a box's reach
  double low_ = 0, high_ = 0, magnitude_ = 0, norm1_ = 0;
  bool usable_ = false;
};

// ---------------------------------------------------------------------------------------
// Exact predicates on triangles given by corner points and corner ids: corners with equal
// ids are shared, so two triangles may touch there and only there.

struct TriangleCorners {
  std::array<Point, 3> points;
  std::array<std::uint32_t, 3> ids;
};

inline bool triangles_meet_beyond_shared(const TriangleCorners& a, const TriangleCorners& b) {
  std::array<int, 3> a_to_b = {-1, -1, -1};
  int shared = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (a.ids[i] == b.ids[j]) {
        a_to_b[i] = j;
        ++shared;
      }
  const CgalTriangle ta(a.points[0], a.points[1], a.points[2]);
  const CgalTriangle tb(b.points[0], b.points[1], b.points[2]);
  if (shared == 0) return CGAL::do_intersect(ta, tb);
  if (shared == 3) return true;
  if (shared == 2) {
    // Common edge pq: the triangles overlap iff their other corners are coplanar with it
    // and on the same side of it.
    int r = 0;
    while (a_to_b[r] >= 0) ++r;
    int s = 0;
    while (s == a_to_b[(r + 1) % 3] || s == a_to_b[(r + 2) % 3]) ++s;
    const Point& p = a.points[(r + 1) % 3];
    const Point& q = a.points[(r + 2) % 3];
    return CGAL::coplanar(p, q, a.points[r], b.points[s]) &&
           CGAL::coplanar_orientation(p, q, a.points[r], b.points[s]) == CGAL::POSITIVE;
  }
  // One common corner: they meet elsewhere iff the side of either opposite that corner
  // meets the other triangle.
  int v = 0;
  while (a_to_b[v] < 0) ++v;
  const int w = a_to_b[v];
  const CgalSegment a_opposite(a.points[(v + 1) % 3], a.points[(v + 2) % 3]);
  const CgalSegment b_opposite(b.points[(w + 1) % 3], b.points[(w + 2) % 3]);
  return CGAL::do_intersect(a_opposite, tb) || CGAL::do_intersect(b_opposite, ta);
}

enum class Crossing { none, proper, degenerate };

// How the segment xy meets triangle abc, decided exactly.
inline Crossing segment_crossing(const Point& x, const Point& y, const CgalTriangle& t) {
  const Point& a = t.vertex(0);
  const Point& b = t.vertex(1);
  const Point& c = t.vertex(2);
  const CGAL::Orientation ox = CGAL::orientation(a, b, c, x);
  const CGAL::Orientation oy = CGAL::orientation(a, b, c, y);
  if (ox == oy && ox != CGAL::ZERO) return Crossing::none;
  const std::array<CGAL::Orientation, 3> sides = {CGAL::orientation(x, y, a, b), CGAL::orientation(x, y, b, c),
                                                  CGAL::orientation(x, y, c, a)};
  const bool any_positive = std::find(sides.begin(), sides.end(), CGAL::POSITIVE) != sides.end();
  const bool any_negative = std::find(sides.begin(), sides.end(), CGAL::NEGATIVE) != sides.end();
  if (any_positive && any_negative) return Crossing::none;
  if (ox == CGAL::ZERO || oy == CGAL::ZERO || !(any_positive || any_negative)) return Crossing::degenerate;
  if (std::find(sides.begin(), sides.end(), CGAL::ZERO) != sides.end()) return Crossing::degenerate;
  return Crossing::proper;
}

// Parity of the number of times rays from x cross the closed surface `triangles` (x not on
// it): true when x is inside. Rays that graze an edge, a corner or a plane are retried in
// other directions; nullopt if every attempt grazed (practically never).
template <typename CrossingsAlong>
std::optional<bool> inside_by_parity(const Point& x, double reach, Random& directions, CrossingsAlong crossings) {
  for (int attempt = 0; attempt < 64; ++attempt) {
    const Vertex d = directions.unit_vector() * reach;
    const Point y(x.x() + d.x(), x.y() + d.y(), x.z() + d.z());
    const std::optional<std::size_t> count = crossings(x, y);
    if (count) return (*count % 2) == 1;
  }
  return std::nullopt;
}

// ---------------------------------------------------------------------------------------
// The input: its triangles for exact intersection tests, one point per component for the
// side tests, and distance queries for the reported bound.

class InputGeometry {
 public:
  explicit InputGeometry(const TriangleMesh& mesh) : mesh_(mesh), primitives_(soup_primitives(mesh)) {
    for (const auto& [from, to] : primitives_.segments) segments_.emplace_back(to_point(from), to_point(to));
    for (const Vertex& p : primitives_.points) points_.push_back(to_point(p));
    triangle_tree_ = std::make_unique<TriangleBoxTree>(mesh, std::move(primitives_.triangle_indices));
    if (!segments_.empty()) {
      segment_tree_.insert(segments_.begin(), segments_.end());
      segment_tree_.build();
    }

    std::size_t component_count = 0;
    const std::vector<std::uint32_t> component = triangle_components(mesh, &component_count);
    representatives_.resize(component_count);
    std::vector<bool> seen(component_count, false);
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      if (seen[component[t]]) continue;
      seen[component[t]] = true;
      representatives_[component[t]] = mesh.positions[mesh.triangles[t][0]];
    }
    const BoundingBox box = bounding_box(mesh);
    magnitude_ = std::max(box.max.cwiseAbs().maxCoeff(), box.min.cwiseAbs().maxCoeff());
    build_representative_grid(box);
  }

  const std::vector<Vertex>& representatives() const { return representatives_; }
  double magnitude() const { return magnitude_; }
  const TriangleBoxTree& triangles() const { return *triangle_tree_; }
  const SoupPrimitives& degenerate() const { return primitives_; }

  /// Does the closed triangle meet any input triangle (or degenerate triangle)?
  bool meets(const CgalTriangle& t) const {
    // Nodes whose boxes lie outside the slab of t's plane hold no triangle that meets t. (An
    // exact triangle-box test prunes a little more but took a quarter of inner:N's time.)
    const TriangleSlab slab(t);
    const auto crosses_node = [&](const CGAL::Bbox_3& node) {
      return !slab.misses({{node.xmin(), node.ymin(), node.zmin()}, {node.xmax(), node.ymax(), node.zmax()}});
    };
    if (any_overlapping(t.bbox(), crosses_node, [&](const CgalTriangle& u) { return CGAL::do_intersect(t, u); }))
      return true;
    if (!segments_.empty() && segment_tree_.do_intersect(t)) return true;
    for (const Point& p : points_)
      if (CGAL::do_intersect(t, p)) return true;
    return false;
  }

  /// Does the closed segment meet any input triangle (or degenerate triangle)? A segment
  /// that is a point is reported as meeting.
  bool meets_segment(const CgalSegment& s) const {
    if (s.is_degenerate()) return true;  // a point: counted as meeting, which only costs the caller a retry
    const auto crosses_node = [&](const CGAL::Bbox_3& node) { return CGAL::do_intersect(s, node); };
    if (any_overlapping(s.bbox(), crosses_node, [&](const CgalTriangle& u) { return CGAL::do_intersect(s, u); }))
      return true;
    if (!segments_.empty() && segment_tree_.do_intersect(s)) return true;
    for (const Point& p : points_)
      if (CGAL::do_intersect(s, p)) return true;
    return false;
  }

  /// Does the triangle (which meets no input triangle) come within `clearance` of one?
  /// Distances in double precision between disjoint triangles, attained at a corner and a
  /// triangle or at two sides; `clearance` is enlarged by 1e-9 relative against rounding.
  bool comes_within(const CgalTriangle& t, double clearance) const {
    const CGAL::Bbox_3 b = t.bbox();
    const CGAL::Bbox_3 query(b.xmin() - clearance, b.ymin() - clearance, b.zmin() - clearance, b.xmax() + clearance,
                             b.ymax() + clearance, b.zmax() + clearance);
    const double limit = clearance * (1 + 1e-9);
    const double limit_squared = limit * limit;
    // Cheap test first: a triangle wholly beyond the clearance on one side of t's plane.
    const Vertex ta(t.vertex(0).x(), t.vertex(0).y(), t.vertex(0).z());
    const Vertex tb(t.vertex(1).x(), t.vertex(1).y(), t.vertex(1).z());
    const Vertex tc(t.vertex(2).x(), t.vertex(2).y(), t.vertex(2).z());
    const Vertex normal = (tb - ta).cross(tc - ta).normalized();
    const double beyond = 2 * limit;  // generous against the rounding of this test
    auto close_to_triangle = [&](const CgalTriangle& u) {
      if (normal.allFinite()) {
        std::array<double, 3> side{};
        for (int i = 0; i < 3; ++i)
          side[static_cast<std::size_t>(i)] =
              normal.dot(Vertex(u.vertex(i).x(), u.vertex(i).y(), u.vertex(i).z()) - ta);
        if (std::min({side[0], side[1], side[2]}) > beyond || std::max({side[0], side[1], side[2]}) < -beyond)
          return false;
      }
      for (int i = 0; i < 3; ++i) {
        if (CGAL::to_double(CGAL::squared_distance(t.vertex(i), u)) < limit_squared) return true;
        if (CGAL::to_double(CGAL::squared_distance(u.vertex(i), t)) < limit_squared) return true;
      }
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          if (CGAL::to_double(CGAL::squared_distance(CgalSegment(t.vertex(i), t.vertex(i + 1)),
                                                     CgalSegment(u.vertex(j), u.vertex(j + 1)))) < limit_squared)
            return true;
      return false;
    };
    // Nodes whose boxes, enlarged by the limit (rounded outwards), lie outside the slab of
    // t's plane hold no triangle within the limit of t: the enlarged box holds every point
    // within the limit of the node's box, and the slab holds t.
    const TriangleSlab slab(t);
    const auto near_node = [&](const CGAL::Bbox_3& node) {
      constexpr double kDown = -std::numeric_limits<double>::infinity();
      constexpr double kUp = std::numeric_limits<double>::infinity();
      const BoundingBox enlarged{{std::nextafter(node.xmin() - limit, kDown), std::nextafter(node.ymin() - limit, kDown),
                                  std::nextafter(node.zmin() - limit, kDown)},
                                 {std::nextafter(node.xmax() + limit, kUp), std::nextafter(node.ymax() + limit, kUp),
                                  std::nextafter(node.zmax() + limit, kUp)}};
      return !slab.misses(enlarged);
    };
    if (any_overlapping(query, near_node, close_to_triangle)) return true;
    std::vector<SegmentPrimitive::Id> segment_hits;  // (const and safe to call from several threads)
    if (!segments_.empty()) segment_tree_.all_intersected_primitives(query, std::back_inserter(segment_hits));
    for (const auto& id : segment_hits) {  // degenerate input triangles
      const CgalSegment& segment = *id;
      if (CGAL::to_double(CGAL::squared_distance(segment.source(), t)) < limit_squared ||
          CGAL::to_double(CGAL::squared_distance(segment.target(), t)) < limit_squared)
        return true;
      for (int i = 0; i < 3; ++i)
        if (CGAL::to_double(CGAL::squared_distance(segment, CgalSegment(t.vertex(i), t.vertex(i + 1)))) < limit_squared)
          return true;
    }
    for (const Point& p : points_)
      if (CGAL::to_double(CGAL::squared_distance(p, t)) < limit_squared) return true;
    return false;
  }

  double distance(const Point& p) const {
    double squared = std::numeric_limits<double>::infinity();
    squared = std::min(squared, triangle_tree_->nearest(Vertex(p.x(), p.y(), p.z())).squared_distance);
    if (!segments_.empty()) squared = std::min(squared, CGAL::to_double(segment_tree_.squared_distance(p)));
    for (const Point& q : points_) squared = std::min(squared, CGAL::to_double(CGAL::squared_distance(p, q)));
    return std::sqrt(squared);
  }

  /// Calls f(representative) for every component representative inside `box`.
  template <typename F>
  void for_representatives_in(const BoundingBox& box, F f) const {
    const std::array<int, 3> lo = cell_of(box.min);
    const std::array<int, 3> hi = cell_of(box.max);
    for (int z = lo[2]; z <= hi[2]; ++z)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int x = lo[0]; x <= hi[0]; ++x) {
          const std::size_t cell = (static_cast<std::size_t>(z) * grid_size_ + static_cast<std::size_t>(y)) *
                                       grid_size_ + static_cast<std::size_t>(x);
          for (std::uint32_t i = cell_start_[cell]; i < cell_start_[cell + 1]; ++i) {
            const Vertex& p = representatives_[cell_items_[i]];
            if ((p.array() >= box.min.array()).all() && (p.array() <= box.max.array()).all()) f(p);
          }
        }
  }

 private:
  // Whether f(u) holds for some input triangle u whose box overlaps `query`, descending
  // through the nodes whose boxes (which hold their triangles' double coordinates) overlap
  // it and pass `may_meet` too: a query shape that misses a node's box misses its triangles.
  template <typename MayMeet, typename F>
  bool any_overlapping(const CGAL::Bbox_3& query, MayMeet may_meet, F f) const {
    const BoundingBox box{{query.xmin(), query.ymin(), query.zmin()}, {query.xmax(), query.ymax(), query.zmax()}};
    return triangle_tree_->any([&](const BoundingBox& node) {
                                 return boxes_overlap(node, box) &&
                                        may_meet(CGAL::Bbox_3(node.min.x(), node.min.y(), node.min.z(), node.max.x(),
                                                              node.max.y(), node.max.z()));
                               },
                               [&](std::uint32_t index) {
                                 const Triangle& t = mesh_.triangles[index];
                                 const std::array<const Vertex*, 3> c = {&mesh_.positions[t[0]], &mesh_.positions[t[1]],
                                                                         &mesh_.positions[t[2]]};
                                 for (int k = 0; k < 3; ++k)
                                   if (std::max({(*c[0])[k], (*c[1])[k], (*c[2])[k]}) < box.min[k] ||
                                       std::min({(*c[0])[k], (*c[1])[k], (*c[2])[k]}) > box.max[k])
                                     return false;
                                 return f(CgalTriangle(to_point(*c[0]), to_point(*c[1]), to_point(*c[2])));
                               });
  }

  std::array<int, 3> cell_of(const Vertex& p) const {
    std::array<int, 3> cell{};
    for (int k = 0; k < 3; ++k) {
      const double t = std::floor((p[k] - grid_box_.min[k]) / cell_size_[k]);
      cell[static_cast<std::size_t>(k)] =
          static_cast<int>(std::clamp(t, 0.0, static_cast<double>(grid_size_ - 1)));
    }
    return cell;
  }

  void build_representative_grid(const BoundingBox& box) {
    grid_box_ = box;
    grid_size_ = std::clamp<std::size_t>(
        static_cast<std::size_t>(std::cbrt(static_cast<double>(representatives_.size()))), 1, 64);
    for (int k = 0; k < 3; ++k)
      cell_size_[k] = std::max((box.max[k] - box.min[k]) / static_cast<double>(grid_size_),
                               std::numeric_limits<double>::min());
    const std::size_t cells = grid_size_ * grid_size_ * grid_size_;
    std::vector<std::size_t> cell_of_item(representatives_.size());
    cell_start_.assign(cells + 1, 0);
    for (std::size_t i = 0; i < representatives_.size(); ++i) {
      const std::array<int, 3> c = cell_of(representatives_[i]);
      cell_of_item[i] = (static_cast<std::size_t>(c[2]) * grid_size_ + static_cast<std::size_t>(c[1])) * grid_size_ +
                        static_cast<std::size_t>(c[0]);
      ++cell_start_[cell_of_item[i] + 1];
    }
    for (std::size_t c = 0; c < cells; ++c) cell_start_[c + 1] += cell_start_[c];
    cell_items_.resize(representatives_.size());
    std::vector<std::uint32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
    for (std::size_t i = 0; i < representatives_.size(); ++i)
      cell_items_[fill[cell_of_item[i]]++] = static_cast<std::uint32_t>(i);
  }

  const TriangleMesh& mesh_;
  SoupPrimitives primitives_;  // the segments and points (the triangles are in triangle_tree_)
  std::unique_ptr<TriangleBoxTree> triangle_tree_;  // the triangles with non-collinear corners
  std::vector<CgalSegment> segments_;
  std::vector<Point> points_;
  double magnitude_ = 0;  // largest coordinate magnitude of the input
  SegmentTree segment_tree_;
  std::vector<Vertex> representatives_;
  BoundingBox grid_box_;
  std::size_t grid_size_ = 1;
  Vertex cell_size_ = Vertex::Ones();
  std::vector<std::uint32_t> cell_start_;
  std::vector<std::uint32_t> cell_items_;
};


struct ConservativeInput::Impl {
  explicit Impl(const TriangleMesh& mesh) : geometry(mesh) {}
  InputGeometry geometry;
};

}  // namespace visproxy::detail
