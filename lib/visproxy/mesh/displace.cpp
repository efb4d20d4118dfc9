#include "visproxy/mesh/displace.h"

#include <cmath>
#include <numbers>
#include <vector>

#include "visproxy/core/random.h"

namespace visproxy {

double mean_edge_length(const TriangleMesh& mesh) {
  double sum = 0;
  for (const Triangle& t : mesh.triangles)
    for (std::size_t i = 0; i < 3; ++i) sum += (mesh.positions[t[(i + 1) % 3]] - mesh.positions[t[i]]).norm();
  return mesh.triangles.empty() ? 0.0 : sum / (3.0 * static_cast<double>(mesh.triangles.size()));
}

TriangleMesh displace_along_normals(const TriangleMesh& mesh, const DisplaceOptions& options) {
  TriangleMesh out = mesh;
  const double edge = mean_edge_length(mesh);
  if (!(edge > 0) || options.waves < 1) return out;
  std::vector<Vertex> normals(mesh.positions.size(), Vertex::Zero());
  for (const Triangle& t : mesh.triangles) {
    const Vertex n = (mesh.positions[t[1]] - mesh.positions[t[0]]).cross(mesh.positions[t[2]] - mesh.positions[t[0]]);
    for (const VertexIndex v : t) normals[v] += n;
  }
  const BoundingBox box = bounding_box(mesh);
  const Vertex centre = 0.5 * (box.min + box.max);
  const double frequency = 2 * std::numbers::pi / (options.wavelength_relative * edge);
  Random random(options.seed);
  std::vector<Vertex> directions;
  std::vector<double> phases;
  for (int k = 0; k < options.waves; ++k) {
    // A uniform direction on the sphere, and a uniform phase.
    const double z = 2 * random.uniform() - 1, angle = 2 * std::numbers::pi * random.uniform();
    const double r = std::sqrt(std::max(0.0, 1 - z * z));
    directions.emplace_back(frequency * r * std::cos(angle), frequency * r * std::sin(angle), frequency * z);
    phases.push_back(2 * std::numbers::pi * random.uniform());
  }
  const double amplitude = options.amplitude_relative * edge;
  for (std::size_t v = 0; v < out.positions.size(); ++v) {
    const double length = normals[v].norm();
    if (!(length > 0)) continue;
    const Vertex p = mesh.positions[v] - centre;
    double sum = 0;
    for (int k = 0; k < options.waves; ++k)
      sum += std::sin(directions[static_cast<std::size_t>(k)].dot(p) + phases[static_cast<std::size_t>(k)]);
    out.positions[v] += amplitude * (sum / options.waves) * (normals[v] / length);
  }
  return out;
}

}  // namespace visproxy
