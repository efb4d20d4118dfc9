// Real meshes from Debian's libcgal-demo load with the counts their files declare.

#include <gtest/gtest.h>

#include "visproxy/mesh/read_mesh.h"
#include "visproxy/mesh/write_mesh.h"
#include "test_meshes.h"
#include "test_support.h"

namespace visproxy {
namespace {

struct RealMesh {
  const char* file;
  std::size_t vertices;
  std::size_t triangles;
};

void PrintTo(const RealMesh& input, std::ostream* out) { *out << input.file; }

class RealMeshes : public ::testing::TestWithParam<RealMesh> {};

TEST_P(RealMeshes, LoadWithDeclaredCountsAndRoundTrip) {
  const RealMesh& expected = GetParam();
  const TriangleMesh mesh = read_mesh(testing::cgal_mesh(expected.file));
  EXPECT_EQ(mesh.positions.size(), expected.vertices);
  EXPECT_EQ(mesh.triangles.size(), expected.triangles);
  EXPECT_EQ(parse_mesh(encode_ply(mesh), MeshFormat::ply, "memory"), mesh);
}

// Counts from the files' headers (OFF, PLY) and, for STL, after welding.
INSTANTIATE_TEST_SUITE_P(LibCgalDemo, RealMeshes,
                         ::testing::Values(RealMesh{"bunny00.off", 37706, 75408}, RealMesh{"armadillo.off", 26002, 52000},
                                           RealMesh{"knot1.off", 3200, 6400}, RealMesh{"knot2.off", 5760, 11520},
                                           RealMesh{"ChineseDragon-10kv.off", 10000, 19994},
                                           RealMesh{"elephant-with-holes.off", 2798, 4463},
                                           RealMesh{"sphere.ply", 162, 320}, RealMesh{"sphere.stl", 162, 320}),
                         [](const ::testing::TestParamInfo<RealMesh>& param_info) { return testing::test_name_from(param_info.param.file); });

}  // namespace
}  // namespace visproxy
