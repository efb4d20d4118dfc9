#pragma once
// Combinatorial structure of an indexed triangle mesh: edges, components, manifoldness,
// orientation. Pure index arithmetic: no coordinates are looked at.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

struct MeshTopology {
  std::size_t referenced_vertices = 0;    ///< vertices used by at least one triangle
  std::size_t edges = 0;                  ///< distinct undirected edges
  std::size_t boundary_edges = 0;         ///< edges with exactly one incident triangle
  std::size_t non_manifold_edges = 0;     ///< edges with three or more incident triangles
  std::size_t non_manifold_vertices = 0;  ///< vertices whose triangles form more than one edge-connected fan
  std::size_t inconsistent_edges = 0;     ///< two-triangle edges that both triangles traverse the same way
  std::size_t components = 0;             ///< connected components (triangles sharing a vertex are connected)
  /// Edges not used as often in one direction as in the other (EdgeBalance): 0 when the
  /// mesh bounds a solid, even where it self-intersects or has non-manifold edges.
  std::size_t unbalanced_edges = 0;

  bool closed() const { return boundary_edges == 0; }
  bool manifold() const { return non_manifold_edges == 0 && non_manifold_vertices == 0; }
  bool consistently_oriented() const { return inconsistent_edges == 0; }
  /// V - E + F over referenced vertices.
  std::int64_t euler_characteristic(std::size_t triangles) const {
    return static_cast<std::int64_t>(referenced_vertices) - static_cast<std::int64_t>(edges) +
           static_cast<std::int64_t>(triangles);
  }
};

/// The most triangles the topology functions take: corners (3 per triangle) are numbered
/// with 32 bits.
inline constexpr std::size_t kMaxTopologyTriangles = 0xFFFFFFFFull / 3;

/// Throws InvalidInputError (empty file name) naming `triangles` when it is above
/// kMaxTopologyTriangles; every function below calls it first.
void require_topology_size(std::size_t triangles);

/// Edge and vertex structure of `mesh`. Edges from a triangle to itself (a triangle with
/// a repeated index) are ignored. Linear in #F and #V but for sorts of each vertex's
/// edges and corners. Throws InvalidInputError (empty file name) for a triangle that
/// refers to a vertex beyond the positions.
MeshTopology analyze_topology(const TriangleMesh& mesh);

/// Whether every edge is used as often in one direction as in the other: the condition
/// under which a triangle mesh is a closed surface (a 2-cycle) whose winding number is
/// constant off the surface, so that its solid {winding number != 0} is well defined, even
/// where it self-intersects or has non-manifold edges. An open edge (boundary) or two
/// triangles that traverse an edge the same way both break it. Edges from a vertex to
/// itself are ignored. O(#F log #F).
struct EdgeBalance {
  std::size_t unbalanced_edges = 0;
  /// The unbalanced edge with the smallest (low, high) vertex pair, and how often it is
  /// used from low to high and from high to low.
  VertexIndex first_low = 0, first_high = 0;
  std::size_t first_forward = 0, first_backward = 0;
  bool balanced() const { return unbalanced_edges == 0; }
};
EdgeBalance check_edge_balance(const TriangleMesh& mesh);

/// Connected component of each triangle (#F entries, numbered 0.. in order of first
/// appearance); triangles that share a vertex index are in the same component.
std::vector<std::uint32_t> triangle_components(const TriangleMesh& mesh, std::size_t* component_count = nullptr);

/// One mesh per connected component (in the order of triangle_components), each holding
/// only the vertices its triangles use, in their original order.
std::vector<TriangleMesh> split_components(const TriangleMesh& mesh);

}  // namespace visproxy
