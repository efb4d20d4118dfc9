#include "visproxy/evaluate/proxy_flags.h"

#include <cmath>
#include <cstdio>
#include <optional>

#include "visproxy/evaluate/measure_proxies.h"

namespace visproxy {
namespace {

using nlohmann::json;

std::optional<double> number_at(const json& object, std::initializer_list<const char*> path) {
  const json* at = &object;
  for (const char* key : path) {
    if (!at->is_object() || !at->contains(key)) return std::nullopt;
    at = &(*at)[key];
  }
  if (!at->is_number()) return std::nullopt;
  return at->get<double>();
}

std::string text(const char* pattern, auto... values) {
  char buffer[400];
  std::snprintf(buffer, sizeof buffer, pattern, values...);
  return buffer;
}

// What the dominance test reads of a measured entry.
struct Figures {
  std::string name, type, kind;
  double primitives = 0, f_hit = 0, f_miss = 0, cost_low = 0, cost_high = 0;
  bool proved = false;
};

// "triangles", "boxes", "spheres".
std::string plural(const std::string& type) { return type == "box" ? "boxes" : type + "s"; }

std::optional<Figures> figures_of(const json& entry) {
  const auto primitives = number_at(entry, {"primitives"});
  const auto f_hit = number_at(entry, {"measure", "f_hit", "value"});
  const auto f_miss = number_at(entry, {"measure", "f_miss", "value"});
  const auto cost = number_at(entry, {"measure", "cost_ns_per_ray", "proxy_over_mesh"});
  if (!primitives || !f_hit || !f_miss || !cost) return std::nullopt;
  Figures f{entry.value("name", std::string("?")), entry.value("primitive_type", std::string()), entry.value("kind", std::string()),
            *primitives, *f_hit, *f_miss, *cost, *cost, false};
  if (const auto interval = cost_ratio_interval(entry["measure"])) f.cost_low = (*interval)[0], f.cost_high = (*interval)[1];
  f.proved = f.kind != "general" && entry.contains("verify") && entry["verify"].is_object() && entry["verify"].value("holds", false);
  return f;
}

bool beats(const Figures& a, const Figures& b) {
  if (a.type != b.type || a.primitives > b.primitives || a.f_hit < b.f_hit || a.f_miss < b.f_miss) return false;
  if (a.cost_low > b.cost_high) return false;                  // measurably dearer
  if (b.proved && !(a.proved && a.kind == b.kind)) return false;  // b's proved claim is worth keeping
  return a.primitives < b.primitives || a.f_hit > b.f_hit || a.f_miss > b.f_miss;
}

}  // namespace

std::vector<ProxyFlag> proxy_flags(const json& manifest) {
  std::vector<ProxyFlag> flags;
  const double mesh_triangles = manifest.at("mesh").value("triangles", 0.0);
  std::vector<std::optional<Figures>> measured;
  for (const json& entry : manifest.at("proxies")) measured.push_back(figures_of(entry));
  std::size_t index = 0;
  for (const json& entry : manifest.at("proxies")) {
    const std::string name = entry.value("name", std::string("?"));
    const std::string type = entry.value("primitive_type", std::string());
    const double primitives = entry.value("primitives", 0.0);
    if (const std::optional<Figures>& mine = measured[index]) {
      for (std::size_t other = 0; other < measured.size(); ++other) {
        if (other == index || !measured[other] || !beats(*measured[other], *mine)) continue;
        const Figures& by = *measured[other];
        flags.push_back({name, "beaten",
                         text("%s is beaten by %s on every measure: %.0f against %.0f %s, f_hit %.4f against %.4f, f_miss "
                              "%.4f against %.4f, cost ratio %.3f against %.3f; ship %s instead.",
                              name.c_str(), by.name.c_str(), by.primitives, mine->primitives, plural(type).c_str(), by.f_hit,
                              mine->f_hit, by.f_miss, mine->f_miss, 0.5 * (by.cost_low + by.cost_high),
                              0.5 * (mine->cost_low + mine->cost_high), by.name.c_str())});
        break;
      }
    }
    if (const json* result = entry.contains("result") ? &entry["result"] : nullptr; result && result->is_object()) {
      if (result->contains("reached_target") && (*result)["reached_target"] == false) {
        flags.push_back({name, "missed_target",
                         text("%s missed its target count: its builder stopped at %.0f %s (reached_target: false).",
                              name.c_str(), primitives, plural(type).c_str())});
      } else if (result->contains("components") && (*result)["components"].is_array()) {
        std::size_t missed = 0, components = 0;
        for (const json& component : (*result)["components"]) {
          ++components;
          missed += component.is_object() && component.contains("reached_target") && component["reached_target"] == false;
        }
        if (missed > 0)
          flags.push_back({name, "missed_target",
                           text("%s missed its target count on %zu of %zu components (reached_target: false).", name.c_str(),
                                missed, components)});
      }
      if (const auto outside = number_at(*result, {"balls_centred_outside_mesh_box"}); outside && *outside > 0)
        flags.push_back({name, "balls_outside_mesh_box",
                         text("%s has %.0f of its %.0f balls centred outside the mesh's bounding box, where they shadow "
                              "what the mesh does not.",
                              name.c_str(), *outside, primitives)});
    }
    if (type == "triangle" && mesh_triangles > 0 && primitives > mesh_triangles)
      flags.push_back({name, "larger_than_mesh",
                       text("%s has %.0f triangles, more than the mesh's %.0f: trace the mesh instead.", name.c_str(),
                            primitives, mesh_triangles)});
    ++index;
  }
  return flags;
}

json flags_json(const std::vector<ProxyFlag>& flags) {
  json array = json::array();
  for (const ProxyFlag& f : flags) array.push_back({{"proxy", f.proxy}, {"flag", f.flag}, {"text", f.text}});
  return array;
}

}  // namespace visproxy
