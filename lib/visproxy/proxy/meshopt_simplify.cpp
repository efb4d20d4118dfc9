#include "visproxy/proxy/meshopt_simplify.h"

#include <meshoptimizer.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/proxy/detail/output_mesh.h"

namespace visproxy {

MeshoptSimplifyResult simplify_meshopt(const TriangleMesh& mesh, const MeshoptSimplifyOptions& options) {
  if (options.max_triangles == 0) throw InvalidInputError("", "the triangle budget of meshopt simplification is 0");
  if (mesh.triangles.empty()) throw InvalidInputError("", "the mesh has no triangles to simplify");
  if (mesh.positions.size() >= std::numeric_limits<unsigned int>::max())
    throw InvalidInputError("", "meshoptimizer takes at most 2^32 - 1 vertices");

  // One simplifier vertex per distinct coordinate triple that a triangle uses (a soup
  // decimates like the welded mesh; unused and repeated vertices would otherwise look like
  // seams to it), each standing for the first input vertex there.
  std::vector<std::uint32_t> order(mesh.positions.size());
  for (std::uint32_t v = 0; v < order.size(); ++v) order[v] = v;
  const auto coordinates = [&mesh](std::uint32_t v) {
    return std::array<double, 3>{mesh.positions[v].x(), mesh.positions[v].y(), mesh.positions[v].z()};
  };
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    const auto ca = coordinates(a), cb = coordinates(b);
    return ca != cb ? ca < cb : a < b;
  });
  std::vector<std::uint32_t> first(mesh.positions.size());  // input vertex -> first input vertex at its coordinates
  for (std::size_t i = 0; i < order.size(); ++i)
    first[order[i]] = i > 0 && coordinates(order[i]) == coordinates(order[i - 1]) ? first[order[i - 1]] : order[i];
  std::vector<unsigned int> compact(mesh.positions.size(), std::numeric_limits<unsigned int>::max());
  std::vector<std::uint32_t> representative;  // simplifier vertex -> input vertex
  std::vector<unsigned int> indices;
  indices.reserve(3 * mesh.triangles.size());
  for (const Triangle& t : mesh.triangles)
    for (const VertexIndex v : t) {
      unsigned int& index = compact[first[v]];
      if (index == std::numeric_limits<unsigned int>::max()) {
        index = static_cast<unsigned int>(representative.size());
        representative.push_back(first[v]);
      }
      indices.push_back(index);
    }

  // Single precision relative to the centre: the coordinates meshoptimizer decides on.
  const BoundingBox bounds = bounding_box(mesh);
  const Vertex center = 0.5 * (bounds.min + bounds.max);
  std::vector<float> positions;
  positions.reserve(3 * representative.size());
  for (const std::uint32_t v : representative)
    for (int axis = 0; axis < 3; ++axis) positions.push_back(static_cast<float>(mesh.positions[v][axis] - center[axis]));
  const std::size_t vertex_count = representative.size();

  const std::size_t target = 3 * options.max_triangles;
  const float scale = meshopt_simplifyScale(positions.data(), vertex_count, 3 * sizeof(float));
  MeshoptSimplifyResult result;
  std::vector<unsigned int> simplified(indices.size());
  float error = 0;
  // A target error of 1 (the whole extent) leaves the budget as the only goal.
  simplified.resize(meshopt_simplify(simplified.data(), indices.data(), indices.size(), positions.data(), vertex_count,
                                     3 * sizeof(float), target, 1.0f, 0, &error));
  result.error_world = static_cast<double>(error) * scale;
  if (simplified.size() > target) {
    // The sloppy pass can merge everything away at a small budget: then the smallest
    // budget, doubling, at which something is left.
    result.sloppy_pass = true;
    for (std::size_t sloppy_target = target;; sloppy_target *= 2) {
      std::vector<unsigned int> sloppy(simplified.size());
      float sloppy_error = 0;
      sloppy.resize(meshopt_simplifySloppy(sloppy.data(), simplified.data(), simplified.size(), positions.data(),
                                           vertex_count, 3 * sizeof(float), sloppy_target, 1.0f, &sloppy_error));
      if (!sloppy.empty()) {
        result.error_world = std::max(result.error_world, static_cast<double>(sloppy_error) * scale);
        simplified = std::move(sloppy);
        break;
      }
      if (sloppy_target >= simplified.size()) break;
    }
  }
  std::vector<Triangle> triangles;
  for (std::size_t i = 0; i + 2 < simplified.size(); i += 3)
    triangles.push_back({representative[simplified[i]], representative[simplified[i + 1]], representative[simplified[i + 2]]});
  result.mesh = detail::clean_output_mesh(mesh.positions, triangles);
  result.reached_target = result.mesh.triangles.size() <= options.max_triangles;
  return result;
}

}  // namespace visproxy
