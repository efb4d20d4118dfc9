// Alpha wrapping with CGAL 5.5's Alpha_wrap_3:
//   C. Portaneri, M. Rouxel-Labbé, M. Hemmer, D. Cohen-Steiner, P. Alliez,
//   "Alpha Wrapping with an Offset", ACM Transactions on Graphics 41(4), 2022.
// CGAL's wrapper asks an oracle about the input: does a tetrahedron or a ball meet it, which
// point of it is nearest, where does a segment enter its offset. CGAL's own oracles build an
// AABB tree over the triangles on one thread (plus a kd-tree of hints and split copies of
// long triangles); the oracle here answers from a BVH over triangle indices built by
// Embree's builder in parallel (trace/triangle_box_tree.h), deciding every intersection
// with the same exact predicates as CGAL's traversal (its Alpha_wrap_AABB_traits), on nodes
// and triangles alike, and nearest points in double precision. Triangles with collinear corners are the segments or points they span, in a
// second, small BVH, so the wrap encloses every point of every input triangle.

#include "visproxy/proxy/alpha_wrap.h"


#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/alpha_wrap_3.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/proxy/alpha_wrap_shared.h"
#include "visproxy/proxy/detail/triangle_soup.h"
#include "visproxy/trace/triangle_box_tree.h"

namespace visproxy {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;

void require_positive(double value, const char* name) {
  if (!(std::isfinite(value) && value > 0))
    throw InvalidInputError("", std::string("alpha wrap: ") + name + " must be a positive finite number, got " +
                                    std::to_string(value));
}

Point point(const Vertex& p) { return {p.x(), p.y(), p.z()}; }
Vertex vertex(const Point& p) { return {p.x(), p.y(), p.z()}; }

// The input as CGAL's Alpha_wrap_3 asks about it (the interface of its AABB_tree_oracle).
class BvhOracle {
 public:
  using Geom_traits = CGAL::Alpha_wraps_3::internal::Alpha_wrap_AABB_traits<Kernel>;
  using FT = Kernel::FT;

  /// Over `triangles`, a BVH of the input's triangles with non-collinear corners, and
  /// `degenerate`, the segments and points its other triangles span (soup_primitives).
  /// `bounds` is bounding_box(mesh): every corner of every triangle is a point of the input
  /// or lies between two.
  BvhOracle(const TriangleMesh& mesh, const BoundingBox& bounds, const TriangleBoxTree& triangles,
            const SoupPrimitives& degenerate)
      : mesh_(mesh),
        bbox_(bounds.min.x(), bounds.min.y(), bounds.min.z(), bounds.max.x(), bounds.max.y(), bounds.max.z()),
        triangles_(&triangles) {
    // Segments as triangles (a, b, b), points as (p, p, p).
    for (const auto& [from, to] : degenerate.segments) {
      const auto first = static_cast<VertexIndex>(degenerate_.positions.size());
      degenerate_.positions.push_back(from);
      degenerate_.positions.push_back(to);
      degenerate_.triangles.push_back({first, first + 1, first + 1});
    }
    for (const Vertex& p : degenerate.points) {
      const auto index = static_cast<VertexIndex>(degenerate_.positions.size());
      degenerate_.positions.push_back(p);
      degenerate_.triangles.push_back({index, index, index});
    }
    std::vector<std::uint32_t> all(degenerate_.triangles.size());
    for (std::uint32_t i = 0; i < all.size(); ++i) all[i] = i;
    if (!all.empty()) degenerates_ = std::make_unique<TriangleBoxTree>(degenerate_, std::move(all));
  }

  const Geom_traits& geom_traits() const { return traits_; }
  CGAL::Bbox_3 bbox() const { return bbox_; }
  bool empty() const { return false; }
  bool do_call() const { return true; }

  /// Does the query (a tetrahedron with its outside facets, or a ball) meet the input?
  template <typename Query>
  bool do_intersect(const Query& query) const {
    const auto meets = traits_.do_intersect_3_object();
    const auto may_meet = [&](const BoundingBox& box) {
      return meets(query, CGAL::Bbox_3(box.min.x(), box.min.y(), box.min.z(), box.max.x(), box.max.y(), box.max.z()));
    };
    if (triangles_->any(may_meet, [&](std::uint32_t t) {
          const Triangle& corners = mesh_.triangles[t];
          return meets(query, Kernel::Triangle_3(point(mesh_.positions[corners[0]]), point(mesh_.positions[corners[1]]),
                                                  point(mesh_.positions[corners[2]])));
        }))
      return true;
    return degenerates_ && degenerates_->any(may_meet, [&](std::uint32_t t) {
             const Triangle& corners = degenerate_.triangles[t];
             const Point from = point(degenerate_.positions[corners[0]]);
             if (corners[0] == corners[1]) return meets(query, from);
             return meets(query, Kernel::Segment_3(from, point(degenerate_.positions[corners[1]])));
           });
  }

