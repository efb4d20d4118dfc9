#pragma once
// Combinatorial structure of an indexed triangle mesh: edges, components, manifoldness,
// orientation. Pure index arithmetic: no coordinates are looked at.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "mesh/triangle_mesh.h"

namespace visproxy {

struct MeshTopology {
  std::size_t referenced_vertices = 0;    ///< vertices used by at least one triangle
  std::size_t edges = 0;                  ///< distinct undirected edges
  std::size_t boundary_edges = 0;         ///< edges with exactly one incident triangle
  std::size_t non_manifold_edges = 0;     ///< edges with three or more incident triangles
  std::size_t non_manifold_vertices = 0;  ///< vertices whose triangles form more than one edge-connected fan
  std::size_t inconsistent_edges = 0;     ///< two-triangle edges that both triangles traverse the same way
  std::size_t components = 0;             ///< connected components (triangles sharing a vertex are connected)

  bool closed() const { return boundary_edges == 0; }
  bool manifold() const { return non_manifold_edges == 0 && non_manifold_vertices == 0; }
  bool consistently_oriented() const { return inconsistent_edges == 0; }
  /// V - E + F over referenced vertices.
  std::int64_t euler_characteristic(std::size_t triangles) const {
    return static_cast<std::int64_t>(referenced_vertices) - static_cast<std::int64_t>(edges) +
           static_cast<std::int64_t>(triangles);
  }
};

/// Edge and vertex structure of `mesh`. Edges from a triangle to itself (a triangle with
/// a repeated index) are ignored. O(#F log #F).
MeshTopology analyze_topology(const TriangleMesh& mesh);

/// Connected component of each triangle (#F entries, numbered 0.. in order of first
/// appearance); triangles that share a vertex index are in the same component.
std::vector<std::uint32_t> triangle_components(const TriangleMesh& mesh, std::size_t* component_count = nullptr);

/// One mesh per connected component (in the order of triangle_components), each holding
/// only the vertices its triangles use, in their original order.
std::vector<TriangleMesh> split_components(const TriangleMesh& mesh);

}  // namespace visproxy
