// Alpha wrapping with CGAL 5.5's Alpha_wrap_3:
//   C. Portaneri, M. Rouxel-Labbé, M. Hemmer, D. Cohen-Steiner, P. Alliez,
//   "Alpha Wrapping with an Offset", ACM Transactions on Graphics 41(4), 2022.
// The input goes in as a triangle soup. CGAL's soup oracle skips triangles with collinear
// corners, so those go in as segments (or points) through CGAL's stacked oracles, and the
// wrap encloses every point of every input triangle.

#include "visproxy/proxy/alpha_wrap.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/alpha_wrap_3.h>

#include <cmath>
#include <string>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/proxy/triangle_soup.h"

namespace visproxy {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using CgalSegment = Kernel::Segment_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;

// Triangles, then segments, then points: each oracle answers for its own primitives and
// asks the one below it for the rest.
using PointOracle = CGAL::Alpha_wraps_3::internal::Point_set_oracle<Kernel>;
using SegmentOracle = CGAL::Alpha_wraps_3::internal::Segment_soup_oracle<Kernel, PointOracle>;
using SoupOracle = CGAL::Alpha_wraps_3::internal::Triangle_soup_oracle<Kernel, SegmentOracle>;
using Wrapper = CGAL::Alpha_wraps_3::internal::Alpha_wrap_3<SoupOracle>;

void require_positive(double value, const char* name) {
  if (!(std::isfinite(value) && value > 0))
    throw InvalidInputError("", std::string("alpha wrap: ") + name + " must be a positive finite number, got " +
                                    std::to_string(value));
}

Point point(const Vertex& p) { return {p.x(), p.y(), p.z()}; }

}  // namespace

AlphaWrapResult build_alpha_wrap(const TriangleMesh& mesh, const AlphaWrapOptions& options) {
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
  const double diagonal = bounding_box(mesh).diagonal();
  if (!(diagonal > 0)) throw InvalidInputError("", "alpha wrap: all triangles are one point (zero diagonal)");

  AlphaWrapResult result;
  result.alpha_world = options.alpha_relative * diagonal;
  result.offset_world = options.offset_relative * diagonal;

  std::vector<Point> points;
  points.reserve(mesh.positions.size());
  for (const Vertex& p : mesh.positions) points.push_back(point(p));
  const SoupPrimitives primitives = soup_primitives(mesh);
  std::vector<CgalSegment> segments;
  for (const auto& [from, to] : primitives.segments) segments.emplace_back(point(from), point(to));
  std::vector<Point> lone_points;
  for (const Vertex& p : primitives.points) lone_points.push_back(point(p));

  SoupOracle oracle(result.alpha_world, SegmentOracle(PointOracle(Kernel()), Kernel()), Kernel());
  oracle.add_triangle_soup(points, primitives.triangles);
  if (!segments.empty()) oracle.add_segment_soup(segments);
  if (!lone_points.empty()) oracle.add_point_set(lone_points);

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

}  // namespace visproxy
