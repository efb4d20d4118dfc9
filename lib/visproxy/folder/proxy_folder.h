#pragma once
// The proxy folder: one file set per proxy and manifest.json listing them, written by
// `visproxy build` and read back by everything else (the mesh it was built from, each
// proxy's geometry). Schema: data/schemas/manifest.schema.json.

#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/mesh/sphere_set.h"
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

/// `mesh`, read from `path` with `weld`, as the manifest describes it (counts, components, bounds).
ManifestMesh describe_mesh(const TriangleMesh& mesh, const std::filesystem::path& path, Weld weld);

/// The manifest entry of one proxy (everything but the file names).
nlohmann::json manifest_entry(const BuiltProxy& proxy);

/// Writes NAME.ply (binary) and NAME.obj for every proxy into `folder` (created if
/// missing) - for sphere proxies NAME.json (the sphere set, the entry's `file`) and NAME.ply
/// (their icospheres, for viewing) - then `folder`/manifest.json; every file is written under a temporary name
/// and renamed, so a failure never leaves a partial file. Built again into a folder, the
/// files of the proxies the old manifest listed and the new one does not are removed once
/// the new manifest is in place (only plain names inside the folder; other files stay).
/// Returns the manifest.
nlohmann::json write_proxy_folder(const std::filesystem::path& folder, const ManifestMesh& mesh,
                                  std::span<const BuiltProxy> proxies, const BuildOptions& options);

/// What build_proxy_folder made: the mesh as described, the proxies as built, and the manifest it wrote.
struct BuiltFolder {
  ManifestMesh mesh;
  std::vector<BuiltProxy> proxies;
  nlohmann::json manifest;
};

/// The job of `visproxy build`, and of every other place that makes a proxy folder (the
/// generated scenes, the render cache, batch, Python): builds `specs` of `mesh` (read from
/// `source` with `weld`) and writes them with their manifest into `folder`, as
/// write_proxy_folder does. `before_writing` runs once everything is built and before the
/// first file is written (the CLI stops its time limit there, so it never cuts a folder in half).
BuiltFolder build_proxy_folder(const std::filesystem::path& folder, const TriangleMesh& mesh,
                               const std::filesystem::path& source, Weld weld, std::span<const ProxySpec> specs,
                               const BuildOptions& options, const std::function<void()>& before_writing = {});

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

/// The check of read_manifest_mesh alone, for a mesh read already (`path` names it in the error).
void check_manifest_mesh(const TriangleMesh& mesh, const std::filesystem::path& path, const nlohmann::json& manifest);

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
