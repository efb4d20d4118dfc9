// The `visproxy` Python module: meshes as numpy arrays, proxies as dicts of arrays with
// their manifest entries, and every result as the JSON objects the CLI records, turned
// into Python dicts and lists.
//
//   import visproxy as vp
//   vertices, triangles = vp.read_mesh("bunny.off")     # (V, 3) float64, (T, 3) int64
//   proxies = vp.build(vertices, triangles, ["hull", "spheres:100"], seed=1)
//   verdicts = vp.verify(vertices, triangles, proxies)  # [{"claim", "holds", ...}, ...]
//   figures = vp.measure(vertices, triangles, proxies, rays=100_000)
//
// The long calls (build, verify, measure, render) let other Python threads run. Errors
// in the input raise visproxy.InvalidInputError (a ValueError) or visproxy.FileError (an
// OSError), both visproxy.Error, with the one-line message the CLI prints.

#include <pybind11/eval.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "visproxy/asset/export_proxies.h"
#include "visproxy/core/errors.h"
#include "visproxy/core/process.h"
#include "visproxy/core/version.h"
#include "visproxy/evaluate/asset_report.h"
#include "visproxy/evaluate/batch.h"
#include "visproxy/folder/asset_folder.h"
#include "visproxy/evaluate/measure_proxies.h"
#include "visproxy/folder/proxy_folder.h"
#include "visproxy/evaluate/report.h"
#include "visproxy/render/scene_proxies.h"
#include "visproxy/folder/verdict.h"
#include "visproxy/inspect/mesh_report.h"
#include "visproxy/render/proxy_pictures.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/mesh/write_mesh.h"
#include "visproxy/proxy/build_proxies.h"
#include "visproxy/render/render_job.h"
#include "visproxy/scene/scene.h"

namespace py = pybind11;
using nlohmann::json;

namespace visproxy::python {
namespace {

// ---- JSON <-> Python --------------------------------------------------------------

py::object to_python(const json& value) {
  switch (value.type()) {
    case json::value_t::null: return py::none();
    case json::value_t::boolean: return py::bool_(value.get<bool>());
    case json::value_t::number_integer: return py::int_(value.get<std::int64_t>());
    case json::value_t::number_unsigned: return py::int_(value.get<std::uint64_t>());
    case json::value_t::number_float: return py::float_(value.get<double>());
    case json::value_t::string: return py::str(value.get_ref<const std::string&>());
    case json::value_t::array: {
      py::list list;
      for (const json& item : value) list.append(to_python(item));
      return list;
    }
    case json::value_t::object: {
      py::dict dict;
      for (const auto& [key, item] : value.items()) dict[py::str(key)] = to_python(item);
      return dict;
    }
    case json::value_t::binary:
    case json::value_t::discarded: break;
  }
  return py::none();
}

json from_python(py::handle value, const std::string& where) {
  if (value.is_none()) return nullptr;
  if (py::isinstance<py::bool_>(value)) return value.cast<bool>();
  if (py::isinstance<py::int_>(value)) {
    const py::int_ number = py::reinterpret_borrow<py::int_>(value);
    if (py::int_(0) > number) return value.cast<std::int64_t>();
    return value.cast<std::uint64_t>();
  }
  if (py::isinstance<py::float_>(value)) return value.cast<double>();
  if (py::isinstance<py::str>(value)) return value.cast<std::string>();
  if (py::isinstance<py::dict>(value)) {
    json object = json::object();
    for (const auto& [key, item] : py::reinterpret_borrow<py::dict>(value)) {
      const std::string name = py::str(key).cast<std::string>();
      object[name] = from_python(item, where + "." + name);
    }
    return object;
  }
  if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value)) {
    json array = json::array();
    std::size_t i = 0;
    for (const py::handle item : value) array.push_back(from_python(item, where + "[" + std::to_string(i++) + "]"));
    return array;
  }
  // numpy scalars
  if (py::hasattr(value, "item") && py::hasattr(value, "dtype")) return from_python(value.attr("item")(), where);
  throw py::type_error(where + ": cannot be stored in a manifest (" + py::str(value.get_type()).cast<std::string>() + ")");
}

// ---- arrays <-> meshes ------------------------------------------------------------

py::array_t<double> vertex_array(const std::vector<Vertex>& positions) {
  py::array_t<double> array({static_cast<py::ssize_t>(positions.size()), py::ssize_t{3}});
  auto out = array.mutable_unchecked<2>();
  for (std::size_t i = 0; i < positions.size(); ++i)
    for (int k = 0; k < 3; ++k) out(static_cast<py::ssize_t>(i), k) = positions[i][k];
  return array;
}

py::array_t<std::int64_t> triangle_array(const std::vector<Triangle>& triangles) {
  py::array_t<std::int64_t> array({static_cast<py::ssize_t>(triangles.size()), py::ssize_t{3}});
  auto out = array.mutable_unchecked<2>();
  for (std::size_t i = 0; i < triangles.size(); ++i)
    for (int k = 0; k < 3; ++k) out(static_cast<py::ssize_t>(i), k) = triangles[i][static_cast<std::size_t>(k)];
  return array;
}

