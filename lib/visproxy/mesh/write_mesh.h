#pragma once
// Writing triangle meshes as binary PLY or OBJ.

#include <filesystem>
#include <string>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

/// Writes `mesh` to `path`, format from the extension: `.ply` gives binary little-endian
/// PLY with double coordinates (exact for every value the mesh holds), `.obj` gives OBJ
/// with shortest round-trip decimal coordinates. The file is written to a temporary name
/// and renamed, so it is either complete or untouched. Throws InvalidInputError for any
/// other extension and IOError if the file cannot be written.
void write_mesh(const std::filesystem::path& path, const TriangleMesh& mesh);

/// The bytes write_mesh puts in a `.ply` file.
std::string encode_ply(const TriangleMesh& mesh);

/// The bytes write_mesh puts in an `.obj` file.
std::string encode_obj(const TriangleMesh& mesh);

}  // namespace visproxy
