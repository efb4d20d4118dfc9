#pragma once
// Independent proof that a proxy is a conservative outside proxy of its input, with exact
// predicates (CGAL's filtered kernel), sharing no code with the builders: the proxy is a
// closed, oriented 2-manifold without self-intersections or degenerate triangles, every
// input vertex is strictly inside it, and no input triangle touches it.

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <vector>

#include "visproxy/inspect/exact_checks.h"
#include "visproxy/mesh/mesh_topology.h"
#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy::testing {

using CheckKernel = CGAL::Exact_predicates_inexact_constructions_kernel;

struct OutsideProxyFindings {
  MeshTopology topology;
  std::size_t degenerate_triangles = 0;
  std::size_t self_intersections = 0;
  double signed_volume = 0;                   ///< positive when outward-oriented
  std::size_t input_vertices_not_inside = 0;  ///< on the proxy or outside it
  std::size_t input_triangles_touching = 0;   ///< meeting the proxy surface anywhere
};

inline OutsideProxyFindings check_outside_proxy(const TriangleMesh& input, const TriangleMesh& proxy) {
  using Point = CheckKernel::Point_3;
  OutsideProxyFindings findings;
  findings.topology = analyze_topology(proxy);
  findings.degenerate_triangles = find_degenerate_triangles(proxy).size();
  findings.self_intersections = find_self_intersections(proxy).size();
  for (const Triangle& t : proxy.triangles)
    findings.signed_volume +=
        proxy.positions[t[0]].dot(proxy.positions[t[1]].cross(proxy.positions[t[2]])) / 6.0;

  auto point = [](const Vertex& p) { return Point(p.x(), p.y(), p.z()); };
  std::vector<Point> points;
  for (const Vertex& p : proxy.positions) points.push_back(point(p));
  std::vector<std::array<std::size_t, 3>> polygons;
  for (const Triangle& t : proxy.triangles) polygons.push_back({t[0], t[1], t[2]});

  // Input triangles against the proxy's triangles, exactly.
  std::vector<CheckKernel::Triangle_3> proxy_triangles;
  for (const auto& t : polygons) proxy_triangles.emplace_back(points[t[0]], points[t[1]], points[t[2]]);
  using Primitive = CGAL::AABB_triangle_primitive<CheckKernel, std::vector<CheckKernel::Triangle_3>::const_iterator>;
  CGAL::AABB_tree<CGAL::AABB_traits<CheckKernel, Primitive>> tree(proxy_triangles.begin(), proxy_triangles.end());
  tree.build();
  for (const Triangle& t : input.triangles) {
    const Point a = point(input.positions[t[0]]);
    const Point b = point(input.positions[t[1]]);
    const Point c = point(input.positions[t[2]]);
    bool touches = false;
    if (!CGAL::collinear(a, b, c)) {
      touches = tree.do_intersect(CheckKernel::Triangle_3(a, b, c));
    } else {
      for (const auto& [p, q] : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}})
        if (p != q && tree.do_intersect(CheckKernel::Segment_3(p, q))) touches = true;
    }
    findings.input_triangles_touching += touches ? 1 : 0;
  }

  // Input vertices strictly inside; needs a closed manifold proxy.
  std::vector<bool> referenced(input.positions.size(), false);
  for (const Triangle& t : input.triangles)
    for (const VertexIndex v : t) referenced[v] = true;
  const std::size_t referenced_count = static_cast<std::size_t>(std::count(referenced.begin(), referenced.end(), true));
  if (!findings.topology.closed() || !findings.topology.manifold() || !findings.topology.consistently_oriented() ||
      !CGAL::Polygon_mesh_processing::is_polygon_soup_a_polygon_mesh(polygons)) {
    findings.input_vertices_not_inside = referenced_count;
    return findings;
  }
  CGAL::Surface_mesh<Point> surface;
  CGAL::Polygon_mesh_processing::polygon_soup_to_polygon_mesh(points, polygons, surface);
  const CGAL::Side_of_triangle_mesh<CGAL::Surface_mesh<Point>, CheckKernel> side(surface);
  for (std::size_t v = 0; v < input.positions.size(); ++v)
    if (referenced[v] && side(point(input.positions[v])) != CGAL::ON_BOUNDED_SIDE) ++findings.input_vertices_not_inside;
  return findings;
}

/// EXPECTs every property of a conservative outside proxy of `input`.
inline void expect_conservative_outside_proxy(const TriangleMesh& input, const TriangleMesh& proxy) {
  const OutsideProxyFindings f = check_outside_proxy(input, proxy);
  EXPECT_GE(proxy.triangles.size(), 4u);
  EXPECT_TRUE(f.topology.closed()) << f.topology.boundary_edges << " boundary edges";
  EXPECT_TRUE(f.topology.manifold()) << f.topology.non_manifold_edges << " non-manifold edges, "
                                     << f.topology.non_manifold_vertices << " non-manifold vertices";
  EXPECT_TRUE(f.topology.consistently_oriented());
  EXPECT_EQ(f.topology.referenced_vertices, proxy.positions.size()) << "unreferenced proxy vertices";
  EXPECT_EQ(f.degenerate_triangles, 0u);
  EXPECT_EQ(f.self_intersections, 0u);
  EXPECT_GT(f.signed_volume, 0.0) << "not outward-oriented";
  EXPECT_EQ(f.input_vertices_not_inside, 0u);
  EXPECT_EQ(f.input_triangles_touching, 0u);
}

}  // namespace visproxy::testing
