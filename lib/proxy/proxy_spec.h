#pragma once
// What to build: the `--proxy SPEC` strings of `visproxy build`, parsed and validated.
//
//   aabb                 axis-aligned bounding box                   (outside)
//   obb                  oriented bounding box                       (outside)
//   hull                 convex hull                                 (outside)
//   hull:N               convex polytope with at most N faces        (outside)
//   wrap                 alpha wrap, default alpha and offset        (outside)
//   wrap:alpha=A,offset=O  alpha wrap; A, O relative to the bbox diagonal (either may be left out)
//   outer:N              non-convex outside mesh, at most N triangles (outside)
//   quadric:N            quadric edge collapse to at most N triangles (general)
//   cluster:F            vertex clustering, cell F x largest bbox extent (general)

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "core/proxy_kind.h"

namespace visproxy {


enum class ProxyMethod { aabb, obb, convex_hull, bounded_hull, alpha_wrap, outer_hull, quadric, clustering };

/// Defaults of `wrap` (CGAL's recommended relative alpha 20 and offset 600), as fractions
/// of the input's bounding-box diagonal.
inline constexpr double kDefaultWrapAlphaRelative = 1.0 / 20;
inline constexpr double kDefaultWrapOffsetRelative = 1.0 / 600;

struct ProxySpec {
  ProxyMethod method = ProxyMethod::aabb;
  std::string text;               ///< the spec as given, e.g. "hull:32"
  std::size_t count = 0;          ///< N of hull:N, outer:N, quadric:N
  double cell_size_relative = 0;  ///< F of cluster:F
  double alpha_relative = kDefaultWrapAlphaRelative;    ///< wrap
  double offset_relative = kDefaultWrapOffsetRelative;  ///< wrap

  /// The file and manifest name: the spec with ':' and ',' turned into '-' ("hull-32").
  std::string name() const;
  ProxyKind kind() const;
};

/// Parses one spec; throws visproxy::Error with a one-line message naming the spec and
/// what is wrong (unknown method, missing or non-positive N, bad number, unknown key).
ProxySpec parse_proxy_spec(std::string_view text);

/// The set `visproxy build` makes when no --proxy is given:
/// aabb, obb, hull, hull:32, wrap, outer:512, quadric:512, cluster:0.03.
std::vector<ProxySpec> default_proxy_specs();

/// Parses every spec and rejects two specs with the same name.
std::vector<ProxySpec> parse_proxy_specs(const std::vector<std::string>& texts);

}  // namespace visproxy
