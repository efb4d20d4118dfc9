#include "visproxy/proxy/hull_facets.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Extreme_points_traits_adapter_3.h>
#include <CGAL/convex_hull_3.h>
#include <CGAL/property_map.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cassert>
#include <functional>
#include <unordered_map>
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

// Looked up only, never iterated: the hash order does not reach the output.
struct CoordinatesHash {
  std::size_t operator()(const std::array<double, 3>& c) const {
    std::size_t h = 0;
    for (const double x : c) h = h * 0x9E3779B97F4A7C15ull + std::hash<double>{}(x);
    return h;
  }
};

}  // namespace

std::vector<Triangle> exact_convex_hull(const std::vector<Vertex>& points) {
  std::vector<Kernel::Point_3> cgal_points;
  cgal_points.reserve(points.size());
  for (const Vertex& p : points) cgal_points.push_back(point(p));
  // The Surface_mesh overload picks CGAL's exact-predicate hull traits (the indexed
  // triangle set overload of CGAL 5.5 falls back to the kernel's rounded planes).
  // Many points: the hull's corners of each of a few slices of them, in parallel, then the
  // hull of those corners alone, which is the hull of all (every corner of the whole is a
  // corner of its slice). The slices and the order of the corners are fixed by the input.
  constexpr std::size_t kSliceFrom = 200'000;
  std::vector<std::size_t> kept;  // when sliced: the input index of each of cgal_points
  if (cgal_points.size() >= kSliceFrom) {
    const std::size_t slices = 8;
    std::vector<std::vector<std::size_t>> corners(slices);
    const auto point_of = CGAL::make_property_map(cgal_points);
    tbb::parallel_for(std::size_t{0}, slices, [&](std::size_t k) {
      const std::size_t begin = cgal_points.size() * k / slices, end = cgal_points.size() * (k + 1) / slices;
      std::vector<std::size_t> slice(end - begin);
      std::iota(slice.begin(), slice.end(), begin);
      try {
        CGAL::extreme_points_3(slice, std::back_inserter(corners[k]), CGAL::make_extreme_points_traits_adapter(point_of));
      } catch (const std::exception&) {
        corners[k].clear();
      }
      if (corners[k].size() < 4) corners[k] = std::move(slice);  // a flat or thinner slice: all of it goes on
    });
    for (const std::vector<std::size_t>& c : corners) kept.insert(kept.end(), c.begin(), c.end());
    std::sort(kept.begin(), kept.end());
    std::vector<Kernel::Point_3> reduced;
    reduced.reserve(kept.size());
    for (const std::size_t i : kept) reduced.push_back(cgal_points[i]);
    cgal_points.swap(reduced);
  }
  CGAL::Surface_mesh<Kernel::Point_3> hull;
  CGAL::convex_hull_3(cgal_points.begin(), cgal_points.end(), hull);

  // The hull over input indices (the first input point at each corner). CGAL's vertex and
  // face order depends on memory addresses.
  std::unordered_map<std::array<double, 3>, VertexIndex, CoordinatesHash> index_of_point;
  index_of_point.reserve(cgal_points.size());
  for (std::size_t i = 0; i < cgal_points.size(); ++i) {
    const std::size_t input = kept.empty() ? i : kept[i];
    index_of_point.emplace(std::array<double, 3>{points[input].x(), points[input].y(), points[input].z()},
                           static_cast<VertexIndex>(input));
  }
  TriangleMesh mesh;
  mesh.positions = points;
  std::vector<VertexIndex> input_index(hull.number_of_vertices());
  for (const auto vertex : hull.vertices()) {
    const Kernel::Point_3& p = hull.point(vertex);
    input_index[vertex.idx()] = index_of_point.at({p.x(), p.y(), p.z()});
  }
  for (const auto face : hull.faces()) {
    Triangle triangle{};
    int corner = 0;
    for (const auto vertex : CGAL::vertices_around_face(hull.halfedge(face), hull))
      triangle[corner++] = input_index[vertex.idx()];
    mesh.triangles.push_back(triangle);
  }
  if (enclosed_volume(mesh) < 0.0)
    for (Triangle& triangle : mesh.triangles) std::swap(triangle[1], triangle[2]);

  // Each planar facet's boundary, counter-clockwise seen from outside: the directed edges
  // whose reverse lies in another facet.
  std::size_t facet_count = 0;
  const std::vector<std::uint32_t> facet_of_triangle = planar_facets(mesh, facet_count);
  struct DirectedEdge {
    VertexIndex from, to;
    std::uint32_t facet;
    bool operator<(const DirectedEdge& other) const { return std::tie(from, to) < std::tie(other.from, other.to); }
  };
  std::vector<DirectedEdge> edges;
  edges.reserve(3 * mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k)
      edges.push_back({mesh.triangles[t][k], mesh.triangles[t][(k + 1) % 3], facet_of_triangle[t]});
  std::sort(edges.begin(), edges.end());
  std::vector<std::vector<std::pair<VertexIndex, VertexIndex>>> boundary(facet_count);
  for (const DirectedEdge& edge : edges) {
    const auto reverse = std::lower_bound(edges.begin(), edges.end(), DirectedEdge{edge.to, edge.from, 0});
    assert(reverse != edges.end() && reverse->from == edge.to && reverse->to == edge.from);
    if (reverse->facet != edge.facet) boundary[edge.facet].emplace_back(edge.from, edge.to);
  }

  std::vector<Triangle> triangles;
  std::vector<VertexIndex> loop, corners;
  for (auto& steps : boundary) {
    std::sort(steps.begin(), steps.end());
    loop.clear();
    VertexIndex at = steps.front().first;
    do {
      loop.push_back(at);
      at = std::lower_bound(steps.begin(), steps.end(), std::make_pair(at, VertexIndex{0}))->second;
    } while (at != loop.front());
    // Keep the corners: drop the points that lie on a straight stretch of the boundary.
    corners.clear();
    for (std::size_t k = 0; k < loop.size(); ++k) {
      const VertexIndex before = loop[(k + loop.size() - 1) % loop.size()];
      const VertexIndex after = loop[(k + 1) % loop.size()];
      if (!CGAL::collinear(point(points[before]), point(points[loop[k]]), point(points[after])))
        corners.push_back(loop[k]);
    }
    std::rotate(corners.begin(), std::min_element(corners.begin(), corners.end()), corners.end());
    for (std::size_t k = 1; k + 1 < corners.size(); ++k) triangles.push_back({corners[0], corners[k], corners[k + 1]});
  }
  std::sort(triangles.begin(), triangles.end());
  return triangles;
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
