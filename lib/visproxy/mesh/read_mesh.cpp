#include "visproxy/mesh/read_mesh.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cstring>
#include <string>
#include <unordered_map>

#include "visproxy/core/errors.h"
#include "visproxy/core/files.h"
#include "visproxy/mesh/asset_parts.h"
#include "visproxy/mesh/mesh_parsing.h"

namespace visproxy {

std::string_view format_name(MeshFormat format) {
  switch (format) {
    case MeshFormat::obj: return "OBJ";
    case MeshFormat::ply: return "PLY";
    case MeshFormat::off: return "OFF";
    case MeshFormat::stl: return "STL";
    case MeshFormat::assimp: return "Assimp";
  }
  return "unknown";
}

namespace parsing {

std::string lowercase_extension(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

}  // namespace parsing

std::optional<MeshFormat> format_from_extension(const std::filesystem::path& path) {
  const std::string extension = parsing::lowercase_extension(path);
  if (extension == ".obj") return MeshFormat::obj;
  if (extension == ".ply") return MeshFormat::ply;
  if (extension == ".off") return MeshFormat::off;
  if (extension == ".stl") return MeshFormat::stl;
  if (parsing::assimp_reads(path)) return MeshFormat::assimp;
  if (split_part_path(path)) return MeshFormat::assimp;  // ASSET:MESH, one mesh of an asset
  return std::nullopt;
}

namespace {

TriangleMesh finish(TriangleMesh mesh, MeshFormat format, const std::filesystem::path& source, const ReadMeshOptions& options) {
  require_coordinates_in_range(mesh, source);
  const bool weld = options.weld == Weld::always ||
                    (options.weld == Weld::automatic && (format == MeshFormat::stl || format == MeshFormat::assimp));
  if (weld) return weld_vertices(mesh);
  return mesh;  // moved, not copied
}

}  // namespace

TriangleMesh parse_mesh(std::string_view bytes, MeshFormat format, const std::filesystem::path& source,
                        const ReadMeshOptions& options) {
  if (bytes.empty()) throw InvalidInputError(source, "the file is empty");
  if (format == MeshFormat::obj || format == MeshFormat::off) {
    const std::size_t nul = bytes.find('\0');
    if (nul != std::string_view::npos)
      throw InvalidInputError(source, "binary data (a NUL byte at offset " + std::to_string(nul) + ") in a text " +
                                          std::string(format_name(format)) + " file");
  }
  TriangleMesh mesh;
  switch (format) {
    case MeshFormat::obj: mesh = parsing::parse_obj(bytes, source); break;
    case MeshFormat::ply: mesh = parsing::parse_ply(bytes, source, options.on_warning); break;
    case MeshFormat::off: mesh = parsing::parse_off(bytes, source); break;
    case MeshFormat::stl: mesh = parsing::parse_stl(bytes, source); break;
    case MeshFormat::assimp: mesh = parsing::parse_assimp(bytes, source); break;
  }
  return finish(std::move(mesh), format, source, options);
}

TriangleMesh read_mesh(const std::filesystem::path& path, const ReadMeshOptions& options) {
  std::error_code error;
  if (const auto part = split_part_path(path); part && !std::filesystem::exists(path, error)) {
    std::vector<AssetPart> parts = read_asset_parts(part->first, options.weld);
    std::string names;
    for (AssetPart& p : parts) {
      if (p.name == part->second) return std::move(p.mesh);
      if (names.size() < 300) names += (names.empty() ? "" : ", ") + p.name;
    }
    throw InvalidInputError(part->first, "holds no mesh named '" + part->second + "' (its meshes: " + names +
                                             (names.size() >= 300 ? ", ..." : "") + ")");
  }
  const std::optional<MeshFormat> format = format_from_extension(path);
  if (!format)
    throw InvalidInputError(path, "unknown mesh file extension " +
                                      (path.extension().empty() ? std::string("(none)") : "'" + path.extension().string() + "'") +
                                      "; expected .obj, .ply, .off, .stl or a format Assimp reads (.gltf, .glb, .fbx, .dae, .3ds, ...)");
  if (*format == MeshFormat::assimp) {
    if (!std::filesystem::is_regular_file(path)) read_file(path);  // the IOError a missing file gets
    return finish(parsing::read_assimp_file(path), *format, path, options);
  }
  const std::string bytes = read_file(path);
  return parse_mesh(bytes, *format, path, options);
}

namespace {

struct PositionKey {
  std::uint64_t x, y, z;
  bool operator==(const PositionKey&) const = default;
};

struct PositionKeyHash {
  std::size_t operator()(const PositionKey& key) const {
    std::uint64_t h = key.x * 0x9E3779B97F4A7C15ull;
    h ^= (key.y + 0x632BE59BD9B4E019ull + (h << 6) + (h >> 2)) * 0xC2B2AE3D27D4EB4Full;
    h ^= (key.z + 0x165667B19E3779F9ull + (h << 6) + (h >> 2)) * 0x9E3779B97F4A7C15ull;
    return static_cast<std::size_t>(h ^ (h >> 29));
  }
};

PositionKey key_of(const Vertex& p) {
  // Adding +0.0 turns -0.0 into +0.0, so the two zeros weld.
  return {std::bit_cast<std::uint64_t>(p.x() + 0.0), std::bit_cast<std::uint64_t>(p.y() + 0.0),
          std::bit_cast<std::uint64_t>(p.z() + 0.0)};
}

}  // namespace

template <>
const std::vector<std::pair<std::string_view, Weld>>& choice_names<Weld>() {
  static const std::vector<std::pair<std::string_view, Weld>> names{
      {"auto", Weld::automatic}, {"never", Weld::never}, {"always", Weld::always}};
  return names;
}

TriangleMesh weld_vertices(const TriangleMesh& mesh) {
  TriangleMesh welded;
  welded.triangles.reserve(mesh.triangles.size());
  std::unordered_map<PositionKey, VertexIndex, PositionKeyHash> index_of;
  index_of.reserve(mesh.positions.size());
  std::vector<VertexIndex> remap(mesh.positions.size(), std::numeric_limits<VertexIndex>::max());
  for (const Triangle& triangle : mesh.triangles) {
    Triangle renumbered;
    for (int k = 0; k < 3; ++k) {
      VertexIndex& target = remap[triangle[k]];
      if (target == std::numeric_limits<VertexIndex>::max()) {
        const Vertex& p = mesh.positions[triangle[k]];
        const auto [it, inserted] = index_of.try_emplace(key_of(p), static_cast<VertexIndex>(welded.positions.size()));
        if (inserted) welded.positions.push_back(p);
        target = it->second;
      }
      renumbered[k] = target;
    }
    welded.triangles.push_back(renumbered);
  }
  return welded;
}

}  // namespace visproxy
