// Box proxies. CGAL's optimal bounding box (Chang, Gorissen, Melchior 2011: "Fast oriented
// bounding box optimization on the rotation group SO(3, R)") provides candidate axes; the
// extents are fitted here and containment is proved with exact predicates.

#include "visproxy/proxy/bounding_boxes.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/optimal_bounding_box.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <numbers>
#include <string_view>
#include <array>
#include <cmath>
#include <limits>
#include <map>

#include "visproxy/core/errors.h"
#include "visproxy/proxy/convex_hull.h"
#include "visproxy/verify/containment.h"

namespace visproxy {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;

Point to_point(const Vertex& p) { return {p.x(), p.y(), p.z()}; }

// Three indices of non-collinear points, or none.
std::optional<std::array<std::size_t, 3>> find_spanning_triangle(const std::vector<Vertex>& points) {
  if (points.size() < 3) return std::nullopt;
  std::size_t second = 1;
  while (second < points.size() && points[second] == points[0]) ++second;
  if (second == points.size()) return std::nullopt;
  for (std::size_t third = second + 1; third < points.size(); ++third)
    if (!CGAL::collinear(to_point(points[0]), to_point(points[second]), to_point(points[third])))
      return std::array<std::size_t, 3>{0, second, third};
  return std::nullopt;
}

// Axes (columns) completed to a right-handed orthonormal frame by Gram-Schmidt.
Eigen::Matrix3d orthonormal(Eigen::Matrix3d axes) {
  axes.col(0).normalize();
  axes.col(1) -= axes.col(0).dot(axes.col(1)) * axes.col(0);
  axes.col(1).normalize();
  axes.col(2) = axes.col(0).cross(axes.col(1));
  return axes;
}

OrientedBox fit_box(const std::vector<Vertex>& points, const Eigen::Matrix3d& axes) {
  Vertex low = Vertex::Constant(std::numeric_limits<double>::infinity());
  Vertex high = -low;
  for (const Vertex& p : points) {
    const Vertex t = axes.transpose() * p;
    low = low.cwiseMin(t);
    high = high.cwiseMax(t);
  }
  OrientedBox box;
  box.axes = axes;
  box.center = axes * (0.5 * (low + high));
  box.half_extents = 0.5 * (high - low);
  return box;
}

// Smallest-area rectangle in the plane spanned by e0, e1: try the direction of every edge
// of the points' 2D convex hull (Freeman and Shapira 1975: one side of the optimum lies
// on a hull edge).
Eigen::Matrix3d best_plane_axes(const std::vector<Vertex>& points, const Vertex& e0, const Vertex& e1) {
  std::vector<Eigen::Vector2d> flat;
  flat.reserve(points.size());
  for (const Vertex& p : points) flat.emplace_back(p.dot(e0), p.dot(e1));
  std::sort(flat.begin(), flat.end(), [](const auto& a, const auto& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
  };
  std::vector<Eigen::Vector2d> hull;  // Andrew's monotone chain
  for (int pass = 0; pass < 2; ++pass) {
    const std::size_t start = hull.size();
    for (const Eigen::Vector2d& p : flat) {
      while (hull.size() >= start + 2 && cross(hull[hull.size() - 2], hull.back(), p) <= 0) hull.pop_back();
      hull.push_back(p);
    }
    hull.pop_back();
    std::reverse(flat.begin(), flat.end());
  }
  double best_area = std::numeric_limits<double>::infinity();
  Eigen::Vector2d best_direction(1, 0);
  for (std::size_t i = 0; i < hull.size(); ++i) {
    const Eigen::Vector2d edge = hull[(i + 1) % hull.size()] - hull[i];
    if (edge.norm() == 0) continue;
    const Eigen::Vector2d u = edge.normalized();
    const Eigen::Vector2d v(-u.y(), u.x());
    double u_low = std::numeric_limits<double>::infinity(), u_high = -u_low, v_low = u_low, v_high = -u_low;
    for (const Eigen::Vector2d& p : hull) {
      u_low = std::min(u_low, p.dot(u));
      u_high = std::max(u_high, p.dot(u));
      v_low = std::min(v_low, p.dot(v));
      v_high = std::max(v_high, p.dot(v));
    }
    const double area = (u_high - u_low) * (v_high - v_low);
    if (area < best_area) {
      best_area = area;
      best_direction = u;
    }
  }
  Eigen::Matrix3d axes;
  axes.col(0) = best_direction.x() * e0 + best_direction.y() * e1;
  axes.col(1) = -best_direction.y() * e0 + best_direction.x() * e1;
  axes.col(2) = e0.cross(e1);
  return orthonormal(axes);
}

// Volume for solid boxes; flat boxes compare by area (their volume is 0 in every frame).
double box_size(const OrientedBox& box, bool flat) {
  const Vertex e = box.half_extents;
  return flat ? 4.0 * std::max({e.x() * e.y(), e.y() * e.z(), e.x() * e.z()}) : box.volume();
}

}  // namespace

std::array<Vertex, 8> OrientedBox::corners() const {
  std::array<Vertex, 8> corners;
  for (int i = 0; i < 8; ++i) {
    Vertex t;
    for (int k = 0; k < 3; ++k) t[k] = ((i >> k) & 1) ? half_extents[k] : -half_extents[k];
    corners[static_cast<std::size_t>(i)] = center + axes * t;
  }
  return corners;
}

TriangleMesh box_mesh(const std::array<Vertex, 8>& corners) {
  // Faces of the cube with corner bits (x, y, z), counter-clockwise from outside.
  static constexpr std::array<Triangle, 12> kFaces = {{{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                                                        {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}}};
  TriangleMesh mesh;
  std::array<VertexIndex, 8> index{};
  for (std::size_t i = 0; i < 8; ++i) {
    const auto same = std::find(mesh.positions.begin(), mesh.positions.end(), corners[i]);
    index[i] = static_cast<VertexIndex>(same - mesh.positions.begin());
    if (same == mesh.positions.end()) mesh.positions.push_back(corners[i]);
  }
  for (const Triangle& face : kFaces) {
    const Triangle t = {index[face[0]], index[face[1]], index[face[2]]};
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
    if (CGAL::collinear(to_point(mesh.positions[t[0]]), to_point(mesh.positions[t[1]]), to_point(mesh.positions[t[2]])))
      continue;
    mesh.triangles.push_back(t);
  }
  return mesh;
}

double flat_box_half_thickness(double diagonal) { return std::ldexp(diagonal, -21); }

TriangleMesh axis_aligned_box_mesh(const TriangleMesh& mesh) {
  const std::vector<Vertex> points = used_positions(mesh);
  if (points.empty()) throw InvalidInputError("", "the mesh has no triangles: a box needs at least one");
  if (!find_spanning_triangle(points)) throw InvalidInputError("", "all vertices are collinear: a box around them has no area");
  BoundingBox bounds = bounding_box(mesh);
  // A flat input (a card, a quad) gets a box of some thickness, so that the box bounds a
  // solid the mesh lies strictly inside: two coincident faces bound nothing.
  const double half_thickness = flat_box_half_thickness(bounds.diagonal());
  for (int k = 0; k < 3; ++k)
    if (bounds.max[k] - bounds.min[k] < 2 * half_thickness) {
      const double middle = 0.5 * (bounds.min[k] + bounds.max[k]);
      bounds.min[k] = std::min(bounds.min[k], middle - half_thickness);
      bounds.max[k] = std::max(bounds.max[k], middle + half_thickness);
    }
  std::array<Vertex, 8> corners;
  for (int i = 0; i < 8; ++i)
    for (int k = 0; k < 3; ++k) corners[static_cast<std::size_t>(i)][k] = ((i >> k) & 1) ? bounds.max[k] : bounds.min[k];
  return box_mesh(corners);
}

// Whether every point is inside or on the closed mesh `box` (outward-oriented), exactly.
// A point on or behind the plane of every triangle, and strictly behind one, is held: seen
// from it, every triangle's signed solid angle is zero or positive and one is positive, so
// its winding number, an integer off the surface, is at least 1. That decides nearly every
// point with a few exact orientations, in parallel, even when rounding leaves a box's faces
// slightly bent (two triangles of a face not quite coplanar). The others are located by
// winding numbers (locate_points); when every vertex of the mesh is on or behind every
// plane, some strictly (a convex mesh), they are outside without asking.
bool holds_every_point(const TriangleMesh& box, const std::vector<Vertex>& points) {
  std::vector<std::array<Point, 3>> planes;
  for (const Triangle& t : box.triangles)
    planes.push_back({to_point(box.positions[t[0]]), to_point(box.positions[t[1]]), to_point(box.positions[t[2]])});
  auto behind_every_plane = [&](const Point& p) {
    bool strictly = false;
    for (const std::array<Point, 3>& plane : planes) {
      const CGAL::Orientation side = CGAL::orientation(plane[0], plane[1], plane[2], p);
      if (side == CGAL::POSITIVE) return false;
      strictly = strictly || side == CGAL::NEGATIVE;
    }
    return strictly;
  };
  const bool convex = std::all_of(box.positions.begin(), box.positions.end(), [&](const Vertex& v) {
    bool behind = true;  // on or behind every plane (a vertex lies on its own triangles' planes)
    for (const std::array<Point, 3>& plane : planes)
      behind = behind && CGAL::orientation(plane[0], plane[1], plane[2], to_point(v)) != CGAL::POSITIVE;
    return behind;
  }) && std::any_of(box.positions.begin(), box.positions.end(), [&](const Vertex& v) { return behind_every_plane(to_point(v)); });
  const std::vector<Vertex> undecided = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, points.size(), 4096), std::vector<Vertex>{},
      [&](const tbb::blocked_range<std::size_t>& range, std::vector<Vertex> left) {
        for (std::size_t i = range.begin(); i != range.end(); ++i)
          if (!behind_every_plane(to_point(points[i]))) left.push_back(points[i]);
        return left;
      },
      [](std::vector<Vertex> a, const std::vector<Vertex>& b) {
        a.insert(a.end(), b.begin(), b.end());
        return a;
      });
  if (undecided.empty()) return true;
  if (convex) return false;
  const std::vector<PointLocation> locations = locate_points(box, undecided);
  return std::none_of(locations.begin(), locations.end(), [](PointLocation l) { return l == PointLocation::outside; });
}

