#pragma once
// Random points on a triangle surface with the normals of their triangles: the input of
// the sphere-set builders.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

struct SurfaceSample {
  Vertex position;
  Vertex normal;  ///< unit normal of the triangle it lies on, (b - a) x (c - a) normalised
  std::uint32_t triangle = 0;
};

/// `count` points spread uniformly by area over the triangles of `mesh` (each triangle
/// chosen with probability proportional to its area, then a uniform point in it), in
/// triangle order. Triangles whose area rounds to zero are never chosen. Deterministic for
/// a seed. Throws InvalidInputError (empty file name) when no triangle has an area, an
/// index is out of range or a coordinate is not finite.
std::vector<SurfaceSample> sample_surface(const TriangleMesh& mesh, std::size_t count, std::uint64_t seed);

/// About `count` points spread evenly over the surface (stratified): 4 x count area-uniform
/// candidates (sample_surface), of which the first in each cell of a uniform grid is kept,
/// the cell size tuned so that about `count` cells hold a candidate. Fewer clumps and gaps
/// than sample_surface at the same count. In candidate order; deterministic for a seed;
/// same errors as sample_surface.
std::vector<SurfaceSample> sample_surface_evenly(const TriangleMesh& mesh, std::size_t count, std::uint64_t seed);

}  // namespace visproxy
