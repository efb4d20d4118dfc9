#include "mesh/triangle_mesh.h"

namespace visproxy {

BoundingBox bounding_box(const TriangleMesh& mesh) {
  std::vector<bool> used(mesh.positions.size(), false);
  BoundingBox box;
  for (const Triangle& triangle : mesh.triangles)
    for (const VertexIndex index : triangle)
      if (!used[index]) {
        used[index] = true;
        box.extend(mesh.positions[index]);
      }
  return box;
}

std::vector<Vertex> used_positions(const TriangleMesh& mesh) {
  std::vector<std::uint8_t> used(mesh.positions.size(), 0);
  for (const Triangle& t : mesh.triangles)
    for (VertexIndex v : t) used[v] = 1;
  std::vector<Vertex> points;
  for (std::size_t v = 0; v < used.size(); ++v)
    if (used[v]) points.push_back(mesh.positions[v]);
  return points;
}

void append_mesh(TriangleMesh& mesh, const TriangleMesh& part) {
  const auto base = static_cast<VertexIndex>(mesh.positions.size());
  mesh.positions.insert(mesh.positions.end(), part.positions.begin(), part.positions.end());
  mesh.triangles.reserve(mesh.triangles.size() + part.triangles.size());
  for (const Triangle& t : part.triangles) mesh.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
}

}  // namespace visproxy