py::array_t<double> sphere_array(const std::vector<Sphere>& spheres) {
  py::array_t<double> array({static_cast<py::ssize_t>(spheres.size()), py::ssize_t{4}});
  auto out = array.mutable_unchecked<2>();
  for (std::size_t i = 0; i < spheres.size(); ++i) {
    const auto row = static_cast<py::ssize_t>(i);
    for (int k = 0; k < 3; ++k) out(row, k) = spheres[i].center[k];
    out(row, 3) = spheres[i].radius;
  }
  return array;
}

std::string dtype_text(const py::array& array) { return py::str(array.dtype()).cast<std::string>(); }

// An (N, columns) float64 array from anything numpy reads as real numbers.
py::array_t<double, py::array::c_style> real_rows(py::handle object, py::ssize_t columns, const std::string& source,
                                                  const char* what) {
  const py::array array = py::array::ensure(object);
  if (!array) throw InvalidInputError(source, std::string(what) + ": not an array");
  const char kind = array.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u')
    throw InvalidInputError(source, std::string(what) + ": must hold real numbers, not " + dtype_text(array));
  if (array.ndim() != 2 || array.shape(1) != columns)
    throw InvalidInputError(source, std::string(what) + ": must have shape (N, " + std::to_string(columns) + ")");
  return py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(array);
}

TriangleMesh mesh_from_arrays(py::handle vertices, py::handle triangles, const std::string& source) {
  const auto points = real_rows(vertices, 3, source, "vertices");
  const py::array faces = py::array::ensure(triangles);
  if (!faces) throw InvalidInputError(source, "triangles: not an array");
  if (faces.dtype().kind() != 'i' && faces.dtype().kind() != 'u')
    throw InvalidInputError(source, "triangles: must hold integer vertex indices, not " + dtype_text(faces));
  if (faces.ndim() != 2 || faces.shape(1) != 3) throw InvalidInputError(source, "triangles: must have shape (T, 3)");
  const auto indices = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(faces);
  // Unsigned 64-bit indices above 2^63 wrap negative here and are refused as such.
  if (faces.dtype().kind() == 'u' && faces.dtype().itemsize() == 8) {
    const auto raw = py::array_t<std::uint64_t, py::array::c_style | py::array::forcecast>::ensure(faces).unchecked<2>();
    for (py::ssize_t i = 0; i < raw.shape(0); ++i)
      for (py::ssize_t k = 0; k < 3; ++k)
        if (raw(i, k) > static_cast<std::uint64_t>(INT64_MAX))
          throw InvalidInputError(source, "triangles[" + std::to_string(i) + ", " + std::to_string(k) + "]: vertex index " +
                                              std::to_string(raw(i, k)) + " is out of range");
  }
  TriangleMesh mesh;
  const auto p = points.unchecked<2>();
  mesh.positions.resize(static_cast<std::size_t>(p.shape(0)));
  for (py::ssize_t i = 0; i < p.shape(0); ++i) mesh.positions[static_cast<std::size_t>(i)] = Vertex(p(i, 0), p(i, 1), p(i, 2));
  const auto t = indices.unchecked<2>();
  mesh.triangles.resize(static_cast<std::size_t>(t.shape(0)));
  const auto count = static_cast<std::int64_t>(mesh.positions.size());
  for (py::ssize_t i = 0; i < t.shape(0); ++i)
    for (py::ssize_t k = 0; k < 3; ++k) {
      const std::int64_t index = t(i, k);
      if (index < 0 || index >= count)
        throw InvalidInputError(source, "triangles[" + std::to_string(i) + ", " + std::to_string(k) + "]: vertex index " +
                                            std::to_string(index) + " is out of range (" + std::to_string(count) +
                                            " vertices)");
      mesh.triangles[static_cast<std::size_t>(i)][static_cast<std::size_t>(k)] = static_cast<VertexIndex>(index);
    }
  require_coordinates_in_range(mesh, source);
  return mesh;
}

std::vector<Sphere> spheres_from_array(py::handle object, const std::string& source) {
  const auto rows = real_rows(object, 4, source, "spheres");
  const auto s = rows.unchecked<2>();
  std::vector<Sphere> spheres(static_cast<std::size_t>(s.shape(0)));
  for (py::ssize_t i = 0; i < s.shape(0); ++i) {
    const Sphere sphere{Vertex(s(i, 0), s(i, 1), s(i, 2)), s(i, 3)};
    if (!sphere.center.allFinite() || !std::isfinite(sphere.radius) || sphere.radius <= 0 ||
        sphere.center.cwiseAbs().maxCoeff() > kMaxCoordinate || sphere.radius > kMaxCoordinate)
      throw InvalidInputError(source, "spheres[" + std::to_string(i) + "]: needs a finite centre and a positive finite radius");
    spheres[static_cast<std::size_t>(i)] = sphere;
  }
  return spheres;
}

// ---- proxies as dicts -------------------------------------------------------------

py::dict proxy_dict(const std::string& name, const json& entry, const ProxyGeometry& geometry) {
  py::dict proxy;
  proxy["name"] = name;
  proxy["kind"] = entry.value("kind", std::string("general"));
  proxy["primitive_type"] = std::string(primitive_type_name(geometry.type));
  const bool spheres = geometry.type == PrimitiveType::sphere;
  proxy["vertices"] = spheres ? py::object(py::none()) : py::object(vertex_array(geometry.mesh.positions));
  proxy["triangles"] = spheres ? py::object(py::none()) : py::object(triangle_array(geometry.mesh.triangles));
  proxy["spheres"] = spheres ? py::object(sphere_array(geometry.spheres)) : py::object(py::none());
  proxy["manifest"] = to_python(entry);
  return proxy;
}

