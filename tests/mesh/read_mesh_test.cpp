#include "visproxy/mesh/read_mesh.h"

#include <gtest/gtest.h>

#include "visproxy/core/errors.h"
#include "mesh/encode_formats.h"
#include "visproxy/mesh/write_mesh.h"
#include "test_meshes.h"

namespace visproxy {
namespace {

using testing::PlyEncoding;
using testing::PlyLayout;

// A mesh whose coordinates are exact in float, so every format can hold it exactly.
TriangleMesh sample_mesh() {
  TriangleMesh mesh = testing::unit_cube();
  for (Vertex& p : mesh.positions) p = 0.5 * p + Vertex(-0.25, 1.5, 3.0);
  return mesh;
}

TriangleMesh parse(std::string_view bytes, MeshFormat format, Weld weld = Weld::never) {
  return parse_mesh(bytes, format, "memory", {.weld = weld, .on_warning = {}});
}

TEST(ReadMesh, PlyRoundTripsEveryEncodingAndScalarType) {
  const TriangleMesh mesh = sample_mesh();
  for (const PlyEncoding encoding : {PlyEncoding::ascii, PlyEncoding::little_endian, PlyEncoding::big_endian})
    for (const char* coordinate : {"float", "double", "float32", "float64"})
      for (const auto& [count, index] : std::vector<std::pair<std::string, std::string>>{
               {"uchar", "int"}, {"uchar", "uint"}, {"int", "int"}, {"ushort", "ushort"}, {"uint8", "uint32"},
               {"char", "short"}, {"uchar", "uchar"}})
        for (const bool extras : {false, true}) {
          const PlyLayout layout{.encoding = encoding, .coordinate_type = coordinate, .count_type = count,
                                 .index_type = index, .extra_properties = extras};
          SCOPED_TRACE(std::string(coordinate) + " " + count + " " + index + " encoding " +
                       std::to_string(static_cast<int>(encoding)) + (extras ? " with extras" : ""));
          EXPECT_EQ(parse(testing::encode_ply_variant(mesh, layout), MeshFormat::ply), mesh);
        }
}

TEST(ReadMesh, PlyIntegerCoordinates) {
  const TriangleMesh cube = testing::unit_cube();
  EXPECT_EQ(parse(testing::encode_ply_variant(cube, {.encoding = PlyEncoding::big_endian, .coordinate_type = "short"}),
                  MeshFormat::ply),
            cube);
}

// Blender 2.4x writes a line that is no PLY keyword after `format`; it is skipped with one
// warning naming the file and the line, in every encoding.
TEST(ReadMesh, PlyBlender24xHeaderLineIsIgnoredWithAWarning) {
  const TriangleMesh mesh = sample_mesh();
  const std::string blender_line = "Created by Blender3D 247 - www.blender.org, source file: 'cube.blend'";
  for (const PlyEncoding encoding : {PlyEncoding::ascii, PlyEncoding::little_endian}) {
    SCOPED_TRACE(encoding == PlyEncoding::ascii ? "ascii" : "binary");
    std::string bytes = testing::encode_ply_variant(mesh, {.encoding = encoding});
    const std::size_t comment = bytes.find("comment test\n");
    ASSERT_NE(comment, std::string::npos);
    bytes.replace(comment, std::string("comment test").size(), blender_line + "\r");  // and a CRLF ending
    std::vector<std::string> warnings;
    const TriangleMesh read = parse_mesh(
        bytes, MeshFormat::ply, "blender.ply",
        {.weld = Weld::never, .on_warning = [&](const std::string& warning) { warnings.push_back(warning); }});
    EXPECT_EQ(read.positions.size(), mesh.positions.size());
    EXPECT_EQ(read.triangles.size(), mesh.triangles.size());
    EXPECT_EQ(read, mesh);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_EQ(warnings[0], "blender.ply:3: unknown header line '" + blender_line + "' ignored");
  }
}

TEST(ReadMesh, PlyWarningsAreCappedAndNotGivenForAFileThatIsNoPly) {
  std::string header = "ply\nformat ascii 1.0\n";
  for (int i = 0; i < 20; ++i) header += "junk " + std::to_string(i) + "\n";
  const std::string body =
      "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  std::vector<std::string> warnings;
  const ReadMeshOptions options{.weld = Weld::automatic,
                                .on_warning = [&](const std::string& warning) { warnings.push_back(warning); }};
  EXPECT_EQ(parse_mesh(header + body, MeshFormat::ply, "junk.ply", options).triangles.size(), 1u);
  ASSERT_EQ(warnings.size(), 9u);
  EXPECT_EQ(warnings[0], "junk.ply:3: unknown header line 'junk 0' ignored");
  EXPECT_EQ(warnings[7], "junk.ply:10: unknown header line 'junk 7' ignored");
  EXPECT_EQ(warnings[8], "junk.ply: 12 more unknown header lines ignored");

  warnings.clear();
  EXPECT_THROW(parse_mesh(header, MeshFormat::ply, "junk.ply", options), InvalidInputError);
  EXPECT_TRUE(warnings.empty()) << "a header without end_header is an error, not a list of warnings";
}

TEST(ReadMesh, PlyMalformedKeywordLinesAreStillErrors) {
  const std::string tail =
      "property float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  const std::pair<std::string, std::string> cases[] = {
      {"ply\nformat ascii 1.0\nelement vertex abc\n" + tail,
       "broken.ply:3: expected the element count (a non-negative integer), found 'abc'"},
      {"ply\nformat ascii 1.0\nelement\n" + tail, "broken.ply:3: element without a name"},
      {"ply\nformat ascii 1.0\nelement vertex 3\nproperty float128 x\n" + tail,
       "broken.ply:4: unknown property type 'float128'"},
      {"ply\nformat ascii 2.0\nelement vertex 3\n" + tail, "broken.ply:2: unsupported PLY version (only 1.0)"},
  };
  for (const auto& [bytes, message] : cases) {
    std::vector<std::string> warnings;
    try {
      parse_mesh(bytes, MeshFormat::ply, "broken.ply",
                 {.weld = Weld::automatic, .on_warning = [&](const std::string& w) { warnings.push_back(w); }});
      ADD_FAILURE() << "accepted " << bytes;
    } catch (const InvalidInputError& error) {
      EXPECT_EQ(std::string(error.what()), message);
    }
    EXPECT_TRUE(warnings.empty());
  }
}

TEST(ReadMesh, OffRoundTrips) {
  const TriangleMesh mesh = sample_mesh();
  EXPECT_EQ(parse(testing::encode_off(mesh), MeshFormat::off), mesh);
}

TEST(ReadMesh, OffVariantsCommentsColoursAndPolygons) {
  const std::string text =
      "COFF 5 2 0 # counts on the header line\n"
      "0 0 0 255 0 0 255\n1 0 0 255 0 0 255\n1 1 0 0 0 0 255\n0 1 0 0 0 0 255\n"
      "# a comment between records\n"
      "0.5 0.5 1 1 1 1 1\n"
      "4 0 1 2 3  200 10 10\n"
      "3 0 1 4\n";
  const TriangleMesh mesh = parse(text, MeshFormat::off);
  ASSERT_EQ(mesh.positions.size(), 5u);
  ASSERT_EQ(mesh.triangles.size(), 3u);  // the quad becomes two triangles
  EXPECT_EQ(mesh.triangles[2], (Triangle{0, 1, 4}));
}

TEST(ReadMesh, StlAsciiAndBinaryWeldByDefault) {
  const TriangleMesh mesh = sample_mesh();
  for (const std::string& bytes : {testing::encode_ascii_stl(mesh), testing::encode_binary_stl(mesh),
                                   testing::encode_binary_stl(mesh, "solid pretending to be ASCII")}) {
    const TriangleMesh soup = parse(bytes, MeshFormat::stl, Weld::never);
    EXPECT_EQ(soup.positions.size(), 3 * mesh.triangles.size());
    const TriangleMesh welded = parse_mesh(bytes, MeshFormat::stl, "memory");  // automatic welding
    EXPECT_EQ(welded.positions.size(), mesh.positions.size());
    ASSERT_EQ(welded.triangles.size(), mesh.triangles.size());
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
      for (int k = 0; k < 3; ++k)
        EXPECT_EQ(welded.positions[welded.triangles[t][k]], mesh.positions[mesh.triangles[t][k]]);
  }
}

TEST(ReadMesh, ObjNegativeIndicesSlashesObjectsAndPolygons) {
  const std::string text =
      "# two objects\n"
      "mtllib scene.mtl\no first\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n"
      "usemtl red\ns off\nf 1/1/1 2/1/1 3/1/1 4/1/1\n"
      "o second\ng part\nv 0 0 5\nv 1 0 5\nv 0 1 5\nf -3//1 -2//1 -1//1\nl 1 2\n";
  const TriangleMesh mesh = parse(text, MeshFormat::obj);
  ASSERT_EQ(mesh.positions.size(), 7u);
  ASSERT_EQ(mesh.triangles.size(), 3u);
  EXPECT_EQ(mesh.triangles[2], (Triangle{4, 5, 6}));
}

TEST(ReadMesh, NonConvexPolygonIsTriangulatedInsideItsOutline) {
  // An L-shaped hexagon in the plane z = 2, listed clockwise seen from +z: a fan from
  // corner 0 would put a triangle outside the outline; ear clipping must not.
  const std::string text =
      "v 0 0 2\nv 0 2 2\nv 1 2 2\nv 1 1 2\nv 2 1 2\nv 2 0 2\n"
      "f 1 2 3 4 5 6\n";
  const TriangleMesh mesh = parse(text, MeshFormat::obj);
  ASSERT_EQ(mesh.triangles.size(), 4u);
  double total_area = 0;
  for (const Triangle& t : mesh.triangles) {
    const Vertex normal = (mesh.positions[t[1]] - mesh.positions[t[0]]).cross(mesh.positions[t[2]] - mesh.positions[t[0]]);
    EXPECT_LT(normal.z(), 0) << "every triangle keeps the polygon's (clockwise) orientation";
    total_area += 0.5 * normal.norm();
    const Vertex centroid = (mesh.positions[t[0]] + mesh.positions[t[1]] + mesh.positions[t[2]]) / 3;
    EXPECT_FALSE(centroid.x() > 1 && centroid.y() > 1) << "triangle in the notch of the L";
  }
  EXPECT_DOUBLE_EQ(total_area, 3.0);
}

TEST(ReadMesh, ObjForwardReferencesAreResolvedAtTheEnd) {
  const TriangleMesh mesh = parse("f 1 2 3 4\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n", MeshFormat::obj);
  EXPECT_EQ(mesh.triangles.size(), 2u);
}

TEST(ReadMesh, WeldMergesSignedZerosAndKeepsTriangles) {
  TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-0.0, 0, 0}, {1, 0, 0}, {0, 0, 1}, {7, 7, 7}};
  mesh.triangles = {{0, 1, 2}, {3, 4, 5}};
  const TriangleMesh welded = weld_vertices(mesh);
  EXPECT_EQ(welded.positions.size(), 4u);  // the unreferenced (7,7,7) is dropped
  EXPECT_EQ(welded.triangles[1], (Triangle{0, 1, 3}));
}

