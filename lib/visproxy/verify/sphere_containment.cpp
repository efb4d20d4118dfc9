// Exact containment of balls in a closed mesh: centre by winding number, radius against
// the exact distance to every nearby triangle (CGAL: filtered predicates, lazy exact kernel),
// the nearby triangles found in one parallel pass over the mesh.

#include "visproxy/verify/sphere_containment.h"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <memory>
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

namespace {

// The spheres on a uniform grid by their boxes, so that a triangle finds the spheres whose
// box its own box meets without a loop over all of them.
class BoxGrid {
 public:
  BoxGrid(const std::vector<CGAL::Bbox_3>& boxes) : boxes_(boxes) {
    CGAL::Bbox_3 all;
    for (const CGAL::Bbox_3& b : boxes) all += b;
    low_ = {all.xmin(), all.ymin(), all.zmin()};
    const Vertex span(all.xmax() - all.xmin(), all.ymax() - all.ymin(), all.zmax() - all.zmin());
    side_ = std::clamp<std::size_t>(static_cast<std::size_t>(2 * std::cbrt(static_cast<double>(boxes.size()))), 1, 64);
    cell_ = (span / static_cast<double>(side_)).cwiseMax(Vertex::Constant(1e-300));
    cells_.resize(side_ * side_ * side_);
    for (std::uint32_t i = 0; i < boxes.size(); ++i)
      for_cells(boxes[i], [&](std::size_t c) { cells_[c].push_back(i); });
  }
  // Calls f(i) for each box i that meets `box` (each once, in increasing order).
  template <class F>
  void for_boxes_meeting(const CGAL::Bbox_3& box, std::vector<std::uint32_t>& scratch, F&& f) const {
    scratch.clear();
    for_cells(box, [&](std::size_t c) { scratch.insert(scratch.end(), cells_[c].begin(), cells_[c].end()); });
    std::sort(scratch.begin(), scratch.end());
    scratch.erase(std::unique(scratch.begin(), scratch.end()), scratch.end());
    for (const std::uint32_t i : scratch)
      if (CGAL::do_overlap(box, boxes_[i])) f(i);
  }

