// Delaunay tetrahedra of a point set (CGAL's incremental Delaunay triangulation, which is
// the Bowyer-Watson insertion the occluding-spheres paper names, with exact predicates).

#include "visproxy/proxy/detail/delaunay_cells.h"

#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

namespace visproxy {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Triangulation_vertex_base_with_info_3<std::uint32_t, Kernel>;
using CellBase = CGAL::Delaunay_triangulation_cell_base_3<Kernel>;
using DataStructure = CGAL::Triangulation_data_structure_3<VertexBase, CellBase>;
using Delaunay = CGAL::Delaunay_triangulation_3<Kernel, DataStructure>;

}  // namespace

Sphere tetrahedron_circumsphere(const Vertex& a, const Vertex& b, const Vertex& c, const Vertex& d) {
  const Vertex ab = b - a, ac = c - a, ad = d - a;
  const Vertex bc_cross = ac.cross(ad), cd_cross = ad.cross(ab), db_cross = ab.cross(ac);
  const double determinant = 2 * ab.dot(bc_cross);
  const Vertex numerator = ab.squaredNorm() * bc_cross + ac.squaredNorm() * cd_cross + ad.squaredNorm() * db_cross;
  // Flat to rounding: the offset would be meaningless (or infinite).
  const double scale = ab.norm() * ac.norm() * ad.norm();
  if (!(std::abs(determinant) > 1e-12 * scale)) return {(a + b + c + d) / 4, 0.0};
  const Vertex offset = numerator / determinant;
  if (!offset.allFinite()) return {(a + b + c + d) / 4, 0.0};
  return {a + offset, offset.norm()};
}

Sphere smallest_enclosing_ball(const Vertex& a, const Vertex& b, const Vertex& c, const Vertex& d) {
  const std::array<Vertex, 4> points = {a, b, c, d};
  double scale = 0;
  for (const Vertex& p : points) scale = std::max(scale, (p - a).norm());
  Sphere best{(a + b + c + d) / 4, std::numeric_limits<double>::infinity()};
  auto consider = [&](const Vertex& center) {
    double radius = 0;
    for (const Vertex& p : points) radius = std::max(radius, (p - center).norm());
    radius += 1e-12 * scale;
    if (center.allFinite() && radius < best.radius) best = {center, radius};
  };
  // Two support points: the ball on a segment as diameter.
  for (std::size_t i = 0; i < 4; ++i)
    for (std::size_t j = i + 1; j < 4; ++j) consider((points[i] + points[j]) / 2);
  // Three: the circumcircle of a face (its centre in the face's plane).
  for (std::size_t skip = 0; skip < 4; ++skip) {
    std::array<Vertex, 3> face;
    for (std::size_t k = 0, n = 0; k < 4; ++k)
      if (k != skip) face[n++] = points[k];
    const Vertex ab = face[1] - face[0], ac = face[2] - face[0];
    const Vertex normal = ab.cross(ac);
    const double squared = normal.squaredNorm();
    if (squared > 0)
      consider(face[0] + (ac.squaredNorm() * normal.cross(ab) + ab.squaredNorm() * ac.cross(normal)) / (2 * squared));
  }
  // Four: the circumsphere.
  const Sphere circumsphere = tetrahedron_circumsphere(a, b, c, d);
  if (circumsphere.radius > 0) consider(circumsphere.center);
  return best;
}

std::vector<DelaunayCell> delaunay_cells(std::span<const Vertex> points) {
  std::vector<std::pair<Kernel::Point_3, std::uint32_t>> indexed;
  indexed.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    indexed.emplace_back(Kernel::Point_3(points[i].x(), points[i].y(), points[i].z()), static_cast<std::uint32_t>(i));
  Delaunay delaunay(indexed.begin(), indexed.end());
  std::vector<DelaunayCell> cells;
  if (delaunay.dimension() < 3) return cells;
  cells.reserve(delaunay.number_of_finite_cells());
  for (const auto cell : delaunay.finite_cell_handles()) {
    DelaunayCell out;
    for (int k = 0; k < 4; ++k) out.corners[static_cast<std::size_t>(k)] = cell->vertex(k)->info();
    out.circumsphere = tetrahedron_circumsphere(points[out.corners[0]], points[out.corners[1]],
                                                points[out.corners[2]], points[out.corners[3]]);
    if (out.circumsphere.radius > 0) cells.push_back(out);
  }
  return cells;
}

}  // namespace visproxy
