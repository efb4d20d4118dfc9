#include "visproxy/mesh/mesh_topology.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <numeric>
#include <string>
#include <vector>

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

// Each vertex's corners (3 * triangle + k, with the triangle's next and previous
// vertices), in increasing order: corners[start[v], start[v + 1]). A counting sort:
// linear, with one scattered write per corner, and the work on a vertex then reads only
// its own corners. Every index must be below vertex_count.
struct Corner {
  std::uint32_t corner;
  VertexIndex next, previous;
};
struct CornersByVertex {
  std::vector<std::uint32_t> start;
  std::vector<Corner> corners;
};

CornersByVertex corners_by_vertex(const std::vector<Triangle>& triangles, std::size_t vertex_count) {
  CornersByVertex by;
  by.start.assign(vertex_count + 1, 0);
  for (const Triangle& t : triangles)
    for (const VertexIndex v : t) ++by.start[v + 1];
  for (std::size_t v = 0; v < vertex_count; ++v) by.start[v + 1] += by.start[v];
  by.corners.resize(3 * triangles.size());
  std::vector<std::uint32_t> fill(by.start.begin(), by.start.end() - 1);
  for (std::uint32_t t = 0; t < triangles.size(); ++t) {
    const Triangle& triangle = triangles[t];
    by.corners[fill[triangle[0]]++] = {3 * t, triangle[1], triangle[2]};
    by.corners[fill[triangle[1]]++] = {3 * t + 1, triangle[2], triangle[0]};
    by.corners[fill[triangle[2]]++] = {3 * t + 2, triangle[0], triangle[1]};
  }
  return by;
}

// One use of an edge at a vertex v: the other end, v's first corner in the use's triangle
// (its number among v's corners), and whether the use runs from the lower vertex to the
// higher.
struct EdgeUse {
  VertexIndex other;
  std::uint32_t corner;
  bool forward;
};

// The uses of the edges at v (every triangle with an edge at v has a corner there), from
// its `count` corners at `first`, sorted by (other end, corner). Edges from a vertex to
// itself are left out.
void edge_uses_at(VertexIndex v, const Corner* first, std::size_t count, std::vector<EdgeUse>& uses) {
  uses.clear();
  for (std::uint32_t i = 0; i < count; ++i) {
    const std::uint32_t base = first[i].corner - first[i].corner % 3;
    // The triangle's first corner at v: v's corners come in increasing order, so those of
    // one triangle are next to each other.
    std::uint32_t local = i;
    while (local > 0 && first[local - 1].corner >= base) --local;
    const VertexIndex next = first[i].next, previous = first[i].previous;
    if (next != v) uses.push_back({next, local, v < next});              // the edge from this corner
    if (previous != v) uses.push_back({previous, local, previous < v});  // the edge into it
  }
  std::sort(uses.begin(), uses.end(),
            [](const EdgeUse& a, const EdgeUse& b) { return a.other != b.other ? a.other < b.other : a.corner < b.corner; });
}

}  // namespace

void require_topology_size(std::size_t triangles) {
  if (triangles > kMaxTopologyTriangles)
    throw InvalidInputError("", std::to_string(triangles) + " triangles: the mesh topology handles at most " +
                                    std::to_string(kMaxTopologyTriangles) + " (corners are numbered with 32 bits)");
}

