#pragma once
// A folder of proxies per part of a multi-mesh asset (`visproxy build --per-mesh`):
// DIR/asset.json lists the asset's meshes, each built once into DIR/PART/ (a proxy folder
// whose mesh is "ASSET:PART"), with the nodes that show it. Schema: data/schemas/asset.schema.json.

#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <string_view>

#include "visproxy/folder/proxy_folder.h"
#include "visproxy/mesh/asset_parts.h"

namespace visproxy {

/// Whether `folder` holds an asset.json (a per-part folder) rather than one proxy folder.
bool is_asset_folder(const std::filesystem::path& folder);

/// Builds `specs` of every part of the asset at `asset` (read_asset_parts) into
/// FOLDER/PART/ with build_proxy_folder, whose manifest names the mesh "ASSET:PART", then
/// writes FOLDER/asset.json atomically:
///   {"format": "visproxy-asset", "format_version": 1, "generator", "source", "weld",
///    "parts": [{"name", "folder", "mesh", "vertices", "triangles",
///               "instances": [{"node", "path", "transform"}], "proxies": [names],
///               "problem": null or one line}]}
/// where `transform` is world from part, 16 numbers row by row. A part whose build fails
/// with InvalidInputError (inside:N of a part that is not closed) keeps its entry with the
/// problem and no folder; the others are built. `on_part(name, i, n)` is called before
/// each part. Built again into a folder, the part folders the old asset.json listed and
/// the new one does not are removed once it is written. Returns asset.json's object.
nlohmann::json build_asset_folder(const std::filesystem::path& folder, const std::filesystem::path& asset, Weld weld,
                                  std::span<const ProxySpec> specs, const BuildOptions& options,
                                  const std::function<void(std::string_view, std::size_t, std::size_t)>& on_part = {});

/// FOLDER/asset.json, checked for the fields the commands read (format, source, parts with
/// name, folder, mesh, instances with node, path and transform). Throws IOError when it
/// cannot be read and InvalidInputError naming it and the JSON path at fault otherwise.
nlohmann::json read_asset_manifest(const std::filesystem::path& folder);

/// One built mesh of a per-mesh folder, read from its asset.
struct BuiltPart {
  nlohmann::json listing;  ///< its entry in asset.json
  std::string name;
  std::filesystem::path folder;     ///< FOLDER/NAME
  std::filesystem::path mesh_path;  ///< "ASSET:NAME", as its manifest records it
  nlohmann::json manifest;          ///< FOLDER/NAME/manifest.json
  TriangleMesh mesh;                ///< checked against the manifest (check_manifest_mesh)
};

struct BuiltParts {
  std::filesystem::path source;  ///< the asset read
  std::vector<BuiltPart> parts;
};

/// The built meshes of the per-mesh folder `folder` (those asset.json lists with a folder),
/// in its order, the asset (`asset`, or asset.json's source when empty) read once with
/// asset.json's welding. Throws InvalidInputError naming the asset when it holds no mesh of
/// a listed name or one differs from its manifest, and what read_asset_parts and
/// read_manifest throw.
BuiltParts read_built_parts(const std::filesystem::path& folder, const std::filesystem::path& asset);

/// An instance's transform as asset.json holds it (16 numbers, row by row).
Eigen::Affine3d instance_transform(const nlohmann::json& instance);

}  // namespace visproxy
