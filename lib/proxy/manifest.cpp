#include "visproxy/proxy/manifest.h"

#include <system_error>

#include "visproxy/core/errors.h"
#include "visproxy/core/files.h"
#include "visproxy/mesh/sphere_set.h"
#include "visproxy/mesh/write_mesh.h"

namespace visproxy {
namespace {

using nlohmann::json;

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

json write_proxy_folder(const std::filesystem::path& folder, const ManifestMesh& mesh,
                        std::span<const BuiltProxy> proxies, const BuildOptions& options) {
  std::error_code error;
  std::filesystem::create_directories(folder, error);
  if (error) throw IOError(folder, "cannot create the output folder: " + error.message());

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
      {"generator", std::string("visproxy ") + VISPROXY_VERSION},
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
        {"tets", inner_tetrahedra_name(options.tets)},
        {"gssa_lines", options.gssa_lines},
        {"builders_at_once", builders_at_once(options.builders_at_once, mesh.triangles)},
        {"seed", options.seed}}},
      {"proxies", entries}};
  write_file_atomically(folder / "manifest.json", manifest.dump(2) + "\n");
  return manifest;
}

}  // namespace visproxy
