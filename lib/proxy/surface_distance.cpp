// Sampled two-sided Hausdorff distance between triangle meshes, in the manner of Metro
// (P. Cignoni, C. Rocchini, R. Scopigno. Metro: measuring error on simplified surfaces.
// Computer Graphics Forum 17(2), 1998): points spread uniformly by area over one surface
// (plus its vertices) are measured to their exact closest point on the other, found with
// CGAL's AABB tree. The tree holds triangle indices only and reads the triangles from the
// mesh (property maps shared by the tree), so that a mesh of millions of triangles is not
// copied; the search tree that speeds up distance queries takes one point in 16 triangles.

#include "visproxy/proxy/surface_distance.h"

#include <CGAL/AABB_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Simple_cartesian.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
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

Point point(const Vertex& p) { return {p.x(), p.y(), p.z()}; }

// Triangle `id` of the mesh, and its first corner as its reference point.
struct TriangleOfMesh {
  using key_type = std::uint32_t;
  using value_type = CgalTriangle;
  using reference = CgalTriangle;
  using category = boost::readable_property_map_tag;
  const TriangleMesh* mesh = nullptr;
  friend CgalTriangle get(const TriangleOfMesh& map, std::uint32_t id) {
    const Triangle& t = map.mesh->triangles[id];
    return {point(map.mesh->positions[t[0]]), point(map.mesh->positions[t[1]]), point(map.mesh->positions[t[2]])};
  }
};
struct CornerOfMesh {
  using key_type = std::uint32_t;
  using value_type = Point;
  using reference = Point;
  using category = boost::readable_property_map_tag;
  const TriangleMesh* mesh = nullptr;
  friend Point get(const CornerOfMesh& map, std::uint32_t id) {
    return point(map.mesh->positions[map.mesh->triangles[id][0]]);
  }
};

using Primitive = CGAL::AABB_primitive<std::uint32_t, TriangleOfMesh, CornerOfMesh, CGAL::Tag_true, CGAL::Tag_false>;
using Traits = CGAL::AABB_traits<Kernel, Primitive>;
using Tree = CGAL::AABB_tree<Traits>;

bool exactly_collinear(const Vertex& a, const Vertex& b, const Vertex& c) {
  using ExactPoint = CGAL::Exact_predicates_inexact_constructions_kernel::Point_3;
  return CGAL::collinear(ExactPoint(a.x(), a.y(), a.z()), ExactPoint(b.x(), b.y(), b.z()),
                         ExactPoint(c.x(), c.y(), c.z()));
}

// Uniform double in [0, 1) from the 53 high bits (std::mt19937_64's output is fixed by the
// standard, unlike the standard distributions).
double uniform(std::mt19937_64& random) { return static_cast<double>(random() >> 11) * 0x1.0p-53; }

// A traversal of the tree that stops at the first triangle nearer than
// sqrt(squared_radius) to the query point.
struct WithinTraversal {
  const TriangleMesh* mesh;
  double squared_radius;
  bool found = false;
  bool go_further() const { return !found; }
  void intersection(const Point& query, const Primitive& primitive) {
    if (CGAL::squared_distance(query, get(TriangleOfMesh{mesh}, primitive.id())) < squared_radius) found = true;
  }
  template <typename Node>
  bool do_intersect(const Point& query, const Node& node) const {
    const CGAL::Bbox_3& box = node.bbox();
    double squared = 0;
    for (int k = 0; k < 3; ++k) {
      const double gap = std::max({box.min(k) - query[k], query[k] - box.max(k), 0.0});
      squared += gap * gap;
    }
    return squared < squared_radius;
  }
};

}  // namespace

// The parts of a mesh that are measured: its used vertices and its triangles of non-zero
// area (indices into the mesh), and the tree over those triangles.
struct MeasuredSurface::Impl {
  const TriangleMesh* mesh = nullptr;
  std::vector<VertexIndex> vertices;
  std::vector<std::uint32_t> triangles;
  std::vector<double> cumulative_area;  // running sum over `triangles`
  std::vector<std::uint32_t> collinear;  // the triangles left out of `triangles`
  Tree tree;

