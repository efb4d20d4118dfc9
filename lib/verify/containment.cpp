// Exact point location and surface crossing tests (CGAL, exact predicates on doubles).

#include "verify/containment.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/intersections.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <cassert>
#include <optional>

#include "core/errors.h"
#include "core/random.h"
#include "mesh/mesh_topology.h"

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

// Signed crossings of segment pq with the triangles; nullopt when pq meets an edge or a
// vertex (try another direction); PointLocation::on_boundary via `on`.
std::optional<int> winding_along(const Tree& tree, const Point& p, const Point& q, bool& on) {
  std::vector<Tree::Primitive_id> hits;
  tree.all_intersected_primitives(CgalSegment(p, q), std::back_inserter(hits));
  int winding = 0;
  for (const auto& hit : hits) {
    const CgalTriangle& t = *hit;
    if (t.is_degenerate()) continue;  // zero area: never separates inside from outside
    const CGAL::Orientation side = CGAL::orientation(t[0], t[1], t[2], p);
    if (side == CGAL::COPLANAR) {
      // p on the triangle's plane and pq meets the triangle: either p is on it, or the
      // segment runs in the plane (degenerate direction).
      if (t.has_on(p)) {
        on = true;
        return 0;
      }
      return std::nullopt;
    }
    if (CGAL::orientation(t[0], t[1], t[2], q) == CGAL::COPLANAR) return std::nullopt;
    const CGAL::Orientation e0 = CGAL::orientation(p, q, t[0], t[1]);
    const CGAL::Orientation e1 = CGAL::orientation(p, q, t[1], t[2]);
    const CGAL::Orientation e2 = CGAL::orientation(p, q, t[2], t[0]);
    if (e0 == CGAL::COPLANAR || e1 == CGAL::COPLANAR || e2 == CGAL::COPLANAR) return std::nullopt;
    // The segment crosses the interior: leaving through a face seen from its inner side
    // counts +1, entering through it -1.
    winding += side == CGAL::NEGATIVE ? 1 : -1;
  }
  return winding;
}

}  // namespace

std::vector<PointLocation> locate_points(const TriangleMesh& container, std::span<const Vertex> points) {
  std::vector<PointLocation> locations(points.size(), PointLocation::outside);
  if (container.triangles.empty() || points.empty()) return locations;
  const Triangles triangles = triangles_of(container);
  Tree tree(triangles.begin(), triangles.end());
  tree.build();
  const BoundingBox box = bounding_box(container);
  const double reach = 4.0 * box.diagonal() + 1.0;

  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 256), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const Vertex& v = points[i];
      if ((v.array() < box.min.array()).any() || (v.array() > box.max.array()).any()) continue;  // outside the box
      const Point p = to_point(v);
      // The first direction is fixed and generic; retries draw seeded directions.
      Random random(0x5EED0000u + i);
      Vertex direction = Vertex(0.5773502691896258, 0.4472135954999579, 0.6831300510639732).normalized();
      for (int attempt = 0;; ++attempt) {
        // A point outside the box in this direction: the segment pq leaves the container.
        const double distance = reach + (v - box.min).norm() + (v - box.max).norm();
        const Point q = to_point(v + distance * direction);
        bool on = false;
        const std::optional<int> winding = winding_along(tree, p, q, on);
        if (on) {
          locations[i] = PointLocation::on_boundary;
          break;
        }
        if (winding) {
          locations[i] = *winding != 0 ? PointLocation::inside : PointLocation::outside;
          break;
        }
        if (attempt == 1000) throw Error("point location: no ray in general position after 1000 tries");
        direction = random.unit_vector();
      }
    }
  });
  return locations;
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> find_crossing_triangles(const TriangleMesh& container,
                                                                              const TriangleMesh& contents) {
  const Triangles a = triangles_of(container);
  const Triangles b = triangles_of(contents);
  auto boxes_of = [](const Triangles& triangles) {
    std::vector<Box> boxes;
    boxes.reserve(triangles.size());
    for (std::size_t t = 0; t < triangles.size(); ++t)
      boxes.emplace_back(triangles[t].bbox(), static_cast<std::uint32_t>(t));
    return boxes;
  };
  std::vector<Box> a_boxes = boxes_of(a);
  std::vector<Box> b_boxes = boxes_of(b);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> crossings;
  CGAL::box_intersection_d(a_boxes.begin(), a_boxes.end(), b_boxes.begin(), b_boxes.end(),
                           [&](const Box& x, const Box& y) {
                             const CgalTriangle& ta = a[x.info()];
                             const CgalTriangle& tb = b[y.info()];
                             if (!ta.is_degenerate() && !tb.is_degenerate() && CGAL::do_intersect(ta, tb))
                               crossings.emplace_back(x.info(), y.info());
                           });
  std::sort(crossings.begin(), crossings.end());
  return crossings;
}

Containment check_containment(const TriangleMesh& container, const TriangleMesh& contents,
                              const ContainmentOptions& options) {
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

  Containment result;
  result.vertices_checked = points.size();
  const std::vector<PointLocation> locations = locate_points(container, points);
  for (std::size_t i = 0; i < locations.size(); ++i) {
    if (locations[i] == PointLocation::outside) {
      if (result.vertices_outside++ == 0) result.first_vertex_outside = point_vertex[i];
    }
    if (locations[i] == PointLocation::on_boundary) ++result.vertices_on_boundary;
  }

  if (options.convex_components) {
    std::vector<bool> vertex_contained(contents.positions.size(), true);
    for (std::size_t i = 0; i < points.size(); ++i)
      vertex_contained[point_vertex[i]] = locations[i] != PointLocation::outside;
    const std::vector<TriangleMesh> pieces = split_components(container);
    std::vector<std::vector<bool>> in_piece(pieces.size());
    for (std::size_t c = 0; c < pieces.size(); ++c) {
      in_piece[c].assign(contents.positions.size(), false);
      const std::vector<PointLocation> piece_locations = locate_points(pieces[c], points);
      for (std::size_t i = 0; i < points.size(); ++i)
        in_piece[c][point_vertex[i]] = piece_locations[i] != PointLocation::outside;
    }
    for (std::size_t t = 0; t < contents.triangles.size(); ++t) {
      const Triangle& triangle = contents.triangles[t];
      bool all_contained = true, together = false;
      for (VertexIndex v : triangle) all_contained = all_contained && vertex_contained[v];
      for (std::size_t c = 0; c < pieces.size() && !together; ++c)
        together = in_piece[c][triangle[0]] && in_piece[c][triangle[1]] && in_piece[c][triangle[2]];
      if (all_contained && !together && result.triangles_split++ == 0)
        result.first_triangle_split = static_cast<std::uint32_t>(t);
    }
  } else if (options.check_surface) {
    result.surface_checked = true;
    const auto crossings = find_crossing_triangles(container, contents);
    result.crossing_triangle_pairs = crossings.size();
    if (!crossings.empty()) result.first_crossing = crossings.front();
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

}  // namespace visproxy
