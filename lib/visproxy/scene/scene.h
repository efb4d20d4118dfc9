#pragma once
// Scenes for the reference renderer: instanced triangle meshes with diffuse albedo and
// the proxies each one uses, area lights and a pinhole camera, read from a JSON file.
// The format is documented in apps/visproxy/README.md (Scenes) and data/schemas/scene.schema.json.

#include <Eigen/Geometry>

#include <array>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

using Color = Eigen::Vector3d;  ///< linear RGB

struct SceneMesh {
  std::string name;
  std::filesystem::path file;  ///< resolved path; empty for meshes given inline
  TriangleMesh mesh;
  /// A `visproxy build` folder holding proxies of this mesh ("proxy_folder" in the file,
  /// relative to the scene); proxies found there are used instead of built. May be empty.
  std::filesystem::path proxy_folder;
};

struct SceneInstance {
  std::string mesh;                  ///< name of a SceneMesh
  Eigen::Affine3d transform = Eigen::Affine3d::Identity();  ///< object to world
  Color albedo = Color::Constant(0.5);
  std::vector<std::string> proxies;  ///< proxy specs, e.g. "outer:512", "inside:40"
};

/// An emitter: triangles in world space, each emitting `radiance` from its front side
/// (counter-clockwise seen from the front) or from both sides.
struct AreaLight {
  std::vector<std::array<Vertex, 3>> triangles;
  Color radiance = Color::Ones();
  bool two_sided = false;
};

struct Camera {
  Vertex from = Vertex(0, 0, 1);
  Vertex at = Vertex::Zero();
  Vertex up = Vertex(0, 1, 0);
  double fov_degrees = 40;  ///< vertical field of view
  int width = 256;
  int height = 256;
};

struct Scene {
  std::filesystem::path file;
  std::vector<SceneMesh> meshes;
  std::vector<SceneInstance> instances;
  std::vector<AreaLight> lights;
  Camera camera;

  const SceneMesh& mesh(const std::string& name) const;
};

/// The folder `cgal-demo:NAME` paths resolve to: $VISPROXY_MESH_DIR when set, else the
/// folder the build extracted Debian's libcgal-demo meshes into.
std::filesystem::path cgal_demo_mesh_dir();

/// Reads a scene file: a visproxy JSON scene, or a file Assimp reads (a glTF 2.0 .gltf or
/// .glb: load_imported_scene in import_scene.h). A JSON scene may "import" such a file,
/// whose instances, lights and camera join its own. Mesh paths are relative to the scene file's folder, or
/// `cgal-demo:NAME` for a libcgal-demo mesh. Throws IOError for unreadable files and
/// InvalidInputError otherwise, naming the mesh file for a mesh file's problems and else
/// the scene file and the JSON path of the value at fault:
///   scene.json: instances[2].transform.fit.height: must be a positive number
/// The mesh readers' warnings (ReadMeshOptions::on_warning) go to `on_warning`.
Scene load_scene(const std::filesystem::path& path, const WarningHandler& on_warning = {});

/// The same from JSON text; `path` names it in errors and anchors relative paths.
Scene parse_scene(const std::string& text, const std::filesystem::path& path, const WarningHandler& on_warning = {});

}  // namespace visproxy
