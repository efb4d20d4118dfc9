#include "visproxy/proxy/detail/surface_samples.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "visproxy/core/errors.h"
#include "visproxy/core/random.h"

namespace visproxy {

std::vector<SurfaceSample> sample_surface(const TriangleMesh& mesh, std::size_t count, std::uint64_t seed) {
  std::vector<double> cumulative_area;
  std::vector<std::uint32_t> triangles;
  double total = 0;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& triangle = mesh.triangles[t];
    for (const VertexIndex v : triangle) {
      if (v >= mesh.positions.size())
        throw InvalidInputError("", "a triangle refers to vertex " + std::to_string(v) + ", which does not exist");
      if (!mesh.positions[v].allFinite())
        throw InvalidInputError("", "vertex " + std::to_string(v) + " has a coordinate that is not finite");
    }
    const Vertex& a = mesh.positions[triangle[0]];
    const double area = 0.5 * (mesh.positions[triangle[1]] - a).cross(mesh.positions[triangle[2]] - a).norm();
    if (!(area > 0)) continue;
    total += area;
    cumulative_area.push_back(total);
    triangles.push_back(static_cast<std::uint32_t>(t));
  }
  if (triangles.empty()) throw InvalidInputError("", "the mesh has no triangle of non-zero area to sample");

  Random random(seed);
  std::vector<double> picks(count);
  for (double& pick : picks) pick = random.uniform() * total;
  std::sort(picks.begin(), picks.end());
  std::vector<SurfaceSample> samples;
  samples.reserve(count);
  std::size_t k = 0;
  for (const double pick : picks) {
    while (k + 1 < cumulative_area.size() && cumulative_area[k] <= pick) ++k;
    const Triangle& triangle = mesh.triangles[triangles[k]];
    const Vertex& a = mesh.positions[triangle[0]];
    const Vertex& b = mesh.positions[triangle[1]];
    const Vertex& c = mesh.positions[triangle[2]];
    const double s = std::sqrt(random.uniform());
    const double r = random.uniform();
    samples.push_back({(1 - s) * a + s * (1 - r) * b + s * r * c, (b - a).cross(c - a).normalized(), triangles[k]});
  }
  return samples;
}

std::vector<SurfaceSample> sample_surface_evenly(const TriangleMesh& mesh, std::size_t count, std::uint64_t seed) {
  std::vector<SurfaceSample> candidates = sample_surface(mesh, 4 * count, seed);
  if (count == 0) return {};
  BoundingBox box;
  for (const SurfaceSample& sample : candidates) box.extend(sample.position);
  const double extent = std::max((box.max - box.min).maxCoeff(), 1e-300);
  // Cells per axis below 2^21, so that a cell's three indices pack into 64 bits.
  const double smallest_cell = extent / 2'000'000.0;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keys(candidates.size());
  auto assign_cells = [&](double cell) {
    for (std::uint32_t i = 0; i < candidates.size(); ++i) {
      const Vertex grid = (candidates[i].position - box.min) / cell;
      keys[i] = {(static_cast<std::uint64_t>(grid.x()) << 42) | (static_cast<std::uint64_t>(grid.y()) << 21) |
                     static_cast<std::uint64_t>(grid.z()),
                 i};
    }
    std::sort(keys.begin(), keys.end());
    std::size_t occupied = 0;
    for (std::size_t k = 0; k < keys.size(); ++k) occupied += k == 0 || keys[k].first != keys[k - 1].first;
    return occupied;
  };
  // A surface of area A meets about c A / cell^2 cells; a few rescalings find the cell.
  double total_area = 0;
  for (const Triangle& t : mesh.triangles) {
    const Vertex& a = mesh.positions[t[0]];
    total_area += 0.5 * (mesh.positions[t[1]] - a).cross(mesh.positions[t[2]] - a).norm();
  }
  double cell = std::max(smallest_cell, std::sqrt(total_area / static_cast<double>(count)));
  for (int iteration = 0; iteration < 4; ++iteration) {
    const std::size_t occupied = assign_cells(cell);
    cell = std::max(smallest_cell, cell * std::sqrt(static_cast<double>(occupied) / static_cast<double>(count)));
  }
  assign_cells(cell);
  std::vector<std::uint32_t> kept;
  for (std::size_t k = 0; k < keys.size(); ++k)
    if (k == 0 || keys[k].first != keys[k - 1].first) kept.push_back(keys[k].second);
  std::sort(kept.begin(), kept.end());
  std::vector<SurfaceSample> samples;
  samples.reserve(kept.size());
  for (const std::uint32_t i : kept) samples.push_back(candidates[i]);
  return samples;
}

}  // namespace visproxy
