#pragma once
// Inputs that break naive proxy builders, built in code.

#include "visproxy/mesh/triangle_mesh.h"
#include "test_meshes.h"

namespace visproxy::testing {

inline TriangleMesh single_triangle() {
  TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0.2, 0.7, 0}};
  mesh.triangles = {{0, 1, 2}};
  return mesh;
}

/// n × n quads in the plane z = 0.3, two triangles each: every corner coplanar.
inline TriangleMesh flat_grid(int n) {
  TriangleMesh mesh;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) mesh.positions.emplace_back(i / double(n), j / double(n), 0.3);
  auto at = [n](int i, int j) { return static_cast<VertexIndex>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      mesh.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      mesh.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  return mesh;
}

/// The unit cube and a copy 50 units away along x.
inline TriangleMesh two_far_cubes() {
  TriangleMesh mesh = unit_cube();
  const TriangleMesh cube = unit_cube();
  const auto offset = static_cast<VertexIndex>(mesh.positions.size());
  for (const Vertex& p : cube.positions) mesh.positions.push_back(p + Vertex(50, 0, 0));
  for (const Triangle& t : cube.triangles) mesh.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  return mesh;
}

/// Every triangle with its own three vertices: a soup with duplicated positions.
inline TriangleMesh unwelded(const TriangleMesh& mesh) {
  TriangleMesh soup;
  for (const Triangle& t : mesh.triangles) {
    const auto first = static_cast<VertexIndex>(soup.positions.size());
    for (const VertexIndex v : t) soup.positions.push_back(mesh.positions[v]);
    soup.triangles.push_back({first, first + 1, first + 2});
  }
  return soup;
}

/// The unit cube with a zero-area triangle sticking out of it (corners on one line, from
/// the cube's centre to 1.5 units beyond a face) and a triangle that is a single point
/// (repeated index) outside the cube.
inline TriangleMesh cube_with_degenerate_triangles() {
  TriangleMesh mesh = unit_cube();
  const auto first = static_cast<VertexIndex>(mesh.positions.size());
  mesh.positions.emplace_back(0.5, 0.5, 0.5);
  mesh.positions.emplace_back(0.5, 0.5, 1.25);
  mesh.positions.emplace_back(0.5, 0.5, 2.5);
  mesh.positions.emplace_back(-0.8, 0.5, 0.5);
  mesh.triangles.push_back({first, first + 1, first + 2});
  mesh.triangles.push_back({first + 3, first + 3, first + 3});
  return mesh;
}

}  // namespace visproxy::testing
