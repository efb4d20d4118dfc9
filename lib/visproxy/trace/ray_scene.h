#pragma once
// Embree behind one small RAII type: a triangle mesh or a set of solid balls made ready
// for ray queries. Embree holds single-precision vertices and rays: positions are rounded
// to float, so a query that grazes the surface within about 1e-7 of the scene's extent may
// be answered either way. Balls are intersected in double precision by our own code.

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "visproxy/mesh/sphere_set.h"
#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

/// Embree holds vertices and rays in single precision (24-bit significands); proofs are
/// made in double. This bound, relative to the magnitude of the coordinates Embree sees,
/// covers the rounding of vertices and rays and the error of Embree's tests: its triangle
/// test works on the vertices relative to the ray's origin, each rounded to float and
/// sheared, so a vertex moves by about 3 ulps of |vertex| + |origin| (half an ulp for each
/// rounding). 2^-21 of a magnitude is 8 float ulps at it: proxies padded by it (outside
/// ones grown, inside ones shrunk) keep their proved claims for float rays.
inline constexpr double kFloatRoundingBound = 0x1.0p-21;

/// The open segment from `from` to `to` (its end points excluded).
struct Segment {
  Vertex from;
  Vertex to;
};

/// A triangle mesh or a sphere set in an Embree scene (its own device, BVH built on
/// construction, robust traversal so that rays do not slip through shared edges).
/// Queries are const and may run from many threads at once. Embree errors, including
/// running out of memory, are thrown as visproxy::Error.
///
/// Everything is handed to Embree relative to `origin` (vertices, balls, segments), so that
/// float rounding is relative to the distance from it rather than from (0, 0, 0): give the
/// centre of what is traced, and the same origin to scenes whose answers are compared.
class RayScene {
 public:
  explicit RayScene(const TriangleMesh& mesh, const Vertex& origin = Vertex::Zero());
  /// Solid balls: a segment is blocked when it meets any ball, including when it starts or
  /// ends inside one (unlike Embree's sphere points, which skip those hits).
  explicit RayScene(std::span<const Sphere> spheres, const Vertex& origin = Vertex::Zero());
  ~RayScene();
  RayScene(const RayScene&) = delete;
  RayScene& operator=(const RayScene&) = delete;

  /// True when the segment hits a triangle (either side) or a ball.
  bool segment_blocked(const Segment& segment) const;

  /// segment_blocked for every segment (#S entries, 1 = blocked), in parallel.
  std::vector<std::uint8_t> segments_blocked(std::span<const Segment> segments) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  static std::unique_ptr<Impl> make_impl();
  void commit();
};

}  // namespace visproxy