EdgeBalance check_edge_balance(const TriangleMesh& mesh) {
  require_topology_size(mesh.triangles.size());
  EdgeBalance balance;
  // The edges at each vertex from its corners, in linear time but for the small sorts of
  // each vertex's edges. Indices beyond the vertices (a malformed mesh) are grouped by one
  // sort of whole keys, each use of an edge (low, high) as (low << 33 | high << 1 |
  // backward), instead.
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
    // Vertex by vertex in parallel (edge_uses_at); the edges at v above v are its own.
    const CornersByVertex by = corners_by_vertex(mesh.triangles, mesh.positions.size());
    struct Found {
      std::size_t unbalanced = 0;
      EdgeBalance first;  // at the lowest vertex with an unbalanced edge
    };
    const Found found = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, mesh.positions.size(), 2048), Found{},
        [&](const tbb::blocked_range<std::size_t>& range, Found sum) {
          std::vector<EdgeUse> uses;
          for (std::size_t vi = range.begin(); vi < range.end(); ++vi) {
            const auto v = static_cast<VertexIndex>(vi);
            edge_uses_at(v, by.corners.data() + by.start[v], by.start[v + 1] - by.start[v], uses);
            for (std::size_t b = 0; b < uses.size();) {
              std::size_t e = b, forward = 0;
              for (; e < uses.size() && uses[e].other == uses[b].other; ++e) forward += uses[e].forward ? 1 : 0;
              if (uses[b].other > v && 2 * forward != e - b && sum.unbalanced++ == 0)
                sum.first = {0, v, uses[b].other, forward, e - b - forward};
              b = e;
            }
          }
          return sum;
        },
        [](Found a, const Found& b) {  // ranges join in order: a is the lower
          if (a.unbalanced == 0) a.first = b.first;
          a.unbalanced += b.unbalanced;
          return a;
        });
    balance = found.first;
    balance.unbalanced_edges = found.unbalanced;
    return balance;
  }
  // Equal edges sort together.
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
  const std::vector<Triangle>& triangles = mesh.triangles;
  if (triangles.empty()) return topology;
  VertexIndex largest = 0;
  for (const Triangle& t : triangles) largest = std::max({largest, t[0], t[1], t[2]});
  if (largest >= mesh.positions.size())
    throw InvalidInputError("", "a triangle refers to vertex " + std::to_string(largest) + " of a mesh with " +
                                    std::to_string(mesh.positions.size()) + " vertices");
  const std::size_t vertex_count = mesh.positions.size();

  // Vertex by vertex in parallel, from each vertex's corners (edge_uses_at); an edge
  // (v, w) is counted at its lower vertex.
  const CornersByVertex by = corners_by_vertex(triangles, vertex_count);
  using Counts = std::array<std::size_t, 7>;  // the MeshTopology counts in the order below
  const Counts counts = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, vertex_count, 2048), Counts{},
      [&](const tbb::blocked_range<std::size_t>& range, Counts sum) {
        std::vector<EdgeUse> uses;
        std::vector<std::uint32_t> fan;  // union-find over v's corners, by their number
        for (std::size_t vi = range.begin(); vi < range.end(); ++vi) {
          const auto v = static_cast<VertexIndex>(vi);
          const std::size_t count = by.start[v + 1] - by.start[v];
          if (count == 0) continue;
          ++sum[0];  // referenced
          edge_uses_at(v, by.corners.data() + by.start[v], count, uses);
          fan.resize(count);
          std::iota(fan.begin(), fan.end(), std::uint32_t{0});
          const auto root = [&](std::uint32_t i) {
            while (fan[i] != i) i = fan[i] = fan[fan[i]];
            return i;
          };
          // Corners around v are joined across two-triangle edges; more than one fan left
          // means v is non-manifold.
          for (std::size_t b = 0; b < uses.size();) {
            std::size_t e = b;
            std::size_t forward = 0;
            for (; e < uses.size() && uses[e].other == uses[b].other; ++e) forward += uses[e].forward ? 1 : 0;
            const std::size_t incident = e - b;
            if (incident == 2) fan[root(uses[b].corner)] = root(uses[b + 1].corner);
            if (uses[b].other > v) {
              ++sum[1];                                                        // edges
              if (incident == 1) ++sum[2];                                     // boundary
              if (incident > 2) ++sum[3];                                      // non-manifold
              if (incident == 2 && uses[b].forward == uses[b + 1].forward) ++sum[4];  // inconsistent
              if (2 * forward != incident) ++sum[5];                           // unbalanced
            }
            b = e;
          }
          std::size_t fans = 0;
          for (std::uint32_t i = 0; i < count; ++i) fans += root(i) == i ? 1 : 0;
          if (fans > 1) ++sum[6];  // non-manifold vertex
        }
        return sum;
      },
      [](Counts a, const Counts& b) {
        for (std::size_t i = 0; i < a.size(); ++i) a[i] += b[i];
        return a;
      });
  topology.referenced_vertices = counts[0];
  topology.edges = counts[1];
  topology.boundary_edges = counts[2];
  topology.non_manifold_edges = counts[3];
  topology.inconsistent_edges = counts[4];
  topology.unbalanced_edges = counts[5];
  topology.non_manifold_vertices = counts[6];
  triangle_components(mesh, &topology.components);
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
