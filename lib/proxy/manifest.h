#pragma once
// The proxy folder: one file set per proxy and manifest.json listing them.
// Schema: data/schemas/manifest.schema.json.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <span>
#include <string>

#include "visproxy/mesh/triangle_mesh.h"
#include "visproxy/proxy/build_proxies.h"

namespace visproxy {

/// The input mesh as the manifest describes it.
struct ManifestMesh {
  std::filesystem::path path;  ///< as the user gave it
  std::string weld = "auto";   ///< how it was read: "auto", "never" or "always" (read_mesh's Weld)
  std::size_t vertices = 0;
  std::size_t triangles = 0;
  std::size_t components = 0;
  BoundingBox bounds;
};

/// The manifest entry of one proxy (everything but the file names).
nlohmann::json manifest_entry(const BuiltProxy& proxy);

/// Writes NAME.ply (binary) and NAME.obj for every proxy into `folder` (created if
/// missing) - for sphere proxies NAME.json (the sphere set, the entry's `file`) and NAME.ply
/// (their icospheres, for viewing) - then `folder`/manifest.json; every file is written under a temporary name
/// and renamed, so a failure never leaves a partial file. Returns the manifest.
nlohmann::json write_proxy_folder(const std::filesystem::path& folder, const ManifestMesh& mesh,
                                  std::span<const BuiltProxy> proxies, const BuildOptions& options);

}  // namespace visproxy
