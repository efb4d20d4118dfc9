#include "visproxy/folder/asset_folder.h"

#include <algorithm>

#include "visproxy/core/files.h"
#include "visproxy/core/json_input.h"
#include "visproxy/core/version.h"

namespace visproxy {
namespace {

using json = nlohmann::json;

constexpr const char* kAssetFile = "asset.json";

}  // namespace

bool is_asset_folder(const std::filesystem::path& folder) {
  std::error_code error;
  return std::filesystem::is_regular_file(folder / kAssetFile, error);
}

json build_asset_folder(const std::filesystem::path& folder, const std::filesystem::path& asset, Weld weld,
                        std::span<const ProxySpec> specs, const BuildOptions& options,
                        const std::function<void(std::string_view, std::size_t, std::size_t)>& on_part) {
  const std::vector<AssetPart> parts = read_asset_parts(asset, weld);
  // The parts an earlier build listed here, whose folders go once the new listing is written.
  std::vector<std::string> earlier;
  if (is_asset_folder(folder)) {
    try {
      const json listing = read_asset_manifest(folder);
      for (const json& part : listing.at("parts"))
        if (!part.at("folder").is_null()) earlier.push_back(part.at("folder").get<std::string>());
    } catch (const Error&) {
      // An unreadable listing names no folders to remove.
    }
  }
  json entries = json::array();
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const AssetPart& part = parts[i];
    if (on_part) on_part(part.name, i, parts.size());
    json instances = json::array();
    for (const PartInstance& instance : part.instances) {
      json transform = json::array();
      for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) transform.push_back(instance.transform.matrix()(r, c));
      instances.push_back({{"node", instance.node}, {"path", instance.path}, {"transform", transform}});
    }
    json entry = {{"name", part.name},
                  {"folder", part.name},
                  {"mesh", asset.string() + ":" + part.name},
                  {"vertices", part.mesh.positions.size()},
                  {"triangles", part.mesh.triangles.size()},
                  {"instances", instances},
                  {"proxies", json::array()},
                  {"problem", nullptr}};
    try {
      const BuiltFolder built =
          build_proxy_folder(folder / part.name, part.mesh, asset.string() + ":" + part.name, weld, specs, options);
      for (const json& proxy : built.manifest.at("proxies")) entry["proxies"].push_back(proxy.at("name"));
    } catch (const InvalidInputError& e) {
      entry["folder"] = nullptr;
      entry["problem"] = e.what();
    }
    entries.push_back(std::move(entry));
  }
  const json manifest = {
      {"format", "visproxy-asset"}, {"format_version", 1},   {"generator", std::string("visproxy ") + version()},
      {"source", asset.string()},   {"weld", name_of(weld)}, {"parts", entries}};
  write_file_atomically(folder / kAssetFile, manifest.dump(2) + "\n");
  for (const std::string& name : earlier) {
    const bool listed =
        std::any_of(entries.begin(), entries.end(), [&](const json& e) { return e.at("folder") == name; });
    std::error_code error;  // only a proxy folder of a plain name inside this folder is removed
    if (!listed && name.find('/') == std::string::npos && name.front() != '.' &&
        std::filesystem::is_regular_file(folder / name / "manifest.json", error))
      std::filesystem::remove_all(folder / name, error);
  }
  return manifest;
}

json read_asset_manifest(const std::filesystem::path& folder) {
  const JsonInput input(folder / kAssetFile);
  const json manifest = input.parse(read_file(folder / kAssetFile));
  input.object(manifest, "");
  if (input.string(input.member(manifest, "format", ""), "format") != "visproxy-asset")
    input.fail("format", "must be \"visproxy-asset\"");
  input.integer(input.member(manifest, "format_version", ""), "format_version", 1, 1);
  input.string(input.member(manifest, "source", ""), "source");
  const json& parts = input.member(manifest, "parts", "");
  if (!parts.is_array()) input.fail("parts", "must be an array");
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const std::string where = json_index_path("parts", i);
    input.object(parts[i], where);
    const std::string& name = input.string(input.member(parts[i], "name", where), where + ".name");
    if (name.empty() || name.find('/') != std::string::npos || name.front() == '.')
      input.fail(where + ".name", "must be a plain file name");
    const json& part_folder = input.member(parts[i], "folder", where);
    if (!part_folder.is_null() && input.string(part_folder, where + ".folder") != name)
      input.fail(where + ".folder", "must be the part's name (or null for a part that was not built)");
    input.string(input.member(parts[i], "mesh", where), where + ".mesh");
    const json& instances = input.member(parts[i], "instances", where);
    if (!instances.is_array()) input.fail(where + ".instances", "must be an array");
    for (std::size_t k = 0; k < instances.size(); ++k) {
      const std::string at = json_index_path(where + ".instances", k);
      input.object(instances[k], at);
      input.string(input.member(instances[k], "node", at), at + ".node");
      const json& path = input.member(instances[k], "path", at);
      if (!path.is_array()) input.fail(at + ".path", "must be an array of child indices");
      for (std::size_t j = 0; j < path.size(); ++j)
        input.integer(path[j], json_index_path(at + ".path", j), 0, 0xFFFFFFFFu);
      const json& transform = input.member(instances[k], "transform", at);
      if (!transform.is_array() || transform.size() != 16)
        input.fail(at + ".transform", "must be an array of 16 numbers");
      for (std::size_t j = 0; j < 16; ++j) input.number(transform[j], json_index_path(at + ".transform", j));
    }
  }
  return manifest;
}

BuiltParts read_built_parts(const std::filesystem::path& folder, const std::filesystem::path& asset) {
  const json listing = read_asset_manifest(folder);
  const std::filesystem::path source =
      asset.empty() ? std::filesystem::path(listing.at("source").get<std::string>()) : asset;
  std::vector<AssetPart> parts =
      read_asset_parts(source, find_choice<Weld>(listing.at("weld").get<std::string>()).value_or(Weld::automatic));
  BuiltParts built{.source = source, .parts = {}};
  for (const json& part : listing.at("parts")) {
    if (part.at("folder").is_null()) continue;
    const std::string name = part.at("name").get<std::string>();
    const auto read = std::find_if(parts.begin(), parts.end(), [&](const AssetPart& p) { return p.name == name; });
    if (read == parts.end())
      throw InvalidInputError(source,
                              "holds no mesh named '" + name + "' (built into " + (folder / name).string() + ")");
    BuiltPart entry{.listing = part,
                    .name = name,
                    .folder = folder / name,
                    .mesh_path = source.string() + ":" + name,
                    .manifest = read_manifest(folder / name),
                    .mesh = std::move(read->mesh)};
    check_manifest_mesh(entry.mesh, entry.mesh_path, entry.manifest);
    built.parts.push_back(std::move(entry));
  }
  return built;
}

Eigen::Affine3d instance_transform(const json& instance) {
  Eigen::Matrix4d matrix;
  const json& t = instance.at("transform");
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) matrix(r, c) = t.at(static_cast<std::size_t>(4 * r + c)).get<double>();
  return Eigen::Affine3d(matrix);
}

}  // namespace visproxy
