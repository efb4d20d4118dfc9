#include "visproxy/asset/gltf_document.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cstring>
#include <limits>
#include <string_view>

#include "visproxy/core/errors.h"
#include "visproxy/core/files.h"

namespace visproxy {
namespace {

using Json = nlohmann::json;

constexpr std::uint32_t kGlbMagic = 0x46546C67;   // "glTF"
constexpr std::uint32_t kJsonChunk = 0x4E4F534A;  // "JSON"
constexpr std::uint32_t kBinChunk = 0x004E4942;   // "BIN\0"
constexpr int kArrayBuffer = 34962;
constexpr int kElementArrayBuffer = 34963;

std::uint32_t read_u32(std::string_view bytes, std::size_t at) {
  std::uint32_t value = 0;
  for (int i = 3; i >= 0; --i)
    value = (value << 8) | static_cast<unsigned char>(bytes[at + static_cast<std::size_t>(i)]);
  return value;
}

void put_u32(std::string& out, std::uint32_t value) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((value >> (8 * i)) & 0xFF));
}

void pad_to_four(std::string& bytes, char with) {
  while (bytes.size() % 4 != 0) bytes.push_back(with);
}

std::string base64(std::string_view bytes) {
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const std::uint32_t v = (static_cast<unsigned char>(bytes[i]) << 16) |
                            (static_cast<unsigned char>(bytes[i + 1]) << 8) | static_cast<unsigned char>(bytes[i + 2]);
    for (int s = 18; s >= 0; s -= 6) out.push_back(kAlphabet[(v >> s) & 63]);
  }
  if (i < bytes.size()) {
    const bool two = i + 1 < bytes.size();
    const std::uint32_t v =
        (static_cast<unsigned char>(bytes[i]) << 16) | (two ? static_cast<unsigned char>(bytes[i + 1]) << 8 : 0);
    out.push_back(kAlphabet[(v >> 18) & 63]);
    out.push_back(kAlphabet[(v >> 12) & 63]);
    out.push_back(two ? kAlphabet[(v >> 6) & 63] : '=');
    out.push_back('=');
  }
  return out;
}

// A relative URI reference: no scheme ("data:", "http:") and not absolute.
bool relative_uri(const std::string& uri) {
  if (uri.empty() || uri.front() == '/') return false;
  const std::size_t colon = uri.find(':');
  const std::size_t slash = uri.find('/');
  return colon == std::string::npos || (slash != std::string::npos && slash < colon);
}

std::string percent_decode(const std::string& uri) {
  std::string out;
  for (std::size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] == '%' && i + 2 < uri.size() && std::isxdigit(static_cast<unsigned char>(uri[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(uri[i + 2]))) {
      out.push_back(static_cast<char>(std::stoi(uri.substr(i + 1, 2), nullptr, 16)));
      i += 2;
    } else {
      out.push_back(uri[i]);
    }
  }
  return out;
}

std::string percent_encode(const std::string& path) {
  static constexpr char kHex[] = "0123456789ABCDEF";
  std::string out;
  for (const char c : path) {
    const auto u = static_cast<unsigned char>(c);
    if (std::isalnum(u) || std::strchr("-._~/", c) != nullptr) {
      out.push_back(c);
    } else {
      out.push_back('%');
      out.push_back(kHex[u >> 4]);
      out.push_back(kHex[u & 15]);
    }
  }
  return out;
}

Json& array_of(Json& object, const char* key) {
  if (!object.contains(key) || !object[key].is_array()) object[key] = Json::array();
  return object[key];
}

}  // namespace