// A proxy dict (build's, read_proxies', or one a user made) as an entry and its geometry.
struct HeldProxy {
  json entry;
  ProxyGeometry geometry;
};

HeldProxy held_proxy(py::handle object, std::size_t index) {
  const std::string where = "proxies[" + std::to_string(index) + "]";
  if (!py::isinstance<py::dict>(object)) throw py::type_error(where + ": must be a dict (as build or read_proxies returns)");
  const py::dict proxy = py::reinterpret_borrow<py::dict>(object);
  HeldProxy held;
  held.entry = proxy.contains("manifest") && !proxy["manifest"].is_none() ? from_python(proxy["manifest"], where + ".manifest")
                                                                          : json::object();
  if (!held.entry.is_object()) throw InvalidInputError(where, "manifest: must be a dict");
  if (proxy.contains("kind") && !proxy["kind"].is_none()) held.entry["kind"] = proxy["kind"].cast<std::string>();
  if (proxy.contains("name") && !proxy["name"].is_none()) held.entry["name"] = proxy["name"].cast<std::string>();
  if (!held.entry.contains("name")) held.entry["name"] = where;
  if (!held.entry.contains("kind")) throw InvalidInputError(where, "needs a kind: \"outside\", \"inside\" or \"general\"");
  const std::string kind = held.entry["kind"].is_string() ? held.entry["kind"].get<std::string>() : "";
  if (kind != "outside" && kind != "inside" && kind != "general")
    throw InvalidInputError(where, "kind: must be \"outside\", \"inside\" or \"general\"");
  const bool has_spheres = proxy.contains("spheres") && !proxy["spheres"].is_none();
  if (has_spheres) {
    held.geometry.type = PrimitiveType::sphere;
    held.geometry.spheres = spheres_from_array(proxy["spheres"], where);
    if (held.geometry.spheres.empty()) throw InvalidInputError(where, "spheres: holds no sphere");
  } else {
    if (!proxy.contains("vertices") || !proxy.contains("triangles") || proxy["vertices"].is_none() ||
        proxy["triangles"].is_none())
      throw InvalidInputError(where, "needs vertices and triangles, or spheres");
    held.geometry.type = proxy.contains("primitive_type") && py::str(proxy["primitive_type"]).cast<std::string>() == "box"
                             ? PrimitiveType::box
                             : PrimitiveType::triangle;
    held.geometry.mesh = mesh_from_arrays(proxy["vertices"], proxy["triangles"], where);
    if (held.geometry.mesh.triangles.empty()) throw InvalidInputError(where, "holds no triangles");
  }
  return held;
}

std::vector<HeldProxy> held_proxies(py::handle proxies) {
  std::vector<HeldProxy> held;
  if (py::isinstance<py::dict>(proxies)) {
    held.push_back(held_proxy(proxies, 0));
    return held;
  }
  std::size_t index = 0;
  for (const py::handle proxy : proxies) {
    held.push_back(held_proxy(proxy, index));
    ++index;
  }
  return held;
}

// ---- the functions ----------------------------------------------------------------

py::tuple read_mesh_arrays(const std::filesystem::path& path, const std::string& weld) {
  TriangleMesh mesh;
  {
    const Weld mode = parse_choice<Weld>("weld", weld);
    py::gil_scoped_release release;
    mesh = read_mesh(path, {.weld = mode, .on_warning = {}});
  }
  return py::make_tuple(vertex_array(mesh.positions), triangle_array(mesh.triangles));
}

void write_mesh_arrays(const std::filesystem::path& path, py::handle vertices, py::handle triangles) {
  const TriangleMesh mesh = mesh_from_arrays(vertices, triangles, path.string());
  py::gil_scoped_release release;
  write_mesh(path, mesh);
}

py::object inspect_arrays(py::handle vertices, py::handle triangles, const std::string& source) {
  const TriangleMesh mesh = mesh_from_arrays(vertices, triangles, source);
  json report;
  {
    py::gil_scoped_release release;
    report = to_json(inspect_mesh(mesh));
  }
  return to_python(report);
}

py::object build_asset_parts(const std::filesystem::path& asset, const std::filesystem::path& output,
                             std::optional<std::vector<std::string>> specs_text, std::uint64_t seed, std::size_t hausdorff_samples,
                             const std::string& weld) {
  const std::vector<ProxySpec> specs = specs_text ? parse_proxy_specs(*specs_text) : default_proxy_specs();
  if (hausdorff_samples < 100) throw py::value_error("hausdorff_samples: must be at least 100");
  BuildOptions options;
  options.hausdorff_samples = hausdorff_samples;
  options.seed = seed;
  options.default_set = !specs_text.has_value();
  const Weld welded = parse_choice<Weld>("weld", weld);
  json listing;
  {
    py::gil_scoped_release release;
    listing = build_asset_folder(output, asset, welded, specs, options);
  }
  return to_python(listing);
}