  // Area-uniform points on the surface, in triangle order (so that consecutive queries are near).
  std::vector<Point> sample(std::size_t count, std::mt19937_64& random) const {
    const double total = cumulative_area.back();
    std::vector<double> picks(count);
    for (double& pick : picks) pick = uniform(random) * total;
    std::sort(picks.begin(), picks.end());
    std::vector<Point> samples;
    samples.reserve(count);
    std::size_t t = 0;
    for (const double pick : picks) {
      while (t + 1 < cumulative_area.size() && cumulative_area[t] <= pick) ++t;
      const Triangle& triangle = mesh->triangles[triangles[t]];
      const double s = std::sqrt(uniform(random));
      const double r = uniform(random);
      const double wa = 1 - s, wb = s * (1 - r), wc = s * r;
      const Vertex& a = mesh->positions[triangle[0]];
      const Vertex& b = mesh->positions[triangle[1]];
      const Vertex& c = mesh->positions[triangle[2]];
      samples.emplace_back(wa * a.x() + wb * b.x() + wc * c.x(), wa * a.y() + wb * b.y() + wc * c.y(),
                           wa * a.z() + wb * b.z() + wc * c.z());
    }
    return samples;
  }

  // Whether some triangle lies closer than sqrt(squared_radius) to q (a traversal that
  // stops at the first one).
  bool within(const Point& q, double squared_radius) const {
    WithinTraversal traversal{mesh, squared_radius};
    tree.traversal(q, traversal);
    return traversal.found;
  }

  // The largest distance from the points to the surface, at least sqrt(squared_floor), in
  // parallel. A point with a triangle nearer than the largest distance found so far minus
  // `noise` (far above the rounding of the distance computations) cannot be the farthest
  // and is not measured exactly, so the result is that of measuring every point, whatever
  // the split and the order.
  template <class Get>
  double farthest(std::size_t count, const Get& get, double squared_floor, double noise, bool prune) const {
    auto raise = [](std::atomic<double>& to, double value) {
      for (double seen = to.load(); value > seen && !to.compare_exchange_weak(seen, value);) {
      }
    };
    std::atomic<double> largest{squared_floor};
    // Every 64th point first, so that the bound prunes from the start.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, (count + 63) / 64, 16), [&](const tbb::blocked_range<std::size_t>& range) {
      for (std::size_t j = range.begin(); j != range.end(); ++j) raise(largest, tree.squared_distance(get(64 * j)));
    });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 1024), [&](const tbb::blocked_range<std::size_t>& range) {
      for (std::size_t i = range.begin(); i != range.end(); ++i) {
        if (i % 64 == 0) continue;
        const Point q = get(i);
        const double reach = std::sqrt(largest.load()) - noise;
        if (prune && reach > 0 && within(q, reach * reach)) continue;
        raise(largest, tree.squared_distance(q));
      }
    });
    return std::sqrt(largest.load());
  }
  double farthest(const std::vector<Point>& points, double floor, double noise, bool prune) const {
    return farthest(points.size(), [&](std::size_t i) { return points[i]; }, floor * floor, noise, prune);
  }
  double farthest_vertex(const Impl& from, double noise, bool prune) const {
    return farthest(from.vertices.size(), [&](std::size_t i) { return point(from.mesh->positions[from.vertices[i]]); },
                    0.0, noise, prune);
  }
  // The largest absolute coordinate of the used vertices.
  double magnitude() const {
    double largest = 0;
    for (const VertexIndex v : vertices) largest = std::max(largest, mesh->positions[v].cwiseAbs().maxCoeff());
    return largest;
  }
};