GltfDocument GltfDocument::read(const std::filesystem::path& path) {
  const std::string bytes = read_file(path);
  GltfDocument document;
  std::string_view text = bytes;
  if (bytes.size() >= 4 && read_u32(bytes, 0) == kGlbMagic) {
    if (bytes.size() < 20)
      throw InvalidInputError(path, "a GLB file shorter than its 12-byte header and one chunk header");
    if (read_u32(bytes, 4) != 2)
      throw InvalidInputError(path, "GLB version " + std::to_string(read_u32(bytes, 4)) + " (only glTF 2.0 is read)");
    const std::size_t length = read_u32(bytes, 8);
    if (length > bytes.size()) throw InvalidInputError(path, "the GLB header gives a length beyond the file's end");
    std::size_t at = 12;
    bool have_json = false;
    while (at + 8 <= length) {
      const std::size_t chunk = read_u32(bytes, at);
      const std::uint32_t type = read_u32(bytes, at + 4);
      if (chunk > length - at - 8) throw InvalidInputError(path, "a GLB chunk runs beyond the file's length");
      if (!have_json) {
        if (type != kJsonChunk) throw InvalidInputError(path, "the first GLB chunk is not JSON");
        text = std::string_view(bytes).substr(at + 8, chunk);
        have_json = true;
      } else if (type == kBinChunk && !document.has_bin_) {
        document.bin_.assign(bytes, at + 8, chunk);
        document.has_bin_ = true;
      }
      at += 8 + chunk;
    }
    if (!have_json) throw InvalidInputError(path, "a GLB file without a JSON chunk");
  }
  try {
    document.json_ = Json::parse(text);
  } catch (const Json::parse_error& e) {
    throw InvalidInputError(path, std::string("is neither GLB nor glTF JSON: ") + e.what());
  }
  const Json& asset = document.json_.is_object() ? document.json_.value("asset", Json()) : Json();
  if (!asset.is_object() || !asset.contains("version") || !asset["version"].is_string() ||
      asset["version"].get<std::string>().rfind("2.", 0) != 0)
    throw InvalidInputError(path, "asset.version is not \"2.x\": not a glTF 2.0 asset");
  if (document.has_bin_) {
    const Json& buffers = document.json_.value("buffers", Json::array());
    if (buffers.empty() || buffers[0].contains("uri"))
      throw InvalidInputError(path, "a GLB binary chunk that no buffer without a uri refers to");
    if (buffers[0].value("byteLength", std::uint64_t{0}) > document.bin_.size())
      throw InvalidInputError(path, "buffers[0].byteLength is larger than the GLB binary chunk");
  } else if (document.json_.contains("buffers") && document.json_["buffers"].is_array()) {
    for (const Json& buffer : document.json_["buffers"])
      if (!buffer.contains("uri")) throw InvalidInputError(path, "a buffer without a uri outside a GLB binary chunk");
  }
  return document;
}

GltfDocument GltfDocument::empty(const std::string& generator) {
  GltfDocument document;
  document.json_ = {{"asset", {{"version", "2.0"}, {"generator", generator}}},
                    {"scene", 0},
                    {"scenes", Json::array({Json{{"nodes", Json::array()}}})}};
  return document;
}

void GltfDocument::ensure_binary_chunk() {
  if (has_bin_) return;
  Json& buffers = array_of(json_, "buffers");
  buffers.insert(buffers.begin(), Json{{"byteLength", 0}});
  if (json_.contains("bufferViews"))
    for (Json& view : json_["bufferViews"]) {
      if (view.contains("buffer") && view["buffer"].is_number_integer())
        view["buffer"] = view["buffer"].get<std::int64_t>() + 1;
      // Compression extensions name their own buffer (EXT_meshopt_compression).
      if (view.contains("extensions") && view["extensions"].is_object())
        for (auto& [name, extension] : view["extensions"].items())
          if (extension.is_object() && extension.contains("buffer") && extension["buffer"].is_number_integer())
            extension["buffer"] = extension["buffer"].get<std::int64_t>() + 1;
    }
  has_bin_ = true;
}

std::size_t GltfDocument::append_view(std::string_view bytes, int target) {
  ensure_binary_chunk();
  pad_to_four(bin_, '\0');
  const std::size_t offset = bin_.size();
  bin_.append(bytes);
  json_["buffers"][0]["byteLength"] = bin_.size();
  Json& views = array_of(json_, "bufferViews");
  views.push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes.size()}, {"target", target}});
  return views.size() - 1;
}

