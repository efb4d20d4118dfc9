#pragma once
// Scenes from files Assimp reads, glTF 2.0 foremost (.gltf, .glb): what a renderer's asset
// pipeline exports, taken as visproxy scene parts.

#include <filesystem>
#include <optional>
#include <vector>

#include "visproxy/scene/scene.h"

namespace visproxy {

struct ImportedScene {
  std::vector<SceneMesh> meshes;
  std::vector<SceneInstance> instances;
  std::vector<AreaLight> lights;
  std::optional<Camera> camera;  ///< the file's first camera, if it has one
};

/// Reads `path` through Assimp:
///  - each mesh (glTF: each primitive) becomes a SceneMesh named "FILE:MESH" (welded,
///    "#N" added to repeated names), and each node that uses it an instance, placed by the
///    product of the node transforms down to it (in double) and lit with its material's
///    base colour as albedo (clamped to [0, 1]);
///  - a mesh whose material emits (glTF emissiveFactor, times KHR_materials_emissive_strength,
///    which this reads from the glTF's own JSON) becomes an area light of that radiance
///    instead, two-sided when the material is;
///  - the first camera becomes the camera: glTF's looks down its node's -Z with +Y up and
///    its vertical field of view; the image is 320 pixels wide at the camera's aspect ratio.
/// Throws IOError when the file cannot be read and InvalidInputError naming it otherwise
/// (Assimp's refusal, no triangles, coordinates or transforms out of range).
ImportedScene import_scene(const std::filesystem::path& path);

/// A whole scene from such a file: import_scene's parts, with a camera fitted to the
/// instances' bounds (looking at their centre from the front, +Z, slightly above) when the
/// file has none. Throws InvalidInputError when it has no instance or no emitting material.
Scene load_imported_scene(const std::filesystem::path& path);

}  // namespace visproxy