MeasuredSurface::MeasuredSurface(const TriangleMesh& mesh, const char* name) : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.mesh = &mesh;
  std::vector<std::uint8_t> used(mesh.positions.size(), 0);
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    const Triangle& triangle = mesh.triangles[i];
    for (const VertexIndex v : triangle) {
      if (v >= mesh.positions.size())
        throw InvalidInputError("", std::string("the ") + name + " mesh has a triangle corner out of range (" +
                                        std::to_string(v) + ")");
      if (used[v]) continue;
      if (!mesh.positions[v].allFinite())
        throw InvalidInputError("", std::string("the ") + name + " mesh has a non-finite vertex (" +
                                        std::to_string(v) + ")");
      used[v] = 1;
      s.vertices.push_back(v);
    }
    const Vertex& a = mesh.positions[triangle[0]];
    const Vertex& b = mesh.positions[triangle[1]];
    const Vertex& c = mesh.positions[triangle[2]];
    if (exactly_collinear(a, b, c)) {
      s.collinear.push_back(static_cast<std::uint32_t>(i));
      continue;
    }
    s.triangles.push_back(static_cast<std::uint32_t>(i));
    const double area = (b - a).cross(c - a).norm() / 2;
    s.cumulative_area.push_back((s.cumulative_area.empty() ? 0.0 : s.cumulative_area.back()) + area);
  }
  if (s.triangles.empty())
    throw InvalidInputError("", std::string("the ") + name + " mesh has no triangle of non-zero area to measure");
  s.tree.rebuild(s.triangles.begin(), s.triangles.end(), TriangleOfMesh{&mesh}, CornerOfMesh{&mesh});
  // The search tree that gives each distance query its first guess: a point of every 16th
  // triangle (the corners of all of them would take as much memory as the tree).
  std::vector<Traits::Point_and_primitive_id> hints;
  hints.reserve(s.triangles.size() / 16 + 1);
  for (std::size_t i = 0; i < s.triangles.size(); i += 16)
    hints.emplace_back(get(CornerOfMesh{&mesh}, s.triangles[i]), s.triangles[i]);
  s.tree.accelerate_distance_queries(hints.begin(), hints.end());
}

MeasuredSurface::~MeasuredSurface() = default;

double MeasuredSurface::distance_to(const Vertex& p) const {
  const Impl& s = *impl_;
  const Point q = point(p);
  double squared = s.tree.squared_distance(q);
  for (const std::uint32_t t : s.collinear) {
    const Triangle& triangle = s.mesh->triangles[t];
    for (std::size_t k = 0; k < 3; ++k)
      squared = std::min(squared, CGAL::squared_distance(q, Kernel::Segment_3(point(s.mesh->positions[triangle[k]]),
                                                                             point(s.mesh->positions[triangle[(k + 1) % 3]]))));
  }
  return std::sqrt(squared);
}

namespace {

SurfaceDistance hausdorff(const MeasuredSurface::Impl& from_a, const MeasuredSurface::Impl& from_b,
                          const SurfaceDistanceOptions& options) {
  std::mt19937_64 random(options.seed);
  // The pruning margin: 2^-36 of the coordinates' magnitude, thousands of times the
  // rounding of a point-triangle distance.
  const double noise = 0x1.0p-36 * std::max({from_a.magnitude(), from_b.magnitude(), 1e-300});
  SurfaceDistance distance;
  const std::vector<Point> samples_a = from_a.sample(options.samples_per_mesh, random);
  distance.a_to_b_world =
      from_b.farthest(samples_a, from_b.farthest_vertex(from_a, noise, options.prune), noise, options.prune);
  const std::vector<Point> samples_b = from_b.sample(options.samples_per_mesh, random);
  distance.b_to_a_world =
      from_a.farthest(samples_b, from_a.farthest_vertex(from_b, noise, options.prune), noise, options.prune);
  return distance;
}

}  // namespace

SurfaceDistance sampled_hausdorff_distance(const TriangleMesh& a, const MeasuredSurface& b,
                                           const SurfaceDistanceOptions& options) {
  const MeasuredSurface surface_a(a, "first");
  return hausdorff(surface_a.impl(), b.impl(), options);
}

SurfaceDistance sampled_hausdorff_distance(const TriangleMesh& a, const TriangleMesh& b,
                                           const SurfaceDistanceOptions& options) {
  const MeasuredSurface surface_a(a, "first");
  const MeasuredSurface surface_b(b, "second");
  return hausdorff(surface_a.impl(), surface_b.impl(), options);
}

}  // namespace visproxy
