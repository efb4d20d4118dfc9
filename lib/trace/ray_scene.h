#pragma once
// Embree behind one small RAII type: a triangle mesh made ready for ray queries.
// Embree holds single-precision vertices: positions are rounded to float, so a query that
// grazes the surface within about 1e-7 of the mesh's extent may be answered either way.

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "mesh/triangle_mesh.h"

namespace visproxy {

/// The open segment from `from` to `to` (its end points excluded).
struct Segment {
  Vertex from;
  Vertex to;
};

/// A triangle mesh in an Embree scene (its own device, BVH built on construction).
/// Queries are const and may run from many threads at once. Embree errors, including
/// running out of memory, are thrown as visproxy::Error.
class RayScene {
 public:
  explicit RayScene(const TriangleMesh& mesh);
  ~RayScene();
  RayScene(const RayScene&) = delete;
  RayScene& operator=(const RayScene&) = delete;

  /// True when the segment hits a triangle (either side).
  bool segment_blocked(const Segment& segment) const;

  /// segment_blocked for every segment (#S entries, 1 = blocked), in parallel.
  std::vector<std::uint8_t> segments_blocked(std::span<const Segment> segments) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace visproxy
