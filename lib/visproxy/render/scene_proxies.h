#pragma once
// The proxies a scene's instances name, built once and cached on disk for every render.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "visproxy/render/world/render_world.h"
#include "visproxy/scene/scene.h"

namespace visproxy {

struct SceneProxyOptions {
  std::filesystem::path cache;  ///< proxy folders live in CACHE/MESHNAME-HASH/SPECNAME/
  /// The proxy `--visibility stochastic` uses for every instance that names proxies;
  /// empty: each instance's first.
  std::optional<std::string> stochastic_spec;
  std::uint64_t seed = 1;  ///< seeds the builders (as `visproxy build --seed`)
  /// Called for each proxy before it is read from the cache (cached) or built.
  std::function<void(std::string_view mesh, std::string_view spec, bool cached)> on_proxy = nullptr;
  /// Called when an outside or inside proxy had no verdict for these files and was verified
  /// now: whether its claim holds, and the counterexample when it does not.
  std::function<void(std::string_view mesh, std::string_view spec, bool holds, std::string_view counterexample)> on_verify =
      nullptr;
};

/// $XDG_CACHE_HOME/visproxy, else $HOME/.cache/visproxy, else a folder in the system's
/// temporary directory.
std::filesystem::path default_proxy_cache();

/// For each instance: its stochastic proxy (see SceneProxyOptions), and for bounds the
/// first outside and the first inside proxy it names. Missing proxies are built with
/// `visproxy build`'s builders into the cache (one proxy folder per mesh content and
/// spec, with its manifest); present ones are read back. An outside or inside proxy keeps
/// its kind (InstanceProxy::proved) only when `visproxy verify`'s check holds for the scene's
/// mesh and the proxy's files as they are now: a verdict recorded for those files (their
/// content hashes) is used, otherwise the proxy is verified on first use and, in the cache,
/// the verdict recorded; a mesh's `proxy_folder` is never written to. Throws
/// InvalidInputError for a bad spec (naming the scene) or a mesh a builder cannot handle.
std::vector<MeshProxies> prepare_scene_proxies(const Scene& scene, const SceneProxyOptions& options);

}  // namespace visproxy
