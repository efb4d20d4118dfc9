#pragma once
// Vertex-clustering decimation on a uniform grid: a *general* proxy whose error is bounded
// by the cell size.

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

struct VertexClusteringOptions {
  /// Cell edge as a fraction of the LARGEST extent of the input's bounding box (not of its
  /// diagonal, following the paper's "3 % of the bounding box"); must be finite and > 0.
  double cell_size_relative = 0.03;
};

struct VertexClusteringResult {
  TriangleMesh mesh;
  double cell_size_world = 0;                ///< edge of a grid cell
  double max_vertex_displacement_world = 0;  ///< largest distance from an input vertex to its cell's representative
};

/// Merges all vertices in each cell of a uniform grid into one representative
/// (Rossignac & Borrel 1993) and keeps the triangles whose corners land in three cells.
/// The grid is anchored at the bounding box's minimum corner. A cell's representative
/// minimises the quadric of the triangles touching the cell (Lindstrom 2000; directions in
/// which that quadric is nearly flat are taken from the area-weighted mean of the cell's
/// triangle corners, so duplicated vertices do not pull it), then is
/// clamped into the cell.
///
/// Guarantees, for any input with at least one triangle:
/// - every used input vertex moves by at most one cell diagonal (sqrt(3) x cell size), up to
///   the rounding of computing its cell; `max_vertex_displacement_world` is the largest move;
/// - no triangle with a repeated index or with collinear corners (decided exactly), no two
///   triangles over the same three vertices (in either orientation; the first is kept), no
///   two output vertices at the same point, no unreferenced vertex;
/// - deterministic; vertices are numbered in order of first use by the output triangles.
/// The result can be empty (cells larger than the model), non-manifold and self-intersecting;
/// thin parts thinner than a cell collapse into sheets, and parts smaller than a cell vanish.
///
/// Throws InvalidInputError (empty file name) if the cell size is not finite and > 0, would
/// make more than 2^21 - 1 cells along an axis (below about 5e-7), or the mesh has no triangle, an index out of range
/// or a non-finite used coordinate. A mesh whose used vertices are all one point gives an
/// empty result.
VertexClusteringResult cluster_vertices(const TriangleMesh& mesh, const VertexClusteringOptions& options);

}  // namespace visproxy
