// ConservativeInput's tree queries, which outer:N and inner:N trust for every change they
// make, against scans of every input triangle: the tree may only skip nodes that hold no
// triangle meeting, or within the clearance of, the query.

#include "visproxy/proxy/detail/conservative_decimation.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <random>
#include <vector>

#include "visproxy/mesh/read_mesh.h"
#include "visproxy/verify/containment.h"
#include "test_meshes.h"

namespace visproxy {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;

Kernel::Triangle_3 cgal_triangle(const TriangleMesh& mesh, const Triangle& t) {
  const auto point = [&](VertexIndex v) {
    const Vertex& p = mesh.positions[v];
    return Kernel::Point_3(p.x(), p.y(), p.z());
  };
  return {point(t[0]), point(t[1]), point(t[2])};
}

TriangleMesh single_triangle(const std::array<Vertex, 3>& corners) {
  TriangleMesh mesh;
  mesh.positions.assign(corners.begin(), corners.end());
  mesh.triangles = {{0, 1, 2}};
  return mesh;
}

// Query triangles about the input's surface: each around a random point of a random input
// triangle, moved along its normal by up to three clearances either way (a quarter of them
// not moved at all, so lying in the plane of the triangle they start from), turned at
// random, from a tenth of the clearance to a tenth of the diagonal in size.
std::vector<std::array<Vertex, 3>> queries_about(const TriangleMesh& input, double clearance, std::size_t count,
                                                 unsigned seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> gaussian;
  const double diagonal = bounding_box(input).diagonal();
  std::vector<std::array<Vertex, 3>> queries;
  for (std::size_t i = 0; i < count; ++i) {
    const Triangle& t = input.triangles[random() % input.triangles.size()];
    const Vertex& a = input.positions[t[0]];
    const Vertex& b = input.positions[t[1]];
    const Vertex& c = input.positions[t[2]];
    double u = unit(random), v = unit(random);
    if (u + v > 1) u = 1 - u, v = 1 - v;
    const Vertex normal = (b - a).cross(c - a).normalized();
    const double offset = i % 4 == 0 ? 0.0 : (2 * unit(random) - 1) * 3 * clearance;
    const Vertex centre = a + u * (b - a) + v * (c - a) + offset * normal;
    const double size = clearance / 10 * std::pow(diagonal / clearance, unit(random));
    std::array<Vertex, 3> corners;
    for (Vertex& corner : corners)
      corner = centre + size * Vertex(gaussian(random), gaussian(random), gaussian(random)).normalized();
    queries.push_back(corners);
  }
  return queries;
}

void expect_tree_queries_match_scans(const TriangleMesh& input, std::size_t count, unsigned seed) {
  const double clearance = 1e-3 * bounding_box(input).diagonal();
  const detail::ConservativeInput geometry(input);
  const std::vector<std::array<Vertex, 3>> queries = queries_about(input, clearance, count, seed);

  TriangleMesh all;
  for (const auto& corners : queries) {
    const auto first = static_cast<VertexIndex>(all.positions.size());
    all.positions.insert(all.positions.end(), corners.begin(), corners.end());
    all.triangles.push_back({first, first + 1, first + 2});
  }
  const std::vector<std::size_t> meeting = geometry.triangles_meeting(all);
  std::vector<bool> tree_meets(queries.size(), false);
  for (const std::size_t index : meeting) tree_meets[index] = true;

  std::size_t meets = 0, near = 0, clear = 0, strict_only = 0;
  for (std::size_t q = 0; q < queries.size(); ++q) {
    const Kernel::Triangle_3 query = cgal_triangle(all, all.triangles[q]);
    bool scan_meets = false;
    for (const Triangle& t : input.triangles)
      if (CGAL::do_intersect(query, cgal_triangle(input, t))) {
        scan_meets = true;
        break;
      }
    EXPECT_EQ(tree_meets[q], scan_meets) << "query " << q << " (seed " << seed << ")";

    const TriangleMesh single = single_triangle(queries[q]);
    const bool scan_clear = surfaces_clear_by(single, input, clearance);
    const bool tree_clear = geometry.keeps_clear(single, clearance);
    // keeps_clear is at least as strict as the scan, never less.
    if (!scan_clear) {
      EXPECT_FALSE(tree_clear) << "query " << q << " (seed " << seed << ")";
    }
    if (scan_clear && !tree_clear) ++strict_only;
    meets += scan_meets;
    near += !scan_meets && !scan_clear;
    clear += scan_clear;
  }
  // Every kind of answer occurs, so the comparisons above test something; and the stricter
  // allowance of keeps_clear decides only the odd query that comes that close.
  EXPECT_GT(meets, count / 10);
  EXPECT_GT(near, count / 20);
  EXPECT_GT(clear, count / 10);
  EXPECT_LE(strict_only, count / 100);
}

TEST(ConservativeInput, TreeQueriesAgreeWithScansOfEveryTriangle) {
  expect_tree_queries_match_scans(read_mesh(testing::cgal_mesh("knot1.off")), 600, 5);
}

// Far from the origin the coordinates' rounding is largest relative to the clearance:
// node boxes and the planes that prune them must keep their allowances relative.
TEST(ConservativeInput, TreeQueriesAgreeWithScansFarFromTheOrigin) {
  TriangleMesh knot = read_mesh(testing::cgal_mesh("knot1.off"));
  const double diagonal = bounding_box(knot).diagonal();
  for (Vertex& p : knot.positions) p += Vertex(3e5, -7e5, 1e6) * diagonal;
  expect_tree_queries_match_scans(knot, 600, 6);
}

}  // namespace
}  // namespace visproxy
