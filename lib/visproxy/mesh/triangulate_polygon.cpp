// Ear-clipping triangulation of the polygonal faces in OBJ, OFF and PLY files.
// The polygon is projected onto the coordinate plane most orthogonal to its Newell
// normal; ears are clipped in that plane (Meisters, "Polygons have ears", 1975).

#include <array>
#include <cmath>

#include "visproxy/mesh/mesh_parsing.h"

namespace visproxy::parsing {
namespace {

constexpr std::size_t kLargestEarClippedPolygon = 256;

using Point2 = std::array<double, 2>;

double cross(const Point2& a, const Point2& b, const Point2& c) {
  return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

void fan(std::span<const VertexIndex> corners, std::vector<Triangle>& triangles) {
  for (std::size_t i = 1; i + 1 < corners.size(); ++i) triangles.push_back({corners[0], corners[i], corners[i + 1]});
}

}  // namespace

void triangulate_polygon(const std::vector<Vertex>& positions, std::span<const VertexIndex> corners,
                         std::vector<Triangle>& triangles) {
  const std::size_t n = corners.size();
  if (n == 3 || n > kLargestEarClippedPolygon) return fan(corners, triangles);

  Vertex normal = Vertex::Zero();  // Newell's method
  for (std::size_t i = 0; i < n; ++i) {
    const Vertex& a = positions[corners[i]];
    const Vertex& b = positions[corners[(i + 1) % n]];
    normal += Vertex((a.y() - b.y()) * (a.z() + b.z()), (a.z() - b.z()) * (a.x() + b.x()),
                     (a.x() - b.x()) * (a.y() + b.y()));
  }
  Eigen::Index drop = 0;
  const double largest = normal.cwiseAbs().maxCoeff(&drop);
  if (!(largest > 0)) return fan(corners, triangles);
  const int u = drop == 0 ? 1 : 0;
  const int v = drop == 2 ? 1 : 2;

  std::vector<Point2> points(n);
  double twice_area = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Vertex& p = positions[corners[i]];
    points[i] = {p[u], p[v]};
  }
  for (std::size_t i = 0; i < n; ++i) {
    const Point2& a = points[i];
    const Point2& b = points[(i + 1) % n];
    twice_area += a[0] * b[1] - a[1] * b[0];
  }
  if (twice_area < 0)  // make the projected polygon counter-clockwise
    for (Point2& p : points) p[1] = -p[1];

  std::vector<std::size_t> ring(n);
  for (std::size_t i = 0; i < n; ++i) ring[i] = i;
  const std::size_t first_triangle = triangles.size();

  auto is_ear = [&](std::size_t k) {
    const std::size_t m = ring.size();
    const Point2& a = points[ring[(k + m - 1) % m]];
    const Point2& b = points[ring[k]];
    const Point2& c = points[ring[(k + 1) % m]];
    if (cross(a, b, c) <= 0) return false;  // reflex or flat corner
    for (std::size_t j = 0; j + 3 <= m; ++j) {
      const Point2& p = points[ring[(k + 2 + j) % m]];
      if (p == a || p == b || p == c) continue;
      if (cross(a, b, p) >= 0 && cross(b, c, p) >= 0 && cross(c, a, p) >= 0) return false;
    }
    return true;
  };

  std::size_t k = 0;
  std::size_t misses = 0;
  while (ring.size() > 3) {
    if (misses >= ring.size()) {
      // No ear left (self-intersecting or numerically flat polygon): undo and fan it.
      triangles.resize(first_triangle);
      return fan(corners, triangles);
    }
    if (is_ear(k)) {
      const std::size_t m = ring.size();
      triangles.push_back({corners[ring[(k + m - 1) % m]], corners[ring[k]], corners[ring[(k + 1) % m]]});
      ring.erase(ring.begin() + static_cast<std::ptrdiff_t>(k));
      if (k == ring.size()) k = 0;
      misses = 0;
    } else {
      k = (k + 1) % ring.size();
      ++misses;
    }
  }
  triangles.push_back({corners[ring[0]], corners[ring[1]], corners[ring[2]]});
}

}  // namespace visproxy::parsing
