#pragma once
// What to look at before shipping a proxy of a folder: a proxy another one beats on every
// measure, one that missed its builder's target count, one with more triangles than the
// mesh, a sphere set with balls centred outside the mesh's bounding box. Read from the
// manifest alone (build results and measures), so `report` and `build` say the same.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace visproxy {

struct ProxyFlag {
  std::string proxy;  ///< the entry's name
  /// "beaten", "missed_target", "larger_than_mesh" or "balls_outside_mesh_box"
  std::string flag;
  std::string text;  ///< one sentence naming the proxy and the figures
};

/// The flags of every entry, in manifest order:
///  - beaten: another measured proxy of the same primitive type and no more primitives has
///    f_hit and f_miss at least as high, is not measurably dearer (its cost ratio's block
///    range starts at or below this one's end), keeps any claim this one has proved, and is
///    strictly better in one of primitives, f_hit and f_miss;
///  - missed_target: the builder reports reached_target false, for the proxy or for some
///    of its components (per-component builds);
///  - larger_than_mesh: a triangle proxy with more triangles than the mesh;
///  - balls_outside_mesh_box: a sphere set with balls centred outside the mesh's bounding box.
std::vector<ProxyFlag> proxy_flags(const nlohmann::json& manifest);

/// [{proxy, flag, text}], as recommendation.json's `flags`.
nlohmann::json flags_json(const std::vector<ProxyFlag>& flags);

}  // namespace visproxy
