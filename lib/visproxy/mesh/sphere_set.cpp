#include "visproxy/mesh/sphere_set.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "visproxy/core/errors.h"
#include "visproxy/core/files.h"
#include "visproxy/core/json_input.h"
#include "visproxy/mesh/subdivide.h"

namespace visproxy {
namespace {

void append_number(std::string& out, double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);  // shortest round-trip form
  out.append(buffer, result.ptr);
}

TriangleMesh unit_icosphere(int levels) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  TriangleMesh mesh;
  mesh.positions = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                    {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  mesh.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                    {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                    {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  mesh = subdivide_midpoint(mesh, levels);
  for (Vertex& p : mesh.positions) p.normalize();
  return mesh;
}

}  // namespace

std::string encode_sphere_set(const std::vector<Sphere>& spheres) {
  std::string out = "{\"spheres\": [";
  for (std::size_t i = 0; i < spheres.size(); ++i) {
    out += i == 0 ? "\n  {\"center\": [" : ",\n  {\"center\": [";
    for (int axis = 0; axis < 3; ++axis) {
      if (axis > 0) out += ", ";
      append_number(out, spheres[i].center[axis]);
    }
    out += "], \"radius\": ";
    append_number(out, spheres[i].radius);
    out += '}';
  }
  out += spheres.empty() ? "]}\n" : "\n]}\n";
  return out;
}

void write_sphere_set(const std::filesystem::path& path, const std::vector<Sphere>& spheres) {
  write_file_atomically(path, encode_sphere_set(spheres));
}

std::vector<Sphere> read_sphere_set(const std::filesystem::path& path) { return parse_sphere_set(read_file(path), path); }

std::vector<Sphere> parse_sphere_set(std::string_view text, const std::filesystem::path& path) {
  const JsonInput input(path);
  const nlohmann::json document = input.parse(text);
  if (!document.is_object()) input.fail("", "expected an object with a \"spheres\" array");
  const nlohmann::json& list = input.member(document, "spheres", "");
  if (!list.is_array()) input.fail("spheres", "expected an array of spheres");
  std::vector<Sphere> spheres;
  spheres.reserve(list.size());
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string where = json_index_path("spheres", i);
    const std::array<double, 3> center =
        input.triple(input.member(list[i], "center", where), json_member_path(where, "center"));
    const std::string radius_path = json_member_path(where, "radius");
    const double radius = input.number(input.member(list[i], "radius", where), radius_path);
    if (radius < 0) input.fail(radius_path, "must not be negative");
    spheres.push_back({{center[0], center[1], center[2]}, radius});
  }
  return spheres;
}

TriangleMesh sphere_set_mesh(const std::vector<Sphere>& spheres, int levels) {
  const TriangleMesh unit = unit_icosphere(levels);
  TriangleMesh mesh;
  mesh.positions.reserve(spheres.size() * unit.positions.size());
  mesh.triangles.reserve(spheres.size() * unit.triangles.size());
  for (const Sphere& sphere : spheres) {
    TriangleMesh part = unit;
    for (Vertex& p : part.positions) p = sphere.center + sphere.radius * p;
    append_mesh(mesh, part);
  }
  return mesh;
}

}  // namespace visproxy

