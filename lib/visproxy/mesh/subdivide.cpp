#include "visproxy/mesh/subdivide.h"

#include <algorithm>
#include <cassert>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "visproxy/core/errors.h"

namespace visproxy {
namespace {

constexpr std::uint64_t kMaxIndexCount = std::numeric_limits<VertexIndex>::max();

TriangleMesh subdivide_once(const TriangleMesh& mesh) {
  // Undirected edges as (low << 32 | high) with the half-edge slot they came from, sorted so
  // that equal edges are adjacent: one midpoint per distinct edge.
  const std::size_t triangle_count = mesh.triangles.size();
  std::vector<std::pair<std::uint64_t, std::uint32_t>> edges;
  edges.reserve(3 * triangle_count);
  for (std::size_t t = 0; t < triangle_count; ++t)
    for (int c = 0; c < 3; ++c) {
      const VertexIndex a = mesh.triangles[t][c], b = mesh.triangles[t][(c + 1) % 3];
      const std::uint64_t key = (std::uint64_t{std::min(a, b)} << 32) | std::max(a, b);
      edges.emplace_back(key, static_cast<std::uint32_t>(3 * t + static_cast<std::size_t>(c)));
    }
  std::sort(edges.begin(), edges.end());

  TriangleMesh result;
  result.positions = mesh.positions;
  std::vector<VertexIndex> midpoint(3 * triangle_count);  // per half-edge slot
  for (std::size_t i = 0; i < edges.size();) {
    const std::uint64_t key = edges[i].first;
    const auto low = static_cast<VertexIndex>(key >> 32), high = static_cast<VertexIndex>(key & 0xffffffffu);
    VertexIndex middle = low;
    if (low != high) {
      if (result.positions.size() >= kMaxIndexCount)
        throw InvalidInputError("", "midpoint subdivision would make more than 2^32 - 1 vertices");
      middle = static_cast<VertexIndex>(result.positions.size());
      result.positions.push_back((mesh.positions[low] + mesh.positions[high]) / 2);
    }
    for (; i < edges.size() && edges[i].first == key; ++i) midpoint[edges[i].second] = middle;
  }

  result.triangles.reserve(4 * triangle_count);
  for (std::size_t t = 0; t < triangle_count; ++t) {
    const Triangle& tri = mesh.triangles[t];
    const VertexIndex m01 = midpoint[3 * t], m12 = midpoint[3 * t + 1], m20 = midpoint[3 * t + 2];
    result.triangles.push_back({tri[0], m01, m20});
    result.triangles.push_back({m01, tri[1], m12});
    result.triangles.push_back({m20, m12, tri[2]});
    result.triangles.push_back({m01, m12, m20});
  }
  return result;
}

}  // namespace

TriangleMesh subdivide_midpoint(const TriangleMesh& mesh, int levels) {
  assert(levels >= 0);
  for (const Triangle& triangle : mesh.triangles)
    for (const VertexIndex v : triangle)
      if (v >= mesh.positions.size())
        throw InvalidInputError("", "triangle corner " + std::to_string(v) + " is out of range (" +
                                        std::to_string(mesh.positions.size()) + " vertices)");
  std::uint64_t triangles = mesh.triangles.size();
  for (int level = 0; level < levels; ++level) {
    triangles *= 4;
    if (triangles > kMaxIndexCount)
      throw InvalidInputError("", "midpoint subdivision would make more than 2^32 - 1 triangles");
  }
  TriangleMesh result = mesh;
  for (int level = 0; level < levels; ++level) result = subdivide_once(result);
  return result;
}

}  // namespace visproxy
