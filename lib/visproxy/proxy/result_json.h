#pragma once
// How builders' results are written into a manifest entry: points, oriented boxes and
// intervals as JSON (data/schemas/manifest.schema.json). For build_proxies and the method
// table, not part of the library's interface.

#include <cmath>
#include <nlohmann/json.hpp>

#include "visproxy/mesh/triangle_mesh.h"
#include "visproxy/proxy/bounding_boxes.h"

namespace visproxy::detail {

/// [x, y, z]
inline nlohmann::json to_json(const Vertex& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); }

/// {center, axes (three unit columns), half_extents}
inline nlohmann::json box_json(const OrientedBox& box) {
  nlohmann::json axes = nlohmann::json::array();
  for (int k = 0; k < 3; ++k) axes.push_back(to_json(box.axes.col(k)));
  return {{"center", to_json(box.center)}, {"axes", axes}, {"half_extents", to_json(box.half_extents)}};
}

/// {value, lower, upper}; an unbounded upper end is null (schema: $defs/interval).
inline nlohmann::json interval_json(double value, double lower, double upper) {
  return {{"value", value}, {"lower", lower}, {"upper", std::isfinite(upper) ? nlohmann::json(upper) : nlohmann::json(nullptr)}};
}

}  // namespace visproxy::detail
