#pragma once
// Where the trace tests put a mesh to try single-precision structures against double
// coordinates: in place, far from the origin, and tiny far from the origin; and the list of
// every triangle their structures take.

#include <array>
#include <cstdint>
#include <numeric>
#include <vector>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy::testing {

struct Placement {
  const char* name;
  double scale;
  Vertex offset;
};

inline const std::array<Placement, 3> kPlacements = {{{"in place", 1.0, Vertex::Zero()},
                                                      {"10^6 away", 1.0, Vertex(1e6, -2e6, 5e5)},
                                                      {"10^-6 of its size, 10^3 away", 1e-6, Vertex(1e3, 0, -1e3)}}};

/// The mesh scaled and moved as `placement` says.
inline TriangleMesh placed(TriangleMesh mesh, const Placement& placement) {
  for (Vertex& p : mesh.positions) p = placement.scale * p + placement.offset;
  return mesh;
}

inline std::vector<std::uint32_t> every_triangle(const TriangleMesh& mesh) {
  std::vector<std::uint32_t> all(mesh.triangles.size());
  std::iota(all.begin(), all.end(), 0u);
  return all;
}

}  // namespace visproxy::testing