TEST(ReadMesh, FormatFromExtensionIgnoresCase) {
  EXPECT_EQ(format_from_extension("a/b/Model.PLY"), MeshFormat::ply);
  EXPECT_EQ(format_from_extension("x.Obj"), MeshFormat::obj);
  EXPECT_EQ(format_from_extension("x.stl"), MeshFormat::stl);
  EXPECT_EQ(format_from_extension("x.off"), MeshFormat::off);
  EXPECT_EQ(format_from_extension("x.3DS"), MeshFormat::assimp);
  EXPECT_EQ(format_from_extension("x.glb"), MeshFormat::assimp);
  EXPECT_EQ(format_from_extension("x.gltf"), MeshFormat::assimp);
  EXPECT_EQ(format_from_extension("x.Dae"), MeshFormat::assimp);
  EXPECT_EQ(format_from_extension("x.fbx"), MeshFormat::assimp);
  EXPECT_FALSE(format_from_extension("x.txt").has_value());
  EXPECT_FALSE(format_from_extension("x.png").has_value());
  EXPECT_FALSE(format_from_extension("noextension").has_value());
}

struct BadInput {
  const char* name;
  MeshFormat format;
  std::string bytes;
  const char* message;  // a fragment the error must contain
};

void PrintTo(const BadInput& input, std::ostream* out) { *out << input.name; }

