#pragma once
// Seeded random lines for measuring how often geometry blocks rays.

#include <cstdint>
#include <vector>

#include "visproxy/mesh/sphere_set.h"
#include "visproxy/mesh/triangle_mesh.h"
#include "visproxy/trace/ray_scene.h"

namespace visproxy {

/// A sphere that contains every vertex triangles use: centred on the bounding box,
/// radius half its diagonal (slightly enlarged so that no vertex lies on it).
Sphere bounding_sphere(const TriangleMesh& mesh);

/// `count` isotropic random lines through `sphere`, each given as the chord between two
/// independent uniform points on the sphere: this is exactly the isotropic (motion
/// invariant) line measure restricted to lines meeting the sphere, so the fraction of
/// chords that hit a convex body K inside the sphere converges to area(K) / area(sphere)
/// (occluding-spheres paper, section 3.3). Deterministic for a given seed.
std::vector<Segment> isotropic_lines(const Sphere& sphere, std::size_t count, std::uint64_t seed);

}  // namespace visproxy
