#pragma once
// Sets of spheres: the primitives of sphere proxies, their JSON file and a mesh for viewing.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

struct Sphere {
  Vertex center = Vertex::Zero();
  double radius = 0.0;

  friend bool operator==(const Sphere&, const Sphere&) = default;
};

/// The bytes of a sphere-set file:
///   {"spheres": [{"center": [x, y, z], "radius": r}, ...]}
/// with shortest round-trip numbers, so reading it back gives the same doubles.
std::string encode_sphere_set(const std::vector<Sphere>& spheres);

/// Writes encode_sphere_set(spheres) to `path` atomically; throws IOError on failure.
void write_sphere_set(const std::filesystem::path& path, const std::vector<Sphere>& spheres);

/// Reads a sphere-set file. Throws IOError when it cannot be read and InvalidInputError
/// naming the file and the JSON path at fault ("spheres[3].radius: must not be negative")
/// when it is not valid JSON of the shape above or a radius is negative.
std::vector<Sphere> read_sphere_set(const std::filesystem::path& path);

/// The same from the file's text; `path` names it in errors.
std::vector<Sphere> parse_sphere_set(std::string_view text, const std::filesystem::path& path);

/// The spheres placed by `transform` (centres mapped, radii scaled), when it is a
/// similarity: a rotation or reflection, a translation and one scale (within 1e-9). nullopt
/// for a shear, an uneven or a zero scale, which would make the balls ellipsoids.
std::optional<std::vector<Sphere>> transformed_spheres(const std::vector<Sphere>& spheres, const Eigen::Affine3d& transform);

/// Every sphere as a closed triangle mesh (an icosahedron subdivided `levels` times and
/// pushed onto the sphere), joined into one mesh: for looking at sphere proxies in a mesh
/// viewer. Its vertices lie on the spheres, so it is slightly smaller than they are.
TriangleMesh sphere_set_mesh(const std::vector<Sphere>& spheres, int levels = 2);

/// sphere_set_mesh without the triangles that lie inside the union: those whose three
/// corners are all strictly inside another ball. What remains approximates the boundary of
/// the union of the balls, the surface a sphere proxy shows to rays (for distances between
/// a sphere set and a mesh). Level 2 keeps within 1.3 % of each radius, level 3 within 0.3 %.
TriangleMesh sphere_union_boundary_mesh(const std::vector<Sphere>& spheres, int levels = 2);

/// A run of nearby spheres, spheres[begin, end) of the set cluster_spheres() reordered, and a
/// ball that holds every one of them. A cluster with children > 0 heads the next `children`
/// clusters of the list, and its run is theirs.
struct SphereCluster {
  Sphere bound;
  std::uint32_t begin = 0, end = 0;
  std::uint32_t children = 0;
  double least_radius = 0;  ///< the smallest radius of its spheres
};

/// Reorders `spheres` into clusters of at most `leaf` (at least 1) by median splits along
/// the longest side of their centres' bounding box, and returns the clusters in order; each
/// bound holds its spheres in double arithmetic rounded outwards (centre at the middle of
/// their extents' box, radius the largest distance to a far side, grown by 2^-40 of the
/// magnitudes). With `group` of 2 or more, each run of `group` consecutive clusters (the
/// order keeps siblings of the splits together) is preceded by a cluster that heads them,
/// with a bound of all their spheres. Deterministic. Empty for an empty set.
std::vector<SphereCluster> cluster_spheres(std::vector<Sphere>& spheres, std::size_t leaf, std::size_t group = 0);

}  // namespace visproxy
