#pragma once
// A non-convex *inside* proxy with a triangle budget: a closed surface of at most N
// triangles that provably lies inside the solid of a closed input (a shadow mesh that never
// sticks out of the visible mesh). The mirror of outer_hull.h.

#include <cstddef>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

struct InnerHullOptions {
  std::size_t max_triangles = 512;  ///< triangle budget; must be at least 4
  /// Cells of the starting grid along the longest side of the input's bounding box; 0
  /// chooses sqrt(2 N) within [16, 256] (inner_hull_grid_cells). The start lies about 0.3 of
  /// a cell inside the surface, and parts thinner than about two cells may be lost; but
  /// decimating a fine start to a small budget loses more volume than a coarse start does
  /// (bunny00 at N = 64: f_hit 0.73 from 16 cells; from 64 cells 0.09, and 88 triangles:
  /// the collapses stall above the budget).
  std::size_t grid_cells = 0;
  /// Passes of moving every vertex towards the input after the collapses (each vertex by
  /// 90 %, 60 % or 30 % of its distance to the input, the first the checks allow). Passes
  /// after the third gained nothing measurable on bunny00 and the armadillo at N = 512.
  std::size_t relax_passes = 3;
  /// Clearance the moves towards the input keep, relative to the bounding-box diagonal:
  /// renderers in single precision keep a proof only for a proxy that keeps the rounding
  /// bound (2^-21 of the coordinates' magnitude) from the mesh, which a mesh instanced at
  /// a thousandth of a scene 1 000 units across still gets. Passes are undone, last first,
  /// while the surface comes closer than this to the input (tested through the input's
  /// BVH at least as strictly as surfaces_clear_by).
  double clearance_relative = 1e-4;
};

struct InnerHullResult {
  TriangleMesh mesh;            ///< the proxy, outward-oriented
  bool reached_target = false;  ///< mesh has at most max_triangles triangles
  std::size_t start_triangles = 0;  ///< triangles of the grid surface the decimation started from
  std::size_t grid_cells = 0;       ///< cells along the longest side, as applied
  double grid_cell_world = 0;       ///< edge of a grid cell, input units
  std::size_t components_dropped = 0;  ///< small components left out to meet the budget
  /// Upper bound of the distance from any point of the proxy surface to the input surface
  /// (see OuterHullResult::max_distance_to_input_world): how deep the proxy may sit.
  double max_distance_to_input_world = 0;
  double volume = 0;  ///< enclosed volume of the proxy, input units cubed
  double clearance_world = 0;  ///< clearance_relative x the input's diagonal
  /// Whether every point of the proxy surface keeps clearance_world from the input (the
  /// exact claim holds either way; renderers may use the proxy as general).
  bool clearance_kept = false;
  std::size_t relax_passes_kept = 0;  ///< moves towards the input kept under the clearance
};

/// The grid build_inner_hull uses for a budget of `max_triangles` when grid_cells is 0:
/// round(sqrt(2 max_triangles)) within [16, 256] (32 cells for 512 triangles).
std::size_t inner_hull_grid_cells(std::size_t max_triangles);

/// Inner hull of at most `max_triangles` triangles inside the solid of `input`
/// ({winding number != 0}; the input must be closed: every edge used as often in one
/// direction as in the other, self-intersections and non-manifold edges allowed).
///
///  1. Start: the winding number of the input at the vertices of a grid (scanline
///     crossings) and their distance to the surface; grid points inside with a distance
///     above 0.3 of a cell are marked, and marching tetrahedra (six per cell) separate marked
///     from unmarked points, each vertex within 0.9 of its marked point's distance, so
///     inside the solid. Triangles that meet the input (exact test) have their
///     tetrahedron's marked corners unmarked unless they are safe (a distance above a
///     cell's diagonal: the ball free of the input about such a corner holds the whole
///     tetrahedron), and the surface is made again until none does. The start is then
///     checked exactly (conservative_decimation.h: starts_conservative), not assumed.
///  2. Collapse edges, the one of least quadric error first, each merged vertex placed
///     where the quadric error is least or, if that fails the checks, on the inner side of
///     the planes of the triangles it replaces (a 3-variable LP; conservative_decimation.h),
///     in stages down to 8, 4, 2 and 1 times the budget with a pass of moves towards
///     the input after each, then `relax_passes` more passes; every change is checked with
///     exact predicates, and from the first moves on new triangles must also keep the
///     clearance (clearance_relative) from the input. Final passes are undone, last first,
///     while the surface does not keep it.
///  3. If more than `max_triangles` remain, whole components are left out, smallest volume
///     first: leaving out part of an inside proxy keeps it inside.
///  4. The result is proved as `visproxy verify` proves it (check_containment with
///     contents_solid): every vertex strictly inside, no triangle touching the input, no
///     input vertex inside the proxy. A failure there is a bug and throws visproxy::Error.
///
/// The result is closed, 2-manifold, self-intersection-free and outward-oriented; it may be
/// empty when the solid is thinner everywhere than the grid resolves (reached_target is
/// then true and the caller decides). If the budget cannot be met even so (a budget below
/// 4 triangles per kept component is impossible) the smallest mesh reached is returned
/// with reached_target = false: never a non-conservative one. Deterministic.
///
/// Throws InvalidInputError (empty file name) for max_triangles < 4, grid_cells other than
/// 0 below 4 or above 1024, an input that is not closed (naming its defects) or coordinates beyond
/// kMaxCoordinate; visproxy::Error when the start fails its exact check on three shifted
/// grids.
InnerHullResult build_inner_hull(const TriangleMesh& input, const InnerHullOptions& options);

}  // namespace visproxy
