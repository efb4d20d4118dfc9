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

}  // namespace visproxy
