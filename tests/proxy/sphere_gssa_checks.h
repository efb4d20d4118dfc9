#pragma once
// The GSSA of merged sphere sets against the mesh's, measured with isotropic lines
// (SPEC: the fraction of lines through the bounding sphere that hit a body is its GSSA
// over the sphere's area, so the ratio of two hit counts on the same lines is the ratio
// of GSSAs). Shared by the default and the slow sphere-set tests.

#include <gtest/gtest.h>

#include <vector>

#include "visproxy/measure/proxy_measurement.h"
#include "visproxy/measure/random_lines.h"
#include "visproxy/proxy/merge_spheres.h"
#include "visproxy/trace/ray_scene.h"

namespace visproxy::testing {

// Stated tolerance: at 1000 and 100 spheres the whole 95 % interval of the GSSA ratio lies
// in [0.95, 1.12] (100 000 lines, seed 1).
inline void expect_close_gssa(const TriangleMesh& mesh, const std::vector<Sphere>& initial_spheres) {
  const std::vector<std::size_t> targets = {1000, 100};
  const auto levels = merge_spheres(initial_spheres, targets);
  const RayScene mesh_scene(mesh);
  const ReferenceRays reference =
      trace_reference(mesh_scene, isotropic_lines(bounding_sphere(mesh), 100000, 1), {.rays = 0, .blocks = 0});
  for (std::size_t k = 0; k < targets.size(); ++k) {
    SCOPED_TRACE(targets[k]);
    ASSERT_EQ(levels[k].size(), targets[k]);
    const ProxyMeasurement m = measure_proxy(reference, RayScene(levels[k]), ProxyKind::general, {.rays = 0, .blocks = 0});
    EXPECT_GE(m.gssa_ratio_lower, 0.95) << m.gssa_ratio;
    EXPECT_LE(m.gssa_ratio_upper, 1.12) << m.gssa_ratio;
  }
}

}  // namespace visproxy::testing