py::list build_arrays(py::handle vertices, py::handle triangles, std::optional<std::vector<std::string>> specs_text,
                      std::uint64_t seed, bool per_component, std::size_t hausdorff_samples, const std::string& tets,
                      std::size_t gssa_lines, std::optional<std::filesystem::path> output, const std::string& source,
                      const std::string& weld, std::size_t builders_at_once) {
  const TriangleMesh mesh = mesh_from_arrays(vertices, triangles, source);
  const std::vector<ProxySpec> specs = specs_text ? parse_proxy_specs(*specs_text) : default_proxy_specs();
  if (hausdorff_samples < 100) throw py::value_error("hausdorff_samples: must be at least 100");
  if (gssa_lines < 1000) throw py::value_error("gssa_lines: must be at least 1000");
  BuildOptions options{
      .per_component = per_component,
      .hausdorff_samples = hausdorff_samples,
      .seed = seed,
      .on_start = {},
      .tets = parse_choice<InnerTetrahedra>("tets", tets),
      .gssa_lines = gssa_lines,
      .default_set = !specs_text.has_value(),
      .on_skip = {}};
  options.builders_at_once = builders_at_once;
  const Weld welded = parse_choice<Weld>("weld", weld);  // recorded in the manifest as how the source was read
  std::vector<BuiltProxy> built;
  {
    py::gil_scoped_release release;
    built = output ? build_proxy_folder(*output, mesh, source, welded, specs, options).proxies
                   : build_proxies(mesh, source, specs, options);
  }
  py::list proxies;
  for (const BuiltProxy& proxy : built) {
    ProxyGeometry geometry{.type = proxy.primitive_type, .mesh = {}, .spheres = proxy.spheres, .files_problem = {}};
    if (proxy.primitive_type != PrimitiveType::sphere) geometry.mesh = proxy.mesh;
    py::dict dict = proxy_dict(proxy.name, manifest_entry(proxy), geometry);
    dict["spec"] = proxy.spec.name();
    proxies.append(std::move(dict));
  }
  return proxies;
}

py::list read_proxies_folder(const std::filesystem::path& folder) {
  json manifest;
  std::vector<ProxyGeometry> geometries;
  {
    py::gil_scoped_release release;
    manifest = read_manifest(folder);
    for (const json& entry : manifest.at("proxies")) geometries.push_back(read_proxy_geometry(folder, entry));
  }
  py::list proxies;
  for (std::size_t i = 0; i < geometries.size(); ++i) {
    const json& entry = manifest["proxies"][i];
    proxies.append(proxy_dict(entry.at("name").get<std::string>(), entry, geometries[i]));
  }
  return proxies;
}

py::object read_manifest_dict(const std::filesystem::path& folder) {
  json manifest;
  {
    py::gil_scoped_release release;
    manifest = read_manifest(folder);
  }
  return to_python(manifest);
}

py::object write_folder_report(const std::filesystem::path& folder, const std::optional<std::filesystem::path>& mesh,
                               bool pictures, int picture_size, std::size_t budget) {
  json recommendation;
  const ReportOptions options{.pictures = pictures, .picture_options = {.size = picture_size}, .budget = budget};
  if (is_asset_folder(folder)) {  // a per-mesh folder: each mesh's report and the asset's table
    py::gil_scoped_release release;
    recommendation = write_asset_report(folder, mesh.value_or(std::filesystem::path()), options);
  } else {
    py::gil_scoped_release release;
    const json manifest = read_manifest(folder);
    const TriangleMesh read = read_manifest_mesh(mesh ? *mesh : std::filesystem::path(manifest["mesh"]["path"].get<std::string>()),
                                                 manifest);
    const ReportFigures figures = report_figures(read, folder, manifest, options);
    write_report(folder, manifest, figures);
    recommendation = report_recommendation_json(figures, manifest);
  }
  return to_python(recommendation);
}

py::list export_folder(const std::filesystem::path& folder, const std::filesystem::path& output,
                       const std::optional<std::vector<std::string>>& proxies, const std::optional<std::filesystem::path>& mesh) {
  ExportResult result;
  {
    py::gil_scoped_release release;
    result = export_proxies(folder, output, {.proxies = proxies.value_or(std::vector<std::string>{}), .source = mesh.value_or(std::filesystem::path())});
  }
  py::list out;
  for (const ExportedProxy& proxy : result.proxies) {
    const FloatProxy& g = proxy.geometry;
    out.append(to_python(json{{"name", proxy.name},
                              {"part", proxy.part},
                              {"node", proxy.node},
                              {"claimed", kind_name(g.claimed)},
                              {"kind", kind_name(g.kind)},
                              {"moved", g.moved},
                              {"triangles", g.indices.size() / 3},
                              {"note", g.note}}));
  }
  return out;
}

json mesh_manifest(const TriangleMesh& mesh) {
  const BoundingBox box = bounding_box(mesh);
  return {{"mesh", {{"bbox", {{"diagonal", box.diagonal()}}}}}};
}

