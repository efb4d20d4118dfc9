#include "visproxy/proxy/detail/triangle_soup.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

namespace visproxy {

SoupPrimitives soup_primitives(const TriangleMesh& mesh) {
  using Point = CGAL::Exact_predicates_inexact_constructions_kernel::Point_3;
  SoupPrimitives result;
  for (std::uint32_t index = 0; index < mesh.triangles.size(); ++index) {
    const Triangle& t = mesh.triangles[index];
    const Vertex& a = mesh.positions[t[0]];
    const Vertex& b = mesh.positions[t[1]];
    const Vertex& c = mesh.positions[t[2]];
    const Point pa(a.x(), a.y(), a.z());
    const Point pb(b.x(), b.y(), b.z());
    const Point pc(c.x(), c.y(), c.z());
    if (!CGAL::collinear(pa, pb, pc)) {
      result.triangle_indices.push_back(index);
    } else if (pa == pb && pb == pc) {
      result.points.push_back(a);
    } else if (CGAL::collinear_are_ordered_along_line(pa, pb, pc)) {  // b between a and c
      result.segments.emplace_back(a, c);
    } else if (CGAL::collinear_are_ordered_along_line(pb, pa, pc)) {
      result.segments.emplace_back(b, c);
    } else {
      result.segments.emplace_back(a, b);
    }
  }
  return result;
}

}  // namespace visproxy
