#include "evaluate/scene_proxies.h"

#include <cstdlib>
#include <cstring>
#include <map>

#include "core/errors.h"
#include "evaluate/proxy_folder.h"
#include "mesh/mesh_topology.h"
#include "proxy/build_proxies.h"
#include "proxy/manifest.h"

namespace visproxy {
namespace {

// FNV-1a over the mesh's coordinates and indices: the cache key of a mesh's content.
std::string content_hash(const TriangleMesh& mesh) {
  std::uint64_t hash = 0xCBF29CE484222325ull;
  auto mix = [&](const void* data, std::size_t size) {
    const auto* bytes = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < size; ++i) hash = (hash ^ bytes[i]) * 0x100000001B3ull;
  };
  for (const Vertex& p : mesh.positions) mix(p.data(), 3 * sizeof(double));
  for (const Triangle& t : mesh.triangles) mix(t.data(), sizeof(Triangle));
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(hash));
  return text;
}

InstanceProxy load_or_build(const SceneMesh& mesh, const ProxySpec& spec, const SceneProxyOptions& options) {
  // A proxy folder the scene names comes first.
  if (!mesh.proxy_folder.empty()) {
    const nlohmann::json manifest = read_manifest(mesh.proxy_folder);
    for (const nlohmann::json& entry : manifest.at("proxies"))
      if (entry.at("name") == spec.name()) {
        if (options.on_proxy) options.on_proxy(mesh.name, spec.text, true);
        const ProxyGeometry geometry = read_proxy_geometry(mesh.proxy_folder, entry);
        return {entry_kind(entry), spec.text, geometry.mesh, geometry.spheres};
      }
  }
  const std::filesystem::path folder =
      options.cache / (mesh.name + "-" + content_hash(mesh.mesh)) / spec.name();
  const bool cached = std::filesystem::exists(folder / "manifest.json");
  if (options.on_proxy) options.on_proxy(mesh.name, spec.text, cached);
  nlohmann::json manifest;
  if (cached) {
    manifest = read_manifest(folder);
  } else {
    const std::filesystem::path source = mesh.file.empty() ? std::filesystem::path(mesh.name) : mesh.file;
    const std::vector<ProxySpec> specs{spec};
    const BuildOptions build{.per_component = false, .hausdorff_samples = 2000, .seed = options.seed, .on_start = {}};
    const std::vector<BuiltProxy> built = build_proxies(mesh.mesh, source, specs, build);
    const ManifestMesh described{.path = source,
                                 .weld = "auto",
                                 .vertices = mesh.mesh.positions.size(),
                                 .triangles = mesh.mesh.triangles.size(),
                                 .components = analyze_topology(mesh.mesh).components,
                                 .bounds = bounding_box(mesh.mesh)};
    manifest = write_proxy_folder(folder, described, built, build);
  }
  for (const nlohmann::json& entry : manifest.at("proxies")) {
    if (entry.at("name") != spec.name()) continue;
    const ProxyGeometry geometry = read_proxy_geometry(folder, entry);
    return {entry_kind(entry), spec.text, geometry.mesh, geometry.spheres};
  }
  throw InvalidInputError(folder / "manifest.json", "does not list the proxy " + spec.name());
}

}  // namespace

std::filesystem::path default_proxy_cache() {
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return std::filesystem::path(xdg) / "visproxy";
  if (const char* home = std::getenv("HOME"); home && *home) return std::filesystem::path(home) / ".cache" / "visproxy";
  return std::filesystem::temp_directory_path() / "visproxy-cache";
}

std::vector<MeshProxies> prepare_scene_proxies(const Scene& scene, const SceneProxyOptions& options) {
  std::map<std::string, InstanceProxy> loaded;  // "mesh\nspec"
  auto proxy = [&](const std::string& mesh_name, const std::string& text) -> const InstanceProxy& {
    const std::string key = mesh_name + "\n" + text;
    if (auto it = loaded.find(key); it != loaded.end()) return it->second;
    ProxySpec spec;
    try {
      spec = parse_proxy_spec(text);
    } catch (const Error& error) {
      throw InvalidInputError(scene.file, std::string("mesh \"") + mesh_name + "\": " + error.what());
    }
    return loaded.emplace(key, load_or_build(scene.mesh(mesh_name), spec, options)).first->second;
  };
  std::vector<MeshProxies> result(scene.instances.size());
  for (std::size_t i = 0; i < scene.instances.size(); ++i) {
    const SceneInstance& instance = scene.instances[i];
    if (instance.proxies.empty()) continue;
    const std::string stochastic = options.stochastic_spec.value_or(instance.proxies.front());
    result[i].stochastic = proxy(instance.mesh, stochastic);
    for (const std::string& text : instance.proxies) {
      const InstanceProxy& p = proxy(instance.mesh, text);
      if (p.kind == ProxyKind::outside && !result[i].outside) result[i].outside = p;
      if (p.kind == ProxyKind::inside && !result[i].inside) result[i].inside = p;
    }
  }
  return result;
}

}  // namespace visproxy
