#include "visproxy/evaluate/measure_proxies.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <span>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/folder/proxy_folder.h"
#include "visproxy/measure/random_lines.h"
#include "visproxy/render/renderer.h"

namespace visproxy {
namespace {

using nlohmann::json;

json interval(const Proportion& p) { return {{"value", p.fraction()}, {"lower", p.lower()}, {"upper", p.upper()}}; }

// Isotropic lines are lines. They are drawn as chords of the mesh's bounding sphere, but
// a proxy may reach beyond that sphere (a coarse outer hull, a box's corners), and a chord
// that starts inside the proxy's solid need not cross its surface. Such a proxy is traced
// on the same lines' chords of a concentric sphere of radius `radius` that holds it; the
// mesh, within the first sphere, meets the longer chords where it met the first ones.
std::vector<Segment> lengthen_chords(std::span<const Segment> chords, const Vertex& center, double radius) {
  std::vector<Segment> lines(chords.size());
  for (std::size_t i = 0; i < chords.size(); ++i) {
    const Vertex d = chords[i].to - chords[i].from, m = chords[i].from - center;
    const double a = d.squaredNorm(), b = d.dot(m), c = m.squaredNorm() - radius * radius;
    if (!(a > 0)) {
      lines[i] = chords[i];
      continue;
    }
    const double root = std::sqrt(std::max(0.0, b * b - a * c));
    const double t0 = std::min(0.0, (-b - root) / a), t1 = std::max(1.0, (-b + root) / a);
    lines[i] = {chords[i].from + t0 * d, chords[i].from + t1 * d};
  }
  return lines;
}

// The radius of a sphere about `center` that holds `geometry`, with a margin of 2^-20 of
// it for the rounding of the chords' ends.
double reach(const ProxyGeometry& geometry, const Vertex& center) {
  double r = 0;
  for (const Sphere& s : geometry.spheres) r = std::max(r, (s.center - center).norm() + s.radius);
  for (const Vertex& p : geometry.mesh.positions) r = std::max(r, (p - center).norm());
  return r * (1 + std::ldexp(1.0, -20));
}

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
            {"proxy_over_mesh", m.cost_ratio},
            {"proxy_over_mesh_range", {m.cost_ratio_low, m.cost_ratio_high}},
            {"timing_blocks", m.timing_blocks}}}};
}

json measure_proxies(const TriangleMesh& mesh, const std::filesystem::path& folder, json manifest,
                     const MeasureOptions& options) {
  return measure_proxies(
      mesh, std::move(manifest), [&](const json& entry, std::size_t) { return read_proxy_geometry(folder, entry); }, options);
}

json measure_proxies(const TriangleMesh& mesh, json manifest, const ProxyGeometryReader& read, const MeasureOptions& options) {
  // The mesh's instances in the scene (none: isotropic lines in the mesh's own frame).
  std::vector<Eigen::Affine3d> placements;
  std::vector<Segment> segments;
  json rays;
  const Sphere line_sphere = bounding_sphere(mesh);
  if (options.scene.empty()) {
    segments = isotropic_lines(line_sphere, options.rays, options.seed);
    rays = ray_set_json(mesh, options);
    placements.push_back(Eigen::Affine3d::Identity());
  } else {
    const Scene scene = load_scene(options.scene, options.on_warning);
    std::vector<bool> exclude(scene.instances.size(), false);
    for (std::size_t i = 0; i < scene.instances.size(); ++i)
      if (scene.mesh(scene.instances[i].mesh).mesh == mesh) {
        exclude[i] = true;
        placements.push_back(scene.instances[i].transform);
      }
    if (placements.empty()) throw InvalidInputError(options.scene, "no instance of the scene uses the measured mesh");
    const RenderWorld world(scene, std::vector<MeshProxies>(scene.instances.size()));
    for (const ShadowSegment& s : scene_shadow_segments(scene, world, options.rays, options.seed, exclude))
      segments.push_back({s.from, s.to});
    if (segments.empty()) throw InvalidInputError(options.scene, "the camera sees no lit surface to measure from");
    rays = {{"kind", "scene shadow segments"},
            {"description", "from points the camera sees on other instances to area-uniform points on the lights"},
            {"scene", options.scene.string()},
            {"count", segments.size()},
            {"seed", options.seed},
            {"instances_of_mesh", placements.size()},
            {"timed_rays", std::min(segments.size(), options.timing.rays)}};
  }
  auto place_mesh = [&](const TriangleMesh& object) {
    TriangleMesh placed;
    for (const Eigen::Affine3d& t : placements) append_mesh(placed, transformed_mesh(object, t));
    return placed;
  };
  auto place_spheres = [&](const std::vector<Sphere>& object) {
    std::vector<Sphere> placed;
    for (const Eigen::Affine3d& t : placements) {
      const std::optional<std::vector<Sphere>> balls = transformed_spheres(object, t);
      if (!balls) throw InvalidInputError(options.scene, "sphere proxies need instances placed without shear or uneven scale");
      placed.insert(placed.end(), balls->begin(), balls->end());
    }
    return placed;
  };
  const TriangleMesh placed_mesh = placements.size() == 1 && options.scene.empty() ? mesh : place_mesh(mesh);
  // Mesh and proxies are traced relative to the placed mesh's centre: float rounding then
  // follows its extent, not its distance from the origin.
  const BoundingBox placed_box = bounding_box(placed_mesh);
  const Vertex center = placed_box.empty() ? Vertex::Zero() : Vertex(0.5 * (placed_box.min + placed_box.max));
  const RayScene mesh_scene(placed_mesh, center);
  const ReferenceRays reference = trace_reference(mesh_scene, std::move(segments), options.timing);
  std::size_t index = 0;
  for (json& entry : manifest.at("proxies")) {
    if (options.on_start) options.on_start(entry.at("name").get<std::string>());
    const auto start = std::chrono::steady_clock::now();
    const ProxyGeometry geometry = read(entry, index++);
    const RayScene proxy_scene = geometry.type == PrimitiveType::sphere ? RayScene(place_spheres(geometry.spheres), center)
                                                                        : RayScene(place_mesh(geometry.mesh), center);
    json proxy_rays = rays;
    ProxyMeasurement measurement;
    if (const double radius = options.scene.empty() ? reach(geometry, line_sphere.center) : 0; radius > line_sphere.radius) {
      const ReferenceRays lines{.rays = lengthen_chords(reference.rays, line_sphere.center, radius),
                                .mesh_blocked = reference.mesh_blocked,
                                .mesh_ns_per_ray = reference.mesh_ns_per_ray,
                                .mesh = reference.mesh};
      measurement = measure_proxy(lines, proxy_scene, entry_kind(entry), options.timing);
      proxy_rays["proxy_sphere_radius"] = radius;
    } else {
      measurement = measure_proxy(reference, proxy_scene, entry_kind(entry), options.timing);
    }
    json measured = measurement_json(measurement);
    measured["rays"] = std::move(proxy_rays);
    measured["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    entry["measure"] = std::move(measured);
  }
  return manifest;
}

}  // namespace visproxy
