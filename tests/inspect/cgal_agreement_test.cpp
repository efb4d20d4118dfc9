// find_self_intersections works on any triangle soup; on manifold inputs it must find
// exactly the pairs CGAL's Polygon_mesh_processing::self_intersections finds.

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <gtest/gtest.h>

#include "visproxy/inspect/exact_checks.h"
#include "visproxy/mesh/read_mesh.h"
#include "test_meshes.h"

namespace visproxy {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;

class SelfIntersectionsAgreeWithCgal : public ::testing::TestWithParam<const char*> {};

TEST_P(SelfIntersectionsAgreeWithCgal, OnManifoldMeshes) {
  const TriangleMesh mesh = read_mesh(testing::cgal_mesh(GetParam()));
  std::vector<Kernel::Point_3> points;
  for (const Vertex& p : mesh.positions) points.emplace_back(p.x(), p.y(), p.z());
  std::vector<std::vector<std::size_t>> polygons;
  for (const Triangle& t : mesh.triangles) polygons.push_back({t[0], t[1], t[2]});
  ASSERT_TRUE(CGAL::Polygon_mesh_processing::is_polygon_soup_a_polygon_mesh(polygons));
  SurfaceMesh surface;
  CGAL::Polygon_mesh_processing::polygon_soup_to_polygon_mesh(points, polygons, surface);
  ASSERT_EQ(surface.number_of_faces(), mesh.triangles.size());

  std::vector<std::pair<SurfaceMesh::Face_index, SurfaceMesh::Face_index>> cgal_pairs;
  CGAL::Polygon_mesh_processing::self_intersections(surface, std::back_inserter(cgal_pairs));
  std::vector<std::pair<std::uint32_t, std::uint32_t>> expected;
  for (const auto& [a, b] : cgal_pairs) {
    const auto i = static_cast<std::uint32_t>(a.idx());
    const auto j = static_cast<std::uint32_t>(b.idx());
    expected.emplace_back(std::min(i, j), std::max(i, j));
  }
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(find_self_intersections(mesh), expected);
  EXPECT_EQ(GetParam() == std::string("knot1.off"), expected.empty()) << "the test must see intersections somewhere";
}

INSTANTIATE_TEST_SUITE_P(LibCgalDemo, SelfIntersectionsAgreeWithCgal,
                         ::testing::Values("elephant-with-holes.off", "ChineseDragon-10kv.off", "knot1.off"));

}  // namespace
}  // namespace visproxy