  /// The nearest input point: the nearest triangle found in double precision, then CGAL's
  /// projection onto it, as CGAL's own oracle computes it.
  Point closest_point(const Point& p) const {
    const Vertex q = vertex(p);
    const TriangleBoxTree::Nearest nearest = triangles_->nearest(q);
    const auto project = traits_.construct_projected_point_3_object();
    if (degenerates_) {
      const TriangleBoxTree::Nearest other = degenerates_->nearest(q);
      if (other.squared_distance < nearest.squared_distance) {
        const Triangle& corners = degenerate_.triangles[other.triangle];
        const Point from = point(degenerate_.positions[corners[0]]);
        if (corners[0] == corners[1]) return from;
        return project(Kernel::Segment_3(from, point(degenerate_.positions[corners[1]])), p);
      }
    }
    const Triangle& corners = mesh_.triangles[nearest.triangle];
    return project(Kernel::Triangle_3(point(mesh_.positions[corners[0]]), point(mesh_.positions[corners[1]]),
                                      point(mesh_.positions[corners[2]])),
                   p);
  }

  FT squared_distance(const Point& p) const { return CGAL::squared_distance(p, closest_point(p)); }

  bool first_intersection(const Point& p, const Point& q, Point& o, const FT offset_size,
                          const FT intersection_precision) const {
    CGAL::Alpha_wraps_3::internal::Offset_intersection<Geom_traits, Distance> offset_intersection(
        Distance{this}, offset_size, intersection_precision, 1 /* Lipschitz constant */);
    return offset_intersection.first_intersection(p, q, o);
  }

  bool first_intersection(const Point& p, const Point& q, Point& o, const FT offset_size) const {
    return first_intersection(p, q, o, offset_size, 1e-2 * offset_size);
  }

 private:
  struct Distance {
    const BvhOracle* oracle;
    FT operator()(const Point& p) const { return std::sqrt(oracle->squared_distance(p)); }
  };

  const TriangleMesh& mesh_;
  CGAL::Bbox_3 bbox_;
  TriangleMesh degenerate_;
  Geom_traits traits_;
  const TriangleBoxTree* triangles_;
  std::unique_ptr<TriangleBoxTree> degenerates_;
};

using Wrapper = CGAL::Alpha_wraps_3::internal::Alpha_wrap_3<BvhOracle>;

AlphaWrapResult wrap_with(const TriangleMesh& mesh, const AlphaWrapOptions& options, const TriangleBoxTree& triangles,
                          const SoupPrimitives& degenerate) {
  const BoundingBox bounds = bounding_box(mesh);
  const double diagonal = bounds.diagonal();
  AlphaWrapResult result;
  result.alpha_world = options.alpha_relative * diagonal;
  result.offset_world = options.offset_relative * diagonal;

  const BvhOracle oracle(mesh, bounds, triangles, degenerate);
  SurfaceMesh wrap;
  Wrapper wrapper(oracle);
  wrapper(result.alpha_world, result.offset_world, wrap);

  // A fresh Surface_mesh has contiguous vertex indices.
  result.mesh.positions.reserve(wrap.number_of_vertices());
  for (const SurfaceMesh::Vertex_index v : wrap.vertices()) {
    const Point& p = wrap.point(v);
    result.mesh.positions.emplace_back(p.x(), p.y(), p.z());
  }
  result.mesh.triangles.reserve(wrap.number_of_faces());
  for (const SurfaceMesh::Face_index f : wrap.faces()) {
    Triangle triangle{};
    int corner = 0;
    for (const SurfaceMesh::Vertex_index v : wrap.vertices_around_face(wrap.halfedge(f))) {
      assert(corner < 3);
      triangle[static_cast<std::size_t>(corner++)] = static_cast<VertexIndex>(v.idx());
    }
    result.mesh.triangles.push_back(triangle);
  }
  return result;
}

}  // namespace

namespace detail {

void check_alpha_wrap_input(const TriangleMesh& mesh, const AlphaWrapOptions& options) {
  require_positive(options.alpha_relative, "alpha_relative");
  require_positive(options.offset_relative, "offset_relative");
  if (mesh.triangles.empty()) throw InvalidInputError("", "alpha wrap: the mesh has no triangle");
  for (const Triangle& triangle : mesh.triangles)
    for (const VertexIndex v : triangle) {
      if (v >= mesh.positions.size())
        throw InvalidInputError("", "alpha wrap: vertex index " + std::to_string(v) + " is out of range");
      if (!mesh.positions[v].allFinite())
        throw InvalidInputError("", "alpha wrap: vertex " + std::to_string(v) + " has a non-finite coordinate");
    }
  if (!(bounding_box(mesh).diagonal() > 0))
    throw InvalidInputError("", "alpha wrap: all triangles are one point (zero diagonal)");
}

AlphaWrapResult build_alpha_wrap(const TriangleMesh& mesh, const AlphaWrapOptions& options,
                                 const TriangleBoxTree& triangles, const SoupPrimitives& degenerate) {
  return wrap_with(mesh, options, triangles, degenerate);
}

}  // namespace detail

AlphaWrapResult build_alpha_wrap(const TriangleMesh& mesh, const AlphaWrapOptions& options) {
  detail::check_alpha_wrap_input(mesh, options);
  SoupPrimitives primitives = soup_primitives(mesh);
  const TriangleBoxTree triangles(mesh, std::move(primitives.triangle_indices));
  return wrap_with(mesh, options, triangles, primitives);
}

}  // namespace visproxy
