#pragma once
// Inside proxies made of spheres: maximal balls inscribed in a closed mesh, centred on
// (an approximation of) its medial axis, chosen to cover as much of its volume as possible.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "visproxy/measure/proportion.h"
#include "visproxy/mesh/sphere_set.h"
#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

struct InscribedSpheresOptions {
  std::size_t count = 40;  ///< N: spheres to choose (Billen et al. place 40 in the dragon)
  /// Surface samples whose inner Voronoi poles are the candidate centres; 0 chooses
  /// max(20000, 8 N), at most 2 000 000.
  std::size_t surface_samples = 0;
  /// Points spread uniformly over the union of the candidate balls; the greedy choice
  /// maximises the share of them covered.
  std::size_t volume_samples = 20000;
  /// Each radius is the distance from its centre to the surface minus a margin: this
  /// fraction of the bounding-box diagonal plus 2 float ulps of the largest coordinate
  /// (inscribed_sphere_margin), so that a ray tracer holding the mesh and the spheres in
  /// float in the mesh's own coordinates does not see a sphere poke through the surface.
  /// 0 makes the spheres touch the surface (up to rounding).
  double margin_relative = 1e-6;
  /// Uniform points in the spheres' bounding box for reporting the covered volume.
  std::size_t coverage_samples = 1'000'000;
  std::uint64_t seed = 1;
};

struct InscribedSpheres {
  std::vector<Sphere> spheres;  ///< in the order chosen (most volume first)
  std::size_t surface_samples = 0;
  std::size_t candidates = 0;  ///< inner poles kept (one per grid cell) with their centre strictly inside
  /// Enclosed volume of the mesh (divergence theorem: the integral of the winding number,
  /// which counts twice where parts of a self-intersecting mesh overlap), units cubed.
  double mesh_volume = 0;
  /// Fraction of the mesh's volume inside the union of the spheres: Monte Carlo with
  /// `coverage_samples` uniform points in the spheres' bounding box (box_volume), the
  /// 95 % Wilson interval of that count scaled by box_volume / mesh_volume.
  double covered_volume_fraction = 0, covered_volume_lower = 0, covered_volume_upper = 0;
  Proportion coverage_hits;
  double box_volume = 0;
  std::uint64_t coverage_seed = 0;
  /// check_spheres_inside's smallest margin (distance to the surface minus radius), units.
  double min_margin_world = 0;
  /// Spheres whose rounded radius had to be shrunk (by a few ulps) to pass the exact check.
  std::size_t spheres_shrunk = 0;
};

/// The margin by which build_inscribed_spheres keeps each sphere off the surface of a mesh
/// with these bounds: margin_relative x diagonal + 2^-22 x the largest coordinate magnitude
/// (0 when margin_relative is 0). Mesh units.
double inscribed_sphere_margin(const BoundingBox& bounds, double margin_relative);

/// N balls inside the solid bounded by `mesh`, each proved inside by check_spheres_inside
/// (exact: centre strictly inside, radius^2 at most the squared distance to every triangle).
///
/// Candidates are the inner Voronoi poles of area-uniform surface samples (Amenta, Choi and
/// Kolluri's power crust: for each sample the farthest circumcentre of its Delaunay
/// tetrahedra on the inner side of its normal), which approach the medial axis as samples
/// get denser; of these, the one with the largest circumsphere in each cell of a grid of
/// diagonal / max(64, 8 sqrt(N)) is kept when its centre is strictly inside (exact winding
/// number). Then a greedy maximum coverage: points spread uniformly over the union of the
/// candidate balls stand for the volume, and each step takes the ball holding the most
/// volume not yet covered (lazy greedy, so overlapping balls are passed over), which is
/// within 1 - 1/e of the best N-ball choice for that point set. A candidate's radius is its
/// circumradius until it first tops the queue; then it is measured: distance to the surface
/// (closest point through MeasuredSurface's BVH) minus the margin. Deterministic for a seed.
///
/// The mesh must be closed (every edge used as often in each direction): its solid is
/// {winding number != 0}, which is well defined even where the surface self-intersects or
/// has non-manifold edges (CGAL's camel and cow do), and a segment from outside to a ball
/// inside it must cross the surface. Throws InvalidInputError (empty file name) naming the
/// defects (boundary edges, inconsistent orientation) when it is not, and saying why an
/// inside proxy needs a closed mesh; and when fewer than N candidates exist (asking for at
/// most that many).
InscribedSpheres build_inscribed_spheres(const TriangleMesh& mesh, const InscribedSpheresOptions& options = {});

}  // namespace visproxy
