// TriangleBoxTree against scans of every triangle: its single-precision nodes, moved about
// the triangles' centre, must never prune a triangle whose box meets a query's, nor the
// nearest triangle, at the origin or 10^6 away, for meshes far smaller than their distance
// from the origin, and for boxes that only touch.

#include "visproxy/trace/triangle_box_tree.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <vector>

#include "visproxy/core/random.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/trace/triangle_distance.h"
#include "test_meshes.h"
#include "trace/placed_meshes.h"

namespace visproxy {
namespace {

using testing::every_triangle;
using testing::kPlacements;
using testing::Placement;

BoundingBox triangle_box(const TriangleMesh& mesh, std::uint32_t t) {
  BoundingBox box;
  for (const VertexIndex v : mesh.triangles[t]) box.extend(mesh.positions[v]);
  return box;
}

bool boxes_meet(const BoundingBox& a, const BoundingBox& b) {
  return (a.min.array() <= b.max.array()).all() && (b.min.array() <= a.max.array()).all();
}

// The triangles whose boxes meet `query`, found through the tree (pruning nodes by box
// overlap) and sorted.
std::vector<std::uint32_t> found_in(const TriangleBoxTree& tree, const TriangleMesh& mesh, const BoundingBox& query) {
  std::vector<std::uint32_t> found;
  tree.any([&](const BoundingBox& node) { return boxes_meet(node, query); },
           [&](std::uint32_t t) {
             if (boxes_meet(triangle_box(mesh, t), query)) found.push_back(t);
             return false;
           });
  std::sort(found.begin(), found.end());
  return found;
}

std::vector<std::uint32_t> scanned_in(const TriangleMesh& mesh, const BoundingBox& query) {
  std::vector<std::uint32_t> scanned;
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
    if (boxes_meet(triangle_box(mesh, t), query)) scanned.push_back(t);
  return scanned;
}

// Boxes of every size, and boxes that are exactly a triangle's corner: those touch the
// triangle's box only at a double coordinate that single precision cannot hold.
TEST(TriangleBoxTree, FindsEveryTriangleWhoseBoxMeetsTheQuerysAnywhere) {
  const TriangleMesh bunny = read_mesh(testing::cgal_mesh("bunny00.off"));
  for (const Placement& placement : kPlacements) {
    SCOPED_TRACE(placement.name);
    const TriangleMesh mesh = testing::placed(bunny, placement);
    const BoundingBox box = bounding_box(mesh);
    const TriangleBoxTree tree(mesh, every_triangle(mesh));
    ASSERT_EQ(tree.size(), mesh.triangles.size());
    Random random(5);
    std::size_t nonempty = 0;
    for (int i = 0; i < 200; ++i) {
      BoundingBox query;
      if (i % 2 == 0) {
        const Vertex& corner = mesh.positions[random.below(mesh.positions.size())];
        query.extend(corner);  // a point box on a corner
      } else {
        const Vertex centre =
            box.min + Vertex(random.uniform(), random.uniform(), random.uniform()).cwiseProduct(box.max - box.min);
        const Vertex half = 0.05 * random.uniform() * (box.max - box.min);
        query.extend(centre - half);
        query.extend(centre + half);
      }
      const std::vector<std::uint32_t> scanned = scanned_in(mesh, query);
      ASSERT_EQ(found_in(tree, mesh, query), scanned) << "query " << i;
      nonempty += !scanned.empty();
    }
    EXPECT_GE(nonempty, 100u) << "every corner query meets its own triangles";
  }
}

// The nearest point and triangle of a scan, with the scan's tie rule (smallest index):
// points near the surface, inside its box, far outside, and exactly on corners, where every
// triangle around the corner is at distance zero.
TEST(TriangleBoxTree, FindsTheNearestTriangleOfAScanWithItsTieRule) {
  const TriangleMesh bunny = read_mesh(testing::cgal_mesh("bunny00.off"));
  for (const Placement& placement : kPlacements) {
    SCOPED_TRACE(placement.name);
    const TriangleMesh mesh = testing::placed(bunny, placement);
    const BoundingBox box = bounding_box(mesh);
    const double size = box.diagonal();
    const TriangleBoxTree tree(mesh, every_triangle(mesh));
    Random random(13);
    for (int i = 0; i < 400; ++i) {
      const Vertex& v = mesh.positions[random.below(mesh.positions.size())];
      const Vertex unit(random.uniform(), random.uniform(), random.uniform());
      Vertex p = v;  // on a corner
      if (i % 4 == 1) p = v + 1e-3 * size * (unit - Vertex::Constant(0.5));
      if (i % 4 == 2) p = box.min + unit.cwiseProduct(box.max - box.min);
      if (i % 4 == 3) p = box.min + 3 * size * unit - Vertex::Constant(size);
      TriangleBoxTree::Nearest scanned{Vertex::Zero(), 0, std::numeric_limits<double>::infinity()};
      for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
        const Triangle& c = mesh.triangles[t];
        const Vertex q =
            point_triangle_nearest_point(p, mesh.positions[c[0]], mesh.positions[c[1]], mesh.positions[c[2]]);
        if ((p - q).squaredNorm() < scanned.squared_distance) scanned = {q, t, (p - q).squaredNorm()};
      }
      const TriangleBoxTree::Nearest found = tree.nearest(p);
      ASSERT_EQ(found.squared_distance, scanned.squared_distance) << "point " << i;
      ASSERT_EQ(found.triangle, scanned.triangle) << "point " << i;
      ASSERT_EQ(found.point, scanned.point) << "point " << i;
      if (i % 4 == 0) {
        EXPECT_EQ(found.squared_distance, 0.0);
      }
    }
  }
}

// A subset of the triangles, and none: only those given are reported, by their index into
// the mesh.
TEST(TriangleBoxTree, HoldsOnlyTheTrianglesItIsGiven) {
  const TriangleMesh cube = testing::unit_cube();
  const TriangleBoxTree top(cube, {2, 3});  // the two triangles at z = 1
  const TriangleBoxTree::Nearest nearest = top.nearest({0.5, 0.5, -1});
  EXPECT_EQ(nearest.squared_distance, 4.0);
  EXPECT_TRUE(nearest.triangle == 2 || nearest.triangle == 3);
  std::vector<std::uint32_t> seen;
  top.any([](const BoundingBox&) { return true; },
          [&](std::uint32_t t) {
            seen.push_back(t);
            return false;
          });
  std::sort(seen.begin(), seen.end());
  EXPECT_EQ(seen, (std::vector<std::uint32_t>{2, 3}));

  const TriangleBoxTree none(cube, {});
  EXPECT_EQ(none.size(), 0u);
  EXPECT_EQ(none.nearest({0, 0, 0}).squared_distance, std::numeric_limits<double>::infinity());
  EXPECT_FALSE(none.any([](const BoundingBox&) { return true; }, [](std::uint32_t) { return true; }));
}

// A query stops at the first triangle its test accepts.
TEST(TriangleBoxTree, StopsAtTheFirstAcceptedTriangle) {
  const TriangleMesh bunny = read_mesh(testing::cgal_mesh("bunny00.off"));
  const TriangleBoxTree tree(bunny, every_triangle(bunny));
  std::size_t tested = 0;
  EXPECT_TRUE(tree.any([](const BoundingBox&) { return true; },
                       [&](std::uint32_t) {
                         ++tested;
                         return true;
                       }));
  EXPECT_EQ(tested, 1u);
}

}  // namespace
}  // namespace visproxy
