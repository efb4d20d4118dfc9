#include "visproxy/proxy/build_proxies.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
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
#include "visproxy/proxy/proxy_methods.h"
#include "visproxy/proxy/result_json.h"
#include "visproxy/proxy/surface_distance.h"
#include "visproxy/proxy/detail/watertight_input.h"
#include "visproxy/trace/ray_scene.h"

namespace visproxy {
namespace {

using nlohmann::json;

using detail::box_json;
using detail::interval_json;
using detail::to_json;

// The spec's method on every input (the mesh, or each of its components), the pieces
// joined: one BuiltProxy, or one per level for sphere methods, without the measures.
std::vector<BuiltProxy> build_with_method(const ProxySpec& spec, const std::vector<const TriangleMesh*>& inputs,
                                          const BuildOptions& options, const MethodContext& context, bool per_component,
                                          const std::filesystem::path& source) {
  const ProxyMethodRow& method = *spec.method;
  const bool spheres = method.primitives == PrimitiveType::sphere;
  const std::vector<std::string> names = spec.output_names();
  std::vector<BuiltProxy> proxies(names.size());
  json component_results = json::array(), summary = json::object();
  std::size_t resolved_count = 0;  // the budget of a share, over every input
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t c = 0; c < inputs.size(); ++c) {
    MethodPiece piece;
    const std::string where = per_component ? " (component " + std::to_string(c) + ")" : "";
    try {
      // A budget given as a share of the triangles becomes this input's count.
      ProxySpec resolved = spec;
      if (spec.count_share > 0) {
        resolved.count = std::max<std::size_t>(
            1, static_cast<std::size_t>(std::llround(spec.count_share * static_cast<double>(inputs[c]->triangles.size()))));
        resolved_count += resolved.count;
      }
      piece = method.build(resolved, *inputs[c], options);
    } catch (const InvalidInputError& error) {
      throw InvalidInputError(source, spec.text + where + ": " + error.problem());
    } catch (const std::bad_alloc&) {
      throw OutOfMemoryError(source, spec.text + where + ": out of memory while building it");
    }
    if (spheres) {
      for (std::size_t k = 0; k < proxies.size(); ++k)
        proxies[k].spheres.insert(proxies[k].spheres.end(), piece.levels[k].begin(), piece.levels[k].end());
    } else {
      append_mesh(proxies[0].mesh, piece.mesh);
      proxies[0].boxes.insert(proxies[0].boxes.end(), piece.boxes.begin(), piece.boxes.end());
      piece.result["triangles"] = piece.mesh.triangles.size();
    }
    component_results.push_back(std::move(piece.result));
    summary.update(piece.summary);
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (std::size_t k = 0; k < proxies.size(); ++k) {
    BuiltProxy& proxy = proxies[k];
    proxy.spec = spec;
    proxy.name = names[k];
    proxy.method = std::string(method.method);
    proxy.params = method.params(spec, context, k);
    if (spec.count_share > 0) {
      proxy.params["max_triangles"] = resolved_count;  // summed over the components
      proxy.params["share_of_triangles"] = spec.count_share;
    }
    proxy.primitive_type = method.primitives;
    proxy.build_seconds = seconds;
    if (spheres) {
      proxy.primitives = proxy.spheres.size();
      proxy.mesh = sphere_set_mesh(proxy.spheres);
      // Balls centred outside the mesh's bounding box mostly shadow space the mesh does not.
      std::size_t outside = 0;
      for (const Sphere& ball : proxy.spheres)
        outside += (ball.center.array() < context.bounds.min.array()).any() || (ball.center.array() > context.bounds.max.array()).any();
      proxy.result["balls_centred_outside_mesh_box"] = outside;
    } else if (proxy.mesh.triangles.empty()) {
      throw InvalidInputError(source, spec.text + ": every triangle collapsed, the proxy would be empty" + std::string(method.empty_hint));
    } else {
      proxy.primitives = proxy.primitive_type == PrimitiveType::box ? proxy.boxes.size() : proxy.mesh.triangles.size();
    }
    if (per_component) {
      proxy.result = {{"components", component_results}};
    } else {
      proxy.result = component_results[0];
      proxy.result.erase("triangles");
    }
    proxy.result.update(summary);
    if (proxy.primitive_type == PrimitiveType::box) {
      json boxes = json::array();
      for (const OrientedBox& box : proxy.boxes) boxes.push_back(box_json(box));
      proxy.result["boxes"] = boxes;
    }
  }
  return proxies;
}

}  // namespace

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
                                  {.rays = 0, .blocks = 0});
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
  const MethodContext context{.diagonal = diagonal, .bounds = bounds, .options = &options};
  auto build_spec = [&](const ProxySpec& spec) -> std::vector<BuiltProxy> {
    if (options.on_start) options.on_start(spec.name());
    if (spec.method->needs_closed_mesh && options.default_set) {
      if (const std::optional<std::string> defects = closed_defects(mesh)) {
        if (options.on_skip)
          options.on_skip(spec.name(), "the mesh is not closed (" + *defects + "): an inside proxy needs a closed mesh");
        return {};
      }
    }
    std::vector<BuiltProxy> built = build_with_method(spec, inputs, options, context, options.per_component, source);
    if (options.default_set)
      std::erase_if(built, [&](const BuiltProxy& proxy) {
        const double share = static_cast<double>(proxy.primitives) / static_cast<double>(mesh.triangles.size());
        if (proxy.primitives < kLargeProxyPrimitives || share <= kDefaultMaxShareOfMesh) return false;
        if (options.on_skip) {
          char text[200];
          std::snprintf(text, sizeof text,
                        "it has %zu %ss, %.0f %% of the mesh's %zu triangles (the default set keeps proxies of at most "
                        "%.0f %%); ask for it by name to keep it",
                        proxy.primitives, std::string(primitive_type_name(proxy.primitive_type)).c_str(), 100 * share, mesh.triangles.size(),
                        100 * kDefaultMaxShareOfMesh);
          options.on_skip(proxy.name, text);
        }
        return true;
      });
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
      return specs[a].method->cost_rank < specs[b].method->cost_rank;
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
