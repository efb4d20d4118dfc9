// The parts of an asset, read by Assimp in a child process (assimp_isolated_bytes) and
// handed back as bytes: per part its name, triangles and instances.

#include "visproxy/mesh/asset_parts.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cstring>
#include <map>
#include <set>

#include "visproxy/core/errors.h"
#include "visproxy/core/files.h"
#include "visproxy/mesh/assimp_support.h"
#include "visproxy/mesh/mesh_parsing.h"

namespace visproxy {
namespace {

// Plain bytes in this machine's order, for the pipe from the child.
class Writer {
 public:
  template <class T>
  void put(const T& value) {
    bytes_.append(reinterpret_cast<const char*>(&value), sizeof value);
  }
  void put_text(const std::string& text) {
    put<std::uint64_t>(text.size());
    bytes_ += text;
  }
  std::string bytes_;
};

class Reader {
 public:
  Reader(const std::string& bytes, const std::filesystem::path& source) : bytes_(bytes), source_(source) {}
  template <class T>
  T get() {
    need(sizeof(T));
    T value;
    std::memcpy(&value, bytes_.data() + at_, sizeof value);
    at_ += sizeof value;
    return value;
  }
  std::string get_text() {
    const auto size = get<std::uint64_t>();
    need(size);
    std::string text = bytes_.substr(at_, size);
    at_ += size;
    return text;
  }
  std::uint64_t count(std::uint64_t item_bytes) {
    const auto n = get<std::uint64_t>();
    if (n > (bytes_.size() - at_) / std::max<std::uint64_t>(item_bytes, 1)) fail();
    return n;
  }

