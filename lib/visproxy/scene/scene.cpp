#include "visproxy/scene/scene.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <map>
#include <numbers>

#include "visproxy/core/errors.h"
#include "visproxy/core/files.h"
#include "visproxy/core/json_input.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/mesh/subdivide.h"
#include "visproxy/scene/import_scene.h"

namespace visproxy {

// More than this many triangles after "subdivide" is refused (about 3 GB of mesh and BVH).
constexpr double kMaxSubdividedTriangles = 64e6;
namespace {

using nlohmann::json;

// The scene's checks on top of JsonInput's; every error names the JSON path at fault.
class Parser : public JsonInput {
 public:
  Parser(const std::filesystem::path& path, const WarningHandler& on_warning)
      : JsonInput(path), on_warning_(on_warning) {}

  Eigen::Vector3d vector3(const json& value, const std::string& where) const {
    const std::array<double, 3> xyz = triple(value, where);
    return {xyz[0], xyz[1], xyz[2]};
  }

  // One number for grey, or [r, g, b]; never negative.
  Color color(const json& value, const std::string& where) const {
    if (!value.is_number() && !value.is_array()) fail(where, "expected an array of 3 numbers (r, g, b) or one number");
    const Color c = value.is_number() ? Color::Constant(number(value, where)) : vector3(value, where);
    if ((c.array() < 0).any()) fail(where, "must not be negative");
    return c;
  }

  std::filesystem::path mesh_path(const std::string& file) const {
    static constexpr std::string_view prefix = "cgal-demo:";
    if (file.starts_with(prefix)) return cgal_demo_mesh_dir() / file.substr(prefix.size());
    const std::filesystem::path p(file);
    return p.is_absolute() ? p : this->file().parent_path() / p;
  }

  SceneMesh mesh(const std::string& name, const json& value, const std::string& where) const {
    object(value, where);
    SceneMesh mesh{name, {}, {}, {}};
    if (const json* folder = optional_member(value, "proxy_folder", where))
      mesh.proxy_folder = mesh_path(string(*folder, json_member_path(where, "proxy_folder")));
    if (const json* file = optional_member(value, "file", where)) {
      const std::string& file_name = string(*file, json_member_path(where, "file"));
      if (value.contains("positions") || value.contains("triangles"))
        fail(where, "give either \"file\" or \"positions\" and \"triangles\", not both");
      mesh.file = mesh_path(file_name);
      // Its own errors name the mesh file.
      mesh.mesh = read_mesh(mesh.file, {.weld = Weld::automatic, .on_warning = on_warning_});
      if (mesh.mesh.triangles.empty()) throw InvalidInputError(mesh.file, "has no triangles");
    } else {
      mesh.mesh = inline_mesh(value, where);
    }
    if (const json* levels = optional_member(value, "subdivide", where)) {
      const std::string levels_path = json_member_path(where, "subdivide");
      const auto n = static_cast<int>(integer(*levels, levels_path, 0, 4));
      if (static_cast<double>(mesh.mesh.triangles.size()) * std::pow(4.0, n) > kMaxSubdividedTriangles)
        fail(levels_path, "would make " + std::to_string(mesh.mesh.triangles.size()) + " x 4^" + std::to_string(n) +
                              " triangles, more than " + std::to_string(static_cast<long long>(kMaxSubdividedTriangles)));
      mesh.mesh = subdivide_midpoint(mesh.mesh, n);
    }
    return mesh;
  }

