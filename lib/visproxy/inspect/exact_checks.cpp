// The only translation unit of lib/inspect that includes CGAL.

#include "visproxy/inspect/exact_checks.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/intersections.h>

#include <algorithm>

namespace visproxy {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Segment = Kernel::Segment_3;
using CgalTriangle = Kernel::Triangle_3;
using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::uint32_t>;

Point point(const TriangleMesh& mesh, VertexIndex v) {
  const Vertex& p = mesh.positions[v];
  return {p.x(), p.y(), p.z()};
}

// Do triangles a and b (non-degenerate) meet outside what they share by index?
bool triangles_intersect(const TriangleMesh& mesh, const Triangle& a, const Triangle& b) {
  int shared = 0;
  int a_shared[3] = {-1, -1, -1};  // for each corner of a, the matching corner of b
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (a[i] == b[j]) {
        a_shared[i] = j;
        ++shared;
      }
  const CgalTriangle ta(point(mesh, a[0]), point(mesh, a[1]), point(mesh, a[2]));
  const CgalTriangle tb(point(mesh, b[0]), point(mesh, b[1]), point(mesh, b[2]));
  if (shared == 0) return CGAL::do_intersect(ta, tb);
  if (shared == 3) return true;  // the same triangle twice
  if (shared == 2) {
    // Common edge pq; they overlap iff the opposite corners r, s are coplanar with pq and on the same side.
    int r = 0;
    while (a_shared[r] >= 0) ++r;
    int s = 0;
    while (s == a_shared[(r + 1) % 3] || s == a_shared[(r + 2) % 3]) ++s;
    const Point p = point(mesh, a[(r + 1) % 3]);
    const Point q = point(mesh, a[(r + 2) % 3]);
    const Point pr = point(mesh, a[r]);
    const Point ps = point(mesh, b[s]);
    return CGAL::coplanar(p, q, pr, ps) && CGAL::coplanar_orientation(p, q, pr, ps) == CGAL::POSITIVE;
  }
  // One common vertex: they meet elsewhere iff the edge of either opposite the common
  // vertex meets the other triangle.
  int v = 0;
  while (a_shared[v] < 0) ++v;
  const int w = a_shared[v];
  const Segment a_opposite(point(mesh, a[(v + 1) % 3]), point(mesh, a[(v + 2) % 3]));
  const Segment b_opposite(point(mesh, b[(w + 1) % 3]), point(mesh, b[(w + 2) % 3]));
  return CGAL::do_intersect(a_opposite, tb) || CGAL::do_intersect(b_opposite, ta);
}

bool is_degenerate(const TriangleMesh& mesh, const Triangle& t) {
  return CGAL::collinear(point(mesh, t[0]), point(mesh, t[1]), point(mesh, t[2]));
}

}  // namespace

std::vector<std::uint32_t> find_degenerate_triangles(const TriangleMesh& mesh) {
  std::vector<std::uint32_t> degenerate;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    if (is_degenerate(mesh, mesh.triangles[t])) degenerate.push_back(static_cast<std::uint32_t>(t));
  return degenerate;
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> find_self_intersections(const TriangleMesh& mesh) {
  std::vector<Box> boxes;
  boxes.reserve(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& triangle = mesh.triangles[t];
    if (is_degenerate(mesh, triangle)) continue;
    const CGAL::Bbox_3 box = point(mesh, triangle[0]).bbox() + point(mesh, triangle[1]).bbox() +
                             point(mesh, triangle[2]).bbox();
    boxes.emplace_back(box, static_cast<std::uint32_t>(t));
  }
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  CGAL::box_self_intersection_d(boxes.begin(), boxes.end(), [&](const Box& a, const Box& b) {
    if (triangles_intersect(mesh, mesh.triangles[a.info()], mesh.triangles[b.info()]))
      pairs.emplace_back(std::min(a.info(), b.info()), std::max(a.info(), b.info()));
  });
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

}  // namespace visproxy
