#include "visproxy/proxy/detail/hull_facets.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Extreme_points_traits_adapter_3.h>
#include <CGAL/convex_hull_3.h>
#include <CGAL/property_map.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <functional>
#include <limits>
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

// hull_candidates() (Akl and Toussaint, "A fast convex hull algorithm", 1978). The hull of
// the extreme points is exact (CGAL's), and a point is dropped only when it is certainly
// below every face's CertainPlane, with the diagonal of the points' box as the reach.
// Deterministic: ties go to the lowest index.
std::vector<std::size_t> candidates_of(const std::vector<Kernel::Point_3>& points) {
  std::vector<std::size_t> all(points.size());
  std::iota(all.begin(), all.end(), std::size_t{0});
  std::vector<Vertex> directions;
  for (int x = -1; x <= 1; ++x)
    for (int y = -1; y <= 1; ++y)
      for (int z = -1; z <= 1; ++z)
        if (x != 0 || y != 0 || z != 0) directions.emplace_back(x, y, z);
  struct Extremes {
    std::array<double, 26> value;
    std::array<std::size_t, 26> index;
    BoundingBox box;
  };
  Extremes none;
  none.value.fill(-std::numeric_limits<double>::infinity());
  none.index.fill(points.size());
  const Extremes found = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, points.size(), 4096), none,
      [&](const tbb::blocked_range<std::size_t>& range, Extremes e) {
        for (std::size_t i = range.begin(); i < range.end(); ++i) {
          const Vertex p(points[i].x(), points[i].y(), points[i].z());
          e.box.extend(p);
          for (std::size_t d = 0; d < 26; ++d) {
            const double v = directions[d].dot(p);
            if (v > e.value[d]) e.value[d] = v, e.index[d] = i;  // ranges come in order: the first wins ties
          }
        }
        return e;
      },
      [](Extremes a, const Extremes& b) {
        for (std::size_t d = 0; d < 26; ++d)
          if (b.value[d] > a.value[d] || (b.value[d] == a.value[d] && b.index[d] < a.index[d]))
            a.value[d] = b.value[d], a.index[d] = b.index[d];
        a.box.extend(b.box.min), a.box.extend(b.box.max);
        return a;
      });
  std::vector<std::size_t> corners(found.index.begin(), found.index.end());
  std::sort(corners.begin(), corners.end());
  corners.erase(std::unique(corners.begin(), corners.end()), corners.end());
  if (corners.empty() || corners.back() >= points.size() || corners.size() < 4) return all;
  std::vector<Kernel::Point_3> inner_points;
  for (const std::size_t i : corners) inner_points.push_back(points[i]);
  CGAL::Surface_mesh<Kernel::Point_3> inner;
  CGAL::convex_hull_3(inner_points.begin(), inner_points.end(), inner);
  if (inner.number_of_faces() < 4) return all;  // flat: nothing is strictly inside
  const double diagonal = (found.box.max - found.box.min).norm();
  Vertex centroid = Vertex::Zero();
  for (const auto v : inner.vertices()) centroid += Vertex(inner.point(v).x(), inner.point(v).y(), inner.point(v).z());
  centroid /= static_cast<double>(inner.number_of_vertices());
  std::vector<CertainPlane> planes;
  for (const auto face : inner.faces()) {
    std::array<Vertex, 3> corner;
    int k = 0;
    for (const auto v : CGAL::vertices_around_face(inner.halfedge(face), inner)) {
      if (k == 3) return all;
      corner[static_cast<std::size_t>(k++)] = Vertex(inner.point(v).x(), inner.point(v).y(), inner.point(v).z());
    }
    if (k != 3) return all;
    const std::optional<CertainPlane> plane = CertainPlane::through(corner[0], corner[1], corner[2], diagonal);
    // CGAL orients the faces outwards; the centroid, strictly inside, must say so.
    if (!plane || !plane->certainly_below(centroid)) return all;
    planes.push_back(*plane);
  }
  std::vector<std::uint8_t> keep(points.size(), 1);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 4096), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t i = range.begin(); i < range.end(); ++i) {
      const Vertex p(points[i].x(), points[i].y(), points[i].z());
      bool inside = true;
      for (const CertainPlane& plane : planes)
        if (!plane.certainly_below(p)) {
          inside = false;
          break;
        }
      keep[i] = inside ? 0 : 1;
    }
  });
  std::vector<std::size_t> kept;
  for (std::size_t i = 0; i < points.size(); ++i)
    if (keep[i]) kept.push_back(i);
  return kept;
}

}  // namespace

std::optional<CertainPlane> CertainPlane::through(const Vertex& a, const Vertex& b, const Vertex& c, double reach) {
  const Vertex u = b - a, v = c - a;
  // |b - a| |c - a| reach bounds every product in the test; below 1e300 their sums cannot
  // overflow.
  const double bound = u.norm() * v.norm() * reach;
  CertainPlane plane{a, u.cross(v), 1e-12 * bound};
  if (!(bound <= 1e300) || !std::isnormal(plane.slack) || !plane.normal.allFinite()) return std::nullopt;
  return plane;
}

std::vector<std::size_t> hull_candidates(const std::vector<Vertex>& points) {
  std::vector<Kernel::Point_3> cgal_points;
  cgal_points.reserve(points.size());
  for (const Vertex& p : points) cgal_points.push_back(point(p));
  return candidates_of(cgal_points);
}

std::vector<Triangle> exact_convex_hull(const std::vector<Vertex>& points) {
  std::vector<Kernel::Point_3> cgal_points;
  cgal_points.reserve(points.size());
  for (const Vertex& p : points) cgal_points.push_back(point(p));
  // The Surface_mesh overload picks CGAL's exact-predicate hull traits (the indexed
  // triangle set overload of CGAL 5.5 falls back to the kernel's rounded planes).
  // Many points: the hull's corners of each of a few slices of them, in parallel, then the
  // hull of those corners alone, which is the hull of all (every corner of the whole is a
  // corner of its slice). The slices and the order of the corners are fixed by the input.
  // Before that, the points certainly inside the hull of a few extreme ones are dropped
  // (hull_candidates).
  constexpr std::size_t kSliceFrom = 200'000;
  std::vector<std::size_t> kept;  // when sliced: the input index of each of cgal_points
  if (cgal_points.size() >= kSliceFrom) {
    const std::vector<std::size_t> candidates = candidates_of(cgal_points);
    const std::size_t slices = 8;
    std::vector<std::vector<std::size_t>> corners(slices);
    const auto point_of = CGAL::make_property_map(cgal_points);
    tbb::parallel_for(std::size_t{0}, slices, [&](std::size_t k) {
      const std::size_t begin = candidates.size() * k / slices, end = candidates.size() * (k + 1) / slices;
      std::vector<std::size_t> slice(candidates.begin() + static_cast<std::ptrdiff_t>(begin),
                                     candidates.begin() + static_cast<std::ptrdiff_t>(end));
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
