// Proxies exported in float32: every claim proved again on the rounded coordinates, also
// where rounding to nearest breaks it (box planes rounded inward, a ball touching the mesh,
// coordinates far from the origin); the glTF keeps a glTF source whole and round-trips
// through Assimp bit for bit; bad requests are refused before anything is written.

#include "visproxy/asset/export_proxies.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <gtest/gtest.h>

#include <assimp/Importer.hpp>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>
#include <string>

#include "test_support.h"
#include "visproxy/asset/float_proxy.h"
#include "visproxy/asset/gltf_document.h"
#include "visproxy/core/files.h"
#include "visproxy/folder/proxy_folder.h"
#include "visproxy/folder/verdict.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/mesh/sphere_set.h"
#include "visproxy/mesh/write_mesh.h"

namespace visproxy {
namespace {

using nlohmann::json;
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Surface = CGAL::Surface_mesh<Kernel::Point_3>;

Surface surface_of(const TriangleMesh& mesh) {
  Surface surface;
  std::vector<Surface::Vertex_index> vertices;
  for (const Vertex& p : mesh.positions) vertices.push_back(surface.add_vertex({p.x(), p.y(), p.z()}));
  for (const Triangle& t : mesh.triangles) surface.add_face(vertices[t[0]], vertices[t[1]], vertices[t[2]]);
  return surface;
}

// How many of `points` CGAL's exact point location puts strictly outside `container`
// (a closed mesh), or, with `strictly_inside`, not strictly inside it.
std::size_t count_outside(const TriangleMesh& container, const std::vector<Vertex>& points,
                          bool strictly_inside = false) {
  const Surface surface = surface_of(container);
  const CGAL::Side_of_triangle_mesh<Surface, Kernel> side(surface);
  std::size_t outside = 0;
  for (const Vertex& p : points) {
    const CGAL::Bounded_side where = side({p.x(), p.y(), p.z()});
    outside += strictly_inside ? where != CGAL::ON_BOUNDED_SIDE : where == CGAL::ON_UNBOUNDED_SIDE;
  }
  return outside;
}

// A bumpy closed ball of radius about `radius` around `center`, its coordinates doubles that
// float cannot hold.
TriangleMesh bumpy_ball(const Vertex& center, double radius) {
  TriangleMesh mesh = sphere_set_mesh({Sphere{Vertex::Zero(), 1.0}}, 3);
  for (Vertex& p : mesh.positions) p = center + radius * (1 + 0.2 * std::sin(3 * p.x()) * std::cos(2 * p.y())) * p;
  return mesh;
}

const json& entry_named(const json& manifest, const std::string& name) {
  for (const json& entry : manifest.at("proxies"))
    if (entry.at("name") == name) return entry;
  throw std::runtime_error("no proxy " + name);
}

struct Placement {
  const char* name;
  Vertex center;
  double radius;
};

class FloatExport : public testing::ScratchFolder, public ::testing::WithParamInterface<Placement> {
 protected:
  void SetUp() override {
    ScratchFolder::SetUp();
    mesh_ = bumpy_ball(GetParam().center, GetParam().radius);
    source_ = folder_ / "ball.ply";
    write_mesh(source_, mesh_);
    BuildOptions options;
    options.hausdorff_samples = 500;
    options.gssa_lines = 2000;
    manifest_ = build_proxy_folder(folder_ / "proxies", mesh_, source_, Weld::never,
                                   parse_proxy_specs({"aabb", "obb", "hull", "inside:8", "spheres:4"}), options)
                    .manifest;
  }

  FloatProxy rounded(const std::string& name) const {
    const json& entry = entry_named(manifest_, name);
    return round_proxy_to_float(mesh_, manifest_, entry, read_proxy_geometry(folder_ / "proxies", entry), folder_);
  }

