#pragma once
// A procedural hairball: many thin tubes wandering through a ball. Highly complex geometry
// with no clean inside (the tubes are open and cross each other), the paper's hardest case.

#include <cstddef>
#include <cstdint>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

struct HairballOptions {
  std::size_t triangles = 2'000'000;  ///< about this many (a whole number of tubes)
  std::uint64_t seed = 1;
  double radius = 1.0;                ///< the tubes stay within this ball around the origin
  double tube_radius = 0.004;
  int sides = 6;                      ///< polygon of each tube's cross-section
  int segments = 40;                  ///< segments along each tube
  double segment_length = 0.05;
};

/// The tubes as one triangle mesh: each a random walk with slowly turning direction,
/// turned back towards the centre near the ball's surface, swept by a `sides`-gon. Open
/// ends; 2 * sides * segments triangles per tube. Deterministic for a seed.
TriangleMesh make_hairball(const HairballOptions& options = {});

}  // namespace visproxy
