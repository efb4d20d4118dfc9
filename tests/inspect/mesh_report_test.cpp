#include "visproxy/inspect/mesh_report.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "visproxy/core/files.h"
#include "visproxy/mesh/read_mesh.h"
#include "test_meshes.h"
#include "test_support.h"

namespace visproxy {
namespace {

TEST(MeshReport, CubeHasExactAreaVolumeAndIsWatertight) {
  const MeshReport report = inspect_mesh(testing::unit_cube());
  EXPECT_DOUBLE_EQ(report.area, 6.0);
  ASSERT_TRUE(report.volume.has_value());
  EXPECT_DOUBLE_EQ(*report.volume, 1.0);
  EXPECT_EQ(report.outward_oriented, true);
  EXPECT_TRUE(report.watertight());
  EXPECT_DOUBLE_EQ(report.bounds.diagonal(), std::sqrt(3.0));
}

TEST(MeshReport, InvertedTetrahedronIsInward) {
  TriangleMesh mesh = testing::tetrahedron();
  for (Triangle& t : mesh.triangles) std::swap(t[1], t[2]);
  const MeshReport report = inspect_mesh(mesh);
  EXPECT_NEAR(*report.volume, -1.0 / 6.0, 1e-15);
  EXPECT_EQ(report.outward_oriented, false);
  EXPECT_TRUE(report.watertight()) << "watertight says nothing about which way the normals point";
}

TEST(MeshReport, EachDefectBreaksWatertightness) {
  TriangleMesh open = testing::unit_cube();
  open.triangles.pop_back();
  const MeshReport open_report = inspect_mesh(open);
  EXPECT_FALSE(open_report.watertight());
  EXPECT_FALSE(open_report.volume.has_value());
  EXPECT_FALSE(open_report.outward_oriented.has_value());

  TriangleMesh flipped = testing::unit_cube();
  std::swap(flipped.triangles[0][1], flipped.triangles[0][2]);
  EXPECT_FALSE(inspect_mesh(flipped).watertight());

  TriangleMesh crossing = testing::unit_cube();  // a second cube through the first
  const auto offset = static_cast<VertexIndex>(crossing.positions.size());
  for (const Vertex& p : testing::unit_cube().positions) crossing.positions.push_back(p + Vertex(0.5, 0.5, 0.5));
  for (Triangle t : testing::unit_cube().triangles) {
    for (VertexIndex& i : t) i += offset;
    crossing.triangles.push_back(t);
  }
  const MeshReport crossing_report = inspect_mesh(crossing);
  EXPECT_TRUE(crossing_report.topology.closed() && crossing_report.topology.manifold());
  EXPECT_TRUE(crossing_report.self_intersecting());
  EXPECT_FALSE(crossing_report.watertight());
}

TEST(MeshReport, JsonHasTheDocumentedKeysAndTypes) {
  const nlohmann::json json = to_json(inspect_mesh(testing::unit_cube()));
  const nlohmann::json schema =
      nlohmann::json::parse(read_file(std::filesystem::path(VISPROXY_SOURCE_DIR) / "data/schemas/info.schema.json"));
  for (const auto& key : schema.at("required")) {
    const std::string name = key.get<std::string>();
    if (name == "file" || name == "format" || name == "read_seconds") continue;  // added by the CLI
    ASSERT_TRUE(json.contains(name)) << name;
  }
  for (const auto& [name, value] : json.items()) EXPECT_TRUE(schema.at("properties").contains(name)) << name;
  EXPECT_EQ(json.at("vertices"), 8);
  EXPECT_EQ(json.at("bbox_max"), nlohmann::json::array({1.0, 1.0, 1.0}));
  EXPECT_EQ(json.at("volume"), 1.0);
  EXPECT_EQ(json.at("watertight"), true);

  TriangleMesh open = testing::unit_cube();
  open.triangles.pop_back();
  const nlohmann::json open_json = to_json(inspect_mesh(open));
  EXPECT_TRUE(open_json.at("volume").is_null());
  EXPECT_TRUE(open_json.at("outward_oriented").is_null());
}

struct Verdict {
  const char* file;
  bool watertight;
  bool has_boundary;
};

void PrintTo(const Verdict& input, std::ostream* out) { *out << input.file; }

class RealMeshVerdicts : public ::testing::TestWithParam<Verdict> {};

TEST_P(RealMeshVerdicts, MatchTheKnownDefects) {
  const MeshReport report = inspect_mesh(read_mesh(testing::cgal_mesh(GetParam().file)));
  EXPECT_EQ(report.watertight(), GetParam().watertight);
  EXPECT_EQ(report.topology.boundary_edges > 0, GetParam().has_boundary);
  if (report.watertight()) {
    EXPECT_EQ(report.outward_oriented, true);
    EXPECT_GT(*report.volume, 0);
    EXPECT_EQ(report.topology.components, 1u);
  }
}

INSTANTIATE_TEST_SUITE_P(LibCgalDemo, RealMeshVerdicts,
                         ::testing::Values(Verdict{"bunny00.off", true, false}, Verdict{"armadillo.off", true, false},
                                           Verdict{"knot1.off", true, false}, Verdict{"sphere.stl", true, false},
                                           Verdict{"elephant-with-holes.off", false, true},
                                           Verdict{"ChineseDragon-10kv.off", false, true}),
                         [](const ::testing::TestParamInfo<Verdict>& param_info) { return testing::test_name_from(param_info.param.file); });

TEST(MeshReport, ChineseDragonHasItsSixBorderEdges) {
  const MeshReport report = inspect_mesh(read_mesh(testing::cgal_mesh("ChineseDragon-10kv.off")));
  EXPECT_EQ(report.topology.boundary_edges, 6u);
}

}  // namespace
}  // namespace visproxy
