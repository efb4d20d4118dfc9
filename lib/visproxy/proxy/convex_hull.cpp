// Exact convex hull: CGAL's quickhull (Barber, Dobkin and Huhdanpaa, "The Quickhull
// Algorithm for Convex Hulls", ACM TOMS 1996) with exact predicates on the input doubles;
// flat inputs get Andrew's monotone chain in the plane, with exact 2D orientations on a
// coordinate projection that keeps the plane's orientation.

#include "visproxy/proxy/convex_hull.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/proxy/detail/hull_facets.h"

namespace visproxy {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point3 = Kernel::Point_3;
using Point2 = Kernel::Point_2;

[[noreturn]] void reject(const std::string& problem) { throw InvalidInputError("convex hull", problem); }

// Convex polygon of coplanar points, counter-clockwise in the projection that drops
// coordinate `dropped_axis` (seen from the side the plane's normal points to when that
// component is positive). Only strictly convex corners are kept.
std::vector<Vertex> flat_hull_polygon(const std::vector<Vertex>& points, int dropped_axis) {
  const int u = (dropped_axis + 1) % 3;
  const int v = (dropped_axis + 2) % 3;
  std::vector<Point2> projected;
  projected.reserve(points.size());
  for (const Vertex& p : points) projected.emplace_back(p[u], p[v]);
  std::vector<std::uint32_t> order(points.size());
  for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return std::make_pair(projected[a].x(), projected[a].y()) < std::make_pair(projected[b].x(), projected[b].y());
  });
  // Andrew's monotone chain: lower then upper chain, dropping right turns and straight corners.
  std::vector<std::uint32_t> chain(2 * order.size());
  std::size_t size = 0;
  auto left_turn = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    return CGAL::orientation(projected[a], projected[b], projected[c]) == CGAL::LEFT_TURN;
  };
  for (const std::uint32_t index : order) {
    while (size >= 2 && !left_turn(chain[size - 2], chain[size - 1], index)) --size;
    chain[size++] = index;
  }
  const std::size_t lower_size = size + 1;
  for (std::size_t i = order.size() - 1; i-- > 0;) {
    while (size >= lower_size && !left_turn(chain[size - 2], chain[size - 1], order[i])) --size;
    chain[size++] = order[i];
  }
  --size;  // the first point closes the chain
  std::vector<Vertex> polygon;
  polygon.reserve(size);
  for (std::size_t i = 0; i < size; ++i) polygon.push_back(points[chain[i]]);
  return polygon;
}

// A closed zero-volume mesh of a convex polygon: one side fanned from corner 0, the other,
// facing the other way, fanned from corner 1.
TriangleMesh two_sided_polygon(std::vector<Vertex> polygon) {
  TriangleMesh mesh;
  const auto k = static_cast<VertexIndex>(polygon.size());
  for (VertexIndex i = 1; i + 1 < k; ++i) mesh.triangles.push_back({0, i, i + 1});
  for (VertexIndex j = 2; j < k; ++j) mesh.triangles.push_back({1, (j + 1) % k, j});
  mesh.positions = std::move(polygon);
  return mesh;
}

}  // namespace

ConvexHullResult build_convex_hull(const TriangleMesh& mesh) {
  std::vector<bool> referenced(mesh.positions.size(), false);
  for (const Triangle& triangle : mesh.triangles)
    for (const VertexIndex index : triangle) {
      if (index >= mesh.positions.size()) reject("a triangle refers to a vertex the mesh does not have");
      referenced[index] = true;
    }
  std::vector<Vertex> points;
  for (std::size_t i = 0; i < mesh.positions.size(); ++i)
    if (referenced[i]) points.push_back(mesh.positions[i]);
  if (points.empty()) reject("the mesh has no triangles");
  for (const Vertex& p : points)
    if (!p.allFinite()) reject("a vertex has a non-finite coordinate");

  std::vector<Point3> cgal_points;
  cgal_points.reserve(points.size());
  for (const Vertex& p : points) cgal_points.emplace_back(p.x(), p.y(), p.z());

  // The dimension of the point set, decided exactly.
  const Point3& first = cgal_points.front();
  const auto second = std::find_if(cgal_points.begin(), cgal_points.end(), [&](const Point3& p) { return p != first; });
  if (second == cgal_points.end()) reject("all referenced vertices are at one point");
  const auto third = std::find_if(cgal_points.begin(), cgal_points.end(),
                                  [&](const Point3& p) { return !CGAL::collinear(first, *second, p); });
  if (third == cgal_points.end()) reject("all referenced vertices are on one line");
  const bool flat = std::none_of(cgal_points.begin(), cgal_points.end(),
                                 [&](const Point3& p) { return !CGAL::coplanar(first, *second, *third, p); });

  ConvexHullResult result;
  if (flat) {
    // Drop the coordinate in which the plane's normal is largest: the projection is then
    // one-to-one on the plane and exact orientations in it are those in the plane.
    const Vertex a = points[0];
    const Vertex b = points[static_cast<std::size_t>(second - cgal_points.begin())];
    const Vertex c = points[static_cast<std::size_t>(third - cgal_points.begin())];
    const Vertex normal = (b - a).cross(c - a);
    int dropped_axis = 0;
    normal.cwiseAbs().maxCoeff(&dropped_axis);
    result.mesh = two_sided_polygon(flat_hull_polygon(points, dropped_axis));
    result.faces = 2;
    result.volume = 0.0;
    return result;
  }

  const std::vector<Triangle> triangles = hull_detail::exact_convex_hull(points);
  // Only the corners, in input order.
  constexpr VertexIndex unused = ~VertexIndex{0};
  std::vector<VertexIndex> output_index(points.size(), unused);
  for (const Triangle& triangle : triangles)
    for (const VertexIndex v : triangle) output_index[v] = 0;
  for (std::size_t i = 0; i < points.size(); ++i)
    if (output_index[i] != unused) {
      output_index[i] = static_cast<VertexIndex>(result.mesh.positions.size());
      result.mesh.positions.push_back(points[i]);
    }
  result.mesh.triangles.reserve(triangles.size());
  for (const Triangle& t : triangles)
    result.mesh.triangles.push_back({output_index[t[0]], output_index[t[1]], output_index[t[2]]});
  result.volume = hull_detail::enclosed_volume(result.mesh);
  hull_detail::planar_facets(result.mesh, result.faces);
  return result;
}

}  // namespace visproxy
