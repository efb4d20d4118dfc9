#pragma once
// Exact check that balls lie inside a closed mesh: the guarantee of inside sphere proxies.

#include <cstddef>
#include <optional>
#include <span>
#include <vector>

#include "visproxy/mesh/sphere_set.h"
#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

struct SphereContainment {
  std::size_t spheres_checked = 0;
  std::size_t spheres_outside = 0;            ///< spheres that fail (centre not inside, or radius too large)
  std::optional<std::size_t> first_outside;   ///< index of the first sphere that fails
  std::vector<std::size_t> outside;           ///< indices of every sphere that fails, increasing
  /// Min over the spheres of (signed distance from the centre to the surface - radius),
  /// in mesh units, computed in doubles (rounded; informative only, the verdict is exact).
  /// The distance is negative when the centre is not strictly inside. 0 for no spheres.
  double min_margin_world = 0;
  bool contained() const { return spheres_outside == 0; }
};

/// Whether every sphere (closed ball) lies inside the solid bounded by `closed_mesh`.
/// A sphere passes when its centre is strictly inside (locate_points: exact winding
/// number) and radius^2 <= the squared distance from the centre to every triangle, both
/// sides exact (the radius as the double it is; no tolerance). The ball can then touch the
/// surface but not cross it. A negative or non-finite radius, or a non-finite centre, fails.
///
/// Triangles near each ball are those whose box meets the ball's bounding box (so that
/// triangles lying wholly inside the ball are found too), found in one parallel pass over
/// the triangles with the balls on a grid; only those are compared exactly (CGAL's lazy
/// exact kernel). The cost is linear in the triangles, with no tree to build, and the
/// verdicts do not depend on the number of threads. Degenerate (zero-area) triangles bound
/// nothing and are not compared.
///
/// Precondition checked: the mesh has triangles and is closed (EdgeBalance: every edge
/// used as often in each direction), otherwise InvalidInputError (empty file name). The
/// mesh may self-intersect, have non-manifold edges or overlapping parts: its solid is
/// where the winding number is not zero, constant off the surface, so a ball whose centre
/// has a non-zero winding number and that crosses no triangle lies in the solid, and a
/// segment from a point of winding number 0 to the ball must cross the surface.
SphereContainment check_spheres_inside(const TriangleMesh& closed_mesh, std::span<const Sphere> spheres);

}  // namespace visproxy
