#pragma once
// `visproxy export`: a folder's proxies written back beside the asset they stand for, in
// the formats engines load (glTF binary or JSON, OBJ, PLY), in float32 with their claims
// proved again on the rounded coordinates.

#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "visproxy/asset/float_proxy.h"
#include "visproxy/core/choices.h"
#include "visproxy/core/errors.h"

namespace visproxy {

enum class ExportFormat { glb, gltf, obj, ply };

/// The format an output path's extension names (.glb, .gltf, .obj, .ply; any case).
/// Throws InvalidInputError naming the path for any other.
ExportFormat export_format(const std::filesystem::path& path);

struct ExportOptions {
  /// The proxies to export, by manifest name; empty: every proxy of the folder.
  std::vector<std::string> proxies = {};
  /// The asset the folder was built from; empty: the manifest's mesh.path. It is read as
  /// the build read it and must be the mesh the manifest describes.
  std::filesystem::path source = {};
  /// Called before each proxy is rounded and proved, with its name (progress).
  std::function<void(std::string_view)> on_proxy = {};
  WarningHandler on_warning = {};
};

struct ExportedProxy {
  std::string name;  ///< the manifest's
  std::string part;  ///< the asset part it stands for (a per-part folder), or empty
  std::string node;  ///< the object's name in the output: SOURCE-STEM.NAME, or PART.NAME
  FloatProxy geometry;
};

struct ExportResult {
  std::filesystem::path path;
  std::filesystem::path source = {};
  ExportFormat format = ExportFormat::glb;
  std::vector<ExportedProxy> proxies;
};

/// Writes the proxies of `folder` into `out` (format from its extension), atomically.
/// `folder` is a proxy folder of the whole asset, or a per-part folder (asset.json, from
/// `build --per-mesh`), whose parts' proxies are all written.
///  - .glb / .gltf: the source asset with the proxies added. A glTF source is kept whole
///    (its nodes, materials, textures, animations; relative URIs rewritten when `out` is in
///    another folder); any other source becomes nodes holding its meshes as read. Each
///    proxy is a mesh of float32 positions and 32-bit indices on a node of its own: a child
///    of every node that shows its part (the same mesh for each), or for the whole asset a
///    root of the default scene (placed in its world). Each node carries extras.visproxy:
///    shadow_only, kind, claim, proved, the verdict's hashes, how far the rounding moved
///    it, and the proxy's name, part, spec and source;
///  - .obj: the source mesh as read as `o STEM` (each part in its own coordinates as
///    `o PART`), each proxy as `o STEM.NAME` (`o PART.NAME`), each preceded by a
///    `# visproxy {...}` comment holding the same object; coordinates are printed so that
///    float and double readers get the proved float values exactly;
///  - .ply: one proxy (refused with more), binary little-endian float32, the same object in
///    a `comment visproxy` header line.
/// Sphere proxies are written as their icospheres. Every claim is proved again on the
/// float32 coordinates written (round_proxy_to_float); a claim that does not survive is
/// exported as general and the proxy's `geometry.note` says why. Throws InvalidInputError
/// naming the file at fault: an unknown proxy name, a source that is not the folder's
/// mesh, an unknown output extension.
ExportResult export_proxies(const std::filesystem::path& folder, const std::filesystem::path& out,
                            const ExportOptions& options = {});

}  // namespace visproxy
