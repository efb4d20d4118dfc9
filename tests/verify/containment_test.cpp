#include "visproxy/verify/containment.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <tbb/global_control.h>

#include "visproxy/core/errors.h"
#include "visproxy/core/random.h"
#include "visproxy/mesh/read_mesh.h"
#include "cgal_hull.h"
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

// A torus of u x v quads, major radius 1, minor radius 0.35, outward, scaled and moved.
TriangleMesh torus(int u, int v, double scale = 1, const Vertex& offset = Vertex::Zero()) {
  TriangleMesh mesh;
  for (int i = 0; i < u; ++i)
    for (int j = 0; j < v; ++j) {
      const double a = 2 * std::numbers::pi * i / u, b = 2 * std::numbers::pi * j / v;
      const double r = 1 + 0.35 * std::cos(b);
      mesh.positions.push_back(scale * Vertex(r * std::cos(a), r * std::sin(a), 0.35 * std::sin(b)) + offset);
    }
  auto at = [&](int i, int j) { return static_cast<VertexIndex>((i % u) * v + (j % v)); };
  for (int i = 0; i < u; ++i)
    for (int j = 0; j < v; ++j) {
      mesh.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      mesh.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  return mesh;
}

using testing::cgal_convex_hull;

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

// The exact answer from CGAL for each point.
std::vector<PointLocation> cgal_locations(const TriangleMesh& mesh, const std::vector<Vertex>& points) {
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;
  SurfaceMesh surface;
  std::vector<SurfaceMesh::Vertex_index> vertices;
  for (const Vertex& p : mesh.positions) vertices.push_back(surface.add_vertex({p.x(), p.y(), p.z()}));
  for (const Triangle& t : mesh.triangles) surface.add_face(vertices[t[0]], vertices[t[1]], vertices[t[2]]);
  const CGAL::Side_of_triangle_mesh<SurfaceMesh, Kernel> side(surface);
  std::vector<PointLocation> out;
  for (const Vertex& p : points) {
    const CGAL::Bounded_side s = side(Kernel::Point_3(p.x(), p.y(), p.z()));
    out.push_back(s == CGAL::ON_BOUNDED_SIDE ? PointLocation::inside
                  : s == CGAL::ON_BOUNDARY   ? PointLocation::on_boundary
                                             : PointLocation::outside);
  }
  return out;
}

// Points a hair's breadth either side of the surface, on it (its vertices), and anywhere in
// the box, on a mesh far from the origin: the binned pass must miss no crossing however
// fine its grid, and give the same answers on one thread as on many.
TEST(LocatePoints, AgreesWithCgalAtTheSurfaceFarFromTheOriginOnAnyNumberOfThreads) {
  const TriangleMesh bunny = transformed(read_mesh(testing::cgal_mesh("bunny00.off")), 1, {3e5, -2e5, 1e5});
  const BoundingBox box = bounding_box(bunny);
  const double d = box.diagonal();
  Random random(7);
  std::vector<Vertex> points;
  for (int i = 0; i < 20000; ++i)
    points.push_back(box.min + Vertex(random.uniform(), random.uniform(), random.uniform()).cwiseProduct(box.max - box.min));
  for (std::size_t t = 0; t < bunny.triangles.size(); t += 7) {
    const Triangle& tri = bunny.triangles[t];
    const Vertex& a = bunny.positions[tri[0]];
    const Vertex normal = (bunny.positions[tri[1]] - a).cross(bunny.positions[tri[2]] - a).normalized();
    const Vertex centre = (a + bunny.positions[tri[1]] + bunny.positions[tri[2]]) / 3;
    points.push_back(a);                          // on the surface
    points.push_back(centre + 1e-9 * d * normal);  // just outside
    points.push_back(centre - 1e-9 * d * normal);  // just inside
  }
  const std::vector<PointLocation> expected = cgal_locations(bunny, points);
  std::vector<PointLocation> one_thread;
  {
    tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    one_thread = locate_points(bunny, points);
  }
  const std::vector<PointLocation> many = locate_points(bunny, points);
  EXPECT_EQ(one_thread, many);
  std::size_t wrong = 0, inside = 0, on = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    wrong += many[i] != expected[i];
    inside += many[i] == PointLocation::inside;
    on += many[i] == PointLocation::on_boundary;
  }
  EXPECT_EQ(wrong, 0u);
  EXPECT_GT(inside, 5000u);
  EXPECT_GT(on, 3000u);
  // Many points in a container of few triangles (each point's ray through a tree): a box
  // holding the bunny, its corners on the box of the points.
  TriangleMesh bounds;
  for (int c = 0; c < 8; ++c)
    bounds.positions.emplace_back(c & 1 ? box.max.x() : box.min.x(), c & 2 ? box.max.y() : box.min.y(),
                                  c & 4 ? box.max.z() : box.min.z());
  bounds.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                      {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  EXPECT_EQ(locate_points(bounds, points), cgal_locations(bounds, points));
  // One point alone (a grid of one cell).
  for (const std::size_t i : {std::size_t{0}, std::size_t{20000}, std::size_t{20001}, std::size_t{20002}})
    EXPECT_EQ(locate_points(bunny, std::vector<Vertex>{points[i]}).front(), expected[i]) << i;
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
  EXPECT_GT(out.triangles_touching, 0u);
  EXPECT_GT(out.triangles_unproved, 0u);  // crossing the cube's faces, they lie in no convex part
  // The counterexamples name the vertex outside (the apex of the tetrahedron) and a pair.
  ASSERT_TRUE(out.first_vertex_outside.has_value());
  EXPECT_GT(poking.positions[*out.first_vertex_outside].z(), 1.0);
  ASSERT_TRUE(out.first_unproved.has_value());
  EXPECT_LT(out.first_unproved->first, cube.triangles.size());
  EXPECT_LT(out.first_unproved->second, poking.triangles.size());
  EXPECT_FALSE(inside.first_vertex_outside.has_value());

  // A flat triangle lying in the cube's face is on the boundary and touches it: the cube
  // is convex, so the triangle lies in its solid (the convex-part argument).
  TriangleMesh flat;
  flat.positions = {{0.1, 0.1, 0}, {0.9, 0.1, 0}, {0.1, 0.9, 0}};
  flat.triangles = {{0, 1, 2}};
  const Containment touching = check_containment(cube, flat, {.check_surface = false});
  EXPECT_TRUE(touching.contained());
  EXPECT_EQ(touching.vertices_on_boundary, 3u);
  EXPECT_FALSE(touching.surface_checked);
  const Containment in_face = check_containment(cube, flat);
  EXPECT_TRUE(in_face.contained());
  EXPECT_EQ(in_face.triangles_touching, 1u);
  EXPECT_EQ(in_face.triangles_in_convex_parts, 1u);
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
  EXPECT_EQ(result.triangles_touching, 1u);
  EXPECT_FALSE(result.contained());
}

TEST(CheckContainment, TouchingTrianglesNeedOneConvexPartHoldingThem) {
  const TriangleMesh two = merged(testing::unit_cube(), transformed(testing::unit_cube(), 1, {3, 0, 0}));
  TriangleMesh sliver;
  sliver.positions = {{0.5, 0.5, 0.5}, {3.5, 0.5, 0.5}, {3.5, 0.6, 0.5}};
  sliver.triangles = {{0, 1, 2}};
  const Containment split = check_containment(two, sliver);
  EXPECT_EQ(split.vertices_outside, 0u);
  EXPECT_EQ(split.triangles_touching, 1u);
  EXPECT_EQ(split.triangles_unproved, 1u);
  ASSERT_TRUE(split.first_unproved.has_value());
  EXPECT_EQ(split.first_unproved->second, 0u);
  EXPECT_FALSE(split.contained());
  // A triangle lying in a face of the second cube touches it and is contained; one wholly
  // inside the first touches nothing.
  TriangleMesh in_face;
  in_face.positions = {{3.1, 0.1, 0}, {3.9, 0.1, 0}, {3.1, 0.9, 0}, {0.2, 0.2, 0.2}, {0.8, 0.2, 0.2}, {0.2, 0.8, 0.9}};
  in_face.triangles = {{0, 1, 2}, {3, 4, 5}};
  const Containment held = check_containment(two, in_face);
  EXPECT_TRUE(held.contained());
  EXPECT_EQ(held.triangles_touching, 1u);
  EXPECT_EQ(held.triangles_in_convex_parts, 1u);
}

// The container is read as it is: an outside proxy with a triangle removed bounds no solid,
// so nothing is contained in it, however inside its vertices look.
TEST(CheckContainment, OpenContainerContainsNothing) {
  TriangleMesh open = testing::unit_cube();
  open.triangles.erase(open.triangles.begin() + 5);
  const TriangleMesh small = transformed(testing::tetrahedron(), 0.5, {0.2, 0.2, 0.2});
  const Containment result = check_containment(open, small);
  EXPECT_FALSE(result.contained());
  EXPECT_EQ(result.container_edges.unbalanced_edges, 3u);
  EXPECT_EQ(result.vertices_checked, 0u);  // nothing else is decided
  // Two cubes, one of them open: the closed one alone would hold its contents, but the
  // whole container is not closed.
  TriangleMesh parts = merged(testing::unit_cube(), transformed(open, 1, {3, 0, 0}));
  EXPECT_FALSE(check_containment(parts, small).contained());
  // A flipped triangle: every edge still used twice, but one direction twice.
  TriangleMesh flipped = testing::unit_cube();
  std::swap(flipped.triangles[0][1], flipped.triangles[0][2]);
  EXPECT_FALSE(check_containment(flipped, small).contained());
  EXPECT_FALSE(check_containment(TriangleMesh{}, small).contained());
}

// A hull whose top is dented inwards: every mesh vertex is still inside, but the dent
// cuts through a mesh triangle near the top. A check that took convexity on trust (from
// the proxy's name) and tested vertices only would pass it.
TEST(CheckContainment, DentedHullIsNotTakenForConvex) {
  TriangleMesh dented = testing::unit_cube();
  // Replace the top face (z = 1: triangles {4, 5, 6}, {5, 7, 6}) by four triangles to a
  // centre vertex pushed down to z = 0.5.
  dented.triangles.erase(dented.triangles.begin() + 2, dented.triangles.begin() + 4);
  dented.positions.emplace_back(0.5, 0.5, 0.5);
  const VertexIndex centre = 8;
  dented.triangles.push_back({4, 5, centre});
  dented.triangles.push_back({5, 7, centre});
  dented.triangles.push_back({7, 6, centre});
  dented.triangles.push_back({6, 4, centre});
  ASSERT_TRUE(check_edge_balance(dented).balanced());
  TriangleMesh contents;  // a flat triangle at z = 0.9 whose corners sit near the top edges
  contents.positions = {{0.05, 0.05, 0.9}, {0.95, 0.05, 0.9}, {0.5, 0.95, 0.9}};
  contents.triangles = {{0, 1, 2}};
  const Containment result = check_containment(dented, contents);
  EXPECT_EQ(result.vertices_outside, 0u);
  EXPECT_EQ(result.triangles_touching, 1u);
  EXPECT_EQ(result.triangles_unproved, 1u);
  EXPECT_FALSE(result.contained());
  // The same triangle in the undented cube is held.
  EXPECT_TRUE(check_containment(testing::unit_cube(), contents).contained());
}

// A degenerate mesh triangle (three collinear corners) is the segment between its outer
// corners: here both ends lie in two far cubes and the segment runs through the gap.
TEST(CheckContainment, DegenerateTrianglePokingOutIsCaught) {
  const TriangleMesh two = merged(testing::unit_cube(), transformed(testing::unit_cube(), 1, {3, 0, 0}));
  TriangleMesh needle;
  needle.positions = {{0.5, 0.5, 0.5}, {3.5, 0.5, 0.5}, {0.6, 0.5, 0.5}};
  needle.triangles = {{0, 1, 2}};
  const Containment result = check_containment(two, needle);
  EXPECT_EQ(result.vertices_outside, 0u);
  EXPECT_EQ(result.triangles_touching, 1u);
  EXPECT_FALSE(result.contained());
  // A degenerate triangle with repeated corners inside one cube is a segment inside it.
  TriangleMesh short_needle;
  short_needle.positions = {{0.2, 0.5, 0.5}, {0.8, 0.5, 0.5}};
  short_needle.triangles = {{0, 1, 1}};
  EXPECT_TRUE(check_containment(two, short_needle).contained());
  EXPECT_EQ(find_crossing_triangles(two, needle).size(), 4u);  // the segment leaves and enters through two faces each
}

// Many small convex parts (one box per component) holding as many small meshes that each
// touch their box: every touching triangle is proved in its own part, without locating
// every vertex in every part.
TEST(CheckContainment, TenThousandConvexPartsEachHoldTheirComponent) {
  TriangleMesh boxes, contents;
  for (int i = 0; i < 10000; ++i) {
    const Vertex offset(2.0 * (i % 100), 2.0 * (i / 100), 0);
    append_mesh(boxes, transformed(testing::unit_cube(), 1, offset));
    append_mesh(contents, transformed(testing::tetrahedron(), 0.9, offset));  // its corners lie on the cube's faces
  }
  const Containment result = check_containment(boxes, contents);
  EXPECT_TRUE(result.contained());
  EXPECT_EQ(result.triangles_touching, 40000u);
  EXPECT_EQ(result.triangles_in_convex_parts, 40000u);
  // One tetrahedron grown so that a corner leaves its box.
  TriangleMesh grown = contents;
  for (VertexIndex v = 0; v < 4; ++v) grown.positions[v] *= 1.2;
  EXPECT_EQ(check_containment(boxes, grown).vertices_outside, 3u);
}

// The planes pass over whole boxes of points at once; a box passed on the wrong side would
// hide a point beyond a plane. Points on the planes, one ulp off them either way, face
// centroids rounded either way, vertices and inner points, on a hull of many faces near
// the origin, far from it with small features, and at tiny scale: the marks must be those
// of every plane tested against every point, one by one.
TEST(BeyondFacePlanes, AgreesWithEveryPlaneTestedOneByOne) {
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  struct Case {
    double scale;
    Vertex offset;
  };
  for (const Case& c : {Case{1, Vertex::Zero()}, Case{1e-3, Vertex(1e8, -3e7, 2e6)}, Case{1e-200, Vertex(1e-199, 0, 0)}}) {
    const TriangleMesh hull = cgal_convex_hull(torus(40, 16, c.scale, c.offset));
    ASSERT_GT(hull.triangles.size(), 300u);
    std::vector<Vertex> points = torus(40, 16, c.scale, c.offset).positions;
    Random random(7);
    for (const Triangle& t : hull.triangles) {
      const Vertex& a = hull.positions[t[0]];
      const Vertex centroid = (a + hull.positions[t[1]] + hull.positions[t[2]]) / 3;
      points.push_back(centroid);
      for (int axis = 0; axis < 3; ++axis)
        for (const double toward : {-1e300, 1e300}) {
          Vertex nudged = a;
          nudged[axis] = std::nextafter(nudged[axis], toward);
          points.push_back(nudged);
        }
      points.push_back(c.offset + 0.9 * (centroid - c.offset) * random.uniform());
    }
    const std::vector<std::uint8_t> marks = beyond_face_planes(hull, points);
    ASSERT_EQ(marks.size(), points.size());
    std::size_t beyond = 0, behind = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const Kernel::Point_3 p(points[i].x(), points[i].y(), points[i].z());
      bool expected = false;
      for (const Triangle& t : hull.triangles) {
        const Kernel::Point_3 a(hull.positions[t[0]].x(), hull.positions[t[0]].y(), hull.positions[t[0]].z());
        const Kernel::Point_3 b(hull.positions[t[1]].x(), hull.positions[t[1]].y(), hull.positions[t[1]].z());
        const Kernel::Point_3 d(hull.positions[t[2]].x(), hull.positions[t[2]].y(), hull.positions[t[2]].z());
        if (!CGAL::collinear(a, b, d) && CGAL::orientation(a, b, d, p) == CGAL::POSITIVE) {
          expected = true;
          break;
        }
      }
      ASSERT_EQ(marks[i] != 0, expected) << "point " << i << " at scale " << c.scale;
      (expected ? beyond : behind) += 1;
    }
    // Both answers occur, many of them: the test can tell a wrong mark from a right one.
    EXPECT_GT(beyond, hull.triangles.size());
    EXPECT_GT(behind, hull.triangles.size());
  }
}

