#include "visproxy/render/options/render_stats.h"

#include <algorithm>

namespace visproxy {

RenderStats& RenderStats::operator+=(const RenderStats& o) {
  camera_samples += o.camera_samples, shading_points += o.shading_points, shadow_rays += o.shadow_rays;
  vpl_connections += o.vpl_connections, exact_tests += o.exact_tests, proxy_tests += o.proxy_tests,
      probe_rays += o.probe_rays;
  for (int i = 0; i < 3; ++i) eq8.terms[i] += o.eq8.terms[i];
  eq8.traced_exactly += o.eq8.traced_exactly;
  control_variate.after_miss += o.control_variate.after_miss, control_variate.after_hit += o.control_variate.after_hit;
  control_variate.traced_exactly += o.control_variate.traced_exactly, control_variate.explored += o.control_variate.explored;
  bounds.unoccluded += o.bounds.unoccluded, bounds.occluded += o.bounds.occluded, bounds.traced += o.bounds.traced;
  bounds.shafts_culled += o.bounds.shafts_culled;
  disks.tests += o.disks.tests, disks.clusters += o.disks.clusters;
  traversal_steps += o.traversal_steps, primitive_tests += o.primitive_tests;
  return *this;
}

nlohmann::json RenderStats::to_json() const {
  const double rays = static_cast<double>(std::max<std::uint64_t>(shadow_rays, 1));
  return {{"seconds", seconds},
          {"passes", passes},
          {"camera_samples", camera_samples},
          {"shading_points", shading_points},
          {"shadow_rays", shadow_rays},
          {"exact_tests", exact_tests},
          {"proxy_tests", proxy_tests},
          {"probe_rays", probe_rays},
          {"exact_tests_per_shadow_ray", static_cast<double>(exact_tests) / rays},
          {"proxy_tests_per_shadow_ray", static_cast<double>(proxy_tests) / rays},
          {"optimal_probabilities", optimal_probabilities},
          {"learned_costs", learned_costs},
          {"disk_gate", disk_gate},
          {"eq8_gate", eq8_gate},
          {"stochastic_terms",
           {{"a_proxy_only", eq8.terms[0]},
            {"b_mesh_if_proxy_hit", eq8.terms[1]},
            {"c_mesh_if_proxy_missed", eq8.terms[2]},
            {"traced_exactly", eq8.traced_exactly}}},
          {"control_variate_corrections",
           {{"after_proxy_missed", control_variate.after_miss},
            {"after_proxy_hit", control_variate.after_hit},
            {"traced_exactly", control_variate.traced_exactly},
            {"explored", control_variate.explored}}},
          {"bounds",
           {{"unoccluded_by_outside_proxies", bounds.unoccluded},
            {"occluded_by_inside_proxies", bounds.occluded},
            {"traced_exactly", bounds.traced},
            {"shading_points_with_culled_shaft", bounds.shafts_culled}}},
          {"vpl_connections", vpl_connections},
          {"disk_tests", disks.tests},
          {"disk_clusters", disks.clusters},
          {"integrator", integrator.is_null() ? nlohmann::json::object() : integrator},
          {"counted", counted},
          {"traversal_steps", counted ? nlohmann::json(traversal_steps) : nlohmann::json(nullptr)},
          {"primitive_tests", counted ? nlohmann::json(primitive_tests) : nlohmann::json(nullptr)},
          {"traversal_steps_per_shadow_ray",
           counted ? nlohmann::json(static_cast<double>(traversal_steps) / rays) : nlohmann::json(nullptr)},
          {"primitive_tests_per_shadow_ray",
           counted ? nlohmann::json(static_cast<double>(primitive_tests) / rays) : nlohmann::json(nullptr)}};
}

}  // namespace visproxy
