#pragma once
// A glTF 2.0 asset held as its JSON and binary chunk, so that meshes and nodes can be
// added to it and everything the source holds (materials, textures, animations,
// extensions) is written back as it was.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>

namespace visproxy {

class GltfDocument {
 public:
  /// Reads a .gltf (JSON) or .glb (binary) file, by its first bytes. Throws
  /// InvalidInputError naming the file when it is neither, when a GLB's chunks do not fit
  /// in the file, when the JSON does not parse or is not a glTF 2.x asset.
  static GltfDocument read(const std::filesystem::path& path);

  /// An asset of its own, one scene and nothing in it. `generator` goes in asset.generator.
  static GltfDocument empty(const std::string& generator);

  /// Adds a mesh of one triangle primitive: float32 positions (3 per vertex; the POSITION
  /// accessor's min and max are their exact extremes) and 32-bit indices (3 per triangle),
  /// both in the binary chunk. Returns the mesh's index.
  std::size_t add_mesh(const std::string& name, std::span<const float> positions,
                       std::span<const std::uint32_t> indices);

  /// Adds a node showing `mesh` (none if nullopt) with `extras` (none if null) and
  /// `matrix` (16 numbers, column by column; none if null), as a child of node `parent`, or
  /// as a root node of the default scene when nullopt. Returns its index.
  std::size_t add_node(const std::string& name, std::optional<std::size_t> mesh, std::optional<std::size_t> parent,
                       const nlohmann::json& extras, const nlohmann::json& matrix = nullptr);

  /// Rewrites every relative URI (buffers and images, not data: URIs) that resolves from
  /// `from` so that it resolves to the same file from `to`: for writing the asset into
  /// another folder than the one it was read from.
  void move_uris(const std::filesystem::path& from, const std::filesystem::path& to);

  /// The bytes of a .glb: a JSON chunk and, if the asset has one, its binary chunk (buffer 0).
  std::string glb() const;
  /// The bytes of a .gltf: the JSON, the binary chunk embedded in buffer 0 as a base64 data: URI.
  std::string gltf() const;

  const nlohmann::json& json() const { return json_; }

 private:
  // Makes buffer 0 the binary chunk (a buffer without a uri), inserting it in front of
  // the source's buffers (their references shifted by one) when it has none.
  void ensure_binary_chunk();
  std::size_t append_view(std::string_view bytes, int target);

  nlohmann::json json_;
  std::string bin_;  // buffer 0's bytes when has_bin_
  bool has_bin_ = false;
};

}  // namespace visproxy
