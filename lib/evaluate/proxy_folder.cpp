#include "evaluate/proxy_folder.h"

#include "core/errors.h"
#include "core/files.h"
#include "mesh/read_mesh.h"

namespace visproxy {
namespace {

using nlohmann::json;

const json& require(const json& object, const char* key, const std::filesystem::path& file, const std::string& where) {
  if (!object.is_object() || !object.contains(key))
    throw InvalidInputError(file, where + " has no \"" + key + "\"");
  return object[key];
}

Weld weld_of(const json& manifest) {
  const std::string mode = manifest.at("mesh").value("weld", "auto");
  if (mode == "never") return Weld::never;
  if (mode == "always") return Weld::always;
  return Weld::automatic;
}

}  // namespace

json read_manifest(const std::filesystem::path& folder) {
  const std::filesystem::path path = folder / "manifest.json";
  return parse_manifest(read_file(path), path);
}

json parse_manifest(std::string_view text, const std::filesystem::path& path) {
  const json manifest = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (manifest.is_discarded()) throw InvalidInputError(path, "not valid JSON");
  if (!manifest.is_object() || manifest.value("format", "") != "visproxy-manifest")
    throw InvalidInputError(path, "not a visproxy manifest (\"format\" is not \"visproxy-manifest\")");
  if (manifest.value("format_version", 0) != 1)
    throw InvalidInputError(path, "unsupported format_version (this visproxy reads version 1)");
  const json& mesh = require(manifest, "mesh", path, "the manifest");
  for (const char* key : {"vertices", "triangles", "bbox"}) require(mesh, key, path, "\"mesh\"");
  require(manifest, "options", path, "the manifest");
  const json& proxies = require(manifest, "proxies", path, "the manifest");
  if (!proxies.is_array()) throw InvalidInputError(path, "\"proxies\" is not an array");
  for (const json& entry : proxies) {
    const std::string where = "proxy entry " + entry.value("name", std::string("?"));
    for (const char* key : {"name", "kind", "file", "primitive_type", "primitives"}) require(entry, key, path, where);
    entry_kind(entry);
  }
  return manifest;
}

void write_manifest(const std::filesystem::path& folder, const json& manifest) {
  write_file_atomically(folder / "manifest.json", manifest.dump(2) + "\n");
}

TriangleMesh read_manifest_mesh(const std::filesystem::path& path, const json& manifest,
                                const WarningHandler& on_warning) {
  TriangleMesh mesh = read_mesh(path, {.weld = weld_of(manifest), .on_warning = on_warning});
  const json& described = manifest.at("mesh");
  const auto vertices = described.at("vertices").get<std::size_t>();
  const auto triangles = described.at("triangles").get<std::size_t>();
  if (mesh.positions.size() != vertices || mesh.triangles.size() != triangles)
    throw InvalidInputError(path, "is not the mesh the proxies were built from (" + std::to_string(mesh.positions.size()) +
                                      " vertices and " + std::to_string(mesh.triangles.size()) +
                                      " triangles; the manifest lists " + std::to_string(vertices) + " and " +
                                      std::to_string(triangles) + ")");
  const BoundingBox box = bounding_box(mesh);
  const json& bbox = described.at("bbox");
  for (int axis = 0; axis < 3; ++axis) {
    const auto i = static_cast<std::size_t>(axis);
    if (box.min[axis] != bbox.at("min").at(i).get<double>() || box.max[axis] != bbox.at("max").at(i).get<double>())
      throw InvalidInputError(path, "is not the mesh the proxies were built from (its bounding box differs from the manifest's)");
  }
  return mesh;
}

ProxyKind entry_kind(const json& entry) {
  const std::string kind = entry.at("kind").get<std::string>();
  if (kind == "outside") return ProxyKind::outside;
  if (kind == "inside") return ProxyKind::inside;
  if (kind == "general") return ProxyKind::general;
  throw Error("manifest entry " + entry.value("name", std::string("?")) + ": unknown kind \"" + kind + "\"");
}

ProxyGeometry read_proxy_geometry(const std::filesystem::path& folder, const json& entry) {
  const std::filesystem::path path = folder / entry.at("file").get<std::string>();
  const std::string type = entry.at("primitive_type").get<std::string>();
  const auto primitives = entry.at("primitives").get<std::size_t>();
  ProxyGeometry geometry;
  if (type == "sphere") {
    geometry.type = PrimitiveType::sphere;
    geometry.spheres = read_sphere_set(path);
    if (geometry.spheres.size() != primitives)
      throw InvalidInputError(path, "holds " + std::to_string(geometry.spheres.size()) + " spheres; the manifest lists " +
                                        std::to_string(primitives));
    return geometry;
  }
  geometry.type = type == "box" ? PrimitiveType::box : PrimitiveType::triangle;
  geometry.mesh = read_mesh(path, {.weld = Weld::never, .on_warning = {}});
  const std::size_t expected = entry.value("triangles", geometry.mesh.triangles.size());
  if (geometry.mesh.triangles.size() != expected)
    throw InvalidInputError(path, "holds " + std::to_string(geometry.mesh.triangles.size()) +
                                      " triangles; the manifest lists " + std::to_string(expected));
  if (geometry.mesh.triangles.empty()) throw InvalidInputError(path, "holds no triangles");
  return geometry;
}

}  // namespace visproxy
