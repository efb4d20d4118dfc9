#include "visproxy/mesh/mesh_topology.h"

#include <gtest/gtest.h>

#include <array>
#include <map>
#include <numeric>
#include <set>
#include <string>
#include <vector>
#include <optional>

#include "visproxy/core/errors.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/mesh/subdivide.h"
#include "test_meshes.h"

namespace visproxy {
namespace {

TEST(MeshTopology, ClosedTetrahedronAndCube) {
  for (const TriangleMesh& mesh : {testing::tetrahedron(), testing::unit_cube()}) {
    const MeshTopology topology = analyze_topology(mesh);
    EXPECT_TRUE(topology.closed());
    EXPECT_TRUE(topology.manifold());
    EXPECT_TRUE(topology.consistently_oriented());
    EXPECT_EQ(topology.components, 1u);
    EXPECT_EQ(topology.euler_characteristic(mesh.triangles.size()), 2);
  }
  EXPECT_EQ(analyze_topology(testing::unit_cube()).edges, 18u);
}

TEST(MeshTopology, OpenMeshHasBoundaryEdges) {
  TriangleMesh mesh = testing::tetrahedron();
  mesh.triangles.pop_back();
  const MeshTopology topology = analyze_topology(mesh);
  EXPECT_EQ(topology.boundary_edges, 3u);
  EXPECT_FALSE(topology.closed());
  EXPECT_TRUE(topology.manifold());
}

TEST(MeshTopology, FlippedTriangleMakesThreeInconsistentEdges) {
  TriangleMesh mesh = testing::tetrahedron();
  std::swap(mesh.triangles[3][0], mesh.triangles[3][1]);
  EXPECT_EQ(analyze_topology(mesh).inconsistent_edges, 3u);
}

TEST(EdgeBalance, ClosedMeshesAreBalancedOpenOrFlippedOnesAreNot) {
  EXPECT_TRUE(check_edge_balance(testing::unit_cube()).balanced());
  EXPECT_EQ(analyze_topology(testing::unit_cube()).unbalanced_edges, 0u);
  TriangleMesh open = testing::tetrahedron();
  open.triangles.pop_back();  // {1, 2, 3}: edges 1-2, 2-3, 3-1 used once
  const EdgeBalance balance = check_edge_balance(open);
  EXPECT_EQ(balance.unbalanced_edges, 3u);
  EXPECT_EQ(balance.first_low, 1u);
  EXPECT_EQ(balance.first_high, 2u);
  EXPECT_EQ(balance.first_forward + balance.first_backward, 1u);
  TriangleMesh flipped = testing::tetrahedron();
  std::swap(flipped.triangles[3][0], flipped.triangles[3][1]);
  EXPECT_EQ(check_edge_balance(flipped).unbalanced_edges, 3u);
  // Two cubes sharing an edge (non-manifold there) and a triangle with a repeated index
  // are still closed: every edge is used as often each way.
  TriangleMesh two = testing::unit_cube();
  TriangleMesh second = testing::unit_cube();
  for (Vertex& p : second.positions) p += Vertex(1, 1, 0);
  append_mesh(two, second);
  two = weld_vertices(two);
  EXPECT_GT(analyze_topology(two).non_manifold_edges, 0u);
  EXPECT_TRUE(check_edge_balance(two).balanced());
  TriangleMesh repeated = testing::unit_cube();
  repeated.triangles.push_back({0, 0, 7});
  EXPECT_TRUE(check_edge_balance(repeated).balanced());
}

// The grouped count against a plain count of every directed edge, on meshes torn at random
// (triangles dropped, flipped, repeated), and with an index beyond the vertices.
TEST(EdgeBalance, AgreesWithAPlainCountOnTornMeshes) {
  const TriangleMesh sphere = subdivide_midpoint(testing::unit_cube(), 3);  // 768 triangles, closed
  std::uint64_t state = 12345;
  auto next = [&](std::uint64_t n) { state = state * 6364136223846793005ull + 1442695040888963407ull; return (state >> 33) % n; };
  for (int round = 0; round < 30; ++round) {
    TriangleMesh torn = sphere;
    for (int k = 0; k < round; ++k) {
      const std::size_t t = next(torn.triangles.size());
      switch (next(3)) {
        case 0: torn.triangles.erase(torn.triangles.begin() + static_cast<std::ptrdiff_t>(t)); break;
        case 1: std::swap(torn.triangles[t][0], torn.triangles[t][1]); break;
        default: torn.triangles.push_back(torn.triangles[t]); break;
      }
    }
    if (round == 29) torn.triangles.push_back({0, 1, static_cast<VertexIndex>(torn.positions.size() + 5)});
    std::map<std::pair<VertexIndex, VertexIndex>, std::array<std::size_t, 2>> uses;
    for (const Triangle& t : torn.triangles)
      for (int k = 0; k < 3; ++k) {
        const VertexIndex a = t[k], b = t[(k + 1) % 3];
        if (a != b) ++uses[{std::min(a, b), std::max(a, b)}][a > b ? 1 : 0];
      }
    std::size_t unbalanced = 0;
    std::optional<std::pair<VertexIndex, VertexIndex>> first;
    for (const auto& [edge, count] : uses)
      if (count[0] != count[1] && unbalanced++ == 0) first = edge;
    const EdgeBalance balance = check_edge_balance(torn);
    EXPECT_EQ(balance.unbalanced_edges, unbalanced) << round;
    if (first) {
      EXPECT_EQ(balance.first_low, first->first) << round;
      EXPECT_EQ(balance.first_high, first->second) << round;
      EXPECT_EQ(balance.first_forward, (uses[*first][0])) << round;
      EXPECT_EQ(balance.first_backward, (uses[*first][1])) << round;
    }
  }
}

// The topology by plain maps and one union-find over every corner, as the definitions
// read: the reference analyze_topology() must match, whatever the defects.
MeshTopology plain_topology(const TriangleMesh& mesh) {
  MeshTopology topology;
  struct Use {
    std::size_t triangle;
    bool forward;
  };
  std::map<std::pair<VertexIndex, VertexIndex>, std::vector<Use>> uses;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const VertexIndex a = mesh.triangles[t][k], b = mesh.triangles[t][(k + 1) % 3];
      if (a != b) uses[{std::min(a, b), std::max(a, b)}].push_back({t, a < b});
    }
  std::vector<std::size_t> parent(3 * mesh.triangles.size());
  std::iota(parent.begin(), parent.end(), std::size_t{0});
  const auto find = [&](std::size_t i) {
    while (parent[i] != i) i = parent[i];
    return i;
  };
  const auto first_corner = [&](std::size_t t, VertexIndex v) {
    for (std::size_t k = 0; k < 3; ++k)
      if (mesh.triangles[t][k] == v) return 3 * t + k;
    return std::size_t{0};
  };
  for (const auto& [edge, list] : uses) {
    ++topology.edges;
    std::size_t forward = 0;
    for (const Use& use : list) forward += use.forward ? 1 : 0;
    if (list.size() == 1) ++topology.boundary_edges;
    if (list.size() > 2) ++topology.non_manifold_edges;
    if (2 * forward != list.size()) ++topology.unbalanced_edges;
    if (list.size() != 2) continue;
    if (list[0].forward == list[1].forward) ++topology.inconsistent_edges;
    for (const VertexIndex end : {edge.first, edge.second})
      parent[find(first_corner(list[0].triangle, end))] = find(first_corner(list[1].triangle, end));
  }
  std::map<VertexIndex, std::set<std::size_t>> fans;
  for (std::size_t corner = 0; corner < parent.size(); ++corner) fans[mesh.triangles[corner / 3][corner % 3]].insert(find(corner));
  topology.referenced_vertices = fans.size();
  for (const auto& [vertex, roots] : fans) topology.non_manifold_vertices += roots.size() > 1 ? 1 : 0;
  triangle_components(mesh, &topology.components);
  return topology;
}

void expect_same_topology(const MeshTopology& got, const MeshTopology& want, const std::string& label) {
  EXPECT_EQ(got.referenced_vertices, want.referenced_vertices) << label;
  EXPECT_EQ(got.edges, want.edges) << label;
  EXPECT_EQ(got.boundary_edges, want.boundary_edges) << label;
  EXPECT_EQ(got.non_manifold_edges, want.non_manifold_edges) << label;
  EXPECT_EQ(got.non_manifold_vertices, want.non_manifold_vertices) << label;
  EXPECT_EQ(got.inconsistent_edges, want.inconsistent_edges) << label;
  EXPECT_EQ(got.components, want.components) << label;
  EXPECT_EQ(got.unbalanced_edges, want.unbalanced_edges) << label;
}

// Torn, flipped, duplicated, pinched (two vertices made one: bow ties and non-manifold
// edges) and collapsed (a repeated index) triangles on a closed 768-triangle sphere.
TEST(MeshTopology, AgreesWithPlainMapsOnTornMeshes) {
  const TriangleMesh sphere = subdivide_midpoint(testing::unit_cube(), 3);  // 768 triangles, closed
  expect_same_topology(analyze_topology(sphere), plain_topology(sphere), "sphere");
  // Collapsed triangles alone: an edge used twice by one triangle joins no fans, so the
  // triangle's two corners at a vertex stay two fans.
  for (const std::vector<Triangle>& triangles : std::vector<std::vector<Triangle>>{{{0, 0, 1}}, {{0, 1, 0}, {0, 1, 2}}, {{1, 1, 1}}}) {
    TriangleMesh collapsed;
    collapsed.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    collapsed.triangles = triangles;
    const MeshTopology want = plain_topology(collapsed);
    expect_same_topology(analyze_topology(collapsed), want, "collapsed " + std::to_string(triangles.size()));
    if (triangles.size() == 1 && triangles[0][0] != triangles[0][2]) {
      EXPECT_EQ(want.non_manifold_vertices, 1u);
    }
  }
  EXPECT_EQ(analyze_topology(sphere).boundary_edges, 0u);
  std::uint64_t state = 777;
  auto next = [&](std::uint64_t n) { state = state * 6364136223846793005ull + 1442695040888963407ull; return (state >> 33) % n; };
  std::size_t seen[5] = {};  // rounds with boundary, non-manifold edges, non-manifold vertices, inconsistent, unbalanced
  for (int round = 0; round < 60; ++round) {
    TriangleMesh torn = sphere;
    for (int k = 0; k < 1 + round / 4; ++k) {
      const std::size_t t = next(torn.triangles.size());
      switch (next(5)) {
        case 0: torn.triangles.erase(torn.triangles.begin() + static_cast<std::ptrdiff_t>(t)); break;
        case 1: std::swap(torn.triangles[t][0], torn.triangles[t][1]); break;
        case 2: torn.triangles.push_back(torn.triangles[t]); break;
        case 3: {  // pinch: every use of one vertex becomes another's
          const auto from = static_cast<VertexIndex>(next(torn.positions.size())), to = static_cast<VertexIndex>(next(torn.positions.size()));
          for (Triangle& triangle : torn.triangles)
            for (VertexIndex& v : triangle)
              if (v == from) v = to;
          break;
        }
        default: torn.triangles[t][next(3)] = torn.triangles[t][next(3)]; break;  // collapse a corner onto another
      }
    }
    const MeshTopology got = analyze_topology(torn), want = plain_topology(torn);
    expect_same_topology(got, want, "round " + std::to_string(round));
    seen[0] += want.boundary_edges > 0, seen[1] += want.non_manifold_edges > 0, seen[2] += want.non_manifold_vertices > 0;
    seen[3] += want.inconsistent_edges > 0, seen[4] += want.unbalanced_edges > 0;
  }
  for (const std::size_t rounds : seen) EXPECT_GE(rounds, 5u);  // every kind of defect was met
}

TEST(MeshTopology, ATriangleBeyondThePositionsIsRefused) {
  TriangleMesh mesh = testing::tetrahedron();
  mesh.triangles.push_back({0, 1, 7});
  try {
    analyze_topology(mesh);
    FAIL() << "no error";
  } catch (const InvalidInputError& error) {
    EXPECT_NE(std::string(error.what()).find("vertex 7 of a mesh with 4 vertices"), std::string::npos) << error.what();
  }
}

TEST(MeshTopology, MoreTrianglesThanCornerIndicesHoldAreRefused) {
  EXPECT_NO_THROW(require_topology_size(kMaxTopologyTriangles));
  try {
    require_topology_size(kMaxTopologyTriangles + 1);
    FAIL() << "no error";
  } catch (const InvalidInputError& error) {
    EXPECT_NE(std::string(error.what()).find("1431655766 triangles"), std::string::npos) << error.what();
  }
}

TEST(MeshTopology, ThreeTrianglesOnOneEdgeAreNonManifold) {
  TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  mesh.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  const MeshTopology topology = analyze_topology(mesh);
  EXPECT_EQ(topology.non_manifold_edges, 1u);
  EXPECT_FALSE(topology.manifold());
}

TEST(MeshTopology, TwoTetrahedraTouchingAtAVertexMakeOneNonManifoldVertex) {
  TriangleMesh mesh = testing::tetrahedron();
  const TriangleMesh other = testing::tetrahedron();
  // Second tetrahedron mirrored through the origin, sharing vertex 0.
  for (std::size_t v = 1; v < 4; ++v) mesh.positions.push_back(-other.positions[v]);
  for (Triangle t : other.triangles) {
    for (VertexIndex& i : t) i = i == 0 ? 0 : i + 3;
    mesh.triangles.push_back(t);
  }
  const MeshTopology topology = analyze_topology(mesh);
  EXPECT_EQ(topology.non_manifold_vertices, 1u);
  EXPECT_EQ(topology.non_manifold_edges, 0u);
  EXPECT_EQ(topology.components, 1u);  // joined by the shared vertex
  EXPECT_TRUE(topology.closed());
}

TEST(MeshTopology, ComponentsAndUnreferencedVertices) {
  TriangleMesh mesh = testing::tetrahedron();
  const TriangleMesh cube = testing::unit_cube();
  const auto offset = static_cast<VertexIndex>(mesh.positions.size());
  mesh.positions.push_back({9, 9, 9});  // unreferenced
  for (const Vertex& p : cube.positions) mesh.positions.push_back(p + Vertex(5, 0, 0));
  for (Triangle t : cube.triangles) {
    for (VertexIndex& i : t) i += offset + 1;
    mesh.triangles.push_back(t);
  }
  std::size_t count = 0;
  const auto components = triangle_components(mesh, &count);
  EXPECT_EQ(count, 2u);
  EXPECT_EQ(components.front(), 0u);
  EXPECT_EQ(components.back(), 1u);
  const MeshTopology topology = analyze_topology(mesh);
  EXPECT_EQ(topology.components, 2u);
  EXPECT_EQ(topology.referenced_vertices, mesh.positions.size() - 1);
}

}  // namespace
}  // namespace visproxy

namespace visproxy {
namespace {

TEST(SplitComponents, SeparatesFarApartPartsAndAppendRejoinsThem) {
  TriangleMesh two = testing::unit_cube();
  TriangleMesh far = testing::tetrahedron();
  for (Vertex& p : far.positions) p += Vertex(100, 0, 0);
  append_mesh(two, far);
  two.positions.emplace_back(7, 7, 7);  // unreferenced: belongs to no part
  ASSERT_EQ(two.triangles.size(), 16u);

  const std::vector<TriangleMesh> parts = split_components(two);
  ASSERT_EQ(parts.size(), 2u);
  EXPECT_EQ(parts[0], testing::unit_cube());
  EXPECT_EQ(parts[1], far);

  TriangleMesh rejoined;
  for (const TriangleMesh& part : parts) append_mesh(rejoined, part);
  two.positions.pop_back();
  EXPECT_EQ(rejoined, two);
  EXPECT_TRUE(split_components(TriangleMesh{}).empty());
}

}  // namespace
}  // namespace visproxy