// A convex hull of thousands of faces around a torus of 80 000 triangles that touches it
// along whole rings: every touching triangle is proved in the one convex part. The same
// hull with one vertex of its flat top cap raised by one ulp is no longer convex: the cap
// triangles at that vertex tilt up about a diagonal, so the cap's far vertices lie beyond
// their planes by far less than any box the planes pass over. The mesh's vertices are
// still inside, but the triangles touching the hull are then unproved.
TEST(CheckContainment, LargeConvexHullHoldsTheTorusItTouches) {
  const TriangleMesh mesh = torus(400, 100);
  TriangleMesh hull = cgal_convex_hull(mesh);
  ASSERT_GT(hull.triangles.size(), 20000u);
  const Containment held = check_containment(hull, mesh);
  EXPECT_TRUE(held.contained());
  EXPECT_TRUE(held.convex_container);  // decided by the planes alone
  EXPECT_GT(held.triangles_touching, 1000u);
  EXPECT_EQ(held.triangles_in_convex_parts, held.triangles_touching);
  // The triangles it counts as touching (a corner on the surface) are those that meet a
  // hull triangle, exactly.
  std::vector<std::uint32_t> meeting;
  for (const auto& pair : find_crossing_triangles(hull, mesh)) meeting.push_back(pair.second);
  std::sort(meeting.begin(), meeting.end());
  EXPECT_EQ(held.triangles_touching, static_cast<std::size_t>(std::unique(meeting.begin(), meeting.end()) - meeting.begin()));
  // One mesh vertex on the hull moved out by one ulp: found, named, and the proof fails.
  TriangleMesh pushed = mesh;
  VertexIndex outermost = 0;
  for (VertexIndex v = 0; v < pushed.positions.size(); ++v)
    if (pushed.positions[v].x() > pushed.positions[outermost].x()) outermost = v;
  pushed.positions[outermost].x() = std::nextafter(pushed.positions[outermost].x(), 2.0);
  const Containment out = check_containment(hull, pushed);
  EXPECT_FALSE(out.contained());
  EXPECT_FALSE(out.convex_container);
  EXPECT_EQ(out.vertices_outside, 1u);
  ASSERT_TRUE(out.first_vertex_outside.has_value());
  EXPECT_EQ(*out.first_vertex_outside, outermost);
  // The cap vertex (z at its highest) in the fewest cap triangles: not the centre of a fan.
  double top = -1;
  for (const Vertex& p : hull.positions) top = std::max(top, p.z());
  std::vector<int> cap_triangles(hull.positions.size(), 0);
  for (const Triangle& t : hull.triangles)
    if (hull.positions[t[0]].z() == top && hull.positions[t[1]].z() == top && hull.positions[t[2]].z() == top)
      for (const VertexIndex v : t) ++cap_triangles[v];
  std::size_t raised = hull.positions.size();
  for (std::size_t v = 0; v < hull.positions.size(); ++v)
    if (cap_triangles[v] > 0 && (raised == hull.positions.size() || cap_triangles[v] < cap_triangles[raised])) raised = v;
  ASSERT_LT(raised, hull.positions.size());
  hull.positions[raised].z() = std::nextafter(top, 1.0);
  const Containment bent = check_containment(hull, mesh);
  EXPECT_EQ(bent.vertices_outside, 0u);
  EXPECT_GT(bent.triangles_unproved, 0u);
  EXPECT_FALSE(bent.contained());
}

