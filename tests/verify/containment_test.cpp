#include "verify/containment.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <gtest/gtest.h>

#include "core/random.h"
#include "mesh/read_mesh.h"
#include "test_meshes.h"

namespace visproxy {
namespace {

TriangleMesh transformed(TriangleMesh mesh, double scale, const Vertex& offset) {
  for (Vertex& p : mesh.positions) p = scale * p + offset;
  return mesh;
}

TriangleMesh merged(const TriangleMesh& a, const TriangleMesh& b) {
  TriangleMesh mesh = a;
  const auto base = static_cast<VertexIndex>(a.positions.size());
  mesh.positions.insert(mesh.positions.end(), b.positions.begin(), b.positions.end());
  for (Triangle t : b.triangles) mesh.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  return mesh;
}

TEST(LocatePoints, CubeInsideOnBoundaryOutside) {
  const TriangleMesh cube = testing::unit_cube();
  const std::vector<Vertex> points = {{0.5, 0.5, 0.5}, {0, 0, 0}, {0.5, 0.5, 1}, {1, 0.25, 0.75},
                                      {1.0000001, 0.5, 0.5}, {-3, 0.5, 0.5}, {0.999999, 0.999999, 0.999999}};
  const std::vector<PointLocation> expected = {PointLocation::inside,      PointLocation::on_boundary,
                                               PointLocation::on_boundary, PointLocation::on_boundary,
                                               PointLocation::outside,     PointLocation::outside,
                                               PointLocation::inside};
  EXPECT_EQ(locate_points(cube, points), expected);
}

TEST(LocatePoints, RaysThroughEdgesAndVerticesAreRetried) {
  // Points whose first ray direction passes exactly through a vertex of the cube: the
  // direction (1, 1, 1) from the centre aims at the corner (1, 1, 1). Use many points on
  // lines through corners and edges; every answer must still be right.
  const TriangleMesh cube = testing::unit_cube();
  std::vector<Vertex> points;
  for (int i = 1; i < 20; ++i) {
    const double t = i / 20.0;
    points.emplace_back(t, t, t);       // the main diagonal: inside
    points.emplace_back(t, 0.5, 0.5);   // inside
    points.emplace_back(t, 1.0, 1.0);   // on an edge
    points.emplace_back(1 + t, 1, 1);   // on the extension of an edge: outside
  }
  const std::vector<PointLocation> locations = locate_points(cube, points);
  for (std::size_t i = 0; i < points.size(); i += 4) {
    EXPECT_EQ(locations[i], PointLocation::inside);
    EXPECT_EQ(locations[i + 1], PointLocation::inside);
    EXPECT_EQ(locations[i + 2], PointLocation::on_boundary);
    EXPECT_EQ(locations[i + 3], PointLocation::outside);
  }
}

TEST(LocatePoints, OverlappingPartsContainTheirUnion) {
  // Two overlapping cubes as one mesh: the overlap has winding number 2 (parity would
  // call it outside); each cube's own part has winding number 1.
  const TriangleMesh two = merged(testing::unit_cube(), transformed(testing::unit_cube(), 1, {0.5, 0.5, 0.5}));
  const std::vector<Vertex> points = {{0.75, 0.75, 0.75}, {0.25, 0.25, 0.25}, {1.25, 1.25, 1.25}, {1.75, 0.25, 0.25}};
  const std::vector<PointLocation> expected = {PointLocation::inside, PointLocation::inside, PointLocation::inside,
                                               PointLocation::outside};
  EXPECT_EQ(locate_points(two, points), expected);
}

TEST(LocatePoints, AgreesWithCgalSideOfTriangleMeshOnBunny) {
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;
  const TriangleMesh bunny = read_mesh(testing::cgal_mesh("bunny00.off"));
  SurfaceMesh surface;
  std::vector<SurfaceMesh::Vertex_index> vertices;
  for (const Vertex& p : bunny.positions) vertices.push_back(surface.add_vertex({p.x(), p.y(), p.z()}));
  for (const Triangle& t : bunny.triangles) surface.add_face(vertices[t[0]], vertices[t[1]], vertices[t[2]]);
  const CGAL::Side_of_triangle_mesh<SurfaceMesh, Kernel> side(surface);

  const BoundingBox box = bounding_box(bunny);
  Random random(11);
  std::vector<Vertex> points;
  for (int i = 0; i < 4000; ++i)
    points.push_back(box.min + Vertex(random.uniform(), random.uniform(), random.uniform()).cwiseProduct(box.max - box.min));
  // Vertices of the mesh itself are on its boundary.
  for (int i = 0; i < 100; ++i) points.push_back(bunny.positions[static_cast<std::size_t>(i) * 300]);

  const std::vector<PointLocation> locations = locate_points(bunny, points);
  std::size_t inside = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const CGAL::Bounded_side cgal = side(Kernel::Point_3(points[i].x(), points[i].y(), points[i].z()));
    const PointLocation expected = cgal == CGAL::ON_BOUNDED_SIDE     ? PointLocation::inside
                                   : cgal == CGAL::ON_BOUNDARY        ? PointLocation::on_boundary
                                                                      : PointLocation::outside;
    EXPECT_EQ(locations[i], expected) << i;
    inside += locations[i] == PointLocation::inside;
  }
  EXPECT_GT(inside, 500u);  // the sample is not trivially all outside
}

TEST(CheckContainment, ScaledCopyInsideAndCrossingCopy) {
  const TriangleMesh cube = testing::unit_cube();
  const TriangleMesh small = transformed(testing::tetrahedron(), 0.5, {0.2, 0.2, 0.2});
  const Containment inside = check_containment(cube, small);
  EXPECT_TRUE(inside.contained());
  EXPECT_EQ(inside.vertices_checked, 4u);
  EXPECT_TRUE(inside.surface_checked);

  // A tetrahedron poking out through one face: one vertex outside and crossings.
  const TriangleMesh poking = transformed(testing::tetrahedron(), 0.6, {0.3, 0.3, 0.5});
  const Containment out = check_containment(cube, poking);
  EXPECT_FALSE(out.contained());
  EXPECT_EQ(out.vertices_outside, 1u);
  EXPECT_GT(out.crossing_triangle_pairs, 0u);
  // The counterexamples name the vertex outside (the apex of the tetrahedron) and a pair.
  ASSERT_TRUE(out.first_vertex_outside.has_value());
  EXPECT_GT(poking.positions[*out.first_vertex_outside].z(), 1.0);
  ASSERT_TRUE(out.first_crossing.has_value());
  EXPECT_LT(out.first_crossing->first, cube.triangles.size());
  EXPECT_LT(out.first_crossing->second, poking.triangles.size());
  EXPECT_FALSE(inside.first_vertex_outside.has_value());

  // A flat triangle lying in the cube's face is on the boundary, and touches it.
  TriangleMesh flat;
  flat.positions = {{0.1, 0.1, 0}, {0.9, 0.1, 0}, {0.1, 0.9, 0}};
  flat.triangles = {{0, 1, 2}};
  const Containment touching = check_containment(cube, flat, {.check_surface = false});
  EXPECT_TRUE(touching.contained());
  EXPECT_EQ(touching.vertices_on_boundary, 3u);
  EXPECT_FALSE(touching.surface_checked);
  EXPECT_FALSE(check_containment(cube, flat).contained());
}

TEST(CheckContainment, SurfaceCrossingWithAllVerticesInsideIsCaught) {
  // A long thin triangle whose corners are inside two far cubes but whose middle passes
  // outside: no vertex is outside, yet the surface is not contained.
  const TriangleMesh two = merged(testing::unit_cube(), transformed(testing::unit_cube(), 1, {3, 0, 0}));
  TriangleMesh sliver;
  sliver.positions = {{0.5, 0.5, 0.5}, {3.5, 0.5, 0.5}, {3.5, 0.6, 0.5}};
  sliver.triangles = {{0, 1, 2}};
  const Containment result = check_containment(two, sliver);
  EXPECT_EQ(result.vertices_outside, 0u);
  EXPECT_GT(result.crossing_triangle_pairs, 0u);
  EXPECT_FALSE(result.contained());
}

TEST(CheckContainment, ConvexComponentsNeedOneComponentHoldingEachTriangle) {
  const TriangleMesh two = merged(testing::unit_cube(), transformed(testing::unit_cube(), 1, {3, 0, 0}));
  TriangleMesh sliver;
  sliver.positions = {{0.5, 0.5, 0.5}, {3.5, 0.5, 0.5}, {3.5, 0.6, 0.5}};
  sliver.triangles = {{0, 1, 2}};
  const Containment split = check_containment(two, sliver, {.convex_components = true});
  EXPECT_EQ(split.vertices_outside, 0u);
  EXPECT_EQ(split.triangles_split, 1u);
  EXPECT_EQ(split.first_triangle_split, 0u);
  EXPECT_FALSE(split.contained());
  // A triangle lying in a face of one cube touches it, and is contained: the surface test
  // would reject it, the convex test accepts it.
  TriangleMesh in_face;
  in_face.positions = {{3.1, 0.1, 0}, {3.9, 0.1, 0}, {3.1, 0.9, 0}, {0.2, 0.2, 0.2}, {0.8, 0.2, 0.2}, {0.2, 0.8, 0.9}};
  in_face.triangles = {{0, 1, 2}, {3, 4, 5}};
  EXPECT_TRUE(check_containment(two, in_face, {.convex_components = true}).contained());
  EXPECT_FALSE(check_containment(two, in_face).contained());
}

TEST(ClosestDistance, FromPointsToACubeSurface) {
  const TriangleMesh cube = testing::unit_cube();
  const std::vector<Vertex> points = {{0.5, 0.5, 0.5}, {0.5, 0.5, 0.9}, {2, 2, 2}};
  const ClosestDistance closest = closest_distance_to_surface(cube, points);
  EXPECT_NEAR(closest.distance, 0.1, 1e-12);
  EXPECT_EQ(closest.point, 1u);
  EXPECT_TRUE(std::isinf(closest_distance_to_surface(cube, {}).distance));
}

}  // namespace
}  // namespace visproxy
