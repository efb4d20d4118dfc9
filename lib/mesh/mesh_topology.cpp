#include "visproxy/mesh/mesh_topology.h"

#include <algorithm>
#include <numeric>
#include <string>

#include "visproxy/core/errors.h"

namespace visproxy {
namespace {

// Union-find with path halving and union by size.
class DisjointSets {
 public:
  explicit DisjointSets(std::size_t count) : parent_(count), size_(count, 1) {
    std::iota(parent_.begin(), parent_.end(), std::uint32_t{0});
  }
  std::uint32_t find(std::uint32_t x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  void unite(std::uint32_t a, std::uint32_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return;
    if (size_[a] < size_[b]) std::swap(a, b);
    parent_[b] = a;
    size_[a] += size_[b];
  }

 private:
  std::vector<std::uint32_t> parent_;
  std::vector<std::uint32_t> size_;
};

struct HalfEdge {
  std::uint64_t key;    // (smaller vertex << 32) | larger vertex
  std::uint32_t corner;  // 3 * triangle + k: the edge runs from corner k to corner k+1
  bool forward;          // runs from the smaller vertex to the larger
};

}  // namespace

void require_topology_size(std::size_t triangles) {
  if (triangles > kMaxTopologyTriangles)
    throw InvalidInputError("", std::to_string(triangles) + " triangles: the mesh topology handles at most " +
                                    std::to_string(kMaxTopologyTriangles) + " (corners are numbered with 32 bits)");
}

EdgeBalance check_edge_balance(const TriangleMesh& mesh) {
  require_topology_size(mesh.triangles.size());
  EdgeBalance balance;
  // Each use of an edge (low, high) as (high << 1 | backward), grouped by its low vertex
  // (a counting sort), then sorted within the group: the edges come in (low, high) order,
  // in linear time but for the small sorts. Indices beyond the vertices (a malformed mesh)
  // are grouped by one sort of whole keys instead.
  VertexIndex largest = 0;
  for (const Triangle& t : mesh.triangles) largest = std::max({largest, t[0], t[1], t[2]});
  auto tally = [&](VertexIndex low, const std::uint64_t* begin, const std::uint64_t* end) {
    for (const std::uint64_t* at = begin; at != end;) {
      const std::uint64_t* next = at;
      std::size_t backward = 0;
      for (; next != end && (*next >> 1) == (*at >> 1); ++next) backward += *next & 1u;
      const std::size_t forward = static_cast<std::size_t>(next - at) - backward;
      if (forward != backward && balance.unbalanced_edges++ == 0) {
        balance.first_low = low;
        balance.first_high = static_cast<VertexIndex>(*at >> 1);
        balance.first_forward = forward;
        balance.first_backward = backward;
      }
      at = next;
    }
  };
  if (!mesh.triangles.empty() && largest < mesh.positions.size()) {
    std::vector<std::uint32_t> start(static_cast<std::size_t>(largest) + 2, 0);
    for (const Triangle& t : mesh.triangles)
      for (int k = 0; k < 3; ++k)
        if (t[k] != t[(k + 1) % 3]) ++start[std::min(t[k], t[(k + 1) % 3]) + 1];
    for (std::size_t v = 0; v + 1 < start.size(); ++v) start[v + 1] += start[v];
    std::vector<std::uint64_t> uses(start.back());
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (const Triangle& t : mesh.triangles)
      for (int k = 0; k < 3; ++k) {
        const VertexIndex a = t[k], b = t[(k + 1) % 3];
        if (a == b) continue;
        uses[fill[std::min(a, b)]++] = (static_cast<std::uint64_t>(std::max(a, b)) << 1) | (a > b ? 1u : 0u);
      }
    for (std::size_t v = 0; v + 1 < start.size(); ++v) {
      std::uint64_t* begin = uses.data() + start[v];
      std::uint64_t* end = uses.data() + start[v + 1];
      std::sort(begin, end);
      tally(static_cast<VertexIndex>(v), begin, end);
    }
    return balance;
  }
  // (low << 33 | high << 1 | backward): equal edges sort together.
  std::vector<std::uint64_t> uses;
  uses.reserve(3 * mesh.triangles.size());
  for (const Triangle& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const std::uint64_t a = t[k], b = t[(k + 1) % 3];
      if (a == b) continue;
      uses.push_back((std::min(a, b) << 33) | (std::max(a, b) << 1) | (a > b ? 1u : 0u));
    }
  std::sort(uses.begin(), uses.end());
  for (std::size_t begin = 0; begin < uses.size();) {
    std::size_t end = begin;
    const std::uint64_t low = uses[begin] >> 33;
    while (end < uses.size() && (uses[end] >> 33) == low) ++end;
    std::vector<std::uint64_t> group;
    for (std::size_t i = begin; i < end; ++i) group.push_back(uses[i] & 0x1FFFFFFFFull);
    tally(static_cast<VertexIndex>(low), group.data(), group.data() + group.size());
    begin = end;
  }
  return balance;
}

MeshTopology analyze_topology(const TriangleMesh& mesh) {
  require_topology_size(mesh.triangles.size());
  MeshTopology topology;
  const std::size_t triangle_count = mesh.triangles.size();

  std::vector<HalfEdge> half_edges;
  half_edges.reserve(3 * triangle_count);
  for (std::size_t t = 0; t < triangle_count; ++t)
    for (std::uint32_t k = 0; k < 3; ++k) {
      const VertexIndex from = mesh.triangles[t][k];
      const VertexIndex to = mesh.triangles[t][(k + 1) % 3];
      if (from == to) continue;
      const std::uint64_t low = std::min(from, to);
      const std::uint64_t high = std::max(from, to);
      half_edges.push_back({(low << 32) | high, static_cast<std::uint32_t>(3 * t + k), from < to});
    }
  std::sort(half_edges.begin(), half_edges.end(),
            [](const HalfEdge& a, const HalfEdge& b) { return a.key != b.key ? a.key < b.key : a.corner < b.corner; });

  // Corners around a vertex are joined across two-triangle edges; more than one group
  // left at a vertex means the vertex is non-manifold.
  DisjointSets corner_fans(3 * triangle_count);
  auto corner_of = [&](std::uint32_t corner, VertexIndex vertex) {
    const std::uint32_t base = corner - corner % 3;
    for (std::uint32_t k = 0; k < 3; ++k)
      if (mesh.triangles[base / 3][k] == vertex) return base + k;
    return corner;
  };
  for (std::size_t begin = 0; begin < half_edges.size();) {
    std::size_t end = begin;
    while (end < half_edges.size() && half_edges[end].key == half_edges[begin].key) ++end;
    const std::size_t incident = end - begin;
    ++topology.edges;
    if (incident == 1) ++topology.boundary_edges;
    if (incident > 2) ++topology.non_manifold_edges;
    if (incident == 2) {
      const HalfEdge& a = half_edges[begin];
      const HalfEdge& b = half_edges[begin + 1];
      if (a.forward == b.forward) ++topology.inconsistent_edges;
      const auto low = static_cast<VertexIndex>(a.key >> 32);
      const auto high = static_cast<VertexIndex>(a.key & 0xFFFFFFFFu);
      corner_fans.unite(corner_of(a.corner, low), corner_of(b.corner, low));
      corner_fans.unite(corner_of(a.corner, high), corner_of(b.corner, high));
    }
    begin = end;
  }

  std::vector<std::pair<VertexIndex, std::uint32_t>> vertex_fans;  // (vertex, fan) for every corner
  vertex_fans.reserve(3 * triangle_count);
  for (std::uint32_t corner = 0; corner < 3 * triangle_count; ++corner)
    vertex_fans.emplace_back(mesh.triangles[corner / 3][corner % 3], corner_fans.find(corner));
  std::sort(vertex_fans.begin(), vertex_fans.end());
  vertex_fans.erase(std::unique(vertex_fans.begin(), vertex_fans.end()), vertex_fans.end());
  for (std::size_t i = 0; i < vertex_fans.size(); ++i) {
    const bool first_of_vertex = i == 0 || vertex_fans[i - 1].first != vertex_fans[i].first;
    if (first_of_vertex) {
      ++topology.referenced_vertices;
    } else if (vertex_fans[i - 1].first == vertex_fans[i].first &&
               (i < 2 || vertex_fans[i - 2].first != vertex_fans[i].first)) {
      ++topology.non_manifold_vertices;  // count each vertex once, at its second fan
    }
  }

  triangle_components(mesh, &topology.components);
  topology.unbalanced_edges = check_edge_balance(mesh).unbalanced_edges;
  return topology;
}

std::vector<std::uint32_t> triangle_components(const TriangleMesh& mesh, std::size_t* component_count) {
  require_topology_size(mesh.triangles.size());
  DisjointSets vertex_sets(mesh.positions.size());
  for (const Triangle& triangle : mesh.triangles) {
    vertex_sets.unite(triangle[0], triangle[1]);
    vertex_sets.unite(triangle[0], triangle[2]);
  }
  constexpr std::uint32_t kUnassigned = UINT32_MAX;
  std::vector<std::uint32_t> component_of_root(mesh.positions.size(), kUnassigned);
  std::vector<std::uint32_t> components(mesh.triangles.size());
  std::uint32_t count = 0;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    std::uint32_t& id = component_of_root[vertex_sets.find(mesh.triangles[t][0])];
    if (id == kUnassigned) id = count++;
    components[t] = id;
  }
  if (component_count != nullptr) *component_count = count;
  return components;
}

std::vector<TriangleMesh> split_components(const TriangleMesh& mesh) {
  std::size_t count = 0;
  const std::vector<std::uint32_t> component = triangle_components(mesh, &count);
  std::vector<TriangleMesh> parts(count);
  std::vector<std::uint32_t> triangles_in(count, 0);
  for (std::uint32_t c : component) ++triangles_in[c];
  for (std::size_t c = 0; c < count; ++c) parts[c].triangles.reserve(triangles_in[c]);
  // A vertex belongs to exactly one component; number it there in original order.
  constexpr VertexIndex kUnassigned = UINT32_MAX;
  std::vector<std::uint32_t> component_of_vertex(mesh.positions.size(), kUnassigned);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (VertexIndex v : mesh.triangles[t]) component_of_vertex[v] = component[t];
  std::vector<VertexIndex> new_index(mesh.positions.size(), kUnassigned);
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    if (component_of_vertex[v] == kUnassigned) continue;
    TriangleMesh& part = parts[component_of_vertex[v]];
    new_index[v] = static_cast<VertexIndex>(part.positions.size());
    part.positions.push_back(mesh.positions[v]);
  }
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& triangle = mesh.triangles[t];
    parts[component[t]].triangles.push_back({new_index[triangle[0]], new_index[triangle[1]], new_index[triangle[2]]});
  }
  return parts;
}

}  // namespace visproxy