py::dict float_proxy_arrays(py::handle vertices, py::handle triangles, py::handle proxy, const std::string& source) {
  const TriangleMesh mesh = mesh_from_arrays(vertices, triangles, source);
  const HeldProxy held = held_proxy(proxy, 0);
  FloatProxy rounded;
  {
    py::gil_scoped_release release;
    rounded = round_proxy_to_float(mesh, mesh_manifest(mesh), held.entry, held.geometry, source);
  }
  py::array_t<float> points({static_cast<py::ssize_t>(rounded.positions.size() / 3), py::ssize_t{3}});
  std::copy(rounded.positions.begin(), rounded.positions.end(), points.mutable_data());
  py::dict out;
  out["vertices"] = points;
  out["triangles"] = triangle_array(rounded.mesh().triangles);
  out["claimed"] = std::string(kind_name(rounded.claimed));
  out["kind"] = std::string(kind_name(rounded.kind));
  out["moved"] = rounded.moved;
  out["verify"] = to_python(rounded.verify);
  out["note"] = rounded.note;
  return out;
}

py::dict shadow_stage_arrays(py::handle vertices, py::handle triangles, py::handle proxy, int size, const std::string& source) {
  const TriangleMesh mesh = mesh_from_arrays(vertices, triangles, source);
  if (size < 8 || size > 4096) throw py::value_error("size: must be from 8 to 4096");
  std::optional<HeldProxy> held;
  if (!proxy.is_none()) held = held_proxy(proxy, 0);
  json stage;
  std::optional<ProxyPictures> pictures;
  {
    py::gil_scoped_release release;
    const ProxyPictureStage picture_stage(mesh, {.size = size});
    stage = picture_stage.geometry();
    if (held) {
      const bool proved = held->entry["kind"] != "general" &&
                          verify_proxy(mesh, mesh_manifest(mesh), held->entry, held->geometry).at("holds").get<bool>();
      pictures = picture_stage.pictures(InstanceProxy{entry_kind(held->entry), held->entry.value("spec", std::string()),
                                                      held->geometry.mesh, held->geometry.spheres, proved});
    }
  }
  py::dict out = to_python(stage).cast<py::dict>();
  if (pictures) {
    out["missed_shadow"] = pictures->missed_shadow;
    out["extra_shadow"] = pictures->extra_shadow;
  }
  return out;
}

py::list verify_arrays(py::handle vertices, py::handle triangles, py::handle proxies, std::size_t hausdorff_samples,
                       std::uint64_t seed, const std::string& source) {
  const TriangleMesh mesh = mesh_from_arrays(vertices, triangles, source);
  const std::vector<HeldProxy> held = held_proxies(proxies);
  if (hausdorff_samples < 100) throw py::value_error("hausdorff_samples: must be at least 100");
  std::vector<json> verdicts;
  {
    py::gil_scoped_release release;
    const json manifest = mesh_manifest(mesh);
    for (const HeldProxy& proxy : held)
      verdicts.push_back(verify_proxy(mesh, manifest, proxy.entry, proxy.geometry,
                                      {.hausdorff_samples = hausdorff_samples, .seed = seed}));
  }
  py::list result;
  for (const json& verdict : verdicts) result.append(to_python(verdict));
  return result;
}

py::list measure_arrays(py::handle vertices, py::handle triangles, py::handle proxies, std::size_t rays, std::uint64_t seed,
                        std::optional<std::filesystem::path> scene, std::size_t timed_rays, const std::string& source) {
  const TriangleMesh mesh = mesh_from_arrays(vertices, triangles, source);
  const std::vector<HeldProxy> held = held_proxies(proxies);
  if (rays < 1) throw py::value_error("rays: must be at least 1");
  json manifest = {{"proxies", json::array()}};
  for (const HeldProxy& proxy : held) manifest["proxies"].push_back(proxy.entry);
  MeasureOptions options{.rays = rays, .seed = seed, .scene = scene.value_or(std::filesystem::path()),
                         .timing = {.rays = timed_rays, .blocks = 6}, .on_start = {}, .on_warning = {}};
  {
    py::gil_scoped_release release;
    manifest = measure_proxies(
        mesh, std::move(manifest), [&](const json&, std::size_t index) { return held[index].geometry; }, options);
  }
  py::list result;
  for (const json& entry : manifest["proxies"]) result.append(to_python(entry["measure"]));
  return result;
}

py::array_t<double> image_array(const Image& image) {
  py::array_t<double> array({static_cast<py::ssize_t>(image.height), static_cast<py::ssize_t>(image.width), py::ssize_t{3}});
  auto out = array.mutable_unchecked<3>();
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      for (int k = 0; k < 3; ++k) out(y, x, k) = image.at(x, y)[k];
  return array;
}

BatchOptions batch_options(const std::optional<std::vector<std::string>>& proxies, std::uint64_t seed, std::size_t rays,
                           std::size_t timed_rays, std::size_t hausdorff_samples, std::size_t gssa_lines) {
  BatchOptions options{.proxies = proxies.value_or(std::vector<std::string>{}), .seed = seed, .rays = rays,
                       .timed_rays = timed_rays, .hausdorff_samples = hausdorff_samples, .gssa_lines = gssa_lines};
  if (!options.proxies.empty()) (void)parse_proxy_specs(options.proxies);
  return options;
}

