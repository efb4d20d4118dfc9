// Exact containment of balls in a closed mesh: centre by winding number, radius against
// the exact distance to every nearby triangle (CGAL: filtered predicates, lazy exact kernel).

#include "visproxy/verify/sphere_containment.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/mesh/mesh_topology.h"
#include "visproxy/verify/containment.h"

namespace visproxy {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using CgalTriangle = Kernel::Triangle_3;
using Triangles = std::vector<CgalTriangle>;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, Triangles::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;
using Exact = CGAL::Exact_predicates_exact_constructions_kernel;

constexpr double kHuge = std::numeric_limits<double>::infinity();

Point to_point(const Vertex& p) { return {p.x(), p.y(), p.z()}; }
Exact::Point_3 to_exact(const Point& p) { return {p.x(), p.y(), p.z()}; }

// Every edge used as often in one direction as in the other: the winding number is then
// well defined everywhere off the surface.
void require_closed(const TriangleMesh& mesh) {
  if (mesh.triangles.empty()) throw InvalidInputError("", "the mesh has no triangles: nothing lies inside it");
  for (const Triangle& t : mesh.triangles)
    for (const VertexIndex v : t)
      if (v >= mesh.positions.size())
        throw InvalidInputError("", "a triangle refers to vertex " + std::to_string(v) + ", which does not exist");
  const EdgeBalance balance = check_edge_balance(mesh);
  if (!balance.balanced())
    throw InvalidInputError("", std::to_string(balance.unbalanced_edges) +
                                    " edges are not used equally often in both directions (boundary or inconsistent "
                                    "orientation; the first is " + std::to_string(balance.first_low) + "-" +
                                    std::to_string(balance.first_high) + "): the mesh does not bound a solid, so "
                                    "nothing can be proved inside it");
}

}  // namespace

SphereContainment check_spheres_inside(const TriangleMesh& closed_mesh, std::span<const Sphere> spheres) {
  SphereContainment result;
  result.spheres_checked = spheres.size();
  require_closed(closed_mesh);
  if (spheres.empty()) return result;

  std::vector<Vertex> centers;
  centers.reserve(spheres.size());
  for (const Sphere& sphere : spheres) centers.push_back(sphere.center.allFinite() ? sphere.center : Vertex::Zero());
  const std::vector<PointLocation> locations = locate_points(closed_mesh, centers);

  Triangles triangles;
  triangles.reserve(closed_mesh.triangles.size());
  for (const Triangle& t : closed_mesh.triangles)
    triangles.emplace_back(to_point(closed_mesh.positions[t[0]]), to_point(closed_mesh.positions[t[1]]),
                           to_point(closed_mesh.positions[t[2]]));
  Tree tree(triangles.begin(), triangles.end());
  tree.build();
  tree.accelerate_distance_queries();

  result.min_margin_world = std::numeric_limits<double>::infinity();
  std::vector<Tree::Primitive_id> near;
  for (std::size_t i = 0; i < spheres.size(); ++i) {
    const Sphere& sphere = spheres[i];
    const bool finite = sphere.center.allFinite() && std::isfinite(sphere.radius) && sphere.radius >= 0;
    const Point center = to_point(centers[i]);
    const bool inside = finite && locations[i] == PointLocation::inside;
    const double distance = std::sqrt(tree.squared_distance(center));
    result.min_margin_world = std::min(result.min_margin_world, (inside ? distance : -distance) - sphere.radius);

    bool passes = inside;
    if (passes && sphere.radius > 0) {
      // Candidates: every triangle whose box meets the ball's box, which holds every
      // triangle that comes within the radius, those wholly inside the ball too (a sphere
      // query would miss them: they do not meet the sphere's surface). The box is the
      // ball's, widened by an ulp of each bound so that rounding cannot shrink it; each
      // candidate is then decided exactly. Degenerate triangles bound nothing.
      const double low[3] = {std::nextafter(center.x() - sphere.radius, -kHuge), std::nextafter(center.y() - sphere.radius, -kHuge),
                             std::nextafter(center.z() - sphere.radius, -kHuge)};
      const double high[3] = {std::nextafter(center.x() + sphere.radius, kHuge), std::nextafter(center.y() + sphere.radius, kHuge),
                              std::nextafter(center.z() + sphere.radius, kHuge)};
      near.clear();
      tree.all_intersected_primitives(CGAL::Bbox_3(low[0], low[1], low[2], high[0], high[1], high[2]), std::back_inserter(near));
      if (!near.empty()) {
        const Exact::Point_3 exact_center = to_exact(center);
        const Exact::FT radius(sphere.radius);
        const Exact::FT squared_radius = radius * radius;
        const double squared = sphere.radius * sphere.radius;
        for (const Tree::Primitive_id& id : near) {
          const CgalTriangle& t = *id;
          if (t.is_degenerate()) continue;
          // A filter: the distance in double is within 1e-12 of the largest squared distance
          // to a corner (thousands of ulps of its rounding error); triangles clearly farther
          // than the radius need no exact arithmetic.
          double reach = 0;
          for (int k = 0; k < 3; ++k) reach = std::max(reach, CGAL::squared_distance(center, t[k]));
          if (CGAL::squared_distance(center, t) - 1e-12 * reach > squared * (1 + 0x1.0p-50)) continue;
          const Exact::Triangle_3 exact_triangle(to_exact(t[0]), to_exact(t[1]), to_exact(t[2]));
          if (CGAL::squared_distance(exact_center, exact_triangle) < squared_radius) {
            passes = false;
            break;
          }
        }
      }
    }
    if (!passes) {
      ++result.spheres_outside;
      if (!result.first_outside) result.first_outside = i;
    }
  }
  if (!std::isfinite(result.min_margin_world)) result.min_margin_world = -std::numeric_limits<double>::max();
  return result;
}

}  // namespace visproxy
