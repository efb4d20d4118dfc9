#pragma once
// Inputs that break naive simplifiers, and the invariants every general proxy must keep.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <set>
#include <vector>

#include "visproxy/inspect/exact_checks.h"
#include "visproxy/mesh/triangle_mesh.h"
#include "test_meshes.h"

namespace visproxy::testing {

/// One triangle in the plane z = 0.
inline TriangleMesh single_triangle() {
  TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0.25, 1, 0}};
  mesh.triangles = {{0, 1, 2}};
  return mesh;
}

/// An n x n grid of unit squares in the plane z = 0, two triangles each, with a border.
inline TriangleMesh flat_grid(int n) {
  TriangleMesh mesh;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) mesh.positions.emplace_back(i, j, 0);
  const auto at = [n](int i, int j) { return static_cast<VertexIndex>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      mesh.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      mesh.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  return mesh;
}

/// Two unit cubes 1000 apart along x.
inline TriangleMesh two_far_apart_cubes() {
  TriangleMesh mesh = unit_cube();
  const TriangleMesh other = unit_cube();
  const auto offset = static_cast<VertexIndex>(mesh.positions.size());
  for (const Vertex& p : other.positions) mesh.positions.push_back(p + Vertex(1000, 0, 0));
  for (const Triangle& t : other.triangles) mesh.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  return mesh;
}

/// The same surface with every triangle owning three vertices of its own (a soup).
inline TriangleMesh unwelded(const TriangleMesh& mesh) {
  TriangleMesh soup;
  for (const Triangle& t : mesh.triangles) {
    const auto first = static_cast<VertexIndex>(soup.positions.size());
    for (const VertexIndex v : t) soup.positions.push_back(mesh.positions[v]);
    soup.triangles.push_back({first, first + 1, first + 2});
  }
  return soup;
}

/// Triangles as sorted triples of corner positions: compares meshes regardless of numbering.
inline std::multiset<std::array<std::array<double, 3>, 3>> triangle_shapes(const TriangleMesh& mesh) {
  std::multiset<std::array<std::array<double, 3>, 3>> shapes;
  for (const Triangle& t : mesh.triangles) {
    std::array<std::array<double, 3>, 3> corners;
    for (int c = 0; c < 3; ++c) {
      const Vertex& p = mesh.positions[t[c]];
      corners[c] = {p.x(), p.y(), p.z()};
    }
    std::sort(corners.begin(), corners.end());
    shapes.insert(corners);
  }
  return shapes;
}

/// What every proxy mesh must be: finite coordinates, indices in range, every vertex used,
/// no repeated corner, no collinear corners (exact), no two triangles over the same vertices.
inline void expect_clean_mesh(const TriangleMesh& mesh) {
  std::vector<bool> used(mesh.positions.size(), false);
  std::set<std::array<VertexIndex, 3>> corner_sets;
  for (const Triangle& t : mesh.triangles) {
    for (const VertexIndex v : t) {
      ASSERT_LT(v, mesh.positions.size());
      used[v] = true;
    }
    EXPECT_TRUE(t[0] != t[1] && t[1] != t[2] && t[2] != t[0]);
    std::array<VertexIndex, 3> sorted = t;
    std::sort(sorted.begin(), sorted.end());
    EXPECT_TRUE(corner_sets.insert(sorted).second) << "repeated triangle " << t[0] << " " << t[1] << " " << t[2];
  }
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    EXPECT_TRUE(used[v]) << "unreferenced vertex " << v;
    EXPECT_TRUE(mesh.positions[v].allFinite()) << "vertex " << v;
  }
  EXPECT_TRUE(find_degenerate_triangles(mesh).empty());
}

}  // namespace visproxy::testing
