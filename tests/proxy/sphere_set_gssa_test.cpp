// The GSSA of merged sphere sets against the mesh's, measured with isotropic lines
// (SPEC: the fraction of lines through the bounding sphere that hit a body is its GSSA
// over the sphere's area, so the ratio of two hit counts on the same lines is the ratio
// of GSSAs).

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

ProxyMeasurement gssa_ratio(const ReferenceRays& reference, const std::vector<Sphere>& spheres) {
  const RayScene scene(spheres);
  const std::vector<std::uint8_t> blocked = scene.segments_blocked(reference.rays);
  RayTypeCounts counts;
  for (std::size_t i = 0; i < blocked.size(); ++i) counts.add(reference.mesh_blocked[i] != 0, blocked[i] != 0);
  return measure_from_counts(counts, ProxyKind::general);
}

// Stated tolerance: at 1000 and 100 spheres the whole 95 % interval of the GSSA ratio lies
// in [0.95, 1.12]. Measured (4000 samples, D2, exact merge, 100 000 lines, seed 1):
// bunny00 1.055 / 1.057, armadillo 1.073 / 1.089, knot1 1.065 / 1.105. The excess comes
// mostly from the initial circumspheres, which bulge out between samples.
void expect_close_gssa(const char* name, InnerTetrahedra tets, std::size_t samples) {
  const TriangleMesh mesh = read_mesh(testing::cgal_mesh(name));
  const CircumsphereSet set = build_circumsphere_set(mesh, {.tetrahedra = tets, .samples = samples});
  const std::vector<std::size_t> targets = {1000, 100};
  const auto levels = merge_spheres(set.spheres, targets);
  const RayScene mesh_scene(mesh);
  const ReferenceRays reference =
      trace_reference(mesh_scene, isotropic_lines(bounding_sphere(mesh), 100000, 1), {.rays = 0, .repeats = 0});
  for (std::size_t k = 0; k < targets.size(); ++k) {
    SCOPED_TRACE(targets[k]);
    ASSERT_EQ(levels[k].size(), targets[k]);
    const ProxyMeasurement m = gssa_ratio(reference, levels[k]);
    EXPECT_GE(m.gssa_ratio_lower, 0.95) << m.gssa_ratio;
    EXPECT_LE(m.gssa_ratio_upper, 1.12) << m.gssa_ratio;
  }
}

class SphereSetGssa : public ::testing::TestWithParam<const char*> {};

TEST_P(SphereSetGssa, ThousandAndHundredSpheresBlockAsManyLinesAsTheMesh) {
  expect_close_gssa(GetParam(), InnerTetrahedra::normals, 4000);
}

INSTANTIATE_TEST_SUITE_P(LibcgalDemo, SphereSetGssa, ::testing::Values("knot1.off", "bunny00.off", "armadillo.off"),
                         [](const auto& test) { return testing::test_name_from(test.param); });

}  // namespace
}  // namespace visproxy