  TriangleMesh inline_mesh(const json& value, const std::string& where) const {
    TriangleMesh mesh;
    const std::string positions_path = json_member_path(where, "positions");
    const std::string triangles_path = json_member_path(where, "triangles");
    const json& positions = member(value, "positions", where);
    if (!positions.is_array()) fail(positions_path, "expected an array of points");
    const json& triangles = member(value, "triangles", where);
    if (!triangles.is_array() || triangles.empty()) fail(triangles_path, "expected a non-empty array of triangles");
    for (std::size_t v = 0; v < positions.size(); ++v) {
      mesh.positions.push_back(vector3(positions[v], json_index_path(positions_path, v)));
      if (!within_coordinate_range(mesh.positions.back()))
        fail(json_index_path(positions_path, v), "a coordinate beyond 1e100 in magnitude, which geometry in double precision cannot square and cube");
    }
    for (std::size_t t = 0; t < triangles.size(); ++t) {
      const json& corners = triangles[t];
      const std::string triangle_path = json_index_path(triangles_path, t);
      if (!corners.is_array() || corners.size() != 3) fail(triangle_path, "expected an array of 3 vertex indices");
      if (mesh.positions.empty()) fail(triangle_path, "refers to vertices, but \"positions\" is empty");
      Triangle triangle{};
      for (std::size_t k = 0; k < 3; ++k)
        triangle[k] = static_cast<VertexIndex>(
            integer(corners[k], json_index_path(triangle_path, k), 0, mesh.positions.size() - 1));
      mesh.triangles.push_back(triangle);
    }
    return mesh;
  }

  // scale, then rotate, then translate; or a 4x4 row-major matrix; "fit" places a mesh by
  // its bounding box after the rotation: uniform scale to the height, bottom centre on base.
  Eigen::Affine3d transform(const json& value, const std::string& where, const TriangleMesh& mesh) const {
    object(value, where);
    Eigen::Affine3d result = Eigen::Affine3d::Identity();
    if (const json* m = optional_member(value, "matrix", where)) {
      for (const char* other : {"scale", "rotate", "translate"})
        if (value.contains(other)) fail(where, std::string("\"matrix\" and \"") + other + "\" exclude each other");
      const std::string matrix_path = json_member_path(where, "matrix");
      if (!m->is_array() || m->size() != 16 ||
          !std::all_of(m->begin(), m->end(), [](const json& x) { return x.is_number(); }))
        fail(matrix_path, "expected an array of 16 numbers (a row-major 4x4 matrix)");
      Eigen::Matrix4d matrix;
      for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) matrix(r, c) = number((*m)[static_cast<std::size_t>(4 * r + c)], matrix_path);
      if (matrix.row(3) != Eigen::RowVector4d(0, 0, 0, 1)) fail(matrix_path, "must be affine (last row 0 0 0 1)");
      result.matrix() = matrix;
    } else {
      Eigen::Vector3d scale = Eigen::Vector3d::Ones();
      if (const json* s = optional_member(value, "scale", where)) {
        const std::string scale_path = json_member_path(where, "scale");
        if (s->is_array())
          scale = vector3(*s, scale_path);
        else if (s->is_number())
          scale = Eigen::Vector3d::Constant(positive_number(*s, scale_path));
        else
          fail(scale_path, "expected a positive number or an array of 3 numbers");
      }
      Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
      if (const json* r = optional_member(value, "rotate", where)) {
        const std::string rotate_path = json_member_path(where, "rotate");
        const std::string axis_path = json_member_path(rotate_path, "axis");
        const Eigen::Vector3d axis = vector3(member(*r, "axis", rotate_path), axis_path);
        if (!(axis.stableNorm() > 0)) fail(axis_path, "must not be zero");
        const double degrees = number(member(*r, "degrees", rotate_path), json_member_path(rotate_path, "degrees"));
        rotation = Eigen::AngleAxisd(degrees * std::numbers::pi / 180, axis.stableNormalized()).toRotationMatrix();
      }
      result.linear() = rotation * scale.asDiagonal();
      if (const json* t = optional_member(value, "translate", where))
        result.translation() = vector3(*t, json_member_path(where, "translate"));
    }
    if (const json* fit = optional_member(value, "fit", where)) {
      const std::string fit_path = json_member_path(where, "fit");
      const Vertex base = vector3(member(*fit, "base", fit_path), json_member_path(fit_path, "base"));
      const double height = positive_number(member(*fit, "height", fit_path), json_member_path(fit_path, "height"));
      BoundingBox box;
      for (const Vertex& p : used_positions(mesh)) box.extend(result * p);
      if (box.empty() || !(box.max.y() > box.min.y())) fail(fit_path, "cannot fit a mesh that is flat in y");
      const double s = height / (box.max.y() - box.min.y());
      const Vertex bottom(0.5 * (box.min.x() + box.max.x()), box.min.y(), 0.5 * (box.min.z() + box.max.z()));
      result = Eigen::Translation3d(base) * Eigen::Scaling(s) * Eigen::Translation3d(-bottom) * result;
    }
    if (!result.matrix().allFinite()) fail(where, "not finite (the product overflows)");
    if (std::abs(result.linear().determinant()) < 1e-300) fail(where, "singular");
    return result;
  }

