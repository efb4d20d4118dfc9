#pragma once
// The meshes of a multi-mesh asset (glTF, FBX, Collada, ... through Assimp), each once in
// its own coordinates with the nodes that show it: what `visproxy build --per-mesh` builds
// proxies of, and what "ASSET:PART" names.

#include <Eigen/Geometry>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "visproxy/mesh/read_mesh.h"
#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

/// A node of the asset that shows a part.
struct PartInstance {
  std::string node;                 ///< the node's name (Assimp's)
  std::vector<std::uint32_t> path;  ///< child indices from the root node down to it (empty: the root)
  Eigen::Affine3d transform =
      Eigen::Affine3d::Identity();  ///< world from part: the product of the transforms down to it
};

/// One mesh of an asset. A node's meshes (glTF: one mesh's primitives) make one part, and
/// every node showing the same meshes is an instance of the same part.
struct AssetPart {
  /// Unique within the asset and usable as a file name: the first mesh's name (a glTF
  /// mesh's own name, without Assimp's "-0" for its first primitive), every character but
  /// letters, digits, '.', '-' and '_' made '_'; "mesh_I" for an unnamed one; "_2", "_3"
  /// added to repeats in node order.
  std::string name;
  TriangleMesh mesh;  ///< the part's triangles in its own coordinates, welded as `weld` asks
  std::vector<PartInstance> instances;
};

/// The parts of the asset at `path`, in the order a depth-first walk of its nodes meets
/// them (children in order). Throws what read_mesh throws for the file, and
/// InvalidInputError naming it when no node shows a mesh with triangles.
std::vector<AssetPart> read_asset_parts(const std::filesystem::path& path, Weld weld = Weld::automatic);

/// "ASSET:PART" split into the asset's path and the part's name, when ASSET is an existing
/// file in a format Assimp reads and PART is not empty; nullopt otherwise.
std::optional<std::pair<std::filesystem::path, std::string>> split_part_path(const std::filesystem::path& path);

}  // namespace visproxy
