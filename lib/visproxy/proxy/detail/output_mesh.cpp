#include "visproxy/proxy/detail/output_mesh.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <numeric>
#include <vector>

namespace visproxy::detail {

TriangleMesh clean_output_mesh(std::span<const Vertex> positions, std::span<const Triangle> triangles) {
  using Point = CGAL::Exact_predicates_inexact_constructions_kernel::Point_3;
  auto point = [&](VertexIndex v) { return Point(positions[v].x(), positions[v].y(), positions[v].z()); };
  std::vector<Triangle> kept, corners;
  for (const Triangle& tri : triangles) {
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) continue;
    if (CGAL::collinear(point(tri[0]), point(tri[1]), point(tri[2]))) continue;
    kept.push_back(tri);
    corners.push_back(tri);
    std::sort(corners.back().begin(), corners.back().end());
  }
  std::vector<std::uint32_t> order(kept.size());
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&corners](std::uint32_t a, std::uint32_t b) {
    return corners[a] != corners[b] ? corners[a] < corners[b] : a < b;
  });
  std::vector<std::uint8_t> duplicate(kept.size(), 0);
  for (std::size_t i = 1; i < order.size(); ++i)
    if (corners[order[i]] == corners[order[i - 1]]) duplicate[order[i]] = 1;

  constexpr std::uint32_t kUnnumbered = std::numeric_limits<std::uint32_t>::max();
  TriangleMesh mesh;
  std::vector<std::uint32_t> output_index(positions.size(), kUnnumbered);
  for (std::size_t t = 0; t < kept.size(); ++t) {
    if (duplicate[t]) continue;
    Triangle out;
    for (int c = 0; c < 3; ++c) {
      const VertexIndex v = kept[t][c];
      if (output_index[v] == kUnnumbered) {
        output_index[v] = static_cast<std::uint32_t>(mesh.positions.size());
        mesh.positions.push_back(positions[v]);
      }
      out[c] = output_index[v];
    }
    mesh.triangles.push_back(out);
  }
  return mesh;
}

}  // namespace visproxy::detail
