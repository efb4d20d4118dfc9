#pragma once
// Alpha wrapping: a watertight, 2-manifold, self-intersection-free surface that contains any
// triangle input, even a soup with holes, cracks and self-intersections. An *outside* proxy.

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

struct AlphaWrapOptions {
  /// Alpha, relative to the input's bounding-box diagonal: roughly the radius of the
  /// smallest ball that may pass through gaps and carve concavities. Smaller alpha follows
  /// the input more closely and gives more triangles. Default 1/20 of the diagonal: the wrap
  /// keeps limbs and large concavities, closes gaps and holes narrower than about 1/10 of
  /// the diagonal.
  double alpha_relative = 1.0 / 20;
  /// Offset, relative to the diagonal: how far the wrap stays from the input. Default 1/600
  /// of the diagonal (0.17 %): far enough above rounding that the wrap never touches the
  /// input, close enough that it adds little visible thickness.
  double offset_relative = 1.0 / 600;
};

struct AlphaWrapResult {
  TriangleMesh mesh;         ///< the wrap, consistently oriented with outward normals
  double alpha_world = 0;    ///< alpha_relative × diagonal, in input units
  double offset_world = 0;   ///< offset_relative × diagonal, in input units
};

/// 3D alpha wrap of the input's triangles (CGAL's Alpha_wrap_3, Portaneri et al. 2022,
/// "Alpha Wrapping with an Offset"). The input is taken as a triangle soup: no manifoldness,
/// orientation or closedness is needed; triangles with collinear corners are wrapped as the
/// segment or point they are. Unreferenced vertices are ignored.
///
/// Guarantees (CGAL's, re-checked by the tests with exact predicates): the result is closed,
/// 2-manifold and free of self-intersections; it encloses every input triangle, and no
/// input triangle touches it. Its vertices lie at about `offset_world` from the input, so
/// the wrap is within roughly alpha_world + offset_world of the input (not a proven bound).
/// Several far-apart input components give several closed components. Cavities inside a
/// closed input are not wrapped (the wrap is the outer boundary only).
///
/// Deterministic: the same input and options give the same output, bit for bit.
/// Throws InvalidInputError (empty file name) if an option is not a positive finite number,
/// the mesh has no triangle, an index is out of range, a used coordinate is not finite, or
/// all triangles collapse to one point (zero diagonal).
AlphaWrapResult build_alpha_wrap(const TriangleMesh& mesh, const AlphaWrapOptions& options);

}  // namespace visproxy
