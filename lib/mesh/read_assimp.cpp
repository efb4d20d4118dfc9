// Every mesh format Assimp reads beyond visproxy's own four: glTF 2.0, FBX, Collada, 3DS,
// and the rest (Debian's libassimp). The node hierarchy is flattened: each node's meshes
// placed by the product of the transforms down to it, in double. Points and lines are
// dropped, polygons triangulated by Assimp.

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cctype>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/mesh/mesh_parsing.h"

namespace visproxy::parsing {
namespace {

constexpr unsigned kImportSteps = aiProcess_Triangulate | aiProcess_ValidateDataStructure;

// Assimp's messages may span lines; errors are one line.
std::string one_line(std::string text) {
  for (char& c : text)
    if (c == '\n' || c == '\r' || c == '\t') c = ' ';
  while (!text.empty() && text.back() == ' ') text.pop_back();
  return text.empty() ? std::string("no reason given") : text;
}

Eigen::Affine3d to_affine(const aiMatrix4x4& m) {
  Eigen::Matrix4d matrix;
  matrix << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3, m.d4;
  return Eigen::Affine3d(matrix);
}

TriangleMesh flatten(const aiScene* scene, const std::filesystem::path& source) {
  TriangleMesh mesh;
  if (scene->mRootNode == nullptr) throw InvalidInputError(source, "Assimp read no node hierarchy");
  std::vector<std::pair<const aiNode*, Eigen::Affine3d>> stack{{scene->mRootNode, to_affine(scene->mRootNode->mTransformation)}};
  std::size_t nodes = 0;
  while (!stack.empty()) {
    const auto [node, transform] = stack.back();
    stack.pop_back();
    if (++nodes > 10'000'000) throw InvalidInputError(source, "more than 10 million nodes");
    for (unsigned i = 0; i < node->mNumMeshes; ++i) {
      if (node->mMeshes[i] >= scene->mNumMeshes) throw InvalidInputError(source, "a node names a mesh that does not exist");
      const aiMesh* part = scene->mMeshes[node->mMeshes[i]];
      if (part->mNumVertices > 0 && part->mVertices == nullptr) throw InvalidInputError(source, "a mesh without positions");
      const std::size_t base = mesh.positions.size();
      if (base + part->mNumVertices > std::numeric_limits<VertexIndex>::max())
        throw InvalidInputError(source, "more than 2^32 - 1 vertices once the nodes are placed");
      for (unsigned v = 0; v < part->mNumVertices; ++v) {
        const aiVector3D& p = part->mVertices[v];
        mesh.positions.push_back(transform * Vertex(p.x, p.y, p.z));
      }
      for (unsigned f = 0; f < part->mNumFaces; ++f) {
        const aiFace& face = part->mFaces[f];
        if (face.mNumIndices != 3) continue;  // points and lines
        Triangle t;
        for (int k = 0; k < 3; ++k) {
          if (face.mIndices[k] >= part->mNumVertices) throw InvalidInputError(source, "a face index is out of range");
          t[static_cast<std::size_t>(k)] = static_cast<VertexIndex>(base + face.mIndices[k]);
        }
        mesh.triangles.push_back(t);
      }
    }
    for (unsigned c = 0; c < node->mNumChildren; ++c)
      if (node->mChildren[c] != nullptr) stack.emplace_back(node->mChildren[c], transform * to_affine(node->mChildren[c]->mTransformation));
  }
  if (mesh.triangles.empty()) throw InvalidInputError(source, "holds no triangles (Assimp found no faces with three corners)");
  return mesh;
}

std::string extension_of(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

}  // namespace

bool assimp_reads(const std::filesystem::path& path) {
  const std::string extension = extension_of(path);
  if (extension.size() < 2) return false;
  static const Assimp::Importer importer;
  return importer.IsExtensionSupported(extension.c_str());
}

TriangleMesh read_assimp_file(const std::filesystem::path& path) {
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(path.string(), kImportSteps);
  if (scene == nullptr) throw InvalidInputError(path, "Assimp cannot read it: " + one_line(importer.GetErrorString()));
  if ((scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0) throw InvalidInputError(path, "Assimp read it only in part (a scene without meshes, or a mesh it could not complete)");
  return flatten(scene, path);
}

TriangleMesh parse_assimp(std::string_view bytes, const std::filesystem::path& source) {
  Assimp::Importer importer;
  const std::string hint = extension_of(source).empty() ? std::string() : extension_of(source).substr(1);
  const aiScene* scene = importer.ReadFileFromMemory(bytes.data(), bytes.size(), kImportSteps, hint.c_str());
  if (scene == nullptr) throw InvalidInputError(source, "Assimp cannot read it: " + one_line(importer.GetErrorString()));
  if ((scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0) throw InvalidInputError(source, "Assimp read it only in part (a scene without meshes, or a mesh it could not complete)");
  return flatten(scene, source);
}

}  // namespace visproxy::parsing
