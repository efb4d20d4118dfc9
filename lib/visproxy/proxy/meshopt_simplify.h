#pragma once
// meshoptimizer's simplifier as a builder of its own (meshopt:N): a *general* proxy, so that
// the industry's fastest decimation is measured beside quadric:N in the same report.

#include <cstddef>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

struct MeshoptSimplifyOptions {
  std::size_t max_triangles = 512;  ///< triangle budget of the result; must be at least 1
};

struct MeshoptSimplifyResult {
  TriangleMesh mesh;
  /// meshopt_simplify's own error estimate of the edge-collapse pass, in mesh units (its
  /// relative error times meshopt_simplifyScale): a measure, not a bound on the Hausdorff
  /// distance (measure that with sampled_hausdorff_distance).
  double error_world = 0;
  /// Whether the topology-preserving pass stopped above the budget (borders, seams, small
  /// components) and meshopt_simplifySloppy, which merges vertices on a grid regardless of
  /// topology, took the rest of the way.
  bool sloppy_pass = false;
  /// At most max_triangles triangles (false only when even the sloppy pass could not get
  /// there; the result is then the smallest it reached).
  bool reached_target = true;
};

/// Decimates with meshoptimizer (meshopt_simplify: edge collapses by a quadric error,
/// topology kept; no target error, so it goes as far as the budget or the topology allow),
/// then, if that stops above the budget, meshopt_simplifySloppy on its result (at the
/// smallest budget, doubling, where it leaves a triangle). Corners at equal coordinates are
/// one vertex to it, so a soup decimates like the welded mesh. meshoptimizer
/// works in single precision: positions are handed to it relative to the bounding box's
/// centre, so meshes far from the origin decimate as well as at it.
///
/// Guarantees, for any input with at least one triangle:
/// - vertices are input vertices with their coordinates exactly (meshoptimizer only picks
///   which to keep); no unreferenced vertex;
/// - no triangle with a repeated index or exactly collinear corners, no two triangles over
///   the same three vertices (the first is kept);
/// - at most `max_triangles` triangles when reached_target;
/// - deterministic: the same input and options give the same output, bit for bit.
/// Throws InvalidInputError for a budget of 0, an empty mesh, or more than 2^32 - 1 vertices.
MeshoptSimplifyResult simplify_meshopt(const TriangleMesh& mesh, const MeshoptSimplifyOptions& options);

}  // namespace visproxy
