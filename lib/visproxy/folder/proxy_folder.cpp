#include "visproxy/folder/proxy_folder.h"

#include <optional>
#include <set>
#include <system_error>

#include "visproxy/core/errors.h"
#include "visproxy/core/files.h"
#include "visproxy/core/json_input.h"
#include "visproxy/core/version.h"
#include "visproxy/mesh/mesh_topology.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/mesh/write_mesh.h"
#include "visproxy/mesh/sphere_set.h"

namespace visproxy {
namespace {

using nlohmann::json;

// The manifest was checked (parse_manifest): the name is one of Weld's.
Weld weld_of(const json& manifest) { return parse_choice<Weld>("mesh.weld", manifest.at("mesh").value("weld", "auto")); }

}  // namespace

json read_manifest(const std::filesystem::path& folder) {
  const std::filesystem::path path = folder / "manifest.json";
  return parse_manifest(read_file(path), path);
}

json parse_manifest(std::string_view text, const std::filesystem::path& path) {
  const JsonInput input(path);
  json manifest = input.parse(text);
  if (!manifest.is_object() || !manifest.contains("format") || manifest["format"] != "visproxy-manifest")
    input.fail("", "not a visproxy manifest (\"format\" is not \"visproxy-manifest\")");
  if (input.member(manifest, "format_version", "") != 1)
    input.fail("format_version", "unsupported (this visproxy reads version 1)");
  if (const json* generator = input.optional_member(manifest, "generator", "")) input.string(*generator, "generator");

  const json& mesh = input.member(manifest, "mesh", "");
  input.string(input.member(mesh, "path", "mesh"), "mesh.path");
  input.count(input.member(mesh, "vertices", "mesh"), "mesh.vertices");
  input.count(input.member(mesh, "triangles", "mesh"), "mesh.triangles");
  const json& bbox = input.member(mesh, "bbox", "mesh");
  input.triple(input.member(bbox, "min", "mesh.bbox"), "mesh.bbox.min");
  input.triple(input.member(bbox, "max", "mesh.bbox"), "mesh.bbox.max");
  if (const json* weld = input.optional_member(mesh, "weld", "mesh");
      weld && !(weld->is_string() && find_choice<Weld>(weld->get<std::string>())))
    input.fail("mesh.weld", "must be one of " + choice_list<Weld>());
  input.object(input.member(manifest, "options", ""), "options");

  const json& proxies = input.member(manifest, "proxies", "");
  if (!proxies.is_array()) input.fail("proxies", "expected an array of proxy entries");
  for (std::size_t i = 0; i < proxies.size(); ++i) {
    const json& entry = proxies[i];
    const std::string where = json_index_path("proxies", i);
    for (const char* key : {"name", "file"})
      input.string(input.member(entry, key, where), json_member_path(where, key));
    const json& kind = input.member(entry, "kind", where);
    if (kind != "outside" && kind != "inside" && kind != "general")
      input.fail(json_member_path(where, "kind"), "must be \"outside\", \"inside\" or \"general\"");
    const json& type = input.member(entry, "primitive_type", where);
    if (type != "triangle" && type != "box" && type != "sphere")
      input.fail(json_member_path(where, "primitive_type"), "must be \"triangle\", \"box\" or \"sphere\"");
    input.count(input.member(entry, "primitives", where), json_member_path(where, "primitives"));
    if (const json* triangles = input.optional_member(entry, "triangles", where))
      input.count(*triangles, json_member_path(where, "triangles"));
  }
  return manifest;
}

void write_manifest(const std::filesystem::path& folder, const json& manifest) {
  write_file_atomically(folder / "manifest.json", manifest.dump(2) + "\n");
}

TriangleMesh read_manifest_mesh(const std::filesystem::path& path, const json& manifest,
                                const WarningHandler& on_warning) {
  TriangleMesh mesh = read_mesh(path, {.weld = weld_of(manifest), .on_warning = on_warning});
  check_manifest_mesh(mesh, path, manifest);
  return mesh;
}

void check_manifest_mesh(const TriangleMesh& mesh, const std::filesystem::path& path, const json& manifest) {
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
}

ProxyKind entry_kind(const json& entry) {
  const std::string kind = entry.at("kind").get<std::string>();
  if (kind == "outside") return ProxyKind::outside;
  if (kind == "inside") return ProxyKind::inside;
  if (kind == "general") return ProxyKind::general;
  throw Error("manifest entry " + entry.value("name", std::string("?")) + ": unknown kind \"" + kind + "\"");
}

namespace {

// The geometry of the entry's `file` alone.
ProxyGeometry read_proxy_file(const std::filesystem::path& folder, const json& entry) {
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

// Where `copy` (read from `path`) first differs from `geometry`'s triangles, or empty.
std::string mesh_difference(const std::filesystem::path& path, const TriangleMesh& copy, const TriangleMesh& geometry,
                            const std::filesystem::path& original) {
  const std::string prefix = path.filename().string() + " does not hold the proxy of " + original.filename().string() + ": ";
  if (copy.positions.size() != geometry.positions.size() || copy.triangles.size() != geometry.triangles.size())
    return prefix + std::to_string(copy.positions.size()) + " vertices and " + std::to_string(copy.triangles.size()) +
           " triangles, not " + std::to_string(geometry.positions.size()) + " and " + std::to_string(geometry.triangles.size());
  for (std::size_t v = 0; v < copy.positions.size(); ++v)
    if (copy.positions[v] != geometry.positions[v]) return prefix + "vertex " + std::to_string(v) + " differs";
  for (std::size_t t = 0; t < copy.triangles.size(); ++t)
    if (copy.triangles[t] != geometry.triangles[t]) return prefix + "triangle " + std::to_string(t) + " differs";
  return {};
}

// The first file of entry.files (other than `file`) that does not hold the geometry.
std::string files_problem(const std::filesystem::path& folder, const json& entry, const ProxyGeometry& geometry) {
  const json* files = entry.contains("files") ? &entry.at("files") : nullptr;
  if (files == nullptr || !files->is_array()) return {};
  const std::filesystem::path original = folder / entry.at("file").get<std::string>();
  std::optional<TriangleMesh> drawn;  // a sphere set as sphere_set_mesh draws it
  for (const json& name : *files) {
    if (!name.is_string()) throw InvalidInputError(folder / "manifest.json", "an entry's files must be file names");
    const std::filesystem::path relative(name.get<std::string>());
    if (relative.empty() || relative.is_absolute() || relative.has_parent_path())
      throw InvalidInputError(folder / "manifest.json", "\"" + relative.string() + "\" is not a file name in the proxy folder");
    const std::filesystem::path path = folder / relative;
    if (path == original) continue;
    if (!std::filesystem::exists(path)) return relative.string() + " is listed but missing";
    TriangleMesh copy;
    try {
      copy = read_mesh(path, {.weld = Weld::never, .on_warning = {}});
    } catch (const Error& error) {
      return relative.string() + " cannot be read: " + error.what();
    }
    if (geometry.type == PrimitiveType::sphere) {
      if (!drawn) drawn = sphere_set_mesh(geometry.spheres);
      if (std::string problem = mesh_difference(path, copy, *drawn, original); !problem.empty()) return problem;
    } else if (std::string problem = mesh_difference(path, copy, geometry.mesh, original); !problem.empty()) {
      return problem;
    }
  }
  return {};
}

}  // namespace

ProxyGeometry read_proxy_geometry(const std::filesystem::path& folder, const json& entry) {
  ProxyGeometry geometry = read_proxy_file(folder, entry);
  geometry.files_problem = files_problem(folder, entry, geometry);
  return geometry;
}

namespace {

json to_json(const Vertex& v) { return json::array({v.x(), v.y(), v.z()}); }

}  // namespace

json manifest_entry(const BuiltProxy& proxy) {
  return {{"name", proxy.name.empty() ? proxy.spec.name() : proxy.name},
          {"spec", proxy.spec.text},
          {"kind", kind_name(proxy.spec.kind())},
          {"method", proxy.method},
          {"params", proxy.params},
          {"primitive_type", primitive_type_name(proxy.primitive_type)},
          {"primitives", proxy.primitives},
          {"vertices", proxy.mesh.positions.size()},
          {"triangles", proxy.mesh.triangles.size()},
          {"build_seconds", proxy.build_seconds},
          {"error", proxy.error},
          {"result", proxy.result}};
}

namespace {

// The files the folder's present manifest lists (each entry's `file` and `files`), as plain
// names inside the folder: a name with a path in it (hand-edited, "../x") is not ours to
// remove and is left out. Nothing when there is no readable manifest.
std::set<std::string> listed_files(const std::filesystem::path& folder) {
  std::set<std::string> names;
  std::error_code error;
  if (!std::filesystem::is_regular_file(folder / "manifest.json", error)) return names;
  json manifest;
  try {
    manifest = read_manifest(folder);
  } catch (const Error&) {
    return names;
  }
  const auto add = [&names](const json& name) {
    if (!name.is_string()) return;
    const std::string text = name.get<std::string>();
    const std::filesystem::path path(text);
    if (text.empty() || text == "." || text == ".." || text == "manifest.json" || path.has_parent_path() ||
        path.filename().string() != text || text.find('\\') != std::string::npos)
      return;
    names.insert(text);
  };
  for (const json& entry : manifest.at("proxies")) {
    if (entry.contains("file")) add(entry["file"]);
    if (entry.contains("files") && entry["files"].is_array())
      for (const json& name : entry["files"]) add(name);
  }
  return names;
}

}  // namespace

json write_proxy_folder(const std::filesystem::path& folder, const ManifestMesh& mesh,
                        std::span<const BuiltProxy> proxies, const BuildOptions& options) {
  std::error_code error;
  std::filesystem::create_directories(folder, error);
  if (error) throw IOError(folder, "cannot create the output folder: " + error.message());
  // Built again into a folder: the proxies the new manifest no longer lists go, once it is
  // in place (files of other names are left alone).
  std::set<std::string> stale = listed_files(folder);

  json entries = json::array();
  for (const BuiltProxy& proxy : proxies) {
    json entry = manifest_entry(proxy);
    const std::string name = entry.at("name");
    if (proxy.primitive_type == PrimitiveType::sphere) {
      // The spheres themselves, and their icospheres for looking at them.
      write_sphere_set(folder / (name + ".json"), proxy.spheres);
      write_mesh(folder / (name + ".ply"), proxy.mesh);
      entry["file"] = name + ".json";
      entry["files"] = json::array({name + ".json", name + ".ply"});
    } else {
      write_mesh(folder / (name + ".ply"), proxy.mesh);
      write_mesh(folder / (name + ".obj"), proxy.mesh);
      entry["file"] = name + ".ply";
      entry["files"] = json::array({name + ".ply", name + ".obj"});
    }
    entries.push_back(std::move(entry));
  }
  const json manifest = {
      {"format", "visproxy-manifest"},
      {"format_version", 1},
      {"generator", std::string("visproxy ") + version()},
      {"mesh",
       {{"path", mesh.path.string()},
        {"weld", mesh.weld},
        {"vertices", mesh.vertices},
        {"triangles", mesh.triangles},
        {"components", mesh.components},
        {"bbox", {{"min", to_json(mesh.bounds.min)}, {"max", to_json(mesh.bounds.max)}, {"diagonal", mesh.bounds.diagonal()}}}}},
      {"options",
       {{"per_component", options.per_component},
        {"hausdorff_samples", options.hausdorff_samples},
        {"tets", name_of(options.tets)},
        {"gssa_lines", options.gssa_lines},
        {"builders_at_once", builders_at_once(options.builders_at_once, mesh.triangles)},
        {"seed", options.seed}}},
      {"proxies", entries}};
  write_file_atomically(folder / "manifest.json", manifest.dump(2) + "\n");
  for (const json& entry : manifest.at("proxies"))
    for (const json& name : entry.at("files")) stale.erase(name.get<std::string>());
  for (const std::string& name : stale) std::filesystem::remove(folder / name, error);
  return manifest;
}

ManifestMesh describe_mesh(const TriangleMesh& mesh, const std::filesystem::path& path, Weld weld) {
  return {.path = path,
          .weld = std::string(name_of(weld)),
          .vertices = mesh.positions.size(),
          .triangles = mesh.triangles.size(),
          .components = analyze_topology(mesh).components,
          .bounds = bounding_box(mesh)};
}

BuiltFolder build_proxy_folder(const std::filesystem::path& folder, const TriangleMesh& mesh,
                               const std::filesystem::path& source, Weld weld, std::span<const ProxySpec> specs,
                               const BuildOptions& options, const std::function<void()>& before_writing) {
  BuiltFolder built{.mesh = describe_mesh(mesh, source, weld), .proxies = {}, .manifest = {}};
  built.proxies = build_proxies(mesh, source, specs, options);
  if (before_writing) before_writing();
  built.manifest = write_proxy_folder(folder, built.mesh, built.proxies, options);
  return built;
}

}  // namespace visproxy
