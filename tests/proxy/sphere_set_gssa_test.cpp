// The GSSA of merged sphere sets against the mesh's (checks in sphere_gssa_checks.h).

#include <gtest/gtest.h>

#include "visproxy/mesh/read_mesh.h"
#include "visproxy/proxy/circumsphere_set.h"
#include "proxy/sphere_gssa_checks.h"
#include "test_meshes.h"
#include "test_support.h"

namespace visproxy {
namespace {

// Measured (4000 samples, D2, exact merge): bunny00 1.055 / 1.057, armadillo 1.073 /
// 1.089, knot1 1.065 / 1.105. The excess comes mostly from the initial circumspheres,
// which bulge out between samples.
void expect_close_gssa(const char* name, InnerTetrahedra tets, std::size_t samples) {
  const TriangleMesh mesh = read_mesh(testing::cgal_mesh(name));
  testing::expect_close_gssa(mesh, build_circumsphere_set(mesh, {.tetrahedra = tets, .samples = samples}).spheres);
}

class SphereSetGssa : public ::testing::TestWithParam<const char*> {};

TEST_P(SphereSetGssa, ThousandAndHundredSpheresBlockAsManyLinesAsTheMesh) {
  expect_close_gssa(GetParam(), InnerTetrahedra::normals, 4000);
}

INSTANTIATE_TEST_SUITE_P(LibcgalDemo, SphereSetGssa, ::testing::Values("knot1.off", "bunny00.off", "armadillo.off"),
                         [](const auto& test) { return testing::test_name_from(test.param); });

}  // namespace
}  // namespace visproxy
