#pragma once
// The initial sphere set of a mesh (occluding-spheres paper, section 3): circumspheres of
// the tetrahedra that fill it. merge_spheres.h reduces it to a few spheres.

#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "visproxy/core/choices.h"
#include "visproxy/mesh/sphere_set.h"
#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

/// How the tetrahedra inside the mesh are found.
enum class InnerTetrahedra {
  /// Paper, 3.1: 3D Delaunay triangulation of area-uniform surface samples; a tetrahedron
  /// is inner when, at each of its four corners, the circumsphere's outward normal makes an
  /// angle of at most 90 degrees with the surface normal there. Any input; needs outward
  /// normals (a closed, consistently oriented mesh that is inside out is flipped first).
  normals,
  /// TetGen's constrained Delaunay tetrahedralization of the mesh (switches "pzQ", no
  /// refinement): every tetrahedron is inside by construction, no normals are consulted.
  /// Each is covered by its circumsphere or, where that reaches further out of the surface
  /// (radius minus the signed distance of the centre, exact inside test), by its smallest
  /// enclosing ball: the circumspheres of flat tetrahedra of a constrained triangulation
  /// are not empty of the mesh's other vertices and can be huge (armadillo: the initial set's
  /// GSSA 4.15 x the mesh's with circumspheres only, 1.057 x with the choice). Needs a
  /// watertight mesh; slower (more spheres, a distance query per tetrahedron).
  tetgen,
};

/// "normals", "tetgen".
template <> const std::vector<std::pair<std::string_view, InnerTetrahedra>>& choice_names<InnerTetrahedra>();

/// Surface samples for a set merged down to at most `largest_level` spheres:
/// max(4000, 4 x largest_level), at most 2 000 000 (bunny00: 4000 samples, 13.5 K
/// circumspheres, 0.35 s for spheres:1000,250,100,25,10).
std::size_t default_circumsphere_samples(std::size_t largest_level);

struct CircumsphereOptions {
  InnerTetrahedra tetrahedra = InnerTetrahedra::normals;
  std::size_t samples = 4000;  ///< surface samples triangulated (normals)
  std::uint64_t seed = 1;       ///< of the samples
};

struct CircumsphereSet {
  /// One ball per inner tetrahedron, sorted by centre (x, y, z) then radius.
  std::vector<Sphere> spheres;
  std::size_t points = 0;      ///< vertices triangulated (samples, or TetGen's output points)
  std::size_t tetrahedra = 0;  ///< finite tetrahedra of the triangulation
  /// tetgen: tetrahedra covered by their smallest enclosing ball instead of their circumsphere
  std::size_t balls_replaced = 0;
};

/// Balls covering the tetrahedra inside `mesh` (see InnerTetrahedra): circumspheres, and
/// for tetgen some smallest enclosing balls. Their union covers the mesh's volume (tetgen:
/// exactly the tetrahedralized volume; normals: up to sampling) and bulges out by about the
/// sample spacing or the tetrahedra's size.
/// Deterministic for a seed. Throws InvalidInputError (empty file name) when the mesh has no
/// triangle of non-zero area, is flat (no tetrahedra), or, for tetgen, is not watertight
/// (naming the defects) or TetGen fails.
CircumsphereSet build_circumsphere_set(const TriangleMesh& mesh, const CircumsphereOptions& options = {});

}  // namespace visproxy
