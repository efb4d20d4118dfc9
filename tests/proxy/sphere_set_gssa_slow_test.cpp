// Slow: sphere sets from TetGen's tetrahedralization (0.1 M - 0.8 M initial spheres) keep
// the mesh's GSSA as well as those from surface samples.

#include <gtest/gtest.h>

#include "visproxy/mesh/read_mesh.h"
#include "visproxy/proxy/circumsphere_set.h"
#include "proxy/sphere_gssa_checks.h"
#include "test_meshes.h"
#include "test_support.h"

namespace visproxy {
namespace {

class TetgenSphereSetGssa : public ::testing::TestWithParam<const char*> {};

// Same tolerance as the default test: the 95 % interval of the GSSA ratio within [0.95, 1.12].
TEST_P(TetgenSphereSetGssa, ThousandAndHundredSpheresBlockAsManyLinesAsTheMesh) {
  const TriangleMesh mesh = read_mesh(testing::cgal_mesh(GetParam()));
  const CircumsphereSet set = build_circumsphere_set(mesh, {.tetrahedra = InnerTetrahedra::tetgen});
  EXPECT_EQ(set.spheres.size(), set.tetrahedra);
  testing::expect_close_gssa(mesh, set.spheres);
}

INSTANTIATE_TEST_SUITE_P(LibcgalDemo, TetgenSphereSetGssa, ::testing::Values("knot1.off", "bunny00.off", "armadillo.off"),
                         [](const auto& test) { return testing::test_name_from(test.param); });

}  // namespace
}  // namespace visproxy
