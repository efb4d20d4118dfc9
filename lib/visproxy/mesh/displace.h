#pragma once
// Seeded smooth bumps on a surface: large test inputs that are not flat. Midpoint
// subdivision keeps a mesh's shape, so every new vertex lies in an old triangle's plane;
// displacing the vertices along their normals by a smooth noise makes the finer mesh a
// finer surface, as scanned meshes are.

#include <cstdint>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

struct DisplaceOptions {
  /// Largest displacement, in mean edge lengths of the mesh.
  double amplitude_relative = 0.25;
  /// Wavelength of the noise, in mean edge lengths: bumps span a few triangles.
  double wavelength_relative = 6;
  int waves = 8;  ///< plane waves summed, each of a seeded random direction and phase
  std::uint64_t seed = 1;
};

/// Each vertex moved along its area-weighted normal by
///   amplitude x (1/waves) sum_k sin(omega_k . (p - c) + phi_k),
/// c the bounding box's centre (so a translated mesh gets the same bumps), |omega_k| = 2 pi /
/// wavelength, directions and phases seeded. No vertex moves further than the amplitude;
/// a vertex with no normal (isolated, or on degenerate triangles only) stays. Triangles are
/// kept as they are, so closedness and orientation are kept; a displacement larger than
/// the local feature size may make the surface self-intersect. Deterministic for a seed.
TriangleMesh displace_along_normals(const TriangleMesh& mesh, const DisplaceOptions& options = {});

/// The mean length of the mesh's edges (each triangle's three sides, shared edges counted
/// once per triangle); 0 for a mesh without triangles.
double mean_edge_length(const TriangleMesh& mesh);

}  // namespace visproxy