namespace {

// A pattern search from `axes`: rotations about each box axis by +-step, from 2 degrees
// halved down to about 0.004 degrees, taking every rotation that shrinks the box fitted to
// `points`. Never larger than the box it starts from.
Eigen::Matrix3d refine_axes(const std::vector<Vertex>& points, Eigen::Matrix3d axes) {
  double best = fit_box(points, axes).volume();
  for (double step = 2.0 * std::numbers::pi / 180; step > 7e-5; step *= 0.5) {
    for (bool improved = true; improved;) {
      improved = false;
      for (int k = 0; k < 3; ++k)
        for (const double angle : {step, -step}) {
          const Eigen::Matrix3d turned = orthonormal(axes * Eigen::AngleAxisd(angle, Eigen::Vector3d::Unit(k)).toRotationMatrix());
          const double size = fit_box(points, turned).volume();
          if (size < best) best = size, axes = turned, improved = true;
        }
    }
  }
  return axes;
}

// The indices of the points extreme along `directions` directions spread evenly over the
// sphere (a Fibonacci lattice), in increasing order; every index when `directions` is 0 or
// there are no more points than directions. The box's extent along an axis is the
// support function of the points there, and the extreme points' support function differs
// from it by at most the diameter times 1 - cos of the lattice's spacing.
std::vector<std::size_t> extreme_corners(const std::vector<Vertex>& points, std::size_t directions) {
  std::vector<std::size_t> chosen;
  if (directions == 0 || points.size() <= directions) {
    for (std::size_t i = 0; i < points.size(); ++i) chosen.push_back(i);
    return chosen;
  }
  const double golden_angle = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (std::size_t d = 0; d < directions; ++d) {
    const double z = 1.0 - (2.0 * static_cast<double>(d) + 1.0) / static_cast<double>(directions);
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = golden_angle * static_cast<double>(d);
    const Vertex u(r * std::cos(phi), r * std::sin(phi), z);
    std::size_t best = 0;
    for (std::size_t i = 1; i < points.size(); ++i)
      if (u.dot(points[i]) > u.dot(points[best])) best = i;
    chosen.push_back(best);
  }
  std::sort(chosen.begin(), chosen.end());
  chosen.erase(std::unique(chosen.begin(), chosen.end()), chosen.end());
  return chosen;
}

}  // namespace