 private:
  void need(std::uint64_t size) {
    if (size > bytes_.size() - at_) fail();
  }
  [[noreturn]] void fail() const { throw InvalidInputError(source_, "Assimp's reader returned truncated parts"); }
  const std::string& bytes_;
  const std::filesystem::path& source_;
  std::size_t at_ = 0;
};

std::string file_name_safe(const std::string& name) {
  std::string out;
  for (const char c : name)
    out.push_back(std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '_' ? c : '_');
  while (!out.empty() && out.front() == '.') out.erase(out.begin());  // no hidden files, no ".."
  return out;
}

std::string encode_parts(const aiScene* scene, const std::filesystem::path& source) {
  if (scene->mRootNode == nullptr) throw InvalidInputError(source, "Assimp read no node hierarchy");
  struct Found {
    std::vector<unsigned> meshes;
    std::vector<PartInstance> instances;
  };
  std::vector<Found> found;
  std::map<std::vector<unsigned>, std::size_t> index_of;
  struct Step {
    const aiNode* node;
    Eigen::Affine3d transform;
    std::vector<std::uint32_t> path;
  };
  std::vector<Step> stack{{scene->mRootNode, parsing::to_affine(scene->mRootNode->mTransformation), {}}};
  std::size_t nodes = 0;
  while (!stack.empty()) {
    Step step = std::move(stack.back());
    stack.pop_back();
    if (++nodes > 10'000'000) throw InvalidInputError(source, "more than 10 million nodes");
    std::vector<unsigned> meshes;
    for (unsigned i = 0; i < step.node->mNumMeshes; ++i) {
      if (step.node->mMeshes[i] >= scene->mNumMeshes)
        throw InvalidInputError(source, "a node names a mesh that does not exist");
      const aiMesh* mesh = scene->mMeshes[step.node->mMeshes[i]];
      // Only meshes with triangles make a part (points and lines are dropped).
      for (unsigned f = 0; f < mesh->mNumFaces; ++f)
        if (mesh->mFaces[f].mNumIndices == 3) {
          meshes.push_back(step.node->mMeshes[i]);
          break;
        }
    }
    if (!meshes.empty()) {
      const auto [it, added] = index_of.try_emplace(meshes, found.size());
      if (added) found.push_back({meshes, {}});
      found[it->second].instances.push_back({step.node->mName.C_Str(), step.path, step.transform});
    }
    // Children pushed in reverse, so that they are met in order.
    for (unsigned c = step.node->mNumChildren; c-- > 0;) {
      const aiNode* child = step.node->mChildren[c];
      if (child == nullptr) continue;
      std::vector<std::uint32_t> path = step.path;
      path.push_back(c);
      stack.push_back({child, step.transform * parsing::to_affine(child->mTransformation), std::move(path)});
    }
  }
  if (found.empty()) throw InvalidInputError(source, "no node shows a mesh with triangles");

  Writer out;
  out.put<std::uint64_t>(found.size());
  std::set<std::string> taken;
  for (std::size_t p = 0; p < found.size(); ++p) {
    const aiMesh& first = *scene->mMeshes[found[p].meshes.front()];
    std::string name = first.mName.C_Str();
    if (found[p].meshes.size() > 1 && name.size() > 2 && name.ends_with("-0")) name.resize(name.size() - 2);
    name = file_name_safe(name);
    if (name.empty()) name = "mesh_" + std::to_string(found[p].meshes.front());
    const std::string base = name;
    for (int k = 2; !taken.insert(name).second; ++k) name = base + "_" + std::to_string(k);
    TriangleMesh mesh;
    for (const unsigned m : found[p].meshes) append_mesh(mesh, parsing::triangles_of(*scene->mMeshes[m], source));
    out.put_text(name);
    out.put<std::uint64_t>(mesh.positions.size());
    for (const Vertex& v : mesh.positions)
      for (int axis = 0; axis < 3; ++axis) out.put(v[axis]);
    out.put<std::uint64_t>(mesh.triangles.size());
    for (const Triangle& t : mesh.triangles) out.put(t);
    out.put<std::uint64_t>(found[p].instances.size());
    for (const PartInstance& instance : found[p].instances) {
      out.put_text(instance.node);
      out.put<std::uint64_t>(instance.path.size());
      for (const std::uint32_t i : instance.path) out.put(i);
      const Eigen::Matrix4d matrix = instance.transform.matrix();
      for (int k = 0; k < 16; ++k) out.put(matrix.data()[k]);
    }
  }
  return std::move(out.bytes_);
}

std::vector<AssetPart> decode_parts(const std::string& bytes, const std::filesystem::path& source) {
  Reader in(bytes, source);
  std::vector<AssetPart> parts(in.count(8));
  for (AssetPart& part : parts) {
    part.name = in.get_text();
    part.mesh.positions.resize(in.count(3 * sizeof(double)));
    for (Vertex& v : part.mesh.positions)
      for (int axis = 0; axis < 3; ++axis) v[axis] = in.get<double>();
    part.mesh.triangles.resize(in.count(sizeof(Triangle)));
    for (Triangle& t : part.mesh.triangles) t = in.get<Triangle>();
    part.instances.resize(in.count(8));
    for (PartInstance& instance : part.instances) {
      instance.node = in.get_text();
      instance.path.resize(in.count(4));
      for (std::uint32_t& i : instance.path) i = in.get<std::uint32_t>();
      Eigen::Matrix4d matrix;
      for (int k = 0; k < 16; ++k) matrix.data()[k] = in.get<double>();
      instance.transform = Eigen::Affine3d(matrix);
    }
  }
  return parts;
}

}  // namespace

std::vector<AssetPart> read_asset_parts(const std::filesystem::path& path, Weld weld) {
  if (!format_from_extension(path) || *format_from_extension(path) != MeshFormat::assimp)
    throw InvalidInputError(path,
                            "the parts of an asset are read from formats Assimp reads (.gltf, .glb, .fbx, .dae, ...)");
  if (!std::filesystem::is_regular_file(path)) read_file(path);  // the IOError a missing file gets
  const std::string bytes = parsing::assimp_isolated_bytes(path, parsing::assimp_input_bytes(path), [&] {
    Assimp::Importer importer;
    const aiScene* scene = importer.ReadFile(path.string(), aiProcess_Triangulate | aiProcess_ValidateDataStructure);
    if (scene == nullptr)
      throw InvalidInputError(path, "Assimp cannot read it: " + parsing::one_line(importer.GetErrorString()));
    if ((scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0)
      throw InvalidInputError(path,
                              "Assimp read it only in part (a scene without meshes, or a mesh it could not complete)");
    return encode_parts(scene, path);
  });
  std::vector<AssetPart> parts = decode_parts(bytes, path);
  for (AssetPart& part : parts) {
    require_coordinates_in_range(part.mesh, path);
    if (weld != Weld::never) part.mesh = weld_vertices(part.mesh);
  }
  return parts;
}

std::optional<std::pair<std::filesystem::path, std::string>> split_part_path(const std::filesystem::path& path) {
  const std::string text = path.string();
  const std::size_t colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 >= text.size()) return std::nullopt;
  const std::filesystem::path asset = text.substr(0, colon);
  const std::optional<MeshFormat> format = format_from_extension(asset);
  std::error_code error;
  if (!format || *format != MeshFormat::assimp || !std::filesystem::is_regular_file(asset, error)) return std::nullopt;
  return std::make_pair(asset, text.substr(colon + 1));
}

}  // namespace visproxy
