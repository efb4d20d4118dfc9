#pragma once
// Small meshes built in code, with answers known exactly, and paths of the real meshes
// extracted from Debian's libcgal-demo package.

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <vector>
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
/// A closed box [0, size] whose top face (z = size.z) is a fan of about `fan` sliver
/// triangles from the corner (0, 0, top) to points along the two far edges, unevenly
/// spaced; the side faces under those edges are fans too, so that every edge is used once
/// each way. Embree's float normal of such slivers can tilt far from their plane.
inline TriangleMesh sliver_fan_box(const Vertex& size, int fan) {
  const double a = size.x(), b = size.y(), c = size.z();
  TriangleMesh mesh;
  auto add = [&](const Vertex& p) {
    mesh.positions.push_back(p);
    return static_cast<VertexIndex>(mesh.positions.size() - 1);
  };
  const VertexIndex b000 = add({0, 0, 0}), b100 = add({a, 0, 0}), b110 = add({a, b, 0}), b010 = add({0, b, 0});
  const VertexIndex apex = add({0, 0, c});
  const int half = std::max(2, fan / 2);
  std::vector<VertexIndex> along_x, along_y;  // top edge points on x = a, then on y = b
  for (int i = 0; i <= half; ++i) {
    const double s = static_cast<double>(i) / half;
    along_x.push_back(add({a, b * s * s * (3 - 2 * s), c}));
  }
  along_y.push_back(along_x.back());
  for (int i = 1; i <= half; ++i) {
    const double s = static_cast<double>(i) / half;
    along_y.push_back(add({a * (1 - s * s * (3 - 2 * s)), b, c}));
  }
  std::vector<VertexIndex> rim = along_x;
  rim.insert(rim.end(), along_y.begin() + 1, along_y.end());
  for (std::size_t i = 0; i + 1 < rim.size(); ++i) mesh.triangles.push_back({apex, rim[i], rim[i + 1]});
  for (std::size_t i = 0; i + 1 < along_x.size(); ++i) mesh.triangles.push_back({b100, along_x[i], along_x[i + 1]});
  mesh.triangles.push_back({b100, along_x.back(), b110});
  for (std::size_t i = 0; i + 1 < along_y.size(); ++i) mesh.triangles.push_back({b110, along_y[i], along_y[i + 1]});
  mesh.triangles.push_back({b110, along_y.back(), b010});
  mesh.triangles.push_back({b000, b100, along_x.front()});
  mesh.triangles.push_back({b000, along_x.front(), apex});
  mesh.triangles.push_back({b000, b010, along_y.back()});
  mesh.triangles.push_back({b000, along_y.back(), apex});
  mesh.triangles.push_back({b000, b100, b110});
  mesh.triangles.push_back({b000, b110, b010});
  // Every face outward: its normal away from the box's centre (the box is convex).
  const Vertex centre = 0.5 * size;
  for (Triangle& t : mesh.triangles) {
    const Vertex& p = mesh.positions[t[0]];
    const Vertex n = (mesh.positions[t[1]] - p).cross(mesh.positions[t[2]] - p);
    if (n.dot((p + mesh.positions[t[1]] + mesh.positions[t[2]]) / 3 - centre) < 0) std::swap(t[1], t[2]);
  }
  return mesh;
}

/// A closed torus about the z axis (major radius R, tube radius r), `around` x `across`
/// quads split into outward-oriented triangles.
inline TriangleMesh torus(double major, double minor, int around, int across) {
  TriangleMesh mesh;
  const double pi = 3.14159265358979323846;
  for (int i = 0; i < around; ++i)
    for (int j = 0; j < across; ++j) {
      const double u = 2 * pi * i / around, v = 2 * pi * j / across;
      mesh.positions.emplace_back((major + minor * std::cos(v)) * std::cos(u), (major + minor * std::cos(v)) * std::sin(u), minor * std::sin(v));
    }
  auto index = [&](int i, int j) { return static_cast<VertexIndex>((i % around) * across + j % across); };
  for (int i = 0; i < around; ++i)
    for (int j = 0; j < across; ++j) {
      // (i, j) -> (i + 1, j) -> (i + 1, j + 1): counter-clockwise seen from outside the tube.
      mesh.triangles.push_back({index(i, j), index(i + 1, j), index(i + 1, j + 1)});
      mesh.triangles.push_back({index(i, j), index(i + 1, j + 1), index(i, j + 1)});
    }
  return mesh;
}

inline std::filesystem::path cgal_mesh(const std::string& name) {
  return std::filesystem::path(VISPROXY_MESH_DIR) / name;
}

}  // namespace visproxy::testing
