#pragma once
// A BVH built by Embree's builder (rtcBuildBVH) and traversed by our own code, so that
// the work of each query can be counted: nodes visited and primitives tested. Debian's
// Embree has no statistics counters; these counts do not depend on machine noise.

#include <cstdint>
#include <memory>
#include <span>

#include "visproxy/mesh/sphere_set.h"
#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

struct TraversalCounts {
  std::uint64_t nodes = 0;       ///< BVH nodes whose boxes a query tested
  std::uint64_t primitives = 0;  ///< triangles or balls a query tested
};

class CountingBvh {
 public:
  explicit CountingBvh(const TriangleMesh& mesh);
  explicit CountingBvh(std::span<const Sphere> spheres);
  ~CountingBvh();
  CountingBvh(const CountingBvh&) = delete;
  CountingBvh& operator=(const CountingBvh&) = delete;

  /// Whether the open segment meets a triangle (either side, double precision
  /// Moller-Trumbore) or a solid ball; adds the work done to `counts`. Stops at the first
  /// hit, visiting nearer children first.
  bool segment_blocked(const Vertex& from, const Vertex& to, TraversalCounts& counts) const;

  /// Bounds of everything in it.
  const BoundingBox& bounds() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace visproxy
