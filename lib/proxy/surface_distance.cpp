// Sampled two-sided Hausdorff distance between triangle meshes, in the manner of Metro
// (P. Cignoni, C. Rocchini, R. Scopigno. Metro: measuring error on simplified surfaces.
// Computer Graphics Forum 17(2), 1998): points spread uniformly by area over one surface
// (plus its vertices) are measured to their exact closest point on the other, found with
// CGAL's AABB tree.

#include "visproxy/proxy/surface_distance.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "visproxy/core/errors.h"

namespace visproxy {
namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using CgalTriangle = Kernel::Triangle_3;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, std::vector<CgalTriangle>::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

Point point(const Vertex& p) { return {p.x(), p.y(), p.z()}; }

bool exactly_collinear(const Vertex& a, const Vertex& b, const Vertex& c) {
  using ExactPoint = CGAL::Exact_predicates_inexact_constructions_kernel::Point_3;
  return CGAL::collinear(ExactPoint(a.x(), a.y(), a.z()), ExactPoint(b.x(), b.y(), b.z()),
                         ExactPoint(c.x(), c.y(), c.z()));
}

// The parts of a mesh that are measured: its used vertices and its triangles of non-zero area.
struct Surface {
  std::vector<Point> vertices;
  std::vector<CgalTriangle> triangles;
  std::vector<double> cumulative_area;  // running sum over `triangles`
};

Surface prepare(const TriangleMesh& mesh, const char* name) {
  Surface surface;
  std::vector<std::uint8_t> used(mesh.positions.size(), 0);
  for (const Triangle& triangle : mesh.triangles) {
    for (const VertexIndex v : triangle) {
      if (v >= mesh.positions.size())
        throw InvalidInputError("", std::string("the ") + name + " mesh has a triangle corner out of range (" +
                                        std::to_string(v) + ")");
      if (used[v]) continue;
      if (!mesh.positions[v].allFinite())
        throw InvalidInputError("", std::string("the ") + name + " mesh has a non-finite vertex (" +
                                        std::to_string(v) + ")");
      used[v] = 1;
      surface.vertices.push_back(point(mesh.positions[v]));
    }
    const Vertex& a = mesh.positions[triangle[0]];
    const Vertex& b = mesh.positions[triangle[1]];
    const Vertex& c = mesh.positions[triangle[2]];
    if (exactly_collinear(a, b, c)) continue;
    surface.triangles.emplace_back(point(a), point(b), point(c));
    const double area = (b - a).cross(c - a).norm() / 2;
    surface.cumulative_area.push_back((surface.cumulative_area.empty() ? 0.0 : surface.cumulative_area.back()) + area);
  }
  if (surface.triangles.empty())
    throw InvalidInputError("", std::string("the ") + name + " mesh has no triangle of non-zero area to measure");
  return surface;
}

// Uniform double in [0, 1) from the 53 high bits (std::mt19937_64's output is fixed by the
// standard, unlike the standard distributions).
double uniform(std::mt19937_64& random) { return static_cast<double>(random() >> 11) * 0x1.0p-53; }

// Area-uniform points on `surface`, in triangle order (so that consecutive queries are near).
std::vector<Point> sample(const Surface& surface, std::size_t count, std::mt19937_64& random) {
  const double total = surface.cumulative_area.back();
  std::vector<double> picks(count);
  for (double& pick : picks) pick = uniform(random) * total;
  std::sort(picks.begin(), picks.end());
  std::vector<Point> samples;
  samples.reserve(count);
  std::size_t t = 0;
  for (const double pick : picks) {
    while (t + 1 < surface.cumulative_area.size() && surface.cumulative_area[t] <= pick) ++t;
    const CgalTriangle& triangle = surface.triangles[t];
    const double s = std::sqrt(uniform(random));
    const double r = uniform(random);
    const double wa = 1 - s, wb = s * (1 - r), wc = s * r;
    const Point& a = triangle[0];
    const Point& b = triangle[1];
    const Point& c = triangle[2];
    samples.emplace_back(wa * a.x() + wb * b.x() + wc * c.x(), wa * a.y() + wb * b.y() + wc * c.y(),
                         wa * a.z() + wb * b.z() + wc * c.z());
  }
  return samples;
}

double farthest(const std::vector<Point>& points, const Tree& tree) {
  double largest = 0;
  for (const Point& p : points) largest = std::max(largest, tree.squared_distance(p));
  return std::sqrt(largest);
}

double one_sided(const Surface& from, const Surface& to, std::size_t samples, std::mt19937_64& random) {
  Tree tree(to.triangles.begin(), to.triangles.end());
  tree.accelerate_distance_queries();
  return std::max(farthest(from.vertices, tree), farthest(sample(from, samples, random), tree));
}

}  // namespace

SurfaceDistance sampled_hausdorff_distance(const TriangleMesh& a, const TriangleMesh& b,
                                           const SurfaceDistanceOptions& options) {
  const Surface surface_a = prepare(a, "first");
  const Surface surface_b = prepare(b, "second");
  std::mt19937_64 random(options.seed);
  SurfaceDistance distance;
  distance.a_to_b_world = one_sided(surface_a, surface_b, options.samples_per_mesh, random);
  distance.b_to_a_world = one_sided(surface_b, surface_a, options.samples_per_mesh, random);
  return distance;
}

}  // namespace visproxy
