#include "visproxy/measure/random_lines.h"

#include "visproxy/core/random.h"

namespace visproxy {

Sphere bounding_sphere(const TriangleMesh& mesh) {
  const BoundingBox box = bounding_box(mesh);
  if (box.empty()) return {};
  // 1e-6 relative headroom keeps every vertex strictly inside despite rounding.
  return {0.5 * (box.min + box.max), 0.5 * box.diagonal() * (1.0 + 1e-6)};
}

std::vector<Segment> isotropic_lines(const Sphere& sphere, std::size_t count, std::uint64_t seed) {
  Random random(seed);
  std::vector<Segment> lines;
  lines.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    const Vertex from = sphere.center + sphere.radius * random.unit_vector();
    const Vertex to = sphere.center + sphere.radius * random.unit_vector();
    lines.push_back({from, to});
  }
  return lines;
}

}  // namespace visproxy
