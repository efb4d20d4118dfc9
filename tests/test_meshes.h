#pragma once
// Small meshes built in code, with answers known exactly, and paths of the real meshes
// extracted from Debian's libcgal-demo package.

#include <filesystem>
#include <string>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy::testing {

/// Axis-aligned cube [0,1]^3 as 12 outward-oriented triangles over 8 vertices.
inline TriangleMesh unit_cube() {
  TriangleMesh mesh;
  for (int i = 0; i < 8; ++i) mesh.positions.emplace_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  mesh.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                    {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return mesh;
}

/// Tetrahedron (0,0,0), (1,0,0), (0,1,0), (0,0,1), outward-oriented; volume 1/6.
inline TriangleMesh tetrahedron() {
  TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  mesh.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return mesh;
}

/// Path of a mesh from libcgal-demo's data/meshes, extracted at build time.
inline std::filesystem::path cgal_mesh(const std::string& name) {
  return std::filesystem::path(VISPROXY_MESH_DIR) / name;
}

}  // namespace visproxy::testing
