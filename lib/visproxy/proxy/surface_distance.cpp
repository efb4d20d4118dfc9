// Sampled two-sided Hausdorff distance between triangle meshes, in the manner of Metro
// (P. Cignoni, C. Rocchini, R. Scopigno. Metro: measuring error on simplified surfaces.
// Computer Graphics Forum 17(2), 1998): points spread uniformly by area over one surface
// (plus its vertices) are measured to their closest point on the other, in double
// precision, found through a BVH over triangle indices (trace/triangle_distance.h: Embree
// user geometry, built in parallel, whose boxes hold the double-precision triangles), so
// that a mesh of millions of triangles is not copied.

#include "visproxy/proxy/surface_distance.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <random>
#include <string>
#include <utility>
#include <memory>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/trace/triangle_distance.h"

namespace visproxy {
namespace {

bool exactly_collinear(const Vertex& a, const Vertex& b, const Vertex& c) {
  using ExactPoint = CGAL::Exact_predicates_inexact_constructions_kernel::Point_3;
  return CGAL::collinear(ExactPoint(a.x(), a.y(), a.z()), ExactPoint(b.x(), b.y(), b.z()),
                         ExactPoint(c.x(), c.y(), c.z()));
}

// Uniform double in [0, 1) from the 53 high bits (std::mt19937_64's output is fixed by the
// standard, unlike the standard distributions).
double uniform(std::mt19937_64& random) { return static_cast<double>(random() >> 11) * 0x1.0p-53; }

}  // namespace

// The parts of a mesh that are measured: its used vertices and its triangles of non-zero
// area (indices into the mesh), and the tree over those triangles.
struct MeasuredSurface::Impl {
  const TriangleMesh* mesh = nullptr;
  std::vector<VertexIndex> vertices;
  std::vector<double> cumulative_area;  // running sum over the tree's triangles
  std::vector<std::uint32_t> collinear;  // the triangles left out of the tree
  std::unique_ptr<TriangleDistance> tree;  // over the triangles of non-zero area
  double magnitude = 0;                    // the largest absolute coordinate of `vertices`

  // Area-uniform points on the surface, in triangle order (so that consecutive queries are near).
  std::vector<Vertex> sample(std::size_t count, std::mt19937_64& random) const {
    const double total = cumulative_area.back();
    std::vector<double> picks(count);
    for (double& pick : picks) pick = uniform(random) * total;
    std::sort(picks.begin(), picks.end());
    std::vector<Vertex> samples;
    samples.reserve(count);
    std::size_t t = 0;
    for (const double pick : picks) {
      while (t + 1 < cumulative_area.size() && cumulative_area[t] <= pick) ++t;
      const Triangle& triangle = mesh->triangles[tree->triangles()[t]];
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
      for (std::size_t j = range.begin(); j != range.end(); ++j) raise(largest, tree->squared_distance(get(64 * j)));
    });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 1024), [&](const tbb::blocked_range<std::size_t>& range) {
      for (std::size_t i = range.begin(); i != range.end(); ++i) {
        if (i % 64 == 0) continue;
        const Vertex q = get(i);
        const double reach = std::sqrt(largest.load()) - noise;
        if (prune && reach > 0 && tree->within(q, reach * reach)) continue;
        raise(largest, tree->squared_distance(q));
      }
    });
    return std::sqrt(largest.load());
  }
  double farthest(const std::vector<Vertex>& points, double floor, double noise, bool prune) const {
    return farthest(points.size(), [&](std::size_t i) { return points[i]; }, floor * floor, noise, prune);
  }
  double farthest_vertex(const Impl& from, double noise, bool prune) const {
    return farthest(from.vertices.size(), [&](std::size_t i) { return from.mesh->positions[from.vertices[i]]; },
                    0.0, noise, prune);
  }
};

MeasuredSurface::MeasuredSurface(const TriangleMesh& mesh, const char* name) : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.mesh = &mesh;
  std::vector<std::uint8_t> used(mesh.positions.size(), 0);
  std::vector<std::uint32_t> measured;  // the triangles of non-zero area, for the tree
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
      s.magnitude = std::max(s.magnitude, mesh.positions[v].cwiseAbs().maxCoeff());
    }
    const Vertex& a = mesh.positions[triangle[0]];
    const Vertex& b = mesh.positions[triangle[1]];
    const Vertex& c = mesh.positions[triangle[2]];
    if (exactly_collinear(a, b, c)) {
      s.collinear.push_back(static_cast<std::uint32_t>(i));
      continue;
    }
    measured.push_back(static_cast<std::uint32_t>(i));
    const double area = (b - a).cross(c - a).norm() / 2;
    s.cumulative_area.push_back((s.cumulative_area.empty() ? 0.0 : s.cumulative_area.back()) + area);
  }
  if (measured.empty())
    throw InvalidInputError("", std::string("the ") + name + " mesh has no triangle of non-zero area to measure");
  s.tree = std::make_unique<TriangleDistance>(mesh, std::move(measured));
}

MeasuredSurface::~MeasuredSurface() = default;

double MeasuredSurface::distance_to(const Vertex& p) const {
  const Impl& s = *impl_;
  double squared = s.tree->squared_distance(p);
  for (const std::uint32_t t : s.collinear) {
    const Triangle& triangle = s.mesh->triangles[t];
    squared = std::min(squared, point_triangle_squared_distance(p, s.mesh->positions[triangle[0]], s.mesh->positions[triangle[1]],
                                                                s.mesh->positions[triangle[2]]));
  }
  return std::sqrt(squared);
}

namespace {

SurfaceDistance hausdorff(const MeasuredSurface::Impl& from_a, const MeasuredSurface::Impl& from_b,
                          const SurfaceDistanceOptions& options) {
  std::mt19937_64 random(options.seed);
  // The pruning margin: 2^-36 of the coordinates' magnitude, thousands of times the
  // rounding of a point-triangle distance.
  const double noise = 0x1.0p-36 * std::max({from_a.magnitude, from_b.magnitude, 1e-300});
  SurfaceDistance distance;
  const std::vector<Vertex> samples_a = from_a.sample(options.samples_per_mesh, random);
  distance.a_to_b_world =
      from_b.farthest(samples_a, from_b.farthest_vertex(from_a, noise, options.prune), noise, options.prune);
  const std::vector<Vertex> samples_b = from_b.sample(options.samples_per_mesh, random);
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