  TriangleMesh mesh_;
  std::filesystem::path source_;
  json manifest_;
};

TEST_P(FloatExport, OutsideClaimsKeptWhereRoundingToNearestLetsTheMeshOut) {
  std::size_t broken_by_nearest = 0;
  for (const char* name : {"aabb", "obb", "hull"}) {
    SCOPED_TRACE(name);
    const FloatProxy proxy = rounded(name);
    ASSERT_EQ(proxy.claimed, ProxyKind::outside);
    EXPECT_EQ(proxy.kind, ProxyKind::outside) << proxy.note;
    EXPECT_TRUE(proxy.verify.at("holds").get<bool>());
    // Every coordinate is a float.
    for (const float f : proxy.positions) EXPECT_TRUE(std::isfinite(f));
    // CGAL, independently: no mesh vertex outside the float proxy.
    EXPECT_EQ(count_outside(proxy.mesh(), mesh_.positions), 0u);
    // The nearest rounding, for comparison.
    const json& entry = entry_named(manifest_, name);
    TriangleMesh nearest = read_proxy_geometry(folder_ / "proxies", entry).mesh;
    for (Vertex& p : nearest.positions) p = p.cast<float>().cast<double>();
    const std::size_t out = count_outside(nearest, mesh_.positions);
    if (out > 0) {
      ++broken_by_nearest;
      EXPECT_GT(proxy.moved, 0) << "rounding to nearest lets " << out << " vertices out, yet the proxy was not moved";
    }
  }
  // The fixture must exercise the fallback: the box's planes sit at doubles that round inward.
  EXPECT_GE(broken_by_nearest, 1u);
}

TEST_P(FloatExport, InsideSpheresStayInsideAsFloatIcospheres) {
  const FloatProxy proxy = rounded("inside-8");
  ASSERT_EQ(proxy.claimed, ProxyKind::inside);
  EXPECT_EQ(proxy.kind, ProxyKind::inside) << proxy.note;
  const TriangleMesh polyhedra = proxy.mesh();
  EXPECT_EQ(polyhedra.triangles.size(), 8u * 320u);
  EXPECT_EQ(count_outside(mesh_, polyhedra.positions, true), 0u);
}

TEST_P(FloatExport, GeneralProxiesAreRoundedToNearestWithoutAClaim) {
  const FloatProxy proxy = rounded("spheres-4");
  EXPECT_EQ(proxy.kind, ProxyKind::general);
  EXPECT_EQ(proxy.moved, 0);
  EXPECT_TRUE(proxy.note.empty());
  EXPECT_TRUE(proxy.verify.is_null());
}

TEST_P(FloatExport, HullEditedByHandIsExportedAsGeneralWithTheReason) {
  // The folder's hull shrunk by 10 % about its centre: it lets the mesh out, whatever the rounding.
  const json& entry = entry_named(manifest_, "hull");
  ProxyGeometry geometry = read_proxy_geometry(folder_ / "proxies", entry);
  const Vertex center = GetParam().center;
  for (Vertex& p : geometry.mesh.positions) p = center + 0.9 * (p - center);
  const FloatProxy proxy = round_proxy_to_float(mesh_, manifest_, entry, geometry, folder_);
  EXPECT_EQ(proxy.kind, ProxyKind::general);
  EXPECT_NE(proxy.note.find("did not survive rounding"), std::string::npos) << proxy.note;
  EXPECT_NE(proxy.note.find("vertex"), std::string::npos) << proxy.note;
  // The verdict kept is the one on the geometry exported (the nearest rounding).
  EXPECT_FALSE(proxy.verify.at("holds").get<bool>());
  ProxyGeometry exported;
  exported.mesh = proxy.mesh();
  EXPECT_EQ(proxy.verify.at("proxy_hash"), proxy_content_hash(exported));
}

INSTANTIATE_TEST_SUITE_P(Placements, FloatExport,
                         ::testing::Values(Placement{"NearOrigin", Vertex(0.1, -0.2, 0.3), 0.7},
                                           Placement{"FarFromOrigin", Vertex(12345.678, -9876.543, 30000.1), 3.7}),
                         [](const auto& param_info) { return std::string(param_info.param.name); });

// A GLB made from an OFF source: the source as one node, each proxy a root node with its
// claim in extras, the float data exactly what was proved, read back by Assimp.
class GltfExport : public testing::ScratchFolder {
 protected:
  void SetUp() override {
    ScratchFolder::SetUp();
    mesh_ = bumpy_ball(Vertex(1.5, 2.5, -3.25), 1.3);
    source_ = folder_ / "ball.off";
    std::string off =
        "OFF\n" + std::to_string(mesh_.positions.size()) + " " + std::to_string(mesh_.triangles.size()) + " 0\n";
    char line[128];
    for (const Vertex& p : mesh_.positions) {
      std::snprintf(line, sizeof line, "%.17g %.17g %.17g\n", p.x(), p.y(), p.z());
      off += line;
    }
    for (const Triangle& t : mesh_.triangles)
      off += "3 " + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) + "\n";
    write_file_atomically(source_, off);
    BuildOptions options;
    options.hausdorff_samples = 500;
    options.gssa_lines = 2000;
    build_proxy_folder(folder_ / "proxies", mesh_, source_, Weld::automatic,
                       parse_proxy_specs({"hull", "inside:4", "quadric:64"}), options);
  }
  TriangleMesh mesh_;
  std::filesystem::path source_;
};

TEST_F(GltfExport, GlbHoldsTheSourceAndEveryProxyWithItsClaim) {
  const std::filesystem::path out = folder_ / "ball.glb";
  const ExportResult result = export_proxies(folder_ / "proxies", out, {.source = source_});
  ASSERT_EQ(result.proxies.size(), 3u);
  const GltfDocument document = GltfDocument::read(out);
  const json& nodes = document.json().at("nodes");
  ASSERT_EQ(nodes.size(), 4u);
  EXPECT_EQ(nodes[0].at("name"), "ball");
  EXPECT_EQ(document.json().at("scenes")[0].at("nodes"), json({0, 1, 2, 3}));
  for (std::size_t i = 0; i < 3; ++i) {
    const json& node = nodes[i + 1];
    const ExportedProxy& proxy = result.proxies[i];
    EXPECT_EQ(node.at("name"), "ball." + proxy.name);
    const json& extras = node.at("extras").at("visproxy");
    EXPECT_EQ(extras.at("shadow_only"), true);
    EXPECT_EQ(extras.at("kind"), kind_name(proxy.geometry.kind));
    EXPECT_EQ(extras.at("proxy_hash"), content_hash(proxy.geometry.mesh()));
    EXPECT_EQ(extras.at("proved"), proxy.geometry.kind != ProxyKind::general);
  }
  EXPECT_EQ(result.proxies[0].geometry.kind, ProxyKind::outside);
  EXPECT_EQ(result.proxies[1].geometry.kind, ProxyKind::inside);
  EXPECT_EQ(result.proxies[2].geometry.kind, ProxyKind::general);

  // Assimp, with no processing that could move or merge vertices, sees every proxy as a
  // node whose mesh holds exactly the proved floats.
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(out.string(), aiProcess_ValidateDataStructure);
  ASSERT_NE(scene, nullptr) << importer.GetErrorString();
  for (const ExportedProxy& proxy : result.proxies) {
    SCOPED_TRACE(proxy.node);
    const aiNode* node = scene->mRootNode->FindNode(proxy.node.c_str());
    ASSERT_NE(node, nullptr);
    ASSERT_EQ(node->mNumMeshes, 1u);
    const aiMesh& mesh = *scene->mMeshes[node->mMeshes[0]];
    ASSERT_EQ(3 * mesh.mNumVertices, proxy.geometry.positions.size());
    ASSERT_EQ(3 * mesh.mNumFaces, proxy.geometry.indices.size());
    for (unsigned v = 0; v < mesh.mNumVertices; ++v)
      for (unsigned axis = 0; axis < 3; ++axis)
        ASSERT_EQ(mesh.mVertices[v][axis], proxy.geometry.positions[3 * v + axis]);
    for (unsigned f = 0; f < mesh.mNumFaces; ++f)
      for (unsigned c = 0; c < 3; ++c) ASSERT_EQ(mesh.mFaces[f].mIndices[c], proxy.geometry.indices[3 * f + c]);
  }
}

TEST_F(GltfExport, ObjAndPlyReadBackAsTheProvedFloats) {
  const ExportResult obj =
      export_proxies(folder_ / "proxies", folder_ / "ball.obj", {.proxies = {"hull"}, .source = source_});
  // The OBJ holds the source as read, then the hull: its last vertices are the hull's floats, exactly.
  const TriangleMesh read_back = read_mesh(folder_ / "ball.obj", {.weld = Weld::never});
  const TriangleMesh hull = obj.proxies.at(0).geometry.mesh();
  ASSERT_EQ(read_back.positions.size(), mesh_.positions.size() + hull.positions.size());
  for (std::size_t v = 0; v < hull.positions.size(); ++v)
    ASSERT_EQ(read_back.positions[mesh_.positions.size() + v], hull.positions[v]) << v;
  const std::string text = read_file(folder_ / "ball.obj");
  EXPECT_NE(text.find("o ball.hull\n"), std::string::npos);
  EXPECT_NE(text.find("# visproxy {"), std::string::npos);

  export_proxies(folder_ / "proxies", folder_ / "hull.ply", {.proxies = {"hull"}, .source = source_});
  EXPECT_EQ(read_mesh(folder_ / "hull.ply", {.weld = Weld::never}), hull);
}

TEST_F(GltfExport, BadRequestsAreRefusedAndWriteNothing) {
  const auto refused = [&](const std::filesystem::path& out, const ExportOptions& options,
                           const std::string& expected) {
    try {
      export_proxies(folder_ / "proxies", out, options);
      ADD_FAILURE() << "no error for " << out;
    } catch (const InvalidInputError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(out));
  };
  refused(folder_ / "x.fbx", {.source = source_}, "unknown export format");
  refused(folder_ / "x.ply", {.source = source_}, "a PLY file holds one mesh");
  refused(folder_ / "x.glb", {.proxies = {"hull-7"}, .source = source_}, "lists no proxy named 'hull-7'");
  refused(folder_ / "x.glb", {.source = folder_ / "missing.off"}, "does not exist here");
  // Another mesh than the one the folder was built from.
  TriangleMesh other = mesh_;
  for (Vertex& p : other.positions) p *= 1.01;
  write_mesh(folder_ / "other.ply", other);
  refused(folder_ / "x.glb", {.source = folder_ / "other.ply"}, "other.ply");
}

// A glTF source is kept whole: its materials, textures and buffers, relative URIs rewritten
// for an output in another folder; the proxies come after the source's own nodes.
TEST(GltfSource, KeptWholeWithUrisRewritten) {
  const std::filesystem::path model =
      std::filesystem::path(VISPROXY_ASSIMP_MODEL_DIR) / "glTF2/BoxTextured-glTF/BoxTextured.gltf";
  if (!std::filesystem::exists(model)) GTEST_SKIP() << model << " is missing (Debian's assimp-testmodels)";
  const std::filesystem::path work =
      std::filesystem::temp_directory_path() / ("visproxy-gltf-source-" + std::to_string(::getpid()));
  std::filesystem::remove_all(work);
  std::filesystem::create_directories(work / "out");
  const TriangleMesh mesh = read_mesh(model);
  BuildOptions options;
  options.hausdorff_samples = 200;
  build_proxy_folder(work / "proxies", mesh, model, Weld::automatic, parse_proxy_specs({"aabb", "hull"}), options);
  const GltfDocument source = GltfDocument::read(model);
  for (const char* name : {"box.gltf", "box.glb"}) {
    SCOPED_TRACE(name);
    const ExportResult result = export_proxies(work / "proxies", work / "out" / name, {.source = model});
    const GltfDocument exported = GltfDocument::read(work / "out" / name);
    EXPECT_EQ(exported.json().at("materials"), source.json().at("materials"));
    EXPECT_EQ(exported.json().at("textures"), source.json().at("textures"));
    const std::size_t source_nodes = source.json().at("nodes").size();
    ASSERT_EQ(exported.json().at("nodes").size(), source_nodes + 2);
    for (std::size_t i = 0; i < source_nodes; ++i) EXPECT_EQ(exported.json()["nodes"][i], source.json()["nodes"][i]);
    // The image is found from the output's folder.
    const std::string uri = exported.json().at("images")[0].at("uri").get<std::string>();
    EXPECT_TRUE(std::filesystem::exists(work / "out" / uri)) << uri;
    // Assimp reads it, and its flattened triangles are the source's and the proxies'.
    const TriangleMesh all = read_mesh(work / "out" / name, {.weld = Weld::never});
    std::size_t proxy_triangles = 0;
    for (const ExportedProxy& proxy : result.proxies) proxy_triangles += proxy.geometry.indices.size() / 3;
    EXPECT_EQ(all.triangles.size(), mesh.triangles.size() + proxy_triangles);
    for (const ExportedProxy& proxy : result.proxies)
      EXPECT_EQ(proxy.geometry.kind, ProxyKind::outside) << proxy.geometry.note;
  }
  std::filesystem::remove_all(work);
}

TEST(GltfDocumentRead, MalformedFilesAreNamedWithTheProblem) {
  const std::filesystem::path work =
      std::filesystem::temp_directory_path() / ("visproxy-gltf-bad-" + std::to_string(::getpid()));
  std::filesystem::create_directories(work);
  const auto problem = [&](const std::string& bytes) -> std::string {
    write_file_atomically(work / "bad.glb", bytes);
    try {
      GltfDocument::read(work / "bad.glb");
    } catch (const InvalidInputError& e) {
      EXPECT_NE(std::string(e.what()).find("bad.glb"), std::string::npos) << e.what();
      return e.what();
    }
    return "no error";
  };
  std::string header("glTF\x02\0\0\0", 8);
  EXPECT_NE(problem(header + std::string("\xff\xff\x00\x00", 4) + std::string(8, '\0')).find("beyond the file"),
            std::string::npos);
  EXPECT_NE(problem("{\"asset\": {\"version\": \"1.0\"}}").find("not a glTF 2.0"), std::string::npos);
  EXPECT_NE(problem("{\"asset\": ").find("neither GLB nor glTF"), std::string::npos);
  std::filesystem::remove_all(work);
}

}  // namespace
}  // namespace visproxy
