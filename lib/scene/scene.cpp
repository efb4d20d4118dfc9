#include "scene/scene.h"

#include <cmath>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <numbers>

#include "core/errors.h"
#include "core/files.h"
#include "mesh/read_mesh.h"

namespace visproxy {
namespace {

using nlohmann::json;

class Parser {
 public:
  explicit Parser(const std::filesystem::path& path) : path_(path) {}

  [[noreturn]] void fail(const std::string& where, const std::string& problem) const {
    throw InvalidInputError(path_, where + ": " + problem);
  }

  const json& member(const json& object, const char* key, const std::string& where) const {
    if (!object.is_object()) fail(where, "expected an object");
    if (!object.contains(key)) fail(where, std::string("missing \"") + key + "\"");
    return object[key];
  }

  double number(const json& value, const std::string& where) const {
    if (!value.is_number()) fail(where, "expected a number");
    const double x = value.get<double>();
    if (!std::isfinite(x)) fail(where, "not finite");
    return x;
  }

  Eigen::Vector3d vector3(const json& value, const std::string& where) const {
    if (!value.is_array() || value.size() != 3) fail(where, "expected an array of 3 numbers");
    return {number(value[0], where), number(value[1], where), number(value[2], where)};
  }

  Color color(const json& value, const std::string& where) const {
    if (value.is_number()) return Color::Constant(number(value, where));
    const Color c = vector3(value, where);
    if ((c.array() < 0).any()) fail(where, "negative colour");
    return c;
  }

  int positive_int(const json& value, const std::string& where, int max) const {
    if (!value.is_number_integer() || value.get<long long>() < 1 || value.get<long long>() > max)
      fail(where, "expected an integer from 1 to " + std::to_string(max));
    return value.get<int>();
  }

  std::filesystem::path mesh_path(const std::string& file) const {
    static constexpr std::string_view prefix = "cgal-demo:";
    if (file.starts_with(prefix)) return cgal_demo_mesh_dir() / file.substr(prefix.size());
    const std::filesystem::path p(file);
    return p.is_absolute() ? p : path_.parent_path() / p;
  }

  TriangleMesh inline_mesh(const json& value, const std::string& where) const {
    TriangleMesh mesh;
    const json& positions = member(value, "positions", where);
    const json& triangles = member(value, "triangles", where);
    if (!positions.is_array() || !triangles.is_array()) fail(where, "\"positions\" and \"triangles\" must be arrays");
    for (const json& p : positions) mesh.positions.push_back(vector3(p, where + " positions"));
    for (const json& t : triangles) {
      if (!t.is_array() || t.size() != 3) fail(where, "a triangle is not 3 indices");
      Triangle triangle{};
      for (std::size_t i = 0; i < 3; ++i) {
        if (!t[i].is_number_integer() || t[i].get<long long>() < 0 ||
            t[i].get<long long>() >= static_cast<long long>(mesh.positions.size()))
          fail(where, "triangle index out of range");
        triangle[i] = t[i].get<VertexIndex>();
      }
      mesh.triangles.push_back(triangle);
    }
    if (mesh.triangles.empty()) fail(where, "no triangles");
    return mesh;
  }

