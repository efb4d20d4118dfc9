#pragma once
// Small scenes built in code for the renderer's tests.

#include <utility>

#include "visproxy/render/renderer.h"
#include "visproxy/scene/scene.h"

namespace visproxy::testing {

inline TriangleMesh quad(const Vertex& corner, const Vertex& u, const Vertex& v) {
  TriangleMesh mesh;
  mesh.positions = {corner, corner + u, corner + u + v, corner + v};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  return mesh;
}

inline TriangleMesh box(const Vertex& min, const Vertex& max) {
  TriangleMesh mesh;
  for (int c = 0; c < 8; ++c)
    mesh.positions.emplace_back(c & 1 ? max.x() : min.x(), c & 2 ? max.y() : min.y(), c & 4 ? max.z() : min.z());
  mesh.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                    {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  return mesh;
}

/// The same samples rendered with exact and with bounds visibility: (exact, bounds).
inline std::pair<RenderResult, RenderResult> exact_and_bounds(const Scene& scene, const RenderWorld& world,
                                                              RenderOptions options) {
  options.visibility = VisibilityMode::exact;
  RenderResult exact = render(scene, world, options);
  options.visibility = VisibilityMode::bounds;
  return {std::move(exact), render(scene, world, options)};
}

}  // namespace visproxy::testing
