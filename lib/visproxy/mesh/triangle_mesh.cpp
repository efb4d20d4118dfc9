#include "visproxy/mesh/triangle_mesh.h"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "visproxy/core/errors.h"

namespace visproxy {

std::optional<std::size_t> first_vertex_out_of_range(const TriangleMesh& mesh) {
  for (std::size_t i = 0; i < mesh.positions.size(); ++i)
    if (!within_coordinate_range(mesh.positions[i])) return i;
  return std::nullopt;
}

void require_coordinates_in_range(const TriangleMesh& mesh, const std::filesystem::path& file) {
  const std::optional<std::size_t> vertex = first_vertex_out_of_range(mesh);
  if (!vertex) return;
  const Vertex& p = mesh.positions[*vertex];
  for (int axis = 0; axis < 3; ++axis) {
    const char name = "xyz"[axis];
    if (!std::isfinite(p[axis]))
      throw InvalidInputError(file, "vertex " + std::to_string(*vertex) + ": " + name + " is not finite (" +
                                        (std::isnan(p[axis]) ? "nan" : p[axis] > 0 ? "inf" : "-inf") + ")");
  }
  char text[64];
  double magnitude = 0;
  for (int axis = 0; axis < 3; ++axis) magnitude = std::max(magnitude, std::abs(p[axis]));
  std::snprintf(text, sizeof text, "%.9g", magnitude);
  throw InvalidInputError(file, "vertex " + std::to_string(*vertex) + " has a coordinate of magnitude " + text +
                                    ", beyond the 1e100 that geometry in double precision can square and cube");
}

BoundingBox bounding_box(const TriangleMesh& mesh) {
  // The used vertices marked first, then extended in order: one pass over the positions in
  // memory order instead of three random reads per triangle.
  std::vector<std::uint8_t> used(mesh.positions.size(), 0);
  for (const Triangle& triangle : mesh.triangles)
    for (const VertexIndex index : triangle) used[index] = 1;
  BoundingBox box;
  for (std::size_t v = 0; v < mesh.positions.size(); ++v)
    if (used[v]) box.extend(mesh.positions[v]);
  return box;
}

double signed_volume(const TriangleMesh& mesh) {
  const BoundingBox box = bounding_box(mesh);
  const Vertex centre = box.empty() ? Vertex::Zero() : Vertex(0.5 * (box.min + box.max));
  double six_volume = 0;
  for (const Triangle& t : mesh.triangles)
    six_volume += (mesh.positions[t[0]] - centre).dot((mesh.positions[t[1]] - centre).cross(mesh.positions[t[2]] - centre));
  return six_volume / 6.0;
}

std::string content_hash(const TriangleMesh& mesh, std::span<const unsigned char> extra) {
  std::uint64_t hash = 0xCBF29CE484222325ull;
  auto mix = [&](const void* data, std::size_t size) {
    const auto* bytes = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < size; ++i) hash = (hash ^ bytes[i]) * 0x100000001B3ull;
  };
  for (const Vertex& p : mesh.positions) mix(p.data(), 3 * sizeof(double));
  for (const Triangle& t : mesh.triangles) mix(t.data(), sizeof(Triangle));
  mix(extra.data(), extra.size());
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(hash));
  return text;
}

std::vector<Vertex> used_positions(const TriangleMesh& mesh) {
  std::vector<std::uint8_t> used(mesh.positions.size(), 0);
  for (const Triangle& t : mesh.triangles)
    for (VertexIndex v : t) used[v] = 1;
  std::vector<Vertex> points;
  for (std::size_t v = 0; v < used.size(); ++v)
    if (used[v]) points.push_back(mesh.positions[v]);
  return points;
}

void append_mesh(TriangleMesh& mesh, const TriangleMesh& part) {
  const auto base = static_cast<VertexIndex>(mesh.positions.size());
  mesh.positions.insert(mesh.positions.end(), part.positions.begin(), part.positions.end());
  mesh.triangles.reserve(mesh.triangles.size() + part.triangles.size());
  for (const Triangle& t : part.triangles) mesh.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
}

TriangleMesh transformed_mesh(const TriangleMesh& mesh, const Eigen::Affine3d& transform) {
  TriangleMesh result = mesh;
  for (Vertex& p : result.positions) p = transform * p;
  if (transform.linear().determinant() < 0)
    for (Triangle& t : result.triangles) std::swap(t[1], t[2]);
  return result;
}

}  // namespace visproxy