 private:
  template <class F>
  void for_cells(const CGAL::Bbox_3& box, F&& f) const {
    std::size_t lo[3], hi[3];
    const double mins[3] = {box.xmin(), box.ymin(), box.zmin()}, maxs[3] = {box.xmax(), box.ymax(), box.zmax()};
    for (int k = 0; k < 3; ++k) {
      const double top = static_cast<double>(side_ - 1);
      lo[k] = static_cast<std::size_t>(std::clamp(std::floor((mins[k] - low_[k]) / cell_[k]), 0.0, top));
      hi[k] = static_cast<std::size_t>(std::clamp(std::floor((maxs[k] - low_[k]) / cell_[k]), 0.0, top));
    }
    for (std::size_t x = lo[0]; x <= hi[0]; ++x)
      for (std::size_t y = lo[1]; y <= hi[1]; ++y)
        for (std::size_t z = lo[2]; z <= hi[2]; ++z) f((x * side_ + y) * side_ + z);
  }
  const std::vector<CGAL::Bbox_3>& boxes_;
  Vertex low_, cell_;
  std::size_t side_ = 1;
  std::vector<std::vector<std::uint32_t>> cells_;
};

// A box around `center` of half-size `half`, widened by an ulp of each bound so that
// rounding cannot shrink it.
CGAL::Bbox_3 box_around(const Point& center, double half) {
  return {std::nextafter(center.x() - half, -kHuge), std::nextafter(center.y() - half, -kHuge),
          std::nextafter(center.z() - half, -kHuge), std::nextafter(center.x() + half, kHuge),
          std::nextafter(center.y() + half, kHuge), std::nextafter(center.z() + half, kHuge)};
}

// Runs f(triangle index, triangle) over the mesh's triangles in parallel.
template <class F>
void for_triangles(const TriangleMesh& mesh, F&& f) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.triangles.size(), 4096), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t t = range.begin(); t != range.end(); ++t) {
      const Triangle& tri = mesh.triangles[t];
      f(CgalTriangle(to_point(mesh.positions[tri[0]]), to_point(mesh.positions[tri[1]]), to_point(mesh.positions[tri[2]])));
    }
  });
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
  const std::size_t n = spheres.size();
  const BoundingBox bounds = bounding_box(closed_mesh);
  const double diagonal = bounds.diagonal();

  // Which balls may cross the surface: only those whose centre is inside and whose radius is
  // positive need the triangles; each is compared exactly with every triangle whose box meets
  // the ball's box, which holds every triangle that comes within the radius, those wholly
  // inside the ball too. One parallel pass over the triangles; no tree to build.
  std::vector<std::uint8_t> passes(n, 0), centre_inside(n, 0);
  std::vector<std::uint32_t> tested;
  std::vector<CGAL::Bbox_3> ball_boxes;
  for (std::size_t i = 0; i < n; ++i) {
    const Sphere& sphere = spheres[i];
    const bool finite = sphere.center.allFinite() && std::isfinite(sphere.radius) && sphere.radius >= 0;
    passes[i] = centre_inside[i] = finite && locations[i] == PointLocation::inside;
    if (passes[i] && sphere.radius > 0) {
      tested.push_back(static_cast<std::uint32_t>(i));
      ball_boxes.push_back(box_around(to_point(centers[i]), sphere.radius));
    }
  }
  const std::unique_ptr<std::atomic<bool>[]> crosses(new std::atomic<bool>[tested.size()]);
  for (std::size_t k = 0; k < tested.size(); ++k) crosses[k] = false;
  if (!tested.empty()) {
    const BoxGrid grid(ball_boxes);
    tbb::enumerable_thread_specific<std::vector<std::uint32_t>> scratch;
    for_triangles(closed_mesh, [&](const CgalTriangle& t) {
      if (t.is_degenerate()) return;  // bounds nothing
      grid.for_boxes_meeting(t.bbox(), scratch.local(), [&](std::uint32_t k) {
        if (crosses[k].load(std::memory_order_relaxed)) return;
        const Sphere& sphere = spheres[tested[k]];
        const Point center = to_point(centers[tested[k]]);
        const double squared = sphere.radius * sphere.radius;
        // A filter: the distance in double is within 1e-12 of the largest squared distance
        // to a corner (thousands of ulps of its rounding error); triangles clearly farther
        // than the radius need no exact arithmetic.
        double reach = 0;
        for (int c = 0; c < 3; ++c) reach = std::max(reach, CGAL::squared_distance(center, t[c]));
        if (CGAL::squared_distance(center, t) - 1e-12 * reach > squared * (1 + 0x1.0p-50)) return;
        const Exact::Triangle_3 exact_triangle(to_exact(t[0]), to_exact(t[1]), to_exact(t[2]));
        const Exact::FT radius(sphere.radius);
        if (CGAL::squared_distance(to_exact(center), exact_triangle) < radius * radius) crosses[k] = true;
      });
    });
  }
  for (std::size_t k = 0; k < tested.size(); ++k)
    if (crosses[k]) passes[tested[k]] = 0;

  // The margins (in double, informative): each centre's distance to the surface, found among
  // the triangles in a box about it that grows until it holds the nearest one (a triangle
  // closer than the box's half-size meets the box).
  std::vector<double> nearest(n, kHuge);
  std::vector<double> half(n);
  for (std::size_t i = 0; i < n; ++i) half[i] = std::max(2 * std::abs(std::isfinite(spheres[i].radius) ? spheres[i].radius : 0.0), 1e-3 * diagonal);
  std::vector<std::uint32_t> open;
  for (std::size_t i = 0; i < n; ++i) open.push_back(static_cast<std::uint32_t>(i));
  while (!open.empty()) {
    std::vector<CGAL::Bbox_3> boxes;
    for (const std::uint32_t i : open) boxes.push_back(box_around(to_point(centers[i]), half[i]));
    const BoxGrid grid(boxes);
    tbb::enumerable_thread_specific<std::vector<double>> local([&] { return std::vector<double>(open.size(), kHuge); });
    tbb::enumerable_thread_specific<std::vector<std::uint32_t>> scratch;
    for_triangles(closed_mesh, [&](const CgalTriangle& t) {
      std::vector<double>& best = local.local();
      grid.for_boxes_meeting(t.bbox(), scratch.local(), [&](std::uint32_t k) {
        best[k] = std::min(best[k], CGAL::squared_distance(to_point(centers[open[k]]), t));
      });
    });
    std::vector<std::uint32_t> still_open;
    for (std::size_t k = 0; k < open.size(); ++k) {
      double best = kHuge;
      for (const std::vector<double>& b : local) best = std::min(best, b[k]);
      const std::uint32_t i = open[k];
      if (std::sqrt(best) <= half[i] || half[i] > 4 * diagonal + std::abs(centers[i].cwiseAbs().maxCoeff())) {
        nearest[i] = std::sqrt(best);
      } else {
        half[i] *= 4;
        still_open.push_back(i);
      }
    }
    open = std::move(still_open);
  }

  result.min_margin_world = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i) {
    result.min_margin_world = std::min(result.min_margin_world, (centre_inside[i] ? nearest[i] : -nearest[i]) - spheres[i].radius);
    if (!passes[i]) {
      ++result.spheres_outside;
      result.outside.push_back(i);
      if (!result.first_outside) result.first_outside = i;
    }
  }
  if (!std::isfinite(result.min_margin_world)) result.min_margin_world = -std::numeric_limits<double>::max();
  return result;
}

}  // namespace visproxy