  // scale, then rotate, then translate; or a 4x4 row-major matrix; "fit" places a mesh by
  // its bounding box after the rotation: uniform scale to the height, bottom centre on base.
  Eigen::Affine3d transform(const json& value, const std::string& where, const TriangleMesh* mesh) const {
    Eigen::Affine3d result = Eigen::Affine3d::Identity();
    if (!value.is_object()) fail(where, "expected an object");
    if (value.contains("matrix")) {
      const json& m = value["matrix"];
      if (!m.is_array() || m.size() != 16) fail(where, "\"matrix\" must hold 16 numbers (row-major 4x4)");
      Eigen::Matrix4d matrix;
      for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) matrix(r, c) = number(m[static_cast<std::size_t>(4 * r + c)], where + " matrix");
      if (matrix.row(3) != Eigen::RowVector4d(0, 0, 0, 1)) fail(where, "\"matrix\" must be affine (last row 0 0 0 1)");
      result.matrix() = matrix;
    } else {
      Eigen::Vector3d scale = Eigen::Vector3d::Ones();
      if (value.contains("scale"))
        scale = value["scale"].is_number() ? Eigen::Vector3d::Constant(number(value["scale"], where + " scale"))
                                           : vector3(value["scale"], where + " scale");
      Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
      if (value.contains("rotate")) {
        const json& r = value["rotate"];
        const Eigen::Vector3d axis = vector3(member(r, "axis", where + " rotate"), where + " rotate axis");
        if (axis.norm() == 0) fail(where, "rotation axis is zero");
        const double degrees = number(member(r, "degrees", where + " rotate"), where + " rotate degrees");
        rotation = Eigen::AngleAxisd(degrees * std::numbers::pi / 180, axis.normalized()).toRotationMatrix();
      }
      result.linear() = rotation * scale.asDiagonal();
      if (value.contains("translate")) result.translation() = vector3(value["translate"], where + " translate");
    }
    if (value.contains("fit")) {
      if (!mesh) fail(where, "\"fit\" needs a mesh");
      const json& fit = value["fit"];
      const Vertex base = vector3(member(fit, "base", where + " fit"), where + " fit base");
      const double height = number(member(fit, "height", where + " fit"), where + " fit height");
      BoundingBox box;
      for (const Vertex& p : used_positions(*mesh)) box.extend(result * p);
      if (box.empty() || box.max.y() <= box.min.y() || height <= 0) fail(where, "cannot fit a flat or empty mesh");
      const double s = height / (box.max.y() - box.min.y());
      const Vertex bottom(0.5 * (box.min.x() + box.max.x()), box.min.y(), 0.5 * (box.min.z() + box.max.z()));
      result = Eigen::Translation3d(base) * Eigen::Scaling(s) * Eigen::Translation3d(-bottom) * result;
    }
    if (std::abs(result.linear().determinant()) < 1e-300) fail(where, "transform is singular");
    return result;
  }

 private:
  std::filesystem::path path_;
};

}  // namespace

const SceneMesh& Scene::mesh(const std::string& name) const {
  for (const SceneMesh& m : meshes)
    if (m.name == name) return m;
  throw InvalidInputError(file, "no mesh named \"" + name + "\"");
}

std::filesystem::path cgal_demo_mesh_dir() {
  if (const char* dir = std::getenv("VISPROXY_MESH_DIR"); dir && *dir) return dir;
  return VISPROXY_DEFAULT_MESH_DIR;
}