class ReadMeshRejects : public ::testing::TestWithParam<BadInput> {};

TEST_P(ReadMeshRejects, WithAClearMessageNamingTheSource) {
  const BadInput& input = GetParam();
  try {
    parse_mesh(input.bytes, input.format, "input-file");
    FAIL() << "accepted " << input.name;
  } catch (const InvalidInputError& error) {
    const std::string message = error.what();
    EXPECT_EQ(message.rfind("input-file", 0), 0u) << message;
    EXPECT_NE(message.find(input.message), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << "one line: " << message;
  }
}

std::string big_endian_count_stl() {
  std::string bytes(80, ' ');
  bytes += std::string("\xff\xff\xff\x7f", 4);
  return bytes + std::string(50, '\0');
}

INSTANTIATE_TEST_SUITE_P(
    Formats, ReadMeshRejects,
    ::testing::Values(
        BadInput{"empty", MeshFormat::off, "", "empty"},
        BadInput{"off_no_header", MeshFormat::off, "3 1 0\n0 0 0\n", "OFF header"},
        BadInput{"off_huge_counts", MeshFormat::off, "OFF\n1000000000000 1 0\n0 0 0\n", "header claims"},
        BadInput{"off_truncated", MeshFormat::off, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1\n# a comment\n",
                 "expected a vertex index, found the end of the line"},
        BadInput{"off_short", MeshFormat::off, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0", "header claims 3 vertices"},
        BadInput{"off_index_range", MeshFormat::off, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "refers to vertex 3"},
        BadInput{"off_nan", MeshFormat::off, "OFF\n3 1 0\n0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n", "not finite"},
        BadInput{"off_inf", MeshFormat::off, "OFF\n3 1 0\n0 0 0\n1e999 0 0\n0 1 0\n3 0 1 2\n", "not finite"},
        BadInput{"off_two_corners", MeshFormat::off, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n# a comment\n", "3 or more"},
        BadInput{"off_binary", MeshFormat::off, "OFF BINARY\n", "binary OFF"},
        BadInput{"off_nul", MeshFormat::off, std::string("OFF\n3 1 0\n\0\0\0", 13), "NUL byte"},
        BadInput{"off_no_faces", MeshFormat::off, "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n", "no faces"},
        BadInput{"obj_zero_index", MeshFormat::obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "vertex 0"},
        BadInput{"obj_relative_too_far", MeshFormat::obj, "v 0 0 0\nf -1 -2 -3\n", "before the first vertex"},
        BadInput{"obj_most_negative_index", MeshFormat::obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -9223372036854775808\n",
                 "before the first vertex"},
        BadInput{"obj_out_of_range", MeshFormat::obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", "refers to vertex 8"},
        BadInput{"obj_bad_number", MeshFormat::obj, "v 0 zero 0\n", "vertex y"},
        BadInput{"obj_short_vertex", MeshFormat::obj, "v 0 0\n", "vertex z"},
        BadInput{"obj_no_faces", MeshFormat::obj, "v 0 0 0\n", "no faces"},
        BadInput{"ply_no_magic", MeshFormat::ply, "plx\n", "'ply'"},
        BadInput{"ply_no_end_header", MeshFormat::ply, "ply\nformat ascii 1.0\nelement vertex 3\n", "end_header"},
        BadInput{"ply_unknown_type", MeshFormat::ply,
                 "ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n", "unknown property type"},
        BadInput{"ply_huge_count", MeshFormat::ply,
                 "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\nproperty float x\n"
                 "property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                 "end_header\n",
                 "header claims 1000000000000"},
        BadInput{"ply_truncated_binary", MeshFormat::ply,
                 "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                 "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n" +
                     std::string(12, '\0') + std::string("\x03\x00\x00", 3),
                 "truncated"},
        BadInput{"ply_index_range", MeshFormat::ply,
                 "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                 "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n",
                 "out of range"},
        BadInput{"ply_huge_list_length", MeshFormat::ply,
                 "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                 "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n"
                 "30000000000000000000000000000000000 0 1 2\n",
                 "is out of range (44 allowed)"},
        BadInput{"ply_point_cloud", MeshFormat::ply,
                 "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                 "end_header\n0 0 0\n",
                 "no faces"},
        BadInput{"ply_missing_z", MeshFormat::ply,
                 "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                 "element face 1\nproperty list uchar int vertex_indices\nend_header\n",
                 "'z'"},
        BadInput{"stl_short", MeshFormat::stl, "not an stl", "too short"},
        BadInput{"stl_count_mismatch", MeshFormat::stl, big_endian_count_stl(), "header claims 2147483647"},
        BadInput{"stl_ascii_truncated", MeshFormat::stl, "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n",
                 "expected 'vertex' or 'endloop'"}),
    [](const ::testing::TestParamInfo<BadInput>& param_info) { return std::string(param_info.param.name); });

TEST(ReadMesh, AcceptsTheSmallestWellFormedFiles) {
  EXPECT_EQ(parse("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2", MeshFormat::off).triangles.size(), 1u);
  EXPECT_EQ(parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3", MeshFormat::obj).triangles.size(), 1u);
  EXPECT_EQ(parse("OFF\n3 1 0\n0 0 0\n1e-999 0 0\n0 1 0\n3 0 1 2\n", MeshFormat::off).positions[1].x(), 0.0)
      << "underflow reads as zero";
}

// Finite but absurd: squares and cubes of such coordinates overflow every distance, normal
// and volume computed in double, so they are refused where they are read, naming the vertex.
TEST(ReadMesh, CoordinatesBeyondWhatDoublesCanSquareAreRefused) {
  try {
    parse("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1.5e300 0\n3 0 1 2\n", MeshFormat::off);
    FAIL() << "no error";
  } catch (const InvalidInputError& error) {
    EXPECT_NE(std::string(error.what()).find("vertex 2 has a coordinate of magnitude 1.5e+300"), std::string::npos)
        << error.what();
  }
  EXPECT_EQ(parse("OFF\n3 1 0\n0 0 0\n1e100 0 0\n0 -1e100 0\n3 0 1 2\n", MeshFormat::off).positions[1].x(), 1e100);
}

TEST(ReadMesh, UnknownExtensionAndMissingFile) {
  EXPECT_THROW(read_mesh("mesh.txt"), InvalidInputError);
  EXPECT_THROW(read_mesh("/nonexistent/mesh.off"), IOError);
  EXPECT_THROW(read_mesh("/nonexistent/mesh.glb"), IOError);  // Assimp's formats too
  EXPECT_THROW(read_mesh(VISPROXY_SOURCE_DIR), InvalidInputError);  // no extension
}

}  // namespace
}  // namespace visproxy