namespace visproxy {

TriangleMesh sphere_union_boundary_mesh(const std::vector<Sphere>& spheres, int levels) {
  const TriangleMesh all = sphere_set_mesh(spheres, levels);
  if (spheres.size() < 2) return all;
  // A uniform grid over the balls' boxes: each cell lists the balls overlapping it.
  BoundingBox box;
  std::vector<double> radii;
  for (const Sphere& s : spheres) {
    box.extend(s.center - Vertex::Constant(s.radius));
    box.extend(s.center + Vertex::Constant(s.radius));
    radii.push_back(s.radius);
  }
  std::nth_element(radii.begin(), radii.begin() + static_cast<std::ptrdiff_t>(radii.size() / 2), radii.end());
  const double cell = std::max(2 * radii[radii.size() / 2], 1e-12 * box.diagonal());
  const Eigen::Vector3i cells = ((box.max - box.min) / cell).array().ceil().cast<int>().cwiseMax(1).cwiseMin(64);
  const Vertex size = (box.max - box.min).cwiseQuotient(cells.cast<double>());
  auto cell_of = [&](const Vertex& p) {
    Eigen::Vector3i c = ((p - box.min).cwiseQuotient(size)).array().floor().cast<int>();
    return c.cwiseMax(0).cwiseMin(cells - Eigen::Vector3i::Ones());
  };
  auto index = [&](const Eigen::Vector3i& c) { return static_cast<std::size_t>((c.z() * cells.y() + c.y()) * cells.x() + c.x()); };
  std::vector<std::vector<std::uint32_t>> grid(static_cast<std::size_t>(cells.prod()));
  for (std::size_t i = 0; i < spheres.size(); ++i) {
    const Eigen::Vector3i lo = cell_of(spheres[i].center - Vertex::Constant(spheres[i].radius));
    const Eigen::Vector3i hi = cell_of(spheres[i].center + Vertex::Constant(spheres[i].radius));
    for (int z = lo.z(); z <= hi.z(); ++z)
      for (int y = lo.y(); y <= hi.y(); ++y)
        for (int x = lo.x(); x <= hi.x(); ++x) grid[index({x, y, z})].push_back(static_cast<std::uint32_t>(i));
  }
  // Vertex v of the joined mesh belongs to ball v / per_ball.
  const std::size_t per_ball = all.positions.size() / spheres.size();
  std::vector<std::uint8_t> buried(all.positions.size(), 0);
  for (std::size_t v = 0; v < all.positions.size(); ++v) {
    const Vertex& p = all.positions[v];
    for (std::uint32_t other : grid[index(cell_of(p))])
      if (other != v / per_ball && (p - spheres[other].center).norm() < spheres[other].radius * (1 - 1e-9)) {
        buried[v] = 1;
        break;
      }
  }
  TriangleMesh boundary;
  boundary.positions = all.positions;
  for (const Triangle& t : all.triangles)
    if (!(buried[t[0]] && buried[t[1]] && buried[t[2]])) boundary.triangles.push_back(t);
  return boundary;
}

namespace {

// A ball holding spheres[begin, end): centre at the middle of their extents' box, radius
// the largest distance to a far side, grown by 2^-40 of the magnitudes.
Sphere bound_of(const std::vector<Sphere>& spheres, std::size_t begin, std::size_t end) {
  Vertex low = Vertex::Constant(std::numeric_limits<double>::infinity()), high = -low;
  for (std::size_t i = begin; i < end; ++i) {
    low = low.cwiseMin(spheres[i].center - Vertex::Constant(spheres[i].radius));
    high = high.cwiseMax(spheres[i].center + Vertex::Constant(spheres[i].radius));
  }
  const Vertex centre = 0.5 * (low + high);
  double radius = 0, magnitude = centre.cwiseAbs().maxCoeff();
  for (std::size_t i = begin; i < end; ++i) {
    radius = std::max(radius, (spheres[i].center - centre).norm() + spheres[i].radius);
    magnitude = std::max(magnitude, spheres[i].center.cwiseAbs().maxCoeff() + spheres[i].radius);
  }
  return {centre, radius + std::ldexp(magnitude, -40)};
}

// The smallest radius of spheres[begin, end).
double least_radius_of(const std::vector<Sphere>& spheres, std::size_t begin, std::size_t end) {
  double least = std::numeric_limits<double>::infinity();
  for (std::size_t i = begin; i < end; ++i) least = std::min(least, spheres[i].radius);
  return least;
}

void split_spheres(std::vector<Sphere>& spheres, std::size_t begin, std::size_t end, std::size_t leaf, std::vector<SphereCluster>& out) {
  if (end - begin <= leaf) {
    out.push_back({bound_of(spheres, begin, end), static_cast<std::uint32_t>(begin), static_cast<std::uint32_t>(end), 0,
                   least_radius_of(spheres, begin, end)});
    return;
  }
  Vertex low = Vertex::Constant(std::numeric_limits<double>::infinity()), high = -low;
  for (std::size_t i = begin; i < end; ++i) low = low.cwiseMin(spheres[i].center), high = high.cwiseMax(spheres[i].center);
  Eigen::Index axis = 0;
  (high - low).maxCoeff(&axis);
  const std::size_t middle = begin + (end - begin) / 2;
  // Ties broken by the other coordinates and the radius, so that the order is deterministic.
  std::nth_element(spheres.begin() + static_cast<std::ptrdiff_t>(begin), spheres.begin() + static_cast<std::ptrdiff_t>(middle),
                   spheres.begin() + static_cast<std::ptrdiff_t>(end), [axis](const Sphere& a, const Sphere& b) {
                     const auto key = [axis](const Sphere& s) {
                       return std::array<double, 4>{s.center[axis], s.center[(axis + 1) % 3], s.center[(axis + 2) % 3], s.radius};
                     };
                     return key(a) < key(b);
                   });
  split_spheres(spheres, begin, middle, leaf, out);
  split_spheres(spheres, middle, end, leaf, out);
}

}  // namespace

std::vector<SphereCluster> cluster_spheres(std::vector<Sphere>& spheres, std::size_t leaf, std::size_t group) {
  std::vector<SphereCluster> clusters;
  if (spheres.empty()) return clusters;
  split_spheres(spheres, 0, spheres.size(), std::max<std::size_t>(leaf, 1), clusters);
  if (group < 2) return clusters;
  std::vector<SphereCluster> headed;
  for (std::size_t first = 0; first < clusters.size(); first += group) {
    const std::size_t last = std::min(first + group, clusters.size());
    const std::uint32_t begin = clusters[first].begin, end = clusters[last - 1].end;
    headed.push_back({bound_of(spheres, begin, end), begin, end, static_cast<std::uint32_t>(last - first), least_radius_of(spheres, begin, end)});
    headed.insert(headed.end(), clusters.begin() + static_cast<std::ptrdiff_t>(first), clusters.begin() + static_cast<std::ptrdiff_t>(last));
  }
  return headed;
}

std::optional<std::vector<Sphere>> transformed_spheres(const std::vector<Sphere>& spheres, const Eigen::Affine3d& transform) {
  const double scale = std::cbrt(std::abs(transform.linear().determinant()));
  if (!(scale > 0) || !((transform.linear() / scale).transpose() * (transform.linear() / scale)).isIdentity(1e-9))
    return std::nullopt;
  std::vector<Sphere> placed;
  placed.reserve(spheres.size());
  for (const Sphere& s : spheres) placed.push_back({transform * s.center, scale * s.radius});
  return placed;
}

}  // namespace visproxy
