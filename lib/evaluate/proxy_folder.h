#pragma once
// A proxy folder written by `visproxy build`, read back: the manifest, the mesh it was
// built from, and each proxy's geometry.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string_view>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/mesh/sphere_set.h"
#include "visproxy/mesh/triangle_mesh.h"
#include "visproxy/proxy/build_proxies.h"

namespace visproxy {

/// FOLDER/manifest.json, checked for the fields read_manifest_mesh, read_proxy_geometry,
/// entry_kind and the commands' summaries read: format and format_version; generator (if
/// present); mesh.path, vertices, triangles, bbox.min and bbox.max, weld (if present);
/// options; each entry's name, kind, file, primitive_type, primitives and triangles (if
/// present). Throws IOError when it cannot be read and InvalidInputError naming it and the
/// JSON path at fault ("manifest.json: proxies[2].kind: must be ...") otherwise. The
/// measure, verify and error objects the report reads are not checked.
nlohmann::json read_manifest(const std::filesystem::path& folder);

/// The same from the manifest's text; `path` names it in errors.
nlohmann::json parse_manifest(std::string_view text, const std::filesystem::path& path);

/// Writes FOLDER/manifest.json atomically (two-space indented, newline at the end).
void write_manifest(const std::filesystem::path& folder, const nlohmann::json& manifest);

/// Reads the mesh at `path` as `visproxy build` did (same welding) and checks it is the
/// one the manifest describes: same vertex and triangle counts and bounding box. Throws
/// InvalidInputError naming `path` otherwise. The reader's warnings go to `on_warning`.
TriangleMesh read_manifest_mesh(const std::filesystem::path& path, const nlohmann::json& manifest,
                                const WarningHandler& on_warning = {});

/// One proxy's geometry: triangles (boxes and meshes) or spheres.
struct ProxyGeometry {
  PrimitiveType type = PrimitiveType::triangle;
  TriangleMesh mesh;            ///< unless spheres
  std::vector<Sphere> spheres;  ///< sphere proxies
  /// Empty, or one line naming a file of the entry's `files` that does not hold this very
  /// geometry (a copy edited by hand): no claim about the folder's files holds then.
  std::string files_problem;
};

/// Reads the file a manifest entry names (`file`, relative to `folder`), and every other
/// file its `files` lists, each of which must hold the same geometry bit for bit (NAME.obj
/// the triangles of NAME.ply; a sphere set's NAME.ply its spheres as sphere_set_mesh draws
/// them): where one does not, files_problem says so. Throws InvalidInputError naming the
/// file when `file` is missing, unreadable, or does not hold what the entry says
/// (primitive type, primitive count), and when `files` names a path outside the folder.
ProxyGeometry read_proxy_geometry(const std::filesystem::path& folder, const nlohmann::json& entry);

/// The entry's kind ("outside", "inside", "general").
ProxyKind entry_kind(const nlohmann::json& entry);

}  // namespace visproxy