 private:
  const WarningHandler& on_warning_;
};

}  // namespace

const SceneMesh& Scene::mesh(const std::string& name) const {
  for (const SceneMesh& m : meshes)
    if (m.name == name) return m;
  throw InvalidInputError(file, "no mesh named " + json_quoted(name));
}

std::filesystem::path cgal_demo_mesh_dir() {
  if (const char* dir = std::getenv("VISPROXY_MESH_DIR"); dir && *dir) return dir;
  return VISPROXY_DEFAULT_MESH_DIR;
}

Scene parse_scene(const std::string& text, const std::filesystem::path& path, const WarningHandler& on_warning) {
  const Parser p(path, on_warning);
  const json document = p.parse(text);
  if (!document.is_object() || !document.contains("format") || document["format"] != "visproxy-scene")
    p.fail("", "not a visproxy scene (\"format\" is not \"visproxy-scene\")");
  if (p.member(document, "format_version", "") != 1)
    p.fail("format_version", "unsupported (this visproxy reads version 1)");
  if (const json* description = p.optional_member(document, "description", "")) p.string(*description, "description");

  Scene scene;
  scene.file = path;
  auto find_mesh = [&](const json& name, const std::string& where) -> const SceneMesh& {
    const std::string& wanted = p.string(name, where);
    for (const SceneMesh& m : scene.meshes)
      if (m.name == wanted) return m;
    p.fail(where, "no mesh named " + json_quoted(wanted));
  };

  // "import": a glTF (or other Assimp) file's meshes, instances, lights and camera, with
  // the proxies every imported instance names; the scene's own parts are added to them.
  std::optional<Camera> imported_camera;
  if (const json* import = p.optional_member(document, "import", "")) {
    p.object(*import, "import");
    const std::filesystem::path file = p.mesh_path(p.string(p.member(*import, "file", "import"), "import.file"));
    ImportedScene imported = import_scene(file);
    // "proxies": specs for every imported instance, or an object of them per imported mesh.
    std::map<std::string, std::vector<std::string>> proxies;
    auto specs = [&](const json& list, const std::string& where) {
      if (!list.is_array()) p.fail(where, "expected an array of proxy specs");
      std::vector<std::string> texts;
      for (std::size_t k = 0; k < list.size(); ++k) texts.push_back(p.string(list[k], json_index_path(where, k)));
      return texts;
    };
    if (const json* given = p.optional_member(*import, "proxies", "import")) {
      if (given->is_object()) {
        for (const auto& [name, list] : given->items()) {
          if (std::none_of(imported.meshes.begin(), imported.meshes.end(), [&](const SceneMesh& m) { return m.name == name; }))
            p.fail(json_member_path("import.proxies", name), "the imported file has no mesh of this name");
          proxies[name] = specs(list, json_member_path("import.proxies", name));
        }
      } else {
        const std::vector<std::string> every = specs(*given, "import.proxies");
        for (const SceneMesh& m : imported.meshes) proxies[m.name] = every;
      }
    }
    for (SceneMesh& mesh : imported.meshes) mesh.file = file;
    scene.meshes = std::move(imported.meshes);
    for (SceneInstance& instance : imported.instances) {
      instance.proxies = proxies[instance.mesh];
      scene.instances.push_back(std::move(instance));
    }
    scene.lights = std::move(imported.lights);
    imported_camera = imported.camera;
  }
  const bool imports = document.contains("import");

  if (const json* meshes = imports ? p.optional_member(document, "meshes", "") : &p.member(document, "meshes", "")) {
    if (!meshes->is_object() || (meshes->empty() && !imports)) p.fail("meshes", "expected an object of named meshes");
    for (const auto& [name, value] : meshes->items()) {
      for (const SceneMesh& m : scene.meshes)
        if (m.name == name) p.fail(json_member_path("meshes", name), "the imported file has a mesh of this name");
      scene.meshes.push_back(p.mesh(name, value, json_member_path("meshes", name)));
    }
  }

  static const json kNone = json::array();
  const json& instances = imports ? (document.contains("instances") ? document["instances"] : kNone) : p.member(document, "instances", "");
  if (!instances.is_array() || (instances.empty() && scene.instances.empty())) p.fail("instances", "expected a non-empty array");
  std::map<std::string, BoundingBox> mesh_boxes;  // each mesh's box, once, however many instances it has
  for (std::size_t i = 0; i < instances.size(); ++i) {
    const json& value = instances[i];
    const std::string where = json_index_path("instances", i);
    SceneInstance instance;
    const SceneMesh& mesh = find_mesh(p.member(value, "mesh", where), json_member_path(where, "mesh"));
    instance.mesh = mesh.name;
    if (const json* transform = p.optional_member(value, "transform", where)) {
      instance.transform = p.transform(*transform, json_member_path(where, "transform"), mesh.mesh);
      auto cached = mesh_boxes.find(mesh.name);
      if (cached == mesh_boxes.end()) cached = mesh_boxes.emplace(mesh.name, bounding_box(mesh.mesh)).first;
      const BoundingBox& box = cached->second;
      for (int corner = 0; corner < 8 && !box.empty(); ++corner) {
        const Vertex placed = instance.transform * Vertex(corner & 1 ? box.max.x() : box.min.x(), corner & 2 ? box.max.y() : box.min.y(),
                                                          corner & 4 ? box.max.z() : box.min.z());
        if (!within_coordinate_range(placed))
          p.fail(json_member_path(where, "transform"), "places the mesh beyond 1e100 in magnitude, which geometry in double precision cannot square and cube");
      }
    }
    if (const json* albedo = p.optional_member(value, "albedo", where)) {
      instance.albedo = p.color(*albedo, json_member_path(where, "albedo"));
      if ((instance.albedo.array() > 1).any())
        p.fail(json_member_path(where, "albedo"), "above 1 reflects more light than it receives");
    }
    if (const json* proxies = p.optional_member(value, "proxies", where)) {
      const std::string proxies_path = json_member_path(where, "proxies");
      if (!proxies->is_array()) p.fail(proxies_path, "expected an array of proxy specs");
      for (std::size_t k = 0; k < proxies->size(); ++k)
        instance.proxies.push_back(p.string((*proxies)[k], json_index_path(proxies_path, k)));
    }
    scene.instances.push_back(std::move(instance));
  }

  const json& lights = imports ? (document.contains("lights") ? document["lights"] : kNone) : p.member(document, "lights", "");
  if (!lights.is_array() || (lights.empty() && scene.lights.empty()))
    p.fail(imports && !document.contains("lights") ? "import" : "lights",
           imports && !document.contains("lights") ? "the imported file has no emitting material, and the scene no \"lights\""
                                                   : "expected a non-empty array");
  for (std::size_t i = 0; i < lights.size(); ++i) {
    const json& value = lights[i];
    const std::string where = json_index_path("lights", i);
    AreaLight light;
    light.radiance = p.color(p.member(value, "radiance", where), json_member_path(where, "radiance"));
    if (const json* two_sided = p.optional_member(value, "two_sided", where))
      light.two_sided = p.boolean(*two_sided, json_member_path(where, "two_sided"));
    const json& type = p.member(value, "type", where);
    if (type == "parallelogram") {
      const Vertex corner = p.vector3(p.member(value, "corner", where), json_member_path(where, "corner"));
      const Vertex u = p.vector3(p.member(value, "edge1", where), json_member_path(where, "edge1"));
      const Vertex v = p.vector3(p.member(value, "edge2", where), json_member_path(where, "edge2"));
      if (!(u.cross(v).stableNorm() > 0)) p.fail(where, "\"edge1\" and \"edge2\" are parallel: the light has no area");
      light.triangles.push_back({corner, corner + u, corner + u + v});
      light.triangles.push_back({corner, corner + u + v, corner + v});
    } else if (type == "mesh") {
      const SceneMesh& mesh = find_mesh(p.member(value, "mesh", where), json_member_path(where, "mesh"));
      const json* transform_value = p.optional_member(value, "transform", where);
      const Eigen::Affine3d transform =
          transform_value ? p.transform(*transform_value, json_member_path(where, "transform"), mesh.mesh)
                          : Eigen::Affine3d::Identity();
      for (const Triangle& t : mesh.mesh.triangles)
        light.triangles.push_back({transform * mesh.mesh.positions[t[0]], transform * mesh.mesh.positions[t[1]],
                                   transform * mesh.mesh.positions[t[2]]});
    } else {
      p.fail(json_member_path(where, "type"), "must be \"parallelogram\" or \"mesh\"");
    }
    for (const std::array<Vertex, 3>& triangle : light.triangles)
      for (const Vertex& corner : triangle)
        if (!corner.allFinite()) p.fail(where, "a corner is not finite (its coordinates overflow)");
    scene.lights.push_back(std::move(light));
  }

  if (imported_camera && !document.contains("camera")) {
    scene.camera = *imported_camera;
    return scene;
  }
  const json& camera = p.object(p.member(document, "camera", ""), "camera");
  scene.camera.from = p.vector3(p.member(camera, "from", "camera"), "camera.from");
  scene.camera.at = p.vector3(p.member(camera, "at", "camera"), "camera.at");
  if (const json* up = p.optional_member(camera, "up", "camera")) scene.camera.up = p.vector3(*up, "camera.up");
  if (const json* fov = p.optional_member(camera, "fov_degrees", "camera")) {
    scene.camera.fov_degrees = p.number(*fov, "camera.fov_degrees");
    if (!(scene.camera.fov_degrees > 0 && scene.camera.fov_degrees < 180))
      p.fail("camera.fov_degrees", "must be in (0, 180)");
  }
  if (const json* width = p.optional_member(camera, "width", "camera"))
    scene.camera.width = static_cast<int>(p.integer(*width, "camera.width", 1, 16384));
  if (const json* height = p.optional_member(camera, "height", "camera"))
    scene.camera.height = static_cast<int>(p.integer(*height, "camera.height", 1, 16384));
  const Vertex view = scene.camera.at - scene.camera.from;
  if (!view.allFinite() || !(view.stableNorm() > 0) || !(view.cross(scene.camera.up).stableNorm() > 0))
    p.fail("camera", "\"from\", \"at\" and \"up\" do not define a view (zero or parallel)");
  return scene;
}

Scene load_scene(const std::filesystem::path& path, const WarningHandler& on_warning) {
  if (const std::optional<MeshFormat> format = format_from_extension(path); format == MeshFormat::assimp)
    return load_imported_scene(path);
  return parse_scene(read_file(path), path, on_warning);
}

}  // namespace visproxy
