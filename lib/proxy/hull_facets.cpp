#include "proxy/hull_facets.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>

#include <algorithm>
#include <array>
#include <numeric>
#include <tuple>

namespace visproxy::hull_detail {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;

Kernel::Point_3 point(const Vertex& p) { return {p.x(), p.y(), p.z()}; }

std::uint32_t find_root(std::vector<std::uint32_t>& parent, std::uint32_t i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

}  // namespace

TriangleMesh exact_convex_hull(const std::vector<Vertex>& points) {
  std::vector<Kernel::Point_3> cgal_points;
  cgal_points.reserve(points.size());
  for (const Vertex& p : points) cgal_points.push_back(point(p));
  // The Surface_mesh overload picks CGAL's exact-predicate hull traits (the indexed
  // triangle set overload of CGAL 5.5 falls back to the kernel's inexact planes).
  CGAL::Surface_mesh<Kernel::Point_3> hull;
  CGAL::convex_hull_3(cgal_points.begin(), cgal_points.end(), hull);
  TriangleMesh mesh;
  mesh.positions.reserve(hull.number_of_vertices());
  for (const auto vertex : hull.vertices()) {
    const Kernel::Point_3& p = hull.point(vertex);
    mesh.positions.emplace_back(p.x(), p.y(), p.z());
  }
  mesh.triangles.reserve(hull.number_of_faces());
  for (const auto face : hull.faces()) {
    Triangle triangle{};
    int corner = 0;
    for (const auto vertex : CGAL::vertices_around_face(hull.halfedge(face), hull))
      triangle[corner++] = static_cast<VertexIndex>(vertex.idx());
    mesh.triangles.push_back(triangle);
  }
  if (enclosed_volume(mesh) < 0.0)
    for (Triangle& triangle : mesh.triangles) std::swap(triangle[1], triangle[2]);
  return mesh;
}

std::vector<std::uint32_t> planar_facets(const TriangleMesh& mesh, std::size_t& facet_count) {
  const std::size_t triangle_count = mesh.triangles.size();
  // Every undirected edge with the triangle that holds it and that triangle's opposite corner.
  struct EdgeUse {
    VertexIndex low, high;
    std::uint32_t triangle;
    VertexIndex opposite;
  };
  std::vector<EdgeUse> uses;
  uses.reserve(3 * triangle_count);
  for (std::size_t t = 0; t < triangle_count; ++t) {
    const Triangle& triangle = mesh.triangles[t];
    for (int corner = 0; corner < 3; ++corner) {
      const VertexIndex a = triangle[corner];
      const VertexIndex b = triangle[(corner + 1) % 3];
      uses.push_back({std::min(a, b), std::max(a, b), static_cast<std::uint32_t>(t), triangle[(corner + 2) % 3]});
    }
  }
  std::sort(uses.begin(), uses.end(), [](const EdgeUse& x, const EdgeUse& y) {
    return std::tie(x.low, x.high, x.triangle) < std::tie(y.low, y.high, y.triangle);
  });

  std::vector<std::uint32_t> parent(triangle_count);
  std::iota(parent.begin(), parent.end(), 0u);
  for (std::size_t i = 0; i + 1 < uses.size(); ++i) {
    const EdgeUse& x = uses[i];
    const EdgeUse& y = uses[i + 1];
    if (x.low != y.low || x.high != y.high) continue;
    if (!CGAL::coplanar(point(mesh.positions[x.low]), point(mesh.positions[x.high]),
                        point(mesh.positions[x.opposite]), point(mesh.positions[y.opposite])))
      continue;
    const std::uint32_t root_x = find_root(parent, x.triangle);
    const std::uint32_t root_y = find_root(parent, y.triangle);
    if (root_x != root_y) parent[std::max(root_x, root_y)] = std::min(root_x, root_y);
  }

  constexpr std::uint32_t unnumbered = ~std::uint32_t{0};
  std::vector<std::uint32_t> number_of_root(triangle_count, unnumbered);
  std::vector<std::uint32_t> facet(triangle_count);
  facet_count = 0;
  for (std::size_t t = 0; t < triangle_count; ++t) {
    const std::uint32_t root = find_root(parent, static_cast<std::uint32_t>(t));
    if (number_of_root[root] == unnumbered) number_of_root[root] = static_cast<std::uint32_t>(facet_count++);
    facet[t] = number_of_root[root];
  }
  return facet;
}

double enclosed_volume(const TriangleMesh& mesh) {
  if (mesh.positions.empty()) return 0.0;
  const Vertex& origin = mesh.positions.front();
  double six_volume = 0.0;
  for (const Triangle& triangle : mesh.triangles) {
    const Vertex a = mesh.positions[triangle[0]] - origin;
    const Vertex b = mesh.positions[triangle[1]] - origin;
    const Vertex c = mesh.positions[triangle[2]] - origin;
    six_volume += a.dot(b.cross(c));
  }
  return six_volume / 6.0;
}

}  // namespace visproxy::hull_detail
