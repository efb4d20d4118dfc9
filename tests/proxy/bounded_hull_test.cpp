#include "visproxy/proxy/bounded_hull.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>

#include "visproxy/core/errors.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/proxy/convex_hull.h"
#include "visproxy/verify/containment.h"
#include "proxy/hull_test_support.h"
#include "test_meshes.h"
#include "test_support.h"

namespace visproxy {
namespace {

using testing::contains_every_vertex;
using testing::is_closed_polytope_surface;

void expect_throws_saying(const TriangleMesh& mesh, std::size_t max_faces, const std::string& words) {
  try {
    build_bounded_hull(mesh, {.max_faces = max_faces});
    ADD_FAILURE() << "no InvalidInputError";
  } catch (const InvalidInputError& error) {
    EXPECT_NE(std::string(error.what()).find(words), std::string::npos) << error.what();
  }
}

// The invariants every result must have.
void expect_valid(const BoundedHullResult& result, const TriangleMesh& input, std::size_t max_faces) {
  EXPECT_LE(result.faces, max_faces);
  EXPECT_GE(result.faces, 4u);
  EXPECT_TRUE(is_closed_polytope_surface(result.mesh));
  EXPECT_TRUE(contains_every_vertex(result.mesh, input));
  // Convex up to the rounding of corners: relative to the extent and to the coordinates' size.
  const BoundingBox box = bounding_box(input);
  const double magnitude = std::max(box.min.cwiseAbs().maxCoeff(), box.max.cwiseAbs().maxCoeff());
  EXPECT_TRUE(testing::is_convex_within(result.mesh, 1e-9 * (box.diagonal() + magnitude)));
  EXPECT_GE(result.volume, result.exact_hull_volume);
}

TriangleMesh translated(TriangleMesh mesh, const Vertex& offset) {
  for (Vertex& p : mesh.positions) p += offset;
  return mesh;
}

TEST(BoundedHull, FewerThanFourFacesIsAnError) {
  expect_throws_saying(testing::tetrahedron(), 3, "at least 4");
  expect_throws_saying(testing::tetrahedron(), 0, "at least 4");
}

TEST(BoundedHull, NothingToHullIsAnError) {
  expect_throws_saying(TriangleMesh{}, 32, "no triangles");
  TriangleMesh collinear;
  collinear.positions = {{0, 0, 0}, {1, 2, 3}, {2, 4, 6}};
  collinear.triangles = {{0, 1, 2}};
  expect_throws_saying(collinear, 32, "one line");
}

TEST(BoundedHull, HullWithFewEnoughFacesIsReturnedExactly) {
  const BoundedHullResult cube = build_bounded_hull(testing::unit_cube(), {.max_faces = 6});
  EXPECT_EQ(cube.faces, 6u);
  EXPECT_EQ(cube.volume, 1.0);
  EXPECT_EQ(cube.exact_hull_volume, 1.0);
  EXPECT_EQ(cube.added_volume_fraction(), 0.0);
  EXPECT_EQ(cube.mesh, build_convex_hull(testing::unit_cube()).mesh);

  const BoundedHullResult tetrahedron = build_bounded_hull(testing::tetrahedron(), {.max_faces = 4});
  EXPECT_EQ(tetrahedron.faces, 4u);
  EXPECT_EQ(tetrahedron.volume, 1.0 / 6.0);

  const TriangleMesh knot = read_mesh(testing::cgal_mesh("knot1.off"));
  const BoundedHullResult loose = build_bounded_hull(knot, {.max_faces = 100000});
  const ConvexHullResult exact = build_convex_hull(knot);
  EXPECT_EQ(loose.mesh, exact.mesh);
  EXPECT_EQ(loose.faces, exact.faces);
}

TEST(BoundedHull, BoxAskedForFiveFacesIsAnError) {
  // Removing any face of a box leaves an unbounded slab: no smaller set of its planes bounds it.
  expect_throws_saying(testing::unit_cube(), 5, "unbounded");
}

TEST(BoundedHull, ChamferedCubeLosesItsChamferFirst) {
  // The unit cube with corner (1, 1, 1) cut off by x + y + z <= 2.5: 7 faces. Removing the
  // chamfer adds 1/48; removing any cube face adds far more (or unbounds it).
  TriangleMesh chamfered;
  for (int i = 0; i < 7; ++i) chamfered.positions.emplace_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  chamfered.positions.insert(chamfered.positions.end(), {{1, 1, 0.5}, {1, 0.5, 1}, {0.5, 1, 1}});
  for (VertexIndex i = 1; i + 1 < chamfered.positions.size(); ++i) chamfered.triangles.push_back({0, i, i + 1});
  const BoundedHullResult result = build_bounded_hull(chamfered, {.max_faces = 6});
  expect_valid(result, chamfered, 6);
  EXPECT_EQ(result.faces, 6u);
  EXPECT_DOUBLE_EQ(result.exact_hull_volume, 1.0 - 1.0 / 48.0);
  EXPECT_NEAR(result.volume, 1.0, 1e-12);  // corners rounded and pushed out by a few ulps at most
  EXPECT_EQ(result.mesh.positions.size(), 8u);
}

TEST(BoundedHull, FlatInputIsItsPolygonWhenFewEnoughEdges) {
  TriangleMesh triangle;
  triangle.positions = {{0.1, 0.2, 0.3}, {1.7, -0.4, 0.9}, {0.5, 2.5, -1.1}};
  triangle.triangles = {{0, 1, 2}};
  const BoundedHullResult result = build_bounded_hull(triangle, {.max_faces = 4});
  EXPECT_EQ(result.faces, 2u);
  EXPECT_EQ(result.volume, 0.0);
  EXPECT_EQ(result.added_volume_fraction(), 0.0);
  EXPECT_TRUE(is_closed_polytope_surface(result.mesh));
  EXPECT_TRUE(contains_every_vertex(result.mesh, triangle));
}

TEST(BoundedHull, FlatInputWithTooManyEdgesIsAnError) {
  // 12 points on a circle-like convex polygon in z = 0: a 12-gon asked for at most 8 edges.
  TriangleMesh flat;
  const std::array<std::array<int, 2>, 12> corners{
      {{4, 0}, {3, 2}, {2, 3}, {0, 4}, {-2, 3}, {-3, 2}, {-4, 0}, {-3, -2}, {-2, -3}, {0, -4}, {2, -3}, {3, -2}}};
  for (const auto& c : corners) flat.positions.emplace_back(c[0], c[1], 0.0);
  for (VertexIndex i = 1; i + 1 < flat.positions.size(); ++i) flat.triangles.push_back({0, i, i + 1});
  expect_throws_saying(flat, 8, "flat");
  EXPECT_EQ(build_bounded_hull(flat, {.max_faces = 12}).faces, 2u);
}

TEST(BoundedHull, TwoFarApartComponents) {
  const TriangleMesh knot = read_mesh(testing::cgal_mesh("knot1.off"));
  const double diagonal = bounding_box(knot).diagonal();
  TriangleMesh two = knot;
  const TriangleMesh far = translated(knot, Vertex(10.0 * diagonal, 3.0 * diagonal, 0.0));
  const auto base = static_cast<VertexIndex>(two.positions.size());
  two.positions.insert(two.positions.end(), far.positions.begin(), far.positions.end());
  for (const Triangle& t : far.triangles) two.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  for (const std::size_t n : {18u, 6u}) expect_valid(build_bounded_hull(two, {.max_faces = n}), two, n);
}

TEST(BoundedHull, FarFromTheOrigin) {
  const TriangleMesh armadillo = read_mesh(testing::cgal_mesh("armadillo.off"));
  const double diagonal = bounding_box(armadillo).diagonal();
  const TriangleMesh far = translated(armadillo, Vertex(1e4 * diagonal, -3e3 * diagonal, 7e3 * diagonal));
  for (const std::size_t n : {32u, 6u}) expect_valid(build_bounded_hull(far, {.max_faces = n}), far, n);
}

// A box whose top edges carry hundreds of points (a fan of slivers on its top face), turned
// into tilted frames: rounding moves the edge points off their lines, and the exact hull
// gets sliver facets with no plane double precision can give. They are left out (the
// result is checked exactly); before, 87 of 200 such boxes were refused as "too thin".
TEST(BoundedHull, TiltedBoxesWithPointsAlongTheirEdges) {
  for (int trial = 0; trial < 40; ++trial) {
    TriangleMesh box = testing::sliver_fan_box(Vertex(0.6 + 0.03 * trial, 1.4 - 0.02 * trial, 0.3 + 0.01 * trial), 40 + 35 * trial);
    const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.3 + 0.17 * trial, Vertex(1, 0.3 * trial, 2 - 0.05 * trial).normalized()).toRotationMatrix();
    for (Vertex& p : box.positions) p = turn * p;
    for (const std::size_t faces : {6u, 8u, 12u}) {
      const BoundedHullResult hull = build_bounded_hull(box, {.max_faces = faces});
      EXPECT_LE(hull.faces, faces) << "trial " << trial;
      EXPECT_TRUE(contains_every_vertex(hull.mesh, box)) << "trial " << trial;
      EXPECT_TRUE(is_closed_polytope_surface(hull.mesh)) << "trial " << trial;
    }
  }
}

TEST(BoundedHull, TriangleSoupGivesTheSameBound) {
  // Every triangle with its own three vertices: the same point set, many times over.
  const TriangleMesh knot = read_mesh(testing::cgal_mesh("knot2.off"));
  TriangleMesh soup;
  for (const Triangle& t : knot.triangles) {
    const auto base = static_cast<VertexIndex>(soup.positions.size());
    for (const VertexIndex v : t) soup.positions.push_back(knot.positions[v]);
    soup.triangles.push_back({base, base + 1, base + 2});
  }
  const BoundedHullResult welded = build_bounded_hull(knot, {.max_faces = 18});
  const BoundedHullResult unwelded = build_bounded_hull(soup, {.max_faces = 18});
  expect_valid(unwelded, soup, 18);
  EXPECT_EQ(unwelded.faces, welded.faces);
  EXPECT_NEAR(unwelded.volume, welded.volume, 1e-9 * welded.volume);
}

TEST(BoundedHull, NonManifoldInput) {
  const TriangleMesh pig = read_mesh(testing::cgal_mesh("pig.stl"));
  expect_valid(build_bounded_hull(pig, {.max_faces = 18}), pig, 18);
}

// A prism of 40 sides, tilted: its hull has 42 faces, and hull:32 keeps the two caps, planes
// the mesh's own cap triangles lie in, so the mesh lies against the kept planes; verify's
// exact check, as a user runs it, must hold at every scale and far from the origin. (Each
// corner here has three planes only; the corners where many meet, which broke the check
// before the planes were kept strictly off the mesh, are the next test's.)
TEST(BoundedHull, PlanesThroughTheMeshsOwnFacesStillVerify) {
  for (const double scale : {1.0, 1e-3, 1e4}) {
    for (const Vertex& offset : {Vertex(0, 0, 0), Vertex(2.5e5, -1.25e5, 3e4)}) {
      SCOPED_TRACE("scale " + std::to_string(scale) + ", offset " + std::to_string(offset.x()));
      constexpr int kSides = 40;
      // Tilted, so that no plane is an axis plane whose corners round onto it exactly.
      const Eigen::Matrix3d tilt = Eigen::AngleAxisd(0.7, Vertex(1, 2, 3).normalized()).toRotationMatrix();
      auto place = [&](const Vertex& p) { return Vertex(offset + scale * (tilt * p)); };
      TriangleMesh prism;
      for (int z = 0; z < 2; ++z)
        for (int i = 0; i < kSides; ++i) {
          const double angle = 2 * 3.14159265358979323846 * i / kSides + 0.1;
          prism.positions.push_back(place(Vertex(std::cos(angle), std::sin(angle) * 0.7, 0.37 * z)));
        }
      const auto bottom_centre = static_cast<std::uint32_t>(prism.positions.size());
      prism.positions.push_back(place(Vertex(0, 0, 0)));
      prism.positions.push_back(place(Vertex(0, 0, 0.37)));
      for (std::uint32_t i = 0; i < kSides; ++i) {
        const std::uint32_t j = (i + 1) % kSides;
        prism.triangles.push_back({i, j, j + kSides});
        prism.triangles.push_back({i, j + kSides, i + kSides});
        prism.triangles.push_back({bottom_centre, j, i});
        prism.triangles.push_back({bottom_centre + 1, i + kSides, j + kSides});
      }
      const BoundedHullResult result = build_bounded_hull(prism, {.max_faces = 32});
      ASSERT_LE(result.faces, 32u);
      const Containment proof = check_containment(result.mesh, prism, {.check_surface = true});
      EXPECT_TRUE(proof.contained()) << proof.vertices_outside << " vertices outside, " << proof.triangles_touching
                                     << " triangles touching";
      EXPECT_LT(result.added_volume_fraction(), 0.05);
    }
  }
}

// Two of libcgal-demo's meshes whose hull:32 failed verify before its planes were kept off
// the mesh's vertices: many planes meet at their corners, and the rounded corners left
// sliver triangles touching the mesh's faces.
TEST(BoundedHull, CgalMeshesWhosePlanesMeetManyAtACornerVerify) {
  for (const char* name : {"tripod.off", "three_peaks.off"}) {
    SCOPED_TRACE(name);
    const TriangleMesh mesh = read_mesh(testing::cgal_mesh(name));
    ASSERT_GT(build_convex_hull(mesh).faces, 32u);  // else the exact hull is returned
    const BoundedHullResult result = build_bounded_hull(mesh, {.max_faces = 32});
    const Containment proof = check_containment(result.mesh, mesh, {.check_surface = true});
    EXPECT_TRUE(proof.contained()) << proof.vertices_outside << " vertices outside, " << proof.triangles_touching
                                   << " triangles touching";
    EXPECT_EQ(proof.vertices_on_boundary, 0u);
  }
}

TEST(BoundedHull, IsDeterministic) {
  const TriangleMesh mesh = read_mesh(testing::cgal_mesh("armadillo.off"));
  const BoundedHullResult first = build_bounded_hull(mesh, {.max_faces = 18});
  const BoundedHullResult second = build_bounded_hull(mesh, {.max_faces = 18});
  EXPECT_EQ(first.mesh, second.mesh);
  EXPECT_EQ(first.faces, second.faces);
  EXPECT_EQ(first.volume, second.volume);
}

// Volume added over the exact hull at 64, 32, 18 and 6 faces, as measured on this code
// (x86-64, GCC 12, RelWithDebInfo), each bound about 25 % above the measured figure so that
// another compiler's rounding cannot fail it while a real loss of tightness does.
// For comparison, Jacobson (arXiv:2604.14468) reports under 5 % at 18 faces on his shapes.
struct AddedVolumeBounds {
  std::string mesh;
  std::array<double, 4> measured;  // at 64, 32, 18, 6 faces
  std::array<double, 4> bound;
};

const AddedVolumeBounds added_volume_table[] = {
    {"bunny00.off", {0.0043, 0.0146, 0.0403, 0.4477}, {0.0055, 0.0185, 0.050, 0.56}},
    {"armadillo.off", {0.0016, 0.0066, 0.0234, 0.2968}, {0.0020, 0.0085, 0.030, 0.37}},
    {"knot1.off", {0.0113, 0.0288, 0.0654, 0.6687}, {0.0145, 0.036, 0.082, 0.84}},
    {"knot2.off", {0.0094, 0.0290, 0.0694, 0.6097}, {0.012, 0.036, 0.087, 0.77}},
    {"ChineseDragon-10kv.off", {0.0042, 0.0156, 0.0401, 0.3040}, {0.0055, 0.020, 0.050, 0.38}},
    {"elephant-with-holes.off", {0.0013, 0.0055, 0.0200, 0.3542}, {0.0017, 0.007, 0.025, 0.45}},
    // The sphere's many equal-cost ties make its coarse results depend on the last bits of
    // the planes (1.16 to 1.47 at 6 faces over small changes to this code): a wider bound.
    {"sphere.ply", {0.0438, 0.1035, 0.2166, 1.4020}, {0.055, 0.13, 0.28, 1.8}},
};

class BoundedHullOfRealMesh : public ::testing::TestWithParam<AddedVolumeBounds> {};

TEST_P(BoundedHullOfRealMesh, ContainsEveryVertexWithLittleAddedVolume) {
  const AddedVolumeBounds& row = GetParam();
  const TriangleMesh mesh = read_mesh(testing::cgal_mesh(row.mesh));
  const double exact_volume = build_convex_hull(mesh).volume;
  const std::array<std::size_t, 4> face_counts{64, 32, 18, 6};
  std::string line;
  for (std::size_t i = 0; i < face_counts.size(); ++i) {
    SCOPED_TRACE("max_faces " + std::to_string(face_counts[i]));
    const BoundedHullResult result = build_bounded_hull(mesh, {.max_faces = face_counts[i]});
    expect_valid(result, mesh, face_counts[i]);
    EXPECT_EQ(result.exact_hull_volume, exact_volume);
    EXPECT_LE(result.added_volume_fraction(), row.bound[i]);
    char cell[64];
    std::snprintf(cell, sizeof cell, "  %2zu faces %+7.2f %%", result.faces, 100.0 * result.added_volume_fraction());
    line += cell;
  }
  std::printf("added volume %-24s%s\n", row.mesh.c_str(), line.c_str());
}

INSTANTIATE_TEST_SUITE_P(CgalDemo, BoundedHullOfRealMesh, ::testing::ValuesIn(added_volume_table),
                         [](const auto& test) { return testing::test_name_from(test.param.mesh); });

}  // namespace
}  // namespace visproxy
