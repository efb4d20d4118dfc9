#pragma once
// What to build: the `--proxy SPEC` strings of `visproxy build`, parsed and validated by the
// method each names (proxy_methods.h, whose table lists every spec's grammar: proxy_spec_help()).

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "visproxy/core/proxy_kind.h"
#include "visproxy/proxy/merge_spheres.h"
#include "visproxy/proxy/proxy_methods.h"

namespace visproxy {


/// Defaults of `wrap` (CGAL's recommended relative alpha 20 and offset 600), as fractions
/// of the input's bounding-box diagonal.
inline constexpr double kDefaultWrapAlphaRelative = 1.0 / 20;
inline constexpr double kDefaultWrapOffsetRelative = 1.0 / 600;

struct ProxySpec {
  const ProxyMethodRow* method = &proxy_method("aabb");  ///< its row in the table of methods
  std::string text;               ///< the spec as given, e.g. "hull:32"
  std::size_t count = 0;          ///< N of hull:N, outer:N, inner:N, quadric:N, inside:N
  /// P / 100 of quadric:P% and meshopt:P%: the budget as a share of the input's triangles
  /// (each component's with --per-component), made a count N when the input is known
  /// (at least 1); 0 when the spec gives N.
  double count_share = 0;
  std::size_t grid_cells = 0;     ///< G of inner:N,grid=G; 0: chosen from N (inner_hull_grid_cells)
  double cell_size_relative = 0;  ///< F of cluster:F
  double alpha_relative = kDefaultWrapAlphaRelative;    ///< wrap
  double offset_relative = kDefaultWrapOffsetRelative;  ///< wrap
  std::vector<std::size_t> levels;  ///< sphere methods: sphere counts, largest first (inside:N: N)
  PairDistance pair_distance = PairDistance::d2;  ///< spheres
  MergeRadius merge_radius = MergeRadius::exact;  ///< spheres
  std::size_t samples = 0;  ///< spheres: surface samples, 0 for max(4000, 4 x levels[0])

  /// The file and manifest name: the spec with ':' and ',' turned into '-' and '%' into
  /// "pct" ("hull-32", "quadric-10pct");
  /// sphere methods: "NAME-N" of the first (largest) level ("spheres-100").
  std::string name() const;
  /// Every proxy the spec makes, by name: one, except sphere methods: "NAME-N" per level.
  std::vector<std::string> output_names() const;
  ProxyKind kind() const { return method->kind; }
  /// Whether the spec is of the method `id` ("bounded_hull").
  bool is(std::string_view id) const { return method->id == id; }
};

/// Parses one spec; throws visproxy::Error with a one-line message naming the spec and
/// what is wrong (unknown method, missing or non-positive N, bad number, unknown key).
ProxySpec parse_proxy_spec(std::string_view text);

/// The set `visproxy build` makes when no --proxy is given:
/// aabb, obb, hull, hull:32, wrap, outer:512, quadric:512, cluster:0.03, inside:40, spheres:100.
std::vector<ProxySpec> default_proxy_specs();

/// Parses every spec and rejects two specs that make a proxy of the same name.
std::vector<ProxySpec> parse_proxy_specs(const std::vector<std::string>& texts);

}  // namespace visproxy