Scene parse_scene(const std::string& text, const std::filesystem::path& path, const WarningHandler& on_warning) {
  const Parser p(path);
  const json document = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (document.is_discarded()) throw InvalidInputError(path, "not valid JSON");
  if (!document.is_object() || document.value("format", "") != "visproxy-scene")
    throw InvalidInputError(path, "not a visproxy scene (\"format\" is not \"visproxy-scene\")");
  if (document.value("format_version", 0) != 1) throw InvalidInputError(path, "unsupported format_version (expected 1)");

  Scene scene;
  scene.file = path;
  const json& meshes = p.member(document, "meshes", "scene");
  if (!meshes.is_object() || meshes.empty()) p.fail("meshes", "expected an object of named meshes");
  for (const auto& [name, value] : meshes.items()) {
    const std::string where = "mesh \"" + name + "\"";
    SceneMesh mesh{name, {}, {}, {}};
    if (value.contains("proxy_folder")) {
      if (!value["proxy_folder"].is_string()) p.fail(where, "\"proxy_folder\" must be a string");
      mesh.proxy_folder = p.mesh_path(value["proxy_folder"].get<std::string>());
    }
    if (value.contains("file")) {
      if (!value["file"].is_string()) p.fail(where, "\"file\" must be a string");
      mesh.file = p.mesh_path(value["file"].get<std::string>());
      // Its own errors name the mesh file.
      mesh.mesh = read_mesh(mesh.file, {.weld = Weld::automatic, .on_warning = on_warning});
      if (mesh.mesh.triangles.empty()) throw InvalidInputError(mesh.file, "has no triangles");
    } else {
      mesh.mesh = p.inline_mesh(value, where);
    }
    scene.meshes.push_back(std::move(mesh));
  }

  const json& instances = p.member(document, "instances", "scene");
  if (!instances.is_array() || instances.empty()) p.fail("instances", "expected a non-empty array");
  for (std::size_t i = 0; i < instances.size(); ++i) {
    const json& value = instances[i];
    const std::string where = "instance " + std::to_string(i);
    SceneInstance instance;
    const json& mesh_name = p.member(value, "mesh", where);
    if (!mesh_name.is_string()) p.fail(where, "\"mesh\" must be a mesh name");
    instance.mesh = mesh_name.get<std::string>();
    const SceneMesh* mesh = nullptr;
    for (const SceneMesh& m : scene.meshes)
      if (m.name == instance.mesh) mesh = &m;
    if (!mesh) p.fail(where, "no mesh named \"" + instance.mesh + "\"");
    if (value.contains("transform")) instance.transform = p.transform(value["transform"], where + " transform", &mesh->mesh);
    if (value.contains("albedo")) {
      instance.albedo = p.color(value["albedo"], where + " albedo");
      if ((instance.albedo.array() > 1).any()) p.fail(where, "albedo above 1 reflects more light than it receives");
    }
    if (value.contains("proxies")) {
      if (!value["proxies"].is_array()) p.fail(where, "\"proxies\" must be an array of proxy specs");
      for (const json& spec : value["proxies"]) {
        if (!spec.is_string()) p.fail(where, "a proxy spec is not a string");
        instance.proxies.push_back(spec.get<std::string>());
      }
    }
    scene.instances.push_back(std::move(instance));
  }

  const json& lights = p.member(document, "lights", "scene");
  if (!lights.is_array() || lights.empty()) p.fail("lights", "expected a non-empty array");
  for (std::size_t i = 0; i < lights.size(); ++i) {
    const json& value = lights[i];
    const std::string where = "light " + std::to_string(i);
    AreaLight light;
    light.radiance = p.color(p.member(value, "radiance", where), where + " radiance");
    light.two_sided = value.value("two_sided", false);
    const std::string type = p.member(value, "type", where).is_string() ? value["type"].get<std::string>() : "";
    if (type == "parallelogram") {
      const Vertex corner = p.vector3(p.member(value, "corner", where), where + " corner");
      const Vertex u = p.vector3(p.member(value, "edge1", where), where + " edge1");
      const Vertex v = p.vector3(p.member(value, "edge2", where), where + " edge2");
      if (u.cross(v).norm() == 0) p.fail(where, "edges are parallel: the light has no area");
      light.triangles.push_back({corner, corner + u, corner + u + v});
      light.triangles.push_back({corner, corner + u + v, corner + v});
    } else if (type == "mesh") {
      const json& name = p.member(value, "mesh", where);
      const SceneMesh* mesh = nullptr;
      for (const SceneMesh& m : scene.meshes)
        if (name.is_string() && m.name == name.get<std::string>()) mesh = &m;
      if (!mesh) p.fail(where, "\"mesh\" names no mesh of the scene");
      const Eigen::Affine3d transform =
          value.contains("transform") ? p.transform(value["transform"], where + " transform", &mesh->mesh) : Eigen::Affine3d::Identity();
      for (const Triangle& t : mesh->mesh.triangles)
        light.triangles.push_back({transform * mesh->mesh.positions[t[0]], transform * mesh->mesh.positions[t[1]],
                                   transform * mesh->mesh.positions[t[2]]});
    } else {
      p.fail(where, "\"type\" must be \"parallelogram\" or \"mesh\"");
    }
    scene.lights.push_back(std::move(light));
  }

  const json& camera = p.member(document, "camera", "scene");
  scene.camera.from = p.vector3(p.member(camera, "from", "camera"), "camera from");
  scene.camera.at = p.vector3(p.member(camera, "at", "camera"), "camera at");
  if (camera.contains("up")) scene.camera.up = p.vector3(camera["up"], "camera up");
  if (camera.contains("fov_degrees")) scene.camera.fov_degrees = p.number(camera["fov_degrees"], "camera fov_degrees");
  if (scene.camera.fov_degrees <= 0 || scene.camera.fov_degrees >= 180) p.fail("camera", "fov_degrees must be in (0, 180)");
  if (camera.contains("width")) scene.camera.width = p.positive_int(camera["width"], "camera width", 16384);
  if (camera.contains("height")) scene.camera.height = p.positive_int(camera["height"], "camera height", 16384);
  const Vertex view = scene.camera.at - scene.camera.from;
  if (view.norm() == 0 || view.cross(scene.camera.up).norm() == 0)
    p.fail("camera", "\"from\", \"at\" and \"up\" do not define a view (zero or parallel)");
  return scene;
}

Scene load_scene(const std::filesystem::path& path, const WarningHandler& on_warning) {
  return parse_scene(read_file(path), path, on_warning);
}

}  // namespace visproxy
