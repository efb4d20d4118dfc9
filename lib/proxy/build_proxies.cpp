#include "visproxy/proxy/build_proxies.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <mutex>
#include <new>
#include <optional>

#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include "visproxy/core/errors.h"
#include "visproxy/inspect/mesh_report.h"
#include "visproxy/measure/proportion.h"
#include "visproxy/measure/proxy_measurement.h"
#include "visproxy/measure/random_lines.h"
#include "visproxy/mesh/mesh_topology.h"
#include "visproxy/proxy/alpha_wrap.h"
#include "visproxy/proxy/bounded_hull.h"
#include "visproxy/proxy/convex_hull.h"
#include "visproxy/proxy/inner_hull.h"
#include "visproxy/proxy/inscribed_spheres.h"
#include "visproxy/proxy/merge_spheres.h"
#include "visproxy/proxy/outer_hull.h"
#include "visproxy/proxy/quadric_simplify.h"
#include "visproxy/proxy/surface_distance.h"
#include "visproxy/proxy/vertex_clustering.h"
#include "visproxy/proxy/watertight_input.h"
#include "visproxy/trace/ray_scene.h"

namespace visproxy {
namespace {

using nlohmann::json;

json to_json(const Vertex& v) { return json::array({v.x(), v.y(), v.z()}); }

json box_json(const OrientedBox& box) {
  json axes = json::array();
  for (int k = 0; k < 3; ++k) axes.push_back(to_json(box.axes.col(k)));
  return {{"center", to_json(box.center)}, {"axes", axes}, {"half_extents", to_json(box.half_extents)}};
}

// One builder run on one mesh (the whole input or one component).
struct Piece {
  TriangleMesh mesh;
  std::vector<OrientedBox> boxes;
  json result = json::object();
};

Piece build_piece(const ProxySpec& spec, const TriangleMesh& mesh, const BuildOptions& options) {
  const double diagonal = bounding_box(mesh).diagonal();
  Piece piece;
  switch (spec.method) {
    case ProxyMethod::aabb: {
      piece.mesh = axis_aligned_box_mesh(mesh);
      const BoundingBox bounds = bounding_box(mesh);
      piece.boxes.push_back({0.5 * (bounds.min + bounds.max), Eigen::Matrix3d::Identity(), 0.5 * (bounds.max - bounds.min)});
      piece.result = {{"min", to_json(bounds.min)}, {"max", to_json(bounds.max)}};
      break;
    }
    case ProxyMethod::obb: {
      OrientedBoxResult box = build_oriented_box(mesh, {.seed = static_cast<std::uint32_t>(options.seed)});
      piece.mesh = std::move(box.mesh);
      piece.boxes.push_back(box.box);
      piece.result = box_json(box.box);
      piece.result["volume"] = box.box.volume();
      piece.result["axes_from"] = box.axes_from;
      piece.result["inflation_world"] = box.inflation_world;
      break;
    }
    case ProxyMethod::convex_hull: {
      ConvexHullResult hull = build_convex_hull(mesh);
      piece.mesh = std::move(hull.mesh);
      piece.result = {{"faces", hull.faces}, {"volume", hull.volume}};
      break;
    }
    case ProxyMethod::bounded_hull: {
      BoundedHullResult hull = build_bounded_hull(mesh, {.max_faces = spec.count});
      piece.mesh = std::move(hull.mesh);
      piece.result = {{"faces", hull.faces},
                      {"volume", hull.volume},
                      {"hull_volume", hull.exact_hull_volume},
                      {"volume_over_hull", hull.added_volume_fraction()}};
      break;
    }
    case ProxyMethod::alpha_wrap: {
      AlphaWrapResult wrap =
          build_alpha_wrap(mesh, {.alpha_relative = spec.alpha_relative, .offset_relative = spec.offset_relative});
      piece.mesh = std::move(wrap.mesh);
      piece.result = {{"alpha_world", wrap.alpha_world}, {"offset_world", wrap.offset_world}};
      break;
    }
    case ProxyMethod::outer_hull: {
      OuterHullResult outer = build_outer_hull(mesh, {.max_triangles = spec.count});
      piece.mesh = std::move(outer.mesh);
      piece.result = {{"reached_target", outer.reached_target},
                      {"wrap_triangles", outer.wrap_triangles},
                      {"wrap_alpha_world", outer.wrap_alpha_world},
                      {"wrap_offset_world", outer.wrap_offset_world},
                      {"max_distance_to_input_world", outer.max_distance_to_input_world},
                      {"clearance_world", outer.clearance_world},
                      {"clearance_kept", outer.clearance_kept}};
      break;
    }
    case ProxyMethod::inner_hull: {
      InnerHullResult inner = build_inner_hull(mesh, {.max_triangles = spec.count, .grid_cells = spec.grid_cells});
      if (inner.mesh.triangles.empty())
        throw InvalidInputError("", "the solid is thinner everywhere than about one grid cell (" +
                                        std::to_string(inner.grid_cell_world) +
                                        " mesh units): no inner hull on this grid; a larger grid=G resolves thinner parts");
      piece.mesh = std::move(inner.mesh);
      piece.result = {{"reached_target", inner.reached_target},
                      {"start_triangles", inner.start_triangles},
                      {"grid_cell_world", inner.grid_cell_world},
                      {"components_dropped", inner.components_dropped},
                      {"volume", inner.volume},
                      {"clearance_world", inner.clearance_world},
                      {"clearance_kept", inner.clearance_kept},
                      {"relax_passes_kept", inner.relax_passes_kept},
                      {"max_distance_to_input_world", inner.max_distance_to_input_world}};
      break;
    }
    case ProxyMethod::quadric: {
      QuadricSimplifyResult simplified = simplify_quadric(mesh, {.max_triangles = spec.count});
      piece.mesh = std::move(simplified.mesh);
      piece.result = {{"collapses", simplified.collapses},
                      {"max_quadric_error_world", simplified.max_quadric_error_relative * diagonal}};
      break;
    }
    case ProxyMethod::inscribed_spheres:
    case ProxyMethod::sphere_set: break;  // build_sphere_levels
    case ProxyMethod::clustering: {
      VertexClusteringResult clustered = cluster_vertices(mesh, {.cell_size_relative = spec.cell_size_relative});
      piece.mesh = std::move(clustered.mesh);
      piece.result = {{"cell_size_world", clustered.cell_size_world},
                      {"max_vertex_displacement_world", clustered.max_vertex_displacement_world}};
      break;
    }
  }
  return piece;
}

std::string describe(ProxyMethod method) {
  switch (method) {
    case ProxyMethod::aabb: return "axis-aligned bounding box";
    case ProxyMethod::obb: return "oriented bounding box (CGAL optimal box, principal axes or axis-aligned: smallest)";
    case ProxyMethod::convex_hull: return "convex hull (CGAL)";
    case ProxyMethod::bounded_hull: return "convex hull simplified by greedy half-space removal";
    case ProxyMethod::alpha_wrap: return "3D alpha wrap (CGAL)";
    case ProxyMethod::outer_hull: return "alpha wrap decimated by conservative edge collapses";
    case ProxyMethod::inner_hull:
      return "marching-tetrahedra surface inside the solid, decimated by conservative edge collapses";
    case ProxyMethod::quadric: return "quadric edge collapse";
    case ProxyMethod::clustering: return "vertex clustering";
    case ProxyMethod::inscribed_spheres:
      return "maximal inscribed spheres: inner Voronoi poles, greedy volume cover, exact containment check";
    case ProxyMethod::sphere_set: return "Delaunay circumsphere set merged pairwise keeping the GSSA (occluding spheres)";
  }
  return "";
}

json params_of(const ProxySpec& spec, double diagonal, const BoundingBox& bounds) {
  switch (spec.method) {
    case ProxyMethod::aabb:
    case ProxyMethod::convex_hull: return json::object();
    case ProxyMethod::obb: return json::object();
    case ProxyMethod::bounded_hull: return {{"max_faces", spec.count}};
    case ProxyMethod::outer_hull:
    case ProxyMethod::quadric: return {{"max_triangles", spec.count}};
    case ProxyMethod::inner_hull:
      return {{"max_triangles", spec.count},
              {"grid_cells", spec.grid_cells != 0 ? spec.grid_cells : inner_hull_grid_cells(spec.count)}};
    case ProxyMethod::alpha_wrap:
      return {{"alpha_relative", spec.alpha_relative},
              {"offset_relative", spec.offset_relative},
              {"alpha_world", spec.alpha_relative * diagonal},
              {"offset_world", spec.offset_relative * diagonal}};
    case ProxyMethod::clustering:
      return {{"cell_size_relative", spec.cell_size_relative},
              {"cell_size_world", spec.cell_size_relative * (bounds.max - bounds.min).maxCoeff()}};
    case ProxyMethod::inscribed_spheres: {
      const InscribedSpheresOptions defaults;
      return {{"spheres", spec.count},
              {"margin_relative", defaults.margin_relative},
              {"margin_world", inscribed_sphere_margin(bounds, defaults.margin_relative)},
              {"volume_samples", defaults.volume_samples},
              {"coverage_samples", defaults.coverage_samples}};
    }
    case ProxyMethod::sphere_set: return json::object();  // per level, in build_sphere_levels
  }
  return json::object();
}

std::size_t circumsphere_samples(const ProxySpec& spec) {
  return spec.samples > 0 ? spec.samples : default_circumsphere_samples(spec.levels.front());
}

// {value, lower, upper}; an unbounded upper end is null (schema: $defs/interval).
json interval_json(double value, double lower, double upper) {
  return {{"value", value}, {"lower", lower}, {"upper", std::isfinite(upper) ? json(upper) : json(nullptr)}};
}

// The spheres of every level of `spec` (inside:N is one level), built once per component
// and joined: BuiltProxy objects without the error and the GSSA measurement.
std::vector<BuiltProxy> build_sphere_levels(const ProxySpec& spec, const std::vector<const TriangleMesh*>& inputs,
                                            const BuildOptions& options, double diagonal, const BoundingBox& bounds) {
  const bool inside = spec.method == ProxyMethod::inscribed_spheres;
  const std::vector<std::size_t> levels = inside ? std::vector<std::size_t>{spec.count} : spec.levels;
  const std::vector<std::string> names = spec.output_names();
  std::vector<std::vector<Sphere>> spheres(levels.size());
  std::vector<json> component_results;
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t c = 0; c < inputs.size(); ++c) {
    try {
      if (inside) {
        const InscribedSpheres built = build_inscribed_spheres(*inputs[c], {.count = spec.count, .seed = options.seed});
        spheres[0].insert(spheres[0].end(), built.spheres.begin(), built.spheres.end());
        component_results.push_back(
            {{"candidates", built.candidates},
             {"surface_samples", built.surface_samples},
             {"mesh_volume", built.mesh_volume},
             {"covered_volume_fraction",
              interval_json(built.covered_volume_fraction, built.covered_volume_lower, built.covered_volume_upper)},
             {"coverage_samples", built.coverage_hits.trials},
             {"coverage_seed", built.coverage_seed},
             {"min_margin_world", built.min_margin_world},
             {"spheres_shrunk", built.spheres_shrunk}});
      } else {
        const CircumsphereSet set = build_circumsphere_set(
            *inputs[c], {.tetrahedra = options.tets, .samples = circumsphere_samples(spec), .seed = options.seed});
        const std::vector<std::vector<Sphere>> merged =
            merge_spheres(set.spheres, levels, {.pair_distance = spec.pair_distance, .radius = spec.merge_radius});
        for (std::size_t k = 0; k < levels.size(); ++k) spheres[k].insert(spheres[k].end(), merged[k].begin(), merged[k].end());
        component_results.push_back(
            {{"points", set.points}, {"tetrahedra", set.tetrahedra}, {"initial_spheres", set.spheres.size()}});
      }
    } catch (const InvalidInputError& error) {
      const std::string where = inputs.size() > 1 ? " (component " + std::to_string(c) + ")" : "";
      throw InvalidInputError("", spec.text + where + ": " + error.problem());
    }
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  std::vector<BuiltProxy> proxies;
  for (std::size_t k = 0; k < levels.size(); ++k) {
    BuiltProxy proxy;
    proxy.spec = spec;
    proxy.name = names[k];
    proxy.method = describe(spec.method);
    proxy.params = params_of(spec, diagonal, bounds);
    if (!inside)
      proxy.params = {{"spheres", levels[k]},
                      {"levels", levels},
                      {"pair_distance", pair_distance_name(spec.pair_distance)},
                      {"merge_radius", spec.merge_radius == MergeRadius::exact ? "exact" : "analytic"},
                      {"samples", circumsphere_samples(spec)},
                      {"tets", inner_tetrahedra_name(options.tets)}};
    proxy.primitive_type = PrimitiveType::sphere;
    proxy.spheres = std::move(spheres[k]);
    proxy.primitives = proxy.spheres.size();
    proxy.mesh = sphere_set_mesh(proxy.spheres);
    proxy.build_seconds = seconds;
    if (inputs.size() > 1) {
      proxy.result = {{"components", component_results}};
    } else {
      proxy.result = component_results[0];
    }
    if (!inside) proxy.result["levels_built_together"] = levels;
    proxies.push_back(std::move(proxy));
  }
  return proxies;
}

// Rough order of the builders' cost on one mesh, slowest first: workers that take the
// slow ones first finish together.
int expected_cost_rank(ProxyMethod method) {
  switch (method) {
    case ProxyMethod::outer_hull:
    case ProxyMethod::inner_hull: return 0;
    case ProxyMethod::alpha_wrap:
    case ProxyMethod::sphere_set:
    case ProxyMethod::inscribed_spheres: return 1;
    case ProxyMethod::obb:
    case ProxyMethod::bounded_hull: return 2;
    case ProxyMethod::quadric:
    case ProxyMethod::convex_hull: return 3;
    case ProxyMethod::clustering:
    case ProxyMethod::aabb: return 4;
  }
  return 4;
}

}  // namespace

std::string_view primitive_type_name(PrimitiveType type) {
  switch (type) {
    case PrimitiveType::triangle: return "triangle";
    case PrimitiveType::box: return "box";
    case PrimitiveType::sphere: return "sphere";
  }
  return "triangle";
}

std::size_t builders_at_once(std::size_t requested, std::size_t triangles) {
  if (requested != 0) return requested;
  if (triangles > kConcurrentBuildTriangles) return 1;
  return std::max<std::size_t>(1, static_cast<std::size_t>(tbb::this_task_arena::max_concurrency()));
}

std::vector<BuiltProxy> build_proxies(const TriangleMesh& mesh, const std::filesystem::path& source,
                                      std::span<const ProxySpec> specs, const BuildOptions& options) {
  if (mesh.triangles.empty()) throw InvalidInputError(source, "the mesh has no triangles: nothing to build proxies of");
  const BoundingBox bounds = bounding_box(mesh);
  const double diagonal = bounds.diagonal();
  const std::vector<TriangleMesh> parts = options.per_component ? split_components(mesh) : std::vector<TriangleMesh>{};
  const std::vector<const TriangleMesh*> inputs = [&] {
    std::vector<const TriangleMesh*> pointers;
    if (options.per_component)
      for (const TriangleMesh& part : parts) pointers.push_back(&part);
    else
      pointers.push_back(&mesh);
    return pointers;
  }();
  const std::size_t at_once = std::min(builders_at_once(options.builders_at_once, mesh.triangles.size()),
                                       std::max<std::size_t>(1, specs.size()));

  // Sampled Hausdorff distance between the proxy's triangles and the mesh; sphere proxies
  // are measured through the boundary of their union (level-2 icospheres, without the
  // triangles buried in other balls: within 1.3 % of each radius).
  // The mesh's side is prepared once, for every proxy, when the first measure needs it.
  std::optional<MeasuredSurface> measured_mesh;
  std::once_flag measured_mesh_made;
  auto measure_error = [&](BuiltProxy& proxy) {
    std::call_once(measured_mesh_made, [&] { measured_mesh.emplace(mesh, "second"); });
    const SurfaceDistance distance = sampled_hausdorff_distance(
        proxy.primitive_type == PrimitiveType::sphere ? sphere_union_boundary_mesh(proxy.spheres, 2) : proxy.mesh,
        *measured_mesh, {.samples_per_mesh = options.hausdorff_samples, .seed = options.seed});
    proxy.error = {{"hausdorff_relative", diagonal > 0 ? distance.hausdorff_world() / diagonal : 0.0},
                   {"hausdorff_world", distance.hausdorff_world()},
                   {"proxy_to_mesh_world", distance.a_to_b_world},
                   {"mesh_to_proxy_world", distance.b_to_a_world},
                   {"samples_per_surface", options.hausdorff_samples},
                   {"seed", options.seed}};
  };
  // Isotropic lines against the mesh, traced once for every sphere proxy.
  std::optional<ReferenceRays> reference;
  std::once_flag reference_made;
  auto measure_gssa = [&](BuiltProxy& proxy) {
    std::call_once(reference_made, [&] {
      const RayScene scene(mesh, bounding_sphere(mesh).center);
      reference = trace_reference(scene, isotropic_lines(bounding_sphere(mesh), options.gssa_lines, options.seed),
                                  {.rays = 0, .repeats = 0});
    });
    const RayScene spheres(proxy.spheres, bounding_sphere(mesh).center);
    const std::vector<std::uint8_t> blocked = spheres.segments_blocked(reference->rays);
    RayTypeCounts counts;
    for (std::size_t i = 0; i < blocked.size(); ++i) counts.add(reference->mesh_blocked[i] != 0, blocked[i] != 0);
    const ProxyMeasurement measured = measure_from_counts(counts, proxy.spec.kind());
    proxy.result["gssa_ratio"] = interval_json(measured.gssa_ratio, measured.gssa_ratio_lower, measured.gssa_ratio_upper);
    const Proportion spheres_hit{counts.counts[0] + counts.counts[2], counts.total()};
    const Proportion mesh_hit{counts.counts[0] + counts.counts[1], counts.total()};
    proxy.result["spheres_hit_fraction"] =
        interval_json(spheres_hit.fraction(), spheres_hit.lower(), spheres_hit.upper());
    proxy.result["mesh_hit_fraction"] = interval_json(mesh_hit.fraction(), mesh_hit.lower(), mesh_hit.upper());
    proxy.result["gssa_lines"] = options.gssa_lines;
    proxy.result["gssa_seed"] = options.seed;
    if (proxy.spec.kind() == ProxyKind::inside) proxy.result["lines_hitting_spheres_not_mesh"] = counts.counts[2];
  };

  // The proxies of one spec (a spheres spec gives one per level; none when inside:N is
  // skipped), without their measures.
  auto build_spec = [&](const ProxySpec& spec) -> std::vector<BuiltProxy> {
    if (spec.method == ProxyMethod::inscribed_spheres || spec.method == ProxyMethod::sphere_set) {
      if (options.on_start) options.on_start(spec.name());
      if (spec.method == ProxyMethod::inscribed_spheres && options.skip_inside_unless_closed) {
        if (const std::optional<std::string> defects = closed_defects(mesh)) {
          if (options.on_skip)
            options.on_skip(spec.name(), "the mesh is not closed (" + *defects + "): an inside proxy needs a closed mesh");
          return {};
        }
      }
      try {
        return build_sphere_levels(spec, inputs, options, diagonal, bounds);
      } catch (const InvalidInputError& error) {
        throw InvalidInputError(source, error.problem());
      } catch (const std::bad_alloc&) {
        throw OutOfMemoryError(source, spec.text + ": out of memory while building it");
      }
    }
    if (options.on_start) options.on_start(spec.name());
    BuiltProxy proxy;
    proxy.spec = spec;
    proxy.name = spec.name();
    proxy.method = describe(spec.method);
    proxy.params = params_of(spec, diagonal, bounds);
    proxy.primitive_type = spec.method == ProxyMethod::aabb || spec.method == ProxyMethod::obb ? PrimitiveType::box
                                                                                               : PrimitiveType::triangle;
    const auto start = std::chrono::steady_clock::now();
    json component_results = json::array();
    for (std::size_t c = 0; c < inputs.size(); ++c) {
      Piece piece;
      try {
        piece = build_piece(spec, *inputs[c], options);
      } catch (const InvalidInputError& error) {
        const std::string where = options.per_component ? " (component " + std::to_string(c) + ")" : "";
        throw InvalidInputError(source, spec.text + where + ": " + error.problem());
      } catch (const std::bad_alloc&) {
        const std::string where = options.per_component ? " (component " + std::to_string(c) + ")" : "";
        throw OutOfMemoryError(source, spec.text + where + ": out of memory while building it");
      }
      append_mesh(proxy.mesh, piece.mesh);
      proxy.boxes.insert(proxy.boxes.end(), piece.boxes.begin(), piece.boxes.end());
      piece.result["triangles"] = piece.mesh.triangles.size();
      component_results.push_back(std::move(piece.result));
    }
    proxy.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (proxy.mesh.triangles.empty())
      throw InvalidInputError(source, spec.text + ": every triangle collapsed, the proxy would be empty" +
                                          (spec.method == ProxyMethod::clustering ? " (use a smaller cell)" : ""));
    proxy.primitives = proxy.primitive_type == PrimitiveType::box ? proxy.boxes.size() : proxy.mesh.triangles.size();
    if (options.per_component) {
      proxy.result = {{"components", component_results}};
    } else {
      proxy.result = std::move(component_results[0]);
      proxy.result.erase("triangles");
    }
    if (proxy.primitive_type == PrimitiveType::box) {
      json boxes = json::array();
      for (const OrientedBox& box : proxy.boxes) boxes.push_back(box_json(box));
      proxy.result["boxes"] = boxes;
    }
    std::vector<BuiltProxy> built;
    built.push_back(std::move(proxy));
    return built;
  };
  // A spec's measures: the GSSA of a sphere set, then every proxy's error.
  auto measure_spec = [&](std::vector<BuiltProxy>& built) {
    const BuiltProxy* measuring = nullptr;
    try {
      for (BuiltProxy& proxy : built)
        if (proxy.primitive_type == PrimitiveType::sphere) {
          if (options.on_measure) options.on_measure(proxy.spec.text);
          measuring = &proxy, measure_gssa(proxy);
        }
      for (BuiltProxy& proxy : built) {
        if (options.on_measure) options.on_measure(proxy.spec.text);
        measuring = &proxy, measure_error(proxy);
      }
    } catch (const std::bad_alloc&) {
      throw OutOfMemoryError(source, (measuring ? measuring->spec.text : std::string("the proxies")) +
                                         ": out of memory while measuring its error");
    }
  };

  std::vector<std::vector<BuiltProxy>> built(specs.size());
  if (at_once == 1) {
    // One after another, the measures once every builder is done, so that the mesh's ray
    // scene and distance tree are made once and are not held while a builder needs its
    // own memory.
    for (std::size_t i = 0; i < specs.size(); ++i) {
      built[i] = build_spec(specs[i]);
      if (options.on_step_done) options.on_step_done(specs[i].text);
    }
    for (std::size_t i = 0; i < specs.size(); ++i) {
      measure_spec(built[i]);
      if (options.on_step_done) options.on_step_done(specs[i].text);
    }
    reference.reset();
  } else {
    // `at_once` workers take the specs, slowest kinds first, and measure each proxy as soon
    // as it is built. Every builder and measure is deterministic on its own, so the
    // proxies are those of one-after-another, bit for bit. The first error in spec order
    // is the one thrown, as one after another would.
    std::vector<std::size_t> order(specs.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      return expected_cost_rank(specs[a].method) < expected_cost_rank(specs[b].method);
    });
    // After a failure only the specs before it still run, so that the error thrown is
    // the first in spec order whatever the timing.
    std::vector<std::exception_ptr> errors(specs.size());
    std::atomic<std::size_t> next{0};
    std::atomic<std::size_t> first_failed{specs.size()};
    tbb::task_group workers;
    for (std::size_t w = 0; w < at_once; ++w)
      workers.run([&] {
        for (std::size_t k = next++; k < order.size(); k = next++) {
          const std::size_t i = order[k];
          if (i > first_failed) continue;
          try {
            // Isolated: while this spec's own parallel loops wait, the thread runs only
            // their tasks, never another worker's spec on top of this one (which could
            // re-enter the call_once that prepares the mesh's distance BVH and deadlock).
            tbb::this_task_arena::isolate([&] {
              built[i] = build_spec(specs[i]);
              measure_spec(built[i]);
            });
            if (options.on_step_done) options.on_step_done(specs[i].text);
          } catch (...) {
            errors[i] = std::current_exception();
            std::size_t seen = first_failed;
            while (i < seen && !first_failed.compare_exchange_weak(seen, i)) {
            }
          }
        }
      });
    workers.wait();
    for (const std::exception_ptr& error : errors)
      if (error) std::rethrow_exception(error);
  }
  std::vector<BuiltProxy> proxies;
  for (std::vector<BuiltProxy>& levels : built)
    for (BuiltProxy& proxy : levels) proxies.push_back(std::move(proxy));
  return proxies;
}

}  // namespace visproxy
