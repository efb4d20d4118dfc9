// Slow: sphere sets from TetGen's tetrahedralization (0.1 M - 0.8 M initial spheres) keep
// the mesh's GSSA as well as those from surface samples.

#include <gtest/gtest.h>

#include "measure/proxy_measurement.h"
#include "measure/random_lines.h"
#include "mesh/read_mesh.h"
#include "proxy/circumsphere_set.h"
#include "proxy/merge_spheres.h"
#include "test_meshes.h"
#include "test_support.h"
#include "trace/ray_scene.h"

namespace visproxy {
namespace {

class TetgenSphereSetGssa : public ::testing::TestWithParam<const char*> {};

// Same tolerance as the default test: the 95 % interval of the GSSA ratio within [0.95, 1.12].
TEST_P(TetgenSphereSetGssa, ThousandAndHundredSpheresBlockAsManyLinesAsTheMesh) {
  const TriangleMesh mesh = read_mesh(testing::cgal_mesh(GetParam()));
  const CircumsphereSet set = build_circumsphere_set(mesh, {.tetrahedra = InnerTetrahedra::tetgen});
  EXPECT_EQ(set.spheres.size(), set.tetrahedra);
  const std::vector<std::size_t> targets = {1000, 100};
  const auto levels = merge_spheres(set.spheres, targets);
  const RayScene mesh_scene(mesh);
  const ReferenceRays reference =
      trace_reference(mesh_scene, isotropic_lines(bounding_sphere(mesh), 100000, 1), {.rays = 0, .repeats = 0});
  for (std::size_t k = 0; k < targets.size(); ++k) {
    SCOPED_TRACE(targets[k]);
    ASSERT_EQ(levels[k].size(), targets[k]);
    const RayScene scene(levels[k]);
    const std::vector<std::uint8_t> blocked = scene.segments_blocked(reference.rays);
    RayTypeCounts counts;
    for (std::size_t i = 0; i < blocked.size(); ++i) counts.add(reference.mesh_blocked[i] != 0, blocked[i] != 0);
    const ProxyMeasurement m = measure_from_counts(counts, ProxyKind::general);
    EXPECT_GE(m.gssa_ratio_lower, 0.95) << m.gssa_ratio;
    EXPECT_LE(m.gssa_ratio_upper, 1.12) << m.gssa_ratio;
  }
}

INSTANTIATE_TEST_SUITE_P(LibcgalDemo, TetgenSphereSetGssa, ::testing::Values("knot1.off", "bunny00.off", "armadillo.off"),
                         [](const auto& test) { return testing::test_name_from(test.param); });

}  // namespace
}  // namespace visproxy