std::size_t GltfDocument::add_mesh(const std::string& name, std::span<const float> positions,
                                   std::span<const std::uint32_t> indices) {
  std::string position_bytes(positions.size_bytes(), '\0');
  std::memcpy(position_bytes.data(), positions.data(), positions.size_bytes());  // little-endian hosts only
  std::string index_bytes(indices.size_bytes(), '\0');
  std::memcpy(index_bytes.data(), indices.data(), indices.size_bytes());
  const std::size_t position_view = append_view(position_bytes, kArrayBuffer);
  const std::size_t index_view = append_view(index_bytes, kElementArrayBuffer);

  std::array<float, 3> low{}, high{};
  low.fill(std::numeric_limits<float>::infinity());
  high.fill(-std::numeric_limits<float>::infinity());
  for (std::size_t i = 0; i < positions.size(); ++i) {
    low[i % 3] = std::min(low[i % 3], positions[i]);
    high[i % 3] = std::max(high[i % 3], positions[i]);
  }
  std::uint32_t max_index = 0;
  for (const std::uint32_t index : indices) max_index = std::max(max_index, index);
  Json& accessors = array_of(json_, "accessors");
  accessors.push_back({{"bufferView", position_view},
                       {"componentType", 5126},
                       {"count", positions.size() / 3},
                       {"type", "VEC3"},
                       {"min", {low[0], low[1], low[2]}},
                       {"max", {high[0], high[1], high[2]}}});
  const std::size_t position_accessor = accessors.size() - 1;
  accessors.push_back({{"bufferView", index_view},
                       {"componentType", 5125},
                       {"count", indices.size()},
                       {"type", "SCALAR"},
                       {"min", {0}},
                       {"max", {max_index}}});
  const std::size_t index_accessor = accessors.size() - 1;
  Json& meshes = array_of(json_, "meshes");
  meshes.push_back({{"name", name},
                    {"primitives", Json::array({Json{{"attributes", {{"POSITION", position_accessor}}},
                                                     {"indices", index_accessor},
                                                     {"mode", 4}}})}});
  return meshes.size() - 1;
}

std::size_t GltfDocument::add_node(const std::string& name, std::optional<std::size_t> mesh,
                                   std::optional<std::size_t> parent, const Json& extras, const Json& matrix) {
  Json& nodes = array_of(json_, "nodes");
  Json node = {{"name", name}};
  if (!matrix.is_null()) node["matrix"] = matrix;
  if (mesh) node["mesh"] = *mesh;
  if (!extras.is_null()) node["extras"] = extras;
  nodes.push_back(std::move(node));
  const std::size_t index = nodes.size() - 1;
  if (parent) {
    array_of(nodes.at(*parent), "children").push_back(index);
  } else {
    Json& scenes = array_of(json_, "scenes");
    if (scenes.empty()) scenes.push_back(Json::object());
    const std::size_t scene =
        json_.contains("scene") && json_["scene"].is_number_unsigned() ? json_["scene"].get<std::size_t>() : 0;
    if (!json_.contains("scene")) json_["scene"] = 0;
    array_of(scenes.at(std::min(scene, scenes.size() - 1)), "nodes").push_back(index);
  }
  return index;
}

void GltfDocument::move_uris(const std::filesystem::path& from, const std::filesystem::path& to) {
  const std::filesystem::path source = std::filesystem::weakly_canonical(from.empty() ? "." : from);
  const std::filesystem::path target = std::filesystem::weakly_canonical(to.empty() ? "." : to);
  if (source == target) return;
  for (const char* list : {"buffers", "images"}) {
    if (!json_.contains(list) || !json_[list].is_array()) continue;
    for (Json& item : json_[list]) {
      if (!item.contains("uri") || !item["uri"].is_string()) continue;
      const std::string uri = item["uri"].get<std::string>();
      if (!relative_uri(uri)) continue;
      const std::filesystem::path file = (source / percent_decode(uri)).lexically_normal();
      item["uri"] = percent_encode(file.lexically_relative(target).generic_string());
    }
  }
}

std::string GltfDocument::glb() const {
  std::string text = json_.dump();
  pad_to_four(text, ' ');
  std::string bin = has_bin_ ? bin_ : std::string();
  pad_to_four(bin, '\0');
  const std::size_t total = 12 + 8 + text.size() + (has_bin_ ? 8 + bin.size() : 0);
  if (total > std::numeric_limits<std::uint32_t>::max()) throw Error("the GLB would exceed 4 GiB, the format's limit");
  std::string out;
  out.reserve(total);
  put_u32(out, kGlbMagic);
  put_u32(out, 2);
  put_u32(out, static_cast<std::uint32_t>(total));
  put_u32(out, static_cast<std::uint32_t>(text.size()));
  put_u32(out, kJsonChunk);
  out += text;
  if (has_bin_) {
    put_u32(out, static_cast<std::uint32_t>(bin.size()));
    put_u32(out, kBinChunk);
    out += bin;
  }
  return out;
}

std::string GltfDocument::gltf() const {
  Json copy = json_;
  if (has_bin_) copy["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64(bin_);
  return copy.dump(1) + "\n";
}

}  // namespace visproxy
