#include "visproxy/scene/hairball.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "visproxy/core/random.h"

namespace visproxy {

TriangleMesh make_hairball(const HairballOptions& options) {
  const std::size_t per_tube = 2 * static_cast<std::size_t>(options.sides) * static_cast<std::size_t>(options.segments);
  const std::size_t tubes = std::max<std::size_t>(1, options.triangles / per_tube);
  const auto sides = static_cast<VertexIndex>(options.sides);
  Random random(options.seed);
  TriangleMesh mesh;
  mesh.positions.reserve(tubes * static_cast<std::size_t>(options.segments + 1) * sides);
  mesh.triangles.reserve(tubes * per_tube);
  for (std::size_t tube = 0; tube < tubes; ++tube) {
    // Start uniformly in the ball, head in a random direction.
    Vertex point = options.radius * std::cbrt(random.uniform()) * random.unit_vector();
    Vertex direction = random.unit_vector();
    Vertex normal = direction.unitOrthogonal();
    const auto first = static_cast<VertexIndex>(mesh.positions.size());
    for (int step = 0; step <= options.segments; ++step) {
      // Ring of the cross-section, in the plane orthogonal to the direction.
      const Vertex binormal = direction.cross(normal);
      for (int side = 0; side < options.sides; ++side) {
        const double angle = 2 * std::numbers::pi * side / options.sides;
        mesh.positions.push_back(point + options.tube_radius * (std::cos(angle) * normal + std::sin(angle) * binormal));
      }
      // Turn a little, and back inwards near the surface.
      direction = (direction + 0.35 * random.unit_vector()).normalized();
      if (point.norm() > 0.85 * options.radius) direction = (direction - 0.5 * point.normalized()).normalized();
      point += options.segment_length * direction;
      normal = (normal - normal.dot(direction) * direction).normalized();  // parallel transport
      if (!normal.allFinite()) normal = direction.unitOrthogonal();
    }
    for (int step = 0; step < options.segments; ++step)
      for (VertexIndex side = 0; side < sides; ++side) {
        const VertexIndex a = first + static_cast<VertexIndex>(step) * sides + side;
        const VertexIndex b = first + static_cast<VertexIndex>(step) * sides + (side + 1) % sides;
        const VertexIndex c = a + sides, d = b + sides;
        mesh.triangles.push_back({a, b, d});
        mesh.triangles.push_back({a, d, c});
      }
  }
  return mesh;
}

}  // namespace visproxy