TEST(LocatePoints, CoordinatesTooLargeToSquareAreRefused) {
  TriangleMesh huge = testing::unit_cube();
  for (Vertex& p : huge.positions) p *= 1e300;
  const std::vector<Vertex> points = {{0.5e300, 0.5e300, 0.5e300}};
  EXPECT_THROW(locate_points(huge, points), InvalidInputError);
  const std::vector<Vertex> far_point = {{1e200, 0, 0}};
  EXPECT_THROW(locate_points(testing::unit_cube(), far_point), InvalidInputError);
  EXPECT_THROW(check_containment(testing::unit_cube(), huge), InvalidInputError);
}

TEST(SurfacesClearBy, TouchingCloseAndApartSurfaces) {
  const TriangleMesh cube = testing::unit_cube();
  EXPECT_FALSE(surfaces_clear_by(cube, cube, 0.0));  // they meet
  const TriangleMesh apart = transformed(testing::unit_cube(), 1, {1.5, 0, 0});  // 0.5 apart
  EXPECT_TRUE(surfaces_clear_by(cube, apart, 0.49));
  EXPECT_FALSE(surfaces_clear_by(cube, apart, 0.51));
  // Edge against edge: a cube turned 45 degrees about z whose vertical edge comes 0.25
  // from the first cube's face x = 1 at mid-height.
  TriangleMesh turned = testing::unit_cube();
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(0.25 * 3.14159265358979323846, Vertex::UnitZ()).toRotationMatrix();
  for (Vertex& p : turned.positions) p = rotation * (p - Vertex(0.5, 0.5, 0.5)) + Vertex(1.25 + std::sqrt(0.5), 0.5, 0.5);
  EXPECT_TRUE(surfaces_clear_by(cube, turned, 0.24));
  EXPECT_FALSE(surfaces_clear_by(cube, turned, 0.26));
  // A degenerate triangle (a segment) 0.1 above the top face.
  TriangleMesh segment;
  segment.positions = {{0.2, 0.5, 1.1}, {0.8, 0.5, 1.1}, {0.5, 0.5, 1.1}};
  segment.triangles = {{0, 1, 2}};
  EXPECT_TRUE(surfaces_clear_by(segment, cube, 0.09));
  EXPECT_FALSE(surfaces_clear_by(segment, cube, 0.11));
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