OrientedBoxResult build_oriented_box(const TriangleMesh& mesh, const OrientedBoxOptions& options) {
  const std::vector<Vertex> points = used_positions(mesh);
  if (points.empty()) throw InvalidInputError("", "the mesh has no triangles: a box needs at least one");
  const auto spanning = find_spanning_triangle(points);
  if (!spanning) throw InvalidInputError("", "all vertices are collinear: a box around them has no area");

  const Point a = to_point(points[(*spanning)[0]]), b = to_point(points[(*spanning)[1]]), c = to_point(points[(*spanning)[2]]);
  const bool flat = std::all_of(points.begin(), points.end(),
                                [&](const Vertex& p) { return CGAL::coplanar(a, b, c, to_point(p)); });

  struct Candidate {
    Eigen::Matrix3d axes;
    const char* name;
  };
  std::vector<Candidate> candidates = {{Eigen::Matrix3d::Identity(), "axis-aligned"}};
  std::vector<Vertex> corners = points;  // the points the boxes are fitted to
  if (flat) {
    const Vertex e0 = (points[(*spanning)[1]] - points[(*spanning)[0]]).normalized();
    const Vertex normal = e0.cross(points[(*spanning)[2]] - points[(*spanning)[0]]).normalized();
    candidates.push_back({best_plane_axes(points, e0, normal.cross(e0)), "plane"});
  } else {
    // The box's extent in any direction is reached at a corner of the convex hull: CGAL's
    // optimisation and the fits below need the hull's corners only (computed exactly, in
    // parallel for large meshes); the proof below still takes every vertex.
    corners = build_convex_hull(mesh).mesh.positions;
    std::vector<Point> cgal_points;
    for (const std::size_t i : extreme_corners(corners, options.search_directions)) cgal_points.push_back(to_point(corners[i]));
    Kernel::Aff_transformation_3 rotation;
    CGAL::oriented_bounding_box(cgal_points, rotation,
                                CGAL::parameters::random_seed(options.seed).use_convex_hull(false));
    Eigen::Matrix3d axes;  // the rotation's rows are the box axes
    for (int row = 0; row < 3; ++row)
      for (int column = 0; column < 3; ++column) axes(column, row) = CGAL::to_double(rotation.m(row, column));
    candidates.push_back({orthonormal(axes), "cgal"});

    Vertex mean = Vertex::Zero();
    for (const Vertex& p : points) mean += p;
    mean /= static_cast<double>(points.size());
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for (const Vertex& p : points) covariance += (p - mean) * (p - mean).transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
    candidates.push_back({orthonormal(solver.eigenvectors()), "principal axes"});
  }

  OrientedBoxResult result;
  double best = std::numeric_limits<double>::infinity();
  for (const Candidate& candidate : candidates) {
    const bool refine = !flat && candidate.name != std::string_view("axis-aligned");
    const OrientedBox box = fit_box(corners, refine ? refine_axes(corners, candidate.axes) : candidate.axes);
    if (box_size(box, flat) < best) {
      best = box_size(box, flat);
      result.box = box;
      result.axes_from = candidate.name;
    }
  }

  // Corners are rounded: prove containment exactly and grow the box until it holds.
  const double diagonal = bounding_box(mesh).diagonal();
  result.inflation_world = 0;
  OrientedBox fitted = result.box;
  fitted.half_extents = fitted.half_extents.cwiseMax(flat_box_half_thickness(diagonal));
  for (int attempt = 0;; ++attempt) {
    result.box.half_extents = fitted.half_extents.array() + result.inflation_world;
    result.mesh = box_mesh(result.box.corners());
    if (holds_every_point(result.mesh, points)) break;
    if (attempt == 60) throw Error("oriented bounding box: cannot prove containment (non-finite coordinates?)");
    result.inflation_world = result.inflation_world == 0 ? 1e-15 * diagonal : 2 * result.inflation_world;
  }
  return result;
}

}  // namespace visproxy
