#include "evaluate/measure_proxies.h"

#include <chrono>

#include "evaluate/proxy_folder.h"
#include "measure/random_lines.h"

namespace visproxy {
namespace {

using nlohmann::json;

json interval(const Proportion& p) { return {{"value", p.fraction()}, {"lower", p.lower()}, {"upper", p.upper()}}; }

}  // namespace

json ray_set_json(const TriangleMesh& mesh, const MeasureOptions& options) {
  const Sphere sphere = bounding_sphere(mesh);
  return {{"kind", "isotropic lines"},
          {"description", "chords between two independent uniform points on the mesh's bounding sphere"},
          {"count", options.rays},
          {"seed", options.seed},
          {"sphere", {{"center", {sphere.center.x(), sphere.center.y(), sphere.center.z()}}, {"radius", sphere.radius}}},
          {"timed_rays", std::min(options.rays, options.timing.rays)}};
}

json measurement_json(const ProxyMeasurement& m) {
  const double ratio = m.mesh_ns_per_ray > 0 ? m.proxy_ns_per_ray / m.mesh_ns_per_ray : 0.0;
  const bool bounded = std::isfinite(m.gssa_ratio_upper);
  return {{"counts", m.counts.counts},
          {"f_hit", interval(m.f_hit)},
          {"f_miss", interval(m.f_miss)},
          {"v_avg", interval(m.v_avg)},
          {"gssa_ratio",
           {{"value", m.gssa_ratio}, {"lower", m.gssa_ratio_lower}, {"upper", bounded ? json(m.gssa_ratio_upper) : json(nullptr)}}},
          {"probabilities",
           {{"form", kind_name(m.probability_form)}, {"p1", m.optimal.p1}, {"p2", m.optimal.p2}, {"p3", m.optimal.p3}}},
          {"variance", {{"optimal", m.variance_optimal}, {"equal", m.variance_equal}}},
          {"rays_contradicting_claim", m.rays_contradicting_claim},
          {"cost_ns_per_ray",
           {{"proxy", m.proxy_ns_per_ray},
            {"mesh", m.mesh_ns_per_ray},
            {"estimator", m.estimator_ns_per_ray},
            {"proxy_over_mesh", ratio}}}};
}

json measure_proxies(const TriangleMesh& mesh, const std::filesystem::path& folder, json manifest,
                     const MeasureOptions& options) {
  const RayScene mesh_scene(mesh);
  const ReferenceRays reference =
      trace_reference(mesh_scene, isotropic_lines(bounding_sphere(mesh), options.rays, options.seed), options.timing);
  const json rays = ray_set_json(mesh, options);
  for (json& entry : manifest.at("proxies")) {
    if (options.on_start) options.on_start(entry.at("name").get<std::string>());
    const auto start = std::chrono::steady_clock::now();
    const ProxyGeometry geometry = read_proxy_geometry(folder, entry);
    const RayScene proxy_scene = geometry.type == PrimitiveType::sphere ? RayScene(geometry.spheres) : RayScene(geometry.mesh);
    json measured = measurement_json(measure_proxy(reference, proxy_scene, entry_kind(entry), options.timing));
    measured["rays"] = rays;
    measured["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    entry["measure"] = std::move(measured);
  }
  return manifest;
}

}  // namespace visproxy