py::object batch_asset(const std::filesystem::path& mesh, const std::filesystem::path& output,
                       const std::optional<std::vector<std::string>>& proxies, std::uint64_t seed, std::size_t rays,
                       std::size_t timed_rays, std::size_t hausdorff_samples, std::size_t gssa_lines, bool retry_failed) {
  const BatchOptions options = batch_options(proxies, seed, rays, timed_rays, hausdorff_samples, gssa_lines);
  json record;
  {
    py::gil_scoped_release release;
    record = process_asset(mesh, output, options, retry_failed);
  }
  return to_python(record);
}

// render(scene, **options): each keyword is a render option of the one table
// (render_options(), as the CLI's flags without "--" and with "_" for "-"); flags take a
// bool in their positive sense (split=False is --no-split); None leaves the default.
py::dict render_scene_file(const std::filesystem::path& scene_path, const py::kwargs& keywords) {
  RenderJob job;
  job.scene = scene_path;
  for (const auto& [key, value] : keywords) {
    const std::string name = py::cast<std::string>(key);
    if (value.is_none()) continue;
    if (name == "output") {
      job.output = py::cast<std::filesystem::path>(value);
      continue;
    }
    const RenderOption* option = find_render_option(name);
    if (option == nullptr || name.starts_with("--"))
      throw py::type_error("render() got an unexpected keyword argument '" + name + "'");
    if (option->type == RenderOption::Type::flag)
      option->set_flag(job, py::cast<bool>(value));
    else
      option->set(job, py::isinstance<py::str>(value) ? py::cast<std::string>(value) : py::cast<std::string>(py::str(value)));
  }
  RenderedScene rendered;
  {
    py::gil_scoped_release release;
    rendered = visproxy::render_scene(job);
    write_render_outputs(job, rendered);
  }
  const RenderResult& result = rendered.result;
  py::dict out;
  out["image"] = image_array(result.image);
  out["p1_map"] = result.p1_map.pixels.empty() ? py::object(py::none()) : py::object(image_array(result.p1_map));
  out["cut_map"] = result.cut_map.pixels.empty() ? py::object(py::none()) : py::object(image_array(result.cut_map));
  out["cost_map"] = image_array(result.cost_map);
  out["stats"] = to_python(result.stats.to_json());
  out["instances"] = to_python(rendered.document["instances"]);
  out["proxy_notes"] = py::cast(rendered.notes);
  out["scene"] = scene_path.string();
  out["seed"] = job.options.seed;
  return out;
}

// The render keywords for the docstring: name, the values it takes, and its help.
std::string render_keywords_help() {
  std::string text;
  for (const RenderOption& option : render_options()) {
    text += "\n  ";
    text += option.name;
    text += option.type == RenderOption::Type::flag ? " (bool)" : "";
    text += ": " + option.help;
  }
  return text;
}

}  // namespace
}  // namespace visproxy::python

