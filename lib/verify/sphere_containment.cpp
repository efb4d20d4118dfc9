// Exact containment of balls in a closed mesh: centre by winding number, radius against
// the exact distance to every nearby triangle (CGAL: filtered predicates, lazy exact kernel).

#include "verify/sphere_containment.h"

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

#include "core/errors.h"
#include "verify/containment.h"

namespace visproxy {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using CgalTriangle = Kernel::Triangle_3;
using Triangles = std::vector<CgalTriangle>;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, Triangles::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;
using Exact = CGAL::Exact_predicates_exact_constructions_kernel;

Point to_point(const Vertex& p) { return {p.x(), p.y(), p.z()}; }
Exact::Point_3 to_exact(const Point& p) { return {p.x(), p.y(), p.z()}; }

// Every edge used as often in one direction as in the other: the winding number is then
// well defined everywhere off the surface.
void require_closed(const TriangleMesh& mesh) {
  if (mesh.triangles.empty()) throw InvalidInputError("", "the mesh has no triangles: nothing lies inside it");
  std::vector<std::pair<std::uint64_t, int>> edges;
  edges.reserve(3 * mesh.triangles.size());
  for (const Triangle& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const VertexIndex a = t[k], b = t[(k + 1) % 3];
      if (a >= mesh.positions.size() || b >= mesh.positions.size())
        throw InvalidInputError("", "a triangle refers to vertex " + std::to_string(std::max(a, b)) +
                                        ", which does not exist");
      if (a == b) continue;
      const auto low = std::min(a, b), high = std::max(a, b);
      edges.emplace_back((std::uint64_t{low} << 32) | high, a < b ? 1 : -1);
    }
  std::sort(edges.begin(), edges.end());
  std::size_t unbalanced = 0;
  for (std::size_t i = 0; i < edges.size();) {
    int balance = 0;
    std::size_t j = i;
    for (; j < edges.size() && edges[j].first == edges[i].first; ++j) balance += edges[j].second;
    if (balance != 0) ++unbalanced;
    i = j;
  }
  if (unbalanced > 0)
    throw InvalidInputError("", std::to_string(unbalanced) +
                                    " edges are not used equally often in both directions (boundary or inconsistent "
                                    "orientation): the mesh does not bound a solid, so nothing can be proved inside it");
}

}  // namespace

SphereContainment check_spheres_inside(const TriangleMesh& watertight_mesh, std::span<const Sphere> spheres) {
  SphereContainment result;
  result.spheres_checked = spheres.size();
  require_closed(watertight_mesh);
  if (spheres.empty()) return result;

  std::vector<Vertex> centers;
  centers.reserve(spheres.size());
  for (const Sphere& sphere : spheres) centers.push_back(sphere.center.allFinite() ? sphere.center : Vertex::Zero());
  const std::vector<PointLocation> locations = locate_points(watertight_mesh, centers);

  Triangles triangles;
  triangles.reserve(watertight_mesh.triangles.size());
  for (const Triangle& t : watertight_mesh.triangles)
    triangles.emplace_back(to_point(watertight_mesh.positions[t[0]]), to_point(watertight_mesh.positions[t[1]]),
                           to_point(watertight_mesh.positions[t[2]]));
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
      // Candidates: triangles meeting the closed ball of a squared radius at least radius^2
      // (the rounded square, enlarged by more than its rounding error); decided exactly.
      const double squared_radius_up = sphere.radius * sphere.radius * (1.0 + 0x1.0p-50);
      near.clear();
      tree.all_intersected_primitives(Kernel::Sphere_3(center, squared_radius_up), std::back_inserter(near));
      if (!near.empty()) {
        const Exact::Point_3 exact_center = to_exact(center);
        const Exact::FT radius(sphere.radius);
        const Exact::FT squared_radius = radius * radius;
        for (const Tree::Primitive_id& id : near) {
          const CgalTriangle& t = *id;
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
