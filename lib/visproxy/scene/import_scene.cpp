#include "visproxy/scene/import_scene.h"

#include <assimp/Importer.hpp>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>

#include "visproxy/core/errors.h"
#include "visproxy/core/files.h"
#include "visproxy/mesh/assimp_support.h"
#include "visproxy/mesh/mesh_parsing.h"
#include "visproxy/mesh/read_mesh.h"

namespace visproxy {
namespace {

// KHR_materials_emissive_strength per glTF material index (Assimp 5.2 does not read it):
// from the .gltf's JSON, or the JSON chunk of a .glb. 1 where absent or unreadable.
std::vector<double> emissive_strengths(const std::filesystem::path& path) {
  const std::string extension = parsing::lowercase_extension(path);
  if (extension != ".gltf" && extension != ".glb") return {};
  std::string text = read_file(path);
  if (extension == ".glb") {
    // 12-byte header, then a chunk: length (4 bytes), type "JSON", data.
    if (text.size() < 20 || text.compare(0, 4, "glTF") != 0 || text.compare(16, 4, "JSON") != 0) return {};
    std::uint32_t length = 0;
    std::memcpy(&length, text.data() + 12, 4);
    if (length > text.size() - 20) return {};
    text = text.substr(20, length);
  }
  const nlohmann::json document = nlohmann::json::parse(text, nullptr, false);
  std::vector<double> strengths;
  if (!document.is_object() || !document.contains("materials") || !document["materials"].is_array()) return strengths;
  for (const nlohmann::json& material : document["materials"]) {
    double strength = 1;
    if (material.is_object() && material.contains("extensions") && material["extensions"].is_object()) {
      const nlohmann::json& extensions = material["extensions"];
      if (extensions.contains("KHR_materials_emissive_strength") && extensions["KHR_materials_emissive_strength"].is_object()) {
        const nlohmann::json& value = extensions["KHR_materials_emissive_strength"];
        if (value.contains("emissiveStrength") && value["emissiveStrength"].is_number())
          strength = value["emissiveStrength"].get<double>();
      }
    }
    strengths.push_back(std::isfinite(strength) && strength >= 0 ? strength : 1.0);
  }
  return strengths;
}

}  // namespace

ImportedScene import_scene(const std::filesystem::path& path) {
  // Read once as a mesh first: read_mesh runs Assimp in a child process under memory and
  // time limits, so a file that would crash Assimp or exhaust memory is refused there (one
  // line naming it) before Assimp reads it here; it reads the same file the same way.
  read_mesh(path, {.weld = Weld::never, .on_warning = {}});
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(path.string(), aiProcess_Triangulate | aiProcess_ValidateDataStructure);
  if (scene == nullptr) throw InvalidInputError(path, "Assimp cannot read it: " + parsing::one_line(importer.GetErrorString()));
  if (scene->mRootNode == nullptr) throw InvalidInputError(path, "Assimp read no node hierarchy");
  const std::string extension = parsing::lowercase_extension(path);
  const bool gltf = extension == ".gltf" || extension == ".glb";
  const std::vector<double> strengths = emissive_strengths(path);

  // Each Assimp mesh as a SceneMesh (welded), with its material's colours.
  struct Part {
    int mesh = -1;  // index into result.meshes; -1 when it holds no triangle
    Color albedo = Color::Constant(0.5);
    Color emission = Color::Zero();
    bool two_sided = false;
  };
  ImportedScene result;
  std::vector<Part> parts(scene->mNumMeshes);
  std::map<std::string, int> names;
  const std::string file_name = path.filename().string();
  for (unsigned i = 0; i < scene->mNumMeshes; ++i) {
    const aiMesh* m = scene->mMeshes[i];
    const TriangleMesh mesh = parsing::triangles_of(*m, path);
    if (mesh.triangles.empty()) continue;
    require_coordinates_in_range(mesh, path);
    Part& part = parts[i];
    if (m->mMaterialIndex < scene->mNumMaterials) {
      const aiMaterial* material = scene->mMaterials[m->mMaterialIndex];
      aiColor4D base(0.5f, 0.5f, 0.5f, 1);
      aiColor3D diffuse(0.5f, 0.5f, 0.5f), emissive(0, 0, 0);
      if (material->Get(AI_MATKEY_BASE_COLOR, base) == aiReturn_SUCCESS) part.albedo = Color(base.r, base.g, base.b);
      else if (material->Get(AI_MATKEY_COLOR_DIFFUSE, diffuse) == aiReturn_SUCCESS) part.albedo = Color(diffuse.r, diffuse.g, diffuse.b);
      if (material->Get(AI_MATKEY_COLOR_EMISSIVE, emissive) == aiReturn_SUCCESS) part.emission = Color(emissive.r, emissive.g, emissive.b);
      if (m->mMaterialIndex < strengths.size()) part.emission *= strengths[m->mMaterialIndex];
      int two_sided = 0;
      if (material->Get(AI_MATKEY_TWOSIDED, two_sided) == aiReturn_SUCCESS) part.two_sided = two_sided != 0;
    }
    if (!part.albedo.allFinite()) part.albedo = Color::Constant(0.5);
    part.albedo = part.albedo.cwiseMax(0.0).cwiseMin(1.0);
    if (!part.emission.allFinite() || (part.emission.array() < 0).any()) part.emission = Color::Zero();
    std::string name = file_name + ":" + (m->mName.length > 0 ? std::string(m->mName.C_Str()) : "mesh" + std::to_string(i));
    if (const int seen = names[name]++; seen > 0) name += "#" + std::to_string(seen + 1);
    part.mesh = static_cast<int>(result.meshes.size());
    result.meshes.push_back({name, {}, weld_vertices(mesh), {}});
  }

  // The nodes, depth first in the file's order, with their world transforms; cameras by their node's name.
  std::map<std::string, Eigen::Affine3d> node_transforms;
  std::vector<std::pair<const aiNode*, Eigen::Affine3d>> stack{{scene->mRootNode, parsing::to_affine(scene->mRootNode->mTransformation)}};
  std::vector<bool> used(result.meshes.size(), false);
  while (!stack.empty()) {
    const auto [node, transform] = stack.back();
    stack.pop_back();
    if (!transform.matrix().allFinite()) throw InvalidInputError(path, "a node's transform is not finite");
    node_transforms.emplace(node->mName.C_Str(), transform);
    for (unsigned i = 0; i < node->mNumMeshes; ++i) {
      if (node->mMeshes[i] >= scene->mNumMeshes) throw InvalidInputError(path, "a node names a mesh that does not exist");
      const Part& part = parts[node->mMeshes[i]];
      if (part.mesh < 0) continue;
      const SceneMesh& mesh = result.meshes[static_cast<std::size_t>(part.mesh)];
      for (const Vertex& p : mesh.mesh.positions)
        if (!within_coordinate_range(transform * p))
          throw InvalidInputError(path, "node '" + std::string(node->mName.C_Str()) + "' places its mesh beyond 1e100 in magnitude");
      if (part.emission.maxCoeff() > 0) {
        AreaLight light{.triangles = {}, .radiance = part.emission, .two_sided = part.two_sided};
        for (const Triangle& t : mesh.mesh.triangles)
          light.triangles.push_back({transform * mesh.mesh.positions[t[0]], transform * mesh.mesh.positions[t[1]],
                                     transform * mesh.mesh.positions[t[2]]});
        result.lights.push_back(std::move(light));
      } else {
        result.instances.push_back({.mesh = mesh.name, .transform = transform, .albedo = part.albedo, .proxies = {}});
        used[static_cast<std::size_t>(part.mesh)] = true;
      }
    }
    for (unsigned c = node->mNumChildren; c-- > 0;)  // reversed, so that children are visited in the file's order
      if (node->mChildren[c] != nullptr) stack.emplace_back(node->mChildren[c], transform * parsing::to_affine(node->mChildren[c]->mTransformation));
  }
  // Meshes only lights use are not scene meshes.
  std::vector<SceneMesh> kept;
  for (std::size_t i = 0; i < result.meshes.size(); ++i)
    if (used[i]) kept.push_back(std::move(result.meshes[i]));
  result.meshes = std::move(kept);

  if (scene->mNumCameras > 0) {
    const aiCamera* c = scene->mCameras[0];
    const auto found = node_transforms.find(c->mName.C_Str());
    const Eigen::Affine3d t = found == node_transforms.end() ? Eigen::Affine3d::Identity() : found->second;
    Camera camera;
    const double aspect = c->mAspect > 0 ? c->mAspect : 4.0 / 3;
    if (gltf) {
      // glTF: the camera sits at its node's origin, looking down -Z with +Y up; Assimp
      // stores yfov x aspect in mHorizontalFOV.
      camera.from = t * Vertex::Zero();
      camera.at = camera.from + t.linear() * Vertex(0, 0, -1);
      camera.up = t.linear() * Vertex(0, 1, 0);
      camera.fov_degrees = (c->mAspect > 0 ? c->mHorizontalFOV / c->mAspect : c->mHorizontalFOV) * 180 / std::numbers::pi;
    } else {
      // Assimp's convention: position, look-at direction and up in the node's space, half
      // the horizontal field of view.
      const Vertex position(c->mPosition.x, c->mPosition.y, c->mPosition.z);
      camera.from = t * position;
      camera.at = t * (position + Vertex(c->mLookAt.x, c->mLookAt.y, c->mLookAt.z));
      camera.up = t.linear() * Vertex(c->mUp.x, c->mUp.y, c->mUp.z);
      camera.fov_degrees = 2 * std::atan(std::tan(double(c->mHorizontalFOV)) / aspect) * 180 / std::numbers::pi;
    }
    camera.width = 320;
    camera.height = std::clamp(static_cast<int>(std::lround(320 / aspect)), 1, 16384);
    const Vertex view = camera.at - camera.from;
    if (camera.from.allFinite() && view.allFinite() && view.stableNorm() > 0 && view.cross(camera.up).stableNorm() > 0 &&
        camera.fov_degrees > 0 && camera.fov_degrees < 180)
      result.camera = camera;
    else
      throw InvalidInputError(path, "its camera does not define a view (zero or parallel directions, or a field of view outside (0, 180) degrees)");
  }
  return result;
}

Scene load_imported_scene(const std::filesystem::path& path) {
  ImportedScene imported = import_scene(path);
  if (imported.instances.empty()) throw InvalidInputError(path, "no mesh to render (every mesh with triangles emits light)");
  if (imported.lights.empty()) throw InvalidInputError(path, "no light: no material emits (glTF: emissiveFactor)");
  Scene scene;
  scene.file = path;
  scene.meshes = std::move(imported.meshes);
  scene.instances = std::move(imported.instances);
  scene.lights = std::move(imported.lights);
  if (imported.camera) {
    scene.camera = *imported.camera;
  } else {
    BoundingBox box;
    for (const SceneInstance& instance : scene.instances)
      for (const Vertex& p : scene.mesh(instance.mesh).mesh.positions) box.extend(instance.transform * p);
    const Vertex centre = 0.5 * (box.min + box.max);
    scene.camera.at = centre;
    scene.camera.from = centre + 1.4 * std::max(box.diagonal(), 1e-30) * Vertex(0, 0.3, 1).normalized();
    scene.camera.up = Vertex(0, 1, 0);
    scene.camera.fov_degrees = 40;
    scene.camera.width = 320;
    scene.camera.height = 240;
  }
  return scene;
}

}  // namespace visproxy
