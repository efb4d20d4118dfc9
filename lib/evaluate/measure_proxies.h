#pragma once
// `visproxy measure`: every proxy of a folder traced with the same seeded rays as the mesh.

#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <string_view>

#include "measure/proxy_measurement.h"
#include "mesh/triangle_mesh.h"

namespace visproxy {

struct MeasureOptions {
  std::size_t rays = 1'000'000;  ///< isotropic lines through the mesh's bounding sphere
  std::uint64_t seed = 1;
  TimingOptions timing;
  /// Called before each proxy is measured with its name (progress display); may be empty.
  std::function<void(std::string_view)> on_start;
};

/// The ray set every proxy of `mesh` is measured on, as the manifest records it.
nlohmann::json ray_set_json(const TriangleMesh& mesh, const MeasureOptions& options);

/// Measures every proxy listed in `manifest` (FOLDER's) on one seeded set of isotropic
/// lines and returns the manifest with a `measure` object added to each entry:
///   rays (count, seed), counts [n1, n2, n3, n4], f_hit / f_miss / v_avg / gssa_ratio
///   {value, lower, upper} (95 %), probabilities {form, p1, p2, p3}, variance {optimal,
///   equal}, rays_contradicting_claim, cost_ns_per_ray {proxy, mesh, estimator,
///   proxy_over_mesh}, seconds.
nlohmann::json measure_proxies(const TriangleMesh& mesh, const std::filesystem::path& folder,
                               nlohmann::json manifest, const MeasureOptions& options = {});

/// The `measure` object of one measured proxy.
nlohmann::json measurement_json(const ProxyMeasurement& measurement);

}  // namespace visproxy
