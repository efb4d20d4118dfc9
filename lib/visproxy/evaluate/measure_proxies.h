#pragma once
// `visproxy measure`: every proxy of a folder traced with the same seeded rays as the mesh.

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string_view>

#include "visproxy/core/errors.h"
#include "visproxy/folder/proxy_folder.h"
#include "visproxy/measure/proxy_measurement.h"
#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

struct MeasureOptions {
  std::size_t rays = 1'000'000;  ///< isotropic lines through the mesh's bounding sphere, or scene segments
  std::uint64_t seed = 1;
  /// A scene file: measure on its shadow segments instead (scene_shadow_segments), from
  /// points the camera sees on other instances to its lights, against every instance of
  /// the mesh in the scene (and the same instances of each proxy).
  std::filesystem::path scene;
  TimingOptions timing;
  /// Called before each proxy is measured with its name (progress display); may be empty.
  std::function<void(std::string_view)> on_start;
  /// Receives the warnings of the readers of the scene's meshes (see ReadMeshOptions).
  WarningHandler on_warning;
};

/// The isotropic ray set every proxy of `mesh` is measured on, as the manifest records it.
nlohmann::json ray_set_json(const TriangleMesh& mesh, const MeasureOptions& options);

/// Measures every proxy listed in `manifest` (FOLDER's) on one seeded set of isotropic
/// lines (or scene segments) and returns the manifest with a `measure` object added to each entry:
///   rays (count, seed), counts [n1, n2, n3, n4], f_hit / f_miss / v_avg / gssa_ratio
///   {value, lower, upper} (95 %), probabilities {form, p1, p2, p3}, variance {optimal,
///   equal}, rays_contradicting_claim, cost_ns_per_ray {proxy, mesh, estimator,
///   proxy_over_mesh, proxy_over_mesh_range, timing_blocks, work, predicted}, seconds, with a
///   scene render_noise and render_time (each use's render pass time over exact's); and
///   at the top, cost_model (the run's model of a ray's cost from its counted work:
///   measure/cost_model.h) and, with a scene, render_share (the share of a render sample's
///   time the mesh's shadow tests take), or no render_share without one.
nlohmann::json measure_proxies(const TriangleMesh& mesh, const std::filesystem::path& folder, nlohmann::json manifest,
                               const MeasureOptions& options = {});

/// Gives the geometry of the manifest's entry `index` (its `entry`): for proxies held in
/// memory rather than in a folder.
using ProxyGeometryReader = std::function<ProxyGeometry(const nlohmann::json& entry, std::size_t index)>;

/// The same for proxies read through `read`: each entry of manifest["proxies"] needs only
/// its `name` and `kind`.
nlohmann::json measure_proxies(const TriangleMesh& mesh, nlohmann::json manifest, const ProxyGeometryReader& read,
                               const MeasureOptions& options = {});

/// The interval of a measured proxy's cost over the mesh's that its `measure` object
/// gives: the cost model's (cost_ns_per_ray.predicted.interval) when the run fitted one,
/// else the timing blocks' least and greatest ratio; none for a manifest measured before
/// either was recorded. Every reader of a proxy's cost takes it from here.
std::optional<std::array<double, 2>> cost_ratio_interval(const nlohmann::json& measure);

/// The `measure` object of one measured proxy.
nlohmann::json measurement_json(const ProxyMeasurement& measurement);

}  // namespace visproxy
