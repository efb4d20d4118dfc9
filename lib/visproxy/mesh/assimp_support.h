#pragma once
// Shared by visproxy's two Assimp readers: meshes (lib/visproxy/mesh/read_assimp.cpp) and scenes
// (lib/visproxy/scene/import_scene.cpp). Not installed: it names Assimp's types.

#include <assimp/matrix4x4.h>
#include <assimp/mesh.h>

#include <Eigen/Geometry>
#include <filesystem>
#include <string>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy::parsing {

/// An Assimp message on one line (errors are one line): line breaks and tabs as spaces.
std::string one_line(std::string text);

/// An Assimp node transform in double.
Eigen::Affine3d to_affine(const aiMatrix4x4& matrix);

/// One Assimp mesh in its own coordinates: every vertex, and the faces with three
/// corners (points and lines dropped). Throws InvalidInputError naming `source` for a mesh
/// without positions or a face index out of range.
TriangleMesh triangles_of(const aiMesh& mesh, const std::filesystem::path& source);

}  // namespace visproxy::parsing
