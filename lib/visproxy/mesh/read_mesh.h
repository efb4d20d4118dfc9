#pragma once
// Reading triangle meshes from OBJ, PLY, OFF and STL.
//
// The readers are written for speed (one pass over the bytes, std::from_chars) and for
// hostile input: every count in a header is checked against the file size before
// anything is allocated, every index is range-checked, every coordinate must be finite.
// Anything wrong throws InvalidInputError naming the file (and line, for text formats).

#include <filesystem>
#include <optional>
#include <string_view>

#include "visproxy/core/choices.h"
#include "visproxy/core/errors.h"
#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

/// assimp: every other format Debian's Assimp reads (glTF 2.0 .gltf/.glb, FBX, Collada
/// .dae, 3DS, Blender, X, LightWave, ...).
enum class MeshFormat { obj, ply, off, stl, assimp };

/// "OBJ", "PLY", "OFF", "STL" or "Assimp".
std::string_view format_name(MeshFormat format);

/// The format implied by a file's extension (case-insensitive), or nullopt if unknown;
/// Assimp for "ASSET:MESH" (split_part_path), one mesh of an asset Assimp reads.
std::optional<MeshFormat> format_from_extension(const std::filesystem::path& path);

enum class Weld {
  automatic,  ///< merge identical vertices for STL and Assimp's formats only, which split corners (STL: every one; glTF, FBX, ...: at normal and texture seams)
  never,      ///< keep the vertices as the file lists them
  always,     ///< merge vertices with identical coordinates in every format
};

/// "auto", "never", "always".
template <> const std::vector<std::pair<std::string_view, Weld>>& choice_names<Weld>();

struct ReadMeshOptions {
  Weld weld = Weld::automatic;
  /// Called once per flaw the reader tolerates, as "FILE:LINE: problem": today only PLY
  /// header lines that are no PLY keyword ("FILE:LINE: unknown header line '...' ignored"),
  /// which Blender 2.4x writes. They are passed on once the header has been read, at most
  /// 8 of them and then one line counting the rest.
  WarningHandler on_warning = {};
};

/// Reads a mesh, choosing the format from the extension.
/// - OBJ: `v` and `f` records; polygons are triangulated (ear clipping in the polygon's
///   plane, a fan for polygons of more than 256 corners); `i`, `i/t`, `i//n`, `i/t/n`
///   and negative (relative) indices; any number of objects and groups, concatenated.
/// - PLY: ascii, binary_little_endian and binary_big_endian; any scalar type for x, y, z;
///   any count and index type for the face list (`vertex_indices` or `vertex_index`);
///   other elements and properties are skipped. A header line that starts with no PLY
///   keyword is skipped with a warning (options.on_warning); a malformed `format`,
///   `element` or `property` line is an error.
/// - OFF: OFF, COFF, NOFF, CNOFF, STOFF headers; `#` comments; per-vertex and per-face
///   extras (colours) ignored; polygons triangulated as for OBJ.
/// - STL: ASCII and binary (recognised by size, whatever the header says).
/// - Assimp's formats: the scene's node hierarchy flattened, each node's meshes placed by
///   the transforms down to it; polygons triangulated, points and lines dropped. Assimp's
///   own refusal becomes an InvalidInputError ("FILE: Assimp cannot read it: ...").
/// Throws IOError if the file cannot be read and InvalidInputError if its content is
/// wrong, including a mesh without a single face and coordinates beyond kMaxCoordinate
/// (1e100).
TriangleMesh read_mesh(const std::filesystem::path& path, const ReadMeshOptions& options = {});

/// Parses a mesh held in memory; `source` names it in error messages.
TriangleMesh parse_mesh(std::string_view bytes, MeshFormat format, const std::filesystem::path& source,
                        const ReadMeshOptions& options = {});

/// Merges vertices with bit-identical coordinates (+0 and -0 are the same) into the first
/// one listed and drops vertices no triangle uses. Triangles are kept as they are, so a
/// triangle whose corners merge becomes degenerate rather than disappearing.
TriangleMesh weld_vertices(const TriangleMesh& mesh);

}  // namespace visproxy
