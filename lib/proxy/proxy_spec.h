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
//   inner:N[,grid=G]     non-convex inside mesh, at most N triangles, started from a grid of
//                        G cells along the longest side (default sqrt(2N), 16-256) (inside)
//   quadric:N            quadric edge collapse to at most N triangles (general)
//   cluster:F            vertex clustering, cell F x largest bbox extent (general)
//   inside:N             N maximal spheres inscribed in a closed mesh (inside)
//   spheres:N[,N2,...][,pair=d1|d2][,merge=exact|analytic][,samples=S]
//                        Delaunay circumsphere set merged to N (and N2, ...) spheres, all
//                        levels in one pass, one proxy each named spheres-N (general).
//                        pair: pair distance D1 = d or D2 = d + r - R (default d2); merge:
//                        the GSSA each merge keeps, exact (default) or the paper's analytic
//                        overestimates; samples: surface samples triangulated (default
//                        max(4000, 4 x largest N)).

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "visproxy/core/proxy_kind.h"
#include "visproxy/proxy/merge_spheres.h"

namespace visproxy {

enum class ProxyMethod {
  aabb,
  obb,
  convex_hull,
  bounded_hull,
  alpha_wrap,
  outer_hull,
  inner_hull,
  quadric,
  clustering,
  inscribed_spheres,
  sphere_set
};

/// Defaults of `wrap` (CGAL's recommended relative alpha 20 and offset 600), as fractions
/// of the input's bounding-box diagonal.
inline constexpr double kDefaultWrapAlphaRelative = 1.0 / 20;
inline constexpr double kDefaultWrapOffsetRelative = 1.0 / 600;

struct ProxySpec {
  ProxyMethod method = ProxyMethod::aabb;
  std::string text;               ///< the spec as given, e.g. "hull:32"
  std::size_t count = 0;          ///< N of hull:N, outer:N, inner:N, quadric:N, inside:N
  std::size_t grid_cells = 0;     ///< G of inner:N,grid=G; 0: chosen from N (inner_hull_grid_cells)
  double cell_size_relative = 0;  ///< F of cluster:F
  double alpha_relative = kDefaultWrapAlphaRelative;    ///< wrap
  double offset_relative = kDefaultWrapOffsetRelative;  ///< wrap
  std::vector<std::size_t> levels;  ///< spheres: sphere counts, largest first
  PairDistance pair_distance = PairDistance::d2;  ///< spheres
  MergeRadius merge_radius = MergeRadius::exact;  ///< spheres
  std::size_t samples = 0;  ///< spheres: surface samples, 0 for max(4000, 4 x levels[0])

  /// The file and manifest name: the spec with ':' and ',' turned into '-' ("hull-32");
  /// spheres: "spheres-N" of the first (largest) level.
  std::string name() const;
  /// Every proxy the spec makes, by name: one, except spheres: "spheres-N" per level.
  std::vector<std::string> output_names() const;
  ProxyKind kind() const;
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