PYBIND11_MODULE(visproxy, m) {
  using namespace visproxy::python;
  using namespace pybind11::literals;
  m.doc() =
      "visproxy: visibility proxies for shadow rays. Meshes are numpy arrays, vertices (V, 3) float64 and triangles "
      "(T, 3) integer; proxies are dicts with name, kind, primitive_type, vertices, triangles, spheres (N, 4: centre, "
      "radius) and manifest (the entry 'visproxy build' writes). Results are the JSON objects the CLI records, as dicts.";
  m.attr("__version__") = visproxy::version();

  // visproxy.Error, and its two kinds as Python's ValueError and OSError too.
  static py::handle error = PyErr_NewException("visproxy.Error", PyExc_Exception, nullptr);
  static py::handle invalid = PyErr_NewException(
      "visproxy.InvalidInputError", py::make_tuple(error, py::handle(PyExc_ValueError)).release().ptr(), nullptr);
  static py::handle file = PyErr_NewException("visproxy.FileError",
                                              py::make_tuple(error, py::handle(PyExc_OSError)).release().ptr(), nullptr);
  m.attr("Error") = error;
  m.attr("InvalidInputError") = invalid;
  m.attr("FileError") = file;
  py::register_exception_translator([](std::exception_ptr thrown) {
    try {
      if (thrown) std::rethrow_exception(thrown);
    } catch (const visproxy::InvalidInputError& e) {
      PyErr_SetString(invalid.ptr(), e.what());
    } catch (const visproxy::IOError& e) {
      PyErr_SetString(file.ptr(), e.what());
    } catch (const visproxy::Error& e) {
      PyErr_SetString(error.ptr(), e.what());
    } catch (const nlohmann::json::exception& e) {
      PyErr_SetString(invalid.ptr(), e.what());
    }
  });

  m.def("read_mesh", &read_mesh_arrays, "path"_a, "weld"_a = "auto",
        "Reads a mesh (OBJ, PLY, OFF, STL, or glTF, FBX, Collada, 3DS, ... through Assimp) as (vertices, triangles): (V, 3) float64 and (T, 3) int64. weld: 'auto' "
        "(merge identical vertices for STL and Assimp's formats only), 'never' or 'always'. Raises InvalidInputError naming the file (and "
        "line) for malformed content, FileError when it cannot be read.");
  m.def("write_mesh", &write_mesh_arrays, "path"_a, "vertices"_a, "triangles"_a,
        "Writes a mesh as binary PLY (double coordinates) or OBJ (shortest round-trip decimals) by the extension, exactly, under a temporary name then renamed.");
  m.def("inspect", &inspect_arrays, "vertices"_a, "triangles"_a, "source"_a = "mesh arrays",
        "The mesh report of 'visproxy info --json' (counts, bounds, topology, orientation, degenerate triangles, "
        "self-intersections, area, volume, watertight) as a dict. `source` names the mesh in errors.");
  m.def("build", &build_arrays, "vertices"_a, "triangles"_a, "specs"_a = py::none(), py::kw_only(), "seed"_a = 1,
        "per_component"_a = false, "hausdorff_samples"_a = 20000, "tets"_a = "normals", "gssa_lines"_a = 100000,
        "output"_a = py::none(), "source"_a = "mesh arrays", "weld"_a = "auto", "builders_at_once"_a = 0,
        "Builds proxies as 'visproxy build' does, from the same specs ('aabb', 'hull:32', 'spheres:100', ...; None: the "
        "default set) and seed: the same arrays, bit for bit. Returns a list of proxy dicts. With `output`, also writes the "
        "proxy folder (PLY/OBJ or sphere-set JSON files and manifest.json) there, recording `source` and `weld` as the "
        "mesh it came from. `builders_at_once` as --builders-at-once (0: the machine's threads up to 2^20 triangles, 1 "
        "above); the proxies do not depend on it.");
  m.def("read_proxies", &read_proxies_folder, "folder"_a,
        "The proxies of a folder 'visproxy build' wrote, as proxy dicts with their manifest entries (verify and measure "
        "results included when recorded). Files that do not hold what the manifest says raise InvalidInputError.");
  m.def("read_manifest", &read_manifest_dict, "folder"_a, "FOLDER/manifest.json, checked, as a dict.");
  m.def("verify", &verify_arrays, "vertices"_a, "triangles"_a, "proxies"_a, py::kw_only(), "hausdorff_samples"_a = 20000,
        "seed"_a = 1, "source"_a = "mesh arrays",
        "Checks each proxy's claim against the mesh exactly, as 'visproxy verify' does: outside proxies must contain the "
        "mesh, inside proxies lie within it; general proxies get a sampled Hausdorff distance. `proxies`: a proxy dict or "
        "a list of them; only kind and geometry are read. Returns one verify dict per proxy: claim, holds, margin, "
        "counterexample, ...");
  m.def("measure", &measure_arrays, "vertices"_a, "triangles"_a, "proxies"_a, py::kw_only(), "rays"_a = 1000000,
        "seed"_a = 1, "scene"_a = py::none(), "timed_rays"_a = 100000, "source"_a = "mesh arrays",
        "Traces every proxy with the same seeded isotropic lines as the mesh (or a scene's shadow segments, `scene`), as "
        "'visproxy measure' does. Returns one measure dict per proxy: counts, f_hit, f_miss, v_avg, gssa_ratio (value, "
        "lower, upper at 95 %), optimal probabilities, variance, cost_ns_per_ray.");
  m.def("report", &write_folder_report, "folder"_a, py::kw_only(), "mesh"_a = py::none(), "pictures"_a = true,
        "picture_size"_a = 192, "budget"_a = 0,
        "Writes the report of a proxy folder as 'visproxy report' does (report.html, report.md, recommendation.json, "
        "f_miss.svg, efficiency.svg and, with `pictures`, pictures/*.png) and returns the recommendation as a dict: for "
        "each use (control_variate, eq8, bounds) the proxy with the best predicted efficiency against the mesh and its "
        "sentence, and every proxy's figures. `mesh`: the mesh the proxies were built from [default: the path the "
        "manifest records]. `budget`: recommend only proxies of at most this many primitives (0: any), as --budget. A "
        "per-mesh folder (build --per-mesh) gets each mesh's report and the asset's table, whose dict is returned.");
  m.def("build_asset", &build_asset_parts, "asset"_a, "output"_a, "specs"_a = py::none(), py::kw_only(), "seed"_a = 1,
        "hausdorff_samples"_a = 20000, "weld"_a = "auto",
        "Builds the proxies of each mesh of a multi-mesh asset once, as 'visproxy build ASSET --per-mesh -o OUTPUT' "
        "does: OUTPUT/MESH/ per mesh and OUTPUT/asset.json, which is returned as a dict. verify, measure (the CLI), "
        "report and export take the folder whole.");
  m.def("export", &export_folder, "folder"_a, "output"_a, py::kw_only(), "proxies"_a = py::none(), "mesh"_a = py::none(),
        "Writes the proxies of a folder (or of a per-mesh folder) into `output` as 'visproxy export' does: .glb or .gltf "
        "(the source asset with each proxy on a node of its own, extras.visproxy holding its claim), .obj or .ply (one "
        "proxy); float32 positions with every outside or inside claim proved again on them. Returns one dict per "
        "proxy: name, part, node, claimed and kept kind, moved (mesh units), triangles, note (why a claim was dropped). "
        "`proxies`: names to export [default: all]; `mesh`: the asset [default: the path the folder records].");
  m.def("float_proxy", &float_proxy_arrays, "vertices"_a, "triangles"_a, "proxy"_a, py::kw_only(), "source"_a = "mesh arrays",
        "The proxy in float32, as a renderer or DCC tool stores it, with its claim proved again on the rounded "
        "coordinates (as 'visproxy export' writes it): a dict with vertices (V, 3) float32, triangles (T, 3) int64, "
        "claimed and kind (the kind kept: the claimed one when proved, else 'general'), moved (how far the vertices "
        "were moved outward or inward before rounding, mesh units), verify (the verdict) and note (why a claim was "
        "dropped). Sphere proxies become icospheres inside their spheres.");
  m.def("shadow_stage", &shadow_stage_arrays, "vertices"_a, "triangles"_a, "proxy"_a = py::none(), py::kw_only(),
        "size"_a = 192, "source"_a = "mesh arrays",
        "The stage of the report's shadow pictures for this mesh (+y up): the ground plane's height, the pictured "
        "square (ground_x0, ground_z0, ground_side; pixel (x, y) is centred at x0 + (x + 0.5) side / size, z0 + "
        "(y + 0.5) side / size), the square area light (light_corner, light_u, light_v; it faces -y) and "
        "light_samples_per_side. With a proxy: missed_shadow and extra_shadow, the fractions of the mesh's shadow "
        "the proxy misses and adds there (a proxy whose claim verifies is padded as the renderer pads it).");
  m.def("disable_transparent_huge_pages", &visproxy::disable_transparent_huge_pages,
        "Turns transparent huge pages off for this process and those it starts, as the visproxy command does (unless "
        "the environment variable VISPROXY_TRANSPARENT_HUGE_PAGES is 1); returns whether they are now off. Embree "
        "marks its BVH builders' memory as huge-page candidates, and where the kernel or a virtual machine's host must "
        "first assemble 2 MiB pages, a fresh process pays seconds for them (on the machine visproxy is measured on, 4.4 "
        "s against 0.8 s for the BVH of a 4.8 M-triangle mesh). The module does not call it on import.");
  m.def("batch_assets", &visproxy::read_asset_list, "list"_a,
        "The meshes of a batch list, as 'visproxy batch' reads it: a text file of paths (relative to the file; blank "
        "lines and # comments skipped) or a folder searched recursively for mesh files, sorted.");
  m.def("batch_shard", &visproxy::shard_assets, "assets"_a, "index"_a, "count"_a,
        "Shard `index` of `count` of an asset list: the assets at positions index, index + count, ...");
  m.def("batch_asset", &batch_asset, "mesh"_a, "output"_a, py::kw_only(), "proxies"_a = py::none(), "seed"_a = 1,
        "rays"_a = 200000, "timed_rays"_a = 50000, "hausdorff_samples"_a = 20000, "gssa_lines"_a = 100000,
        "retry_failed"_a = false,
        "Processes one asset of a batch into the batch folder `output` as 'visproxy batch' does (build, verify, measure, "
        "report into OUTPUT/STEM-KEY, renamed into place when complete; a complete folder is not processed again; an "
        "error is recorded in OUTPUT/STEM-KEY.failed.json, not raised). Returns the asset's record: asset, folder, "
        "status ('ok', 'claims_failed', 'failed'), error, proxies, claims_holding, triangles, seconds, resumed.");
  m.def("batch_merge", [](const std::filesystem::path& folder) { return to_python(visproxy::batch_merge(folder)); }, "folder"_a,
        "Writes FOLDER/summary.json, summary.csv and summary.html from every asset record in the batch folder (all "
        "shards) and returns the summary as a dict: counts, records, one row per asset and proxy, timed_fields.");
  static const std::string render_help =
      "render(scene, **options): renders a scene file as 'visproxy render' does. Each keyword is an option of that "
      "command, named as its flag without '--' and with '_' for '-' (values such as 'control-variate' keep their '-'); "
      "flags take a bool in their positive sense (split=False is --no-split); None leaves an option at its default. With "
      "output (.pfm or .exr) the image, its PNG and OUT.stats.json are written there as the CLI writes them. Returns a "
      "dict: image (H, W, 3) float64 linear radiance, p1_map, cut_map (lightcuts: mean clusters per cut), cost_map, stats, "
      "instances, proxy_notes, scene, seed. Options:" + render_keywords_help();
  m.def("render", &render_scene_file, "scene"_a, render_help.c_str());

  // A call whose arguments match no signature raises pybind11's TypeError, which prints
  // every argument in full: 190 KB for a list of 3000 vertices. Every function of the module
  // raises it with the arguments' types instead.
  py::exec(R"py(
def _shorten_type_errors(module):
    import functools
    def shortened(function):
        @functools.wraps(function)
        def call(*args, **kwargs):
            try:
                return function(*args, **kwargs)
            except TypeError as error:
                text = str(error)
                if "incompatible function arguments" not in text or "Invoked with" not in text:
                    raise
                given = [type(a).__name__ for a in args] + [k + "=" + type(v).__name__ for k, v in kwargs.items()]
                raise TypeError(text.split("Invoked with")[0].rstrip() + "\nInvoked with types: (" + ", ".join(given) + ")") from None
        return call
    for name in dir(module):
        value = getattr(module, name)
        if not name.startswith("_") and type(value).__name__ == "builtin_function_or_method":
            setattr(module, name, shortened(value))
)py",
           m.attr("__dict__"));
  m.attr("_shorten_type_errors")(m);
  py::delattr(m, "_shorten_type_errors");
}
