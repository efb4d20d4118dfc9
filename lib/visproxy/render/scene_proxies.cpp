#include "visproxy/render/scene_proxies.h"

#include <cstdlib>
#include <cstring>
#include <map>

#include "visproxy/core/errors.h"
#include "visproxy/folder/proxy_folder.h"
#include "visproxy/folder/verdict.h"
#include "visproxy/proxy/build_proxies.h"
#include "visproxy/folder/proxy_folder.h"

namespace visproxy {
namespace {

// The proxy's kind is kept only when verify proves its claim for this mesh and these
// files: a verdict recorded for them is used, otherwise the proxy is verified now (and, in
// the cache, the verdict recorded).
InstanceProxy prove(const SceneMesh& mesh, const std::filesystem::path& folder, nlohmann::json& manifest,
                    nlohmann::json& entry, const ProxySpec& spec, bool record, const SceneProxyOptions& options) {
  ProxyGeometry geometry = read_proxy_geometry(folder, entry);
  const ProxyKind kind = entry_kind(entry);
  bool proved = false;
  if (kind != ProxyKind::general) {
    if (entry.contains("verify") && verdict_proves(entry["verify"], entry, mesh.mesh, geometry)) {
      proved = true;
    } else {
      nlohmann::json verdict = verify_proxy(mesh.mesh, manifest, entry, geometry);
      proved = verdict_proves(verdict, entry, mesh.mesh, geometry);
      if (options.on_verify) {
        const nlohmann::json& counterexample = verdict["counterexample"];
        options.on_verify(mesh.name, spec.text, proved, counterexample.is_string() ? counterexample.get<std::string>() : "");
      }
      if (record) {
        entry["verify"] = std::move(verdict);
        write_manifest(folder, manifest);
      }
    }
  }
  return {kind, spec.text, std::move(geometry.mesh), std::move(geometry.spheres), proved};
}

InstanceProxy load_or_build(const SceneMesh& mesh, const ProxySpec& spec, const SceneProxyOptions& options) {
  // A proxy folder the scene names comes first; its verdicts are checked, never written.
  if (!mesh.proxy_folder.empty()) {
    nlohmann::json manifest = read_manifest(mesh.proxy_folder);
    for (nlohmann::json& entry : manifest.at("proxies"))
      if (entry.at("name") == spec.name()) {
        if (options.on_proxy) options.on_proxy(mesh.name, spec.text, true);
        return prove(mesh, mesh.proxy_folder, manifest, entry, spec, false, options);
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
    manifest = build_proxy_folder(folder, mesh.mesh, source, Weld::automatic, specs, build).manifest;
  }
  for (nlohmann::json& entry : manifest.at("proxies"))
    if (entry.at("name") == spec.name()) return prove(mesh, folder, manifest, entry, spec, true, options);
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
