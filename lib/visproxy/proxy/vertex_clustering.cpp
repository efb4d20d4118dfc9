// Vertex-clustering decimation.
//
// J. Rossignac, P. Borrel. Multi-resolution 3D approximations for rendering complex scenes.
// Modeling in Computer Graphics, 1993: vertices in one grid cell merge into one, triangles
// that keep three distinct corners survive.
// P. Lindstrom. Out-of-core simplification of large polygonal models. SIGGRAPH 2000: the
// representative of a cell minimises the summed plane quadric of the triangles touching it,
// solved with a pseudo-inverse about the cell's area-weighted mean, so that flat and
// ridge-like cells stay well defined.

#include "visproxy/proxy/vertex_clustering.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <string>
#include <vector>

#include "visproxy/core/errors.h"

namespace visproxy {
namespace {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
// Cell coordinates packed 21 bits per axis, x highest: sorting the keys sorts the cells.
using CellKey = std::uint64_t;
constexpr int kBitsPerAxis = 21;

// Eigenvalues of a cell's quadric below this fraction of the largest are treated as zero.
constexpr double kRelativeEigenvalueCutoff = 1e-3;
constexpr double kMaxCellsPerAxis = (1u << kBitsPerAxis) - 1;

struct Cluster {
  CellKey cell = 0;
  Mat3 a = Mat3::Zero();  // sum of w n n^T
  Vec3 b = Vec3::Zero();  // sum of w d n
  Vec3 sum = Vec3::Zero();  // of the local positions of its vertices
  double count = 0;
  Vec3 area_weighted_sum = Vec3::Zero();  // of its triangle corners, weighted by area
  double area = 0;

  // Area-weighted mean of its corners (the same for a soup as for the welded mesh), or the
  // plain mean of its vertices when they touch no triangle of non-zero area.
  Vec3 mean() const { return area > 0 ? Vec3(area_weighted_sum / area) : Vec3(sum / count); }
};

bool exactly_collinear(const Vertex& a, const Vertex& b, const Vertex& c) {
  using Point = CGAL::Exact_predicates_inexact_constructions_kernel::Point_3;
  return CGAL::collinear(Point(a.x(), a.y(), a.z()), Point(b.x(), b.y(), b.z()), Point(c.x(), c.y(), c.z()));
}

// Minimiser of |A x + b|-type quadric x^T A x + 2 b.x nearest to `mean` in the flat directions.
Vec3 quadric_minimiser(const Cluster& cluster, const Vec3& mean) {
  if (!(cluster.a.trace() > 0)) return mean;
  const Eigen::SelfAdjointEigenSolver<Mat3> solver(cluster.a);
  if (solver.info() != Eigen::Success) return mean;
  const Vec3& eigenvalues = solver.eigenvalues();  // ascending
  const double cutoff = kRelativeEigenvalueCutoff * eigenvalues[2];
  const Vec3 gradient = cluster.a * mean + cluster.b;
  Vec3 x = mean;
  for (int i = 0; i < 3; ++i)
    if (eigenvalues[i] > cutoff) {
      const Vec3 direction = solver.eigenvectors().col(i);
      x -= direction * (direction.dot(gradient) / eigenvalues[i]);
    }
  return x.allFinite() ? x : mean;
}

}  // namespace

VertexClusteringResult cluster_vertices(const TriangleMesh& mesh, const VertexClusteringOptions& options) {
  if (!std::isfinite(options.cell_size_relative) || !(options.cell_size_relative > 0))
    throw InvalidInputError("", "the clustering cell size " + std::to_string(options.cell_size_relative) +
                                    " is not a finite positive fraction of the bounding box");
  if (mesh.triangles.empty()) throw InvalidInputError("", "the mesh has no triangles to cluster");
  const std::size_t vertex_count = mesh.positions.size();
  std::vector<std::uint8_t> used(vertex_count, 0);
  for (const Triangle& triangle : mesh.triangles)
    for (const VertexIndex v : triangle) {
      if (v >= vertex_count)
        throw InvalidInputError("", "triangle corner " + std::to_string(v) + " is out of range (" +
                                        std::to_string(vertex_count) + " vertices)");
      if (!used[v] && !mesh.positions[v].allFinite())
        throw InvalidInputError("", "vertex " + std::to_string(v) + " has a non-finite coordinate");
      used[v] = 1;
    }

  const BoundingBox box = bounding_box(mesh);
  const double largest_extent = (box.max - box.min).maxCoeff();
  VertexClusteringResult result;
  result.cell_size_world = options.cell_size_relative * largest_extent;
  if (!(largest_extent > 0)) return result;  // every triangle is a point
  if (!(largest_extent / result.cell_size_world <= kMaxCellsPerAxis))
    throw InvalidInputError("", "the clustering cell size " + std::to_string(options.cell_size_relative) +
                                    " makes more than 2^21 - 1 cells along an axis");
  const double cell = result.cell_size_world;

  // Cell of every used vertex; clusters numbered in cell order.
  std::vector<std::pair<CellKey, VertexIndex>> used_vertices;
  for (std::size_t v = 0; v < vertex_count; ++v) {
    if (!used[v]) continue;
    const Vec3 scaled = (mesh.positions[v] - box.min) / cell;
    CellKey key = 0;
    for (int axis = 0; axis < 3; ++axis)
      key = (key << kBitsPerAxis) | static_cast<CellKey>(std::floor(scaled[axis]));
    used_vertices.emplace_back(key, static_cast<VertexIndex>(v));
  }
  std::sort(used_vertices.begin(), used_vertices.end());
  std::vector<std::uint32_t> cluster_of(vertex_count, 0);
  std::vector<Cluster> clusters;
  // Quadrics and means in a frame at the box's minimum, scaled by the largest extent.
  const double scale = 1 / largest_extent;
  for (const auto& [key, v] : used_vertices) {
    if (clusters.empty() || clusters.back().cell != key) clusters.push_back(Cluster{key});
    cluster_of[v] = static_cast<std::uint32_t>(clusters.size() - 1);
    clusters.back().sum += (mesh.positions[v] - box.min) * scale;
    clusters.back().count += 1;
  }
  for (const Triangle& triangle : mesh.triangles) {
    const Vec3 p0 = (mesh.positions[triangle[0]] - box.min) * scale;
    const Vec3 p1 = (mesh.positions[triangle[1]] - box.min) * scale;
    const Vec3 p2 = (mesh.positions[triangle[2]] - box.min) * scale;
    const Vec3 cross = (p1 - p0).cross(p2 - p0);
    const double length = cross.norm();
    if (!(length > 0)) continue;
    const Vec3 n = cross / length;
    const double weight = length / 2, d = -n.dot(p0);
    const Mat3 a = weight * n * n.transpose();
    const Vec3 b = weight * d * n;
    const std::uint32_t c0 = cluster_of[triangle[0]], c1 = cluster_of[triangle[1]], c2 = cluster_of[triangle[2]];
    const Vec3* corners[3] = {&p0, &p1, &p2};
    for (int c = 0; c < 3; ++c) {
      Cluster& cluster = clusters[cluster_of[triangle[c]]];
      cluster.area_weighted_sum += weight * *corners[c];
      cluster.area += weight;
    }
    clusters[c0].a += a;
    clusters[c0].b += b;
    if (c1 != c0) {
      clusters[c1].a += a;
      clusters[c1].b += b;
    }
    if (c2 != c0 && c2 != c1) {
      clusters[c2].a += a;
      clusters[c2].b += b;
    }
  }

  // Representatives, clamped into their cells.
  std::vector<Vertex> representative(clusters.size());
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    const Cluster& cluster = clusters[c];
    const Vec3 local = quadric_minimiser(cluster, cluster.mean());
    Vertex world = box.min + local * largest_extent;
    for (int axis = 0; axis < 3; ++axis) {
      const CellKey index = (cluster.cell >> (kBitsPerAxis * (2 - axis))) & ((CellKey{1} << kBitsPerAxis) - 1);
      const double low = box.min[axis] + static_cast<double>(index) * cell;
      const double high = box.min[axis] + static_cast<double>(index + 1) * cell;
      world[axis] = std::clamp(world[axis], low, high);
    }
    representative[c] = world;
  }
  for (const auto& [key, v] : used_vertices)
    result.max_vertex_displacement_world =
        std::max(result.max_vertex_displacement_world, (mesh.positions[v] - representative[cluster_of[v]]).norm());

  // Clusters whose representatives coincide become one vertex.
  std::vector<std::uint32_t> by_position(clusters.size());
  std::iota(by_position.begin(), by_position.end(), 0u);
  const auto lexicographic = [&representative](std::uint32_t a, std::uint32_t b) {
    const Vertex& p = representative[a];
    const Vertex& q = representative[b];
    if (p.x() != q.x()) return p.x() < q.x();
    if (p.y() != q.y()) return p.y() < q.y();
    if (p.z() != q.z()) return p.z() < q.z();
    return a < b;
  };
  std::sort(by_position.begin(), by_position.end(), lexicographic);
  std::vector<std::uint32_t> merged(clusters.size());
  for (std::size_t i = 0; i < by_position.size(); ++i)
    merged[by_position[i]] =
        i > 0 && representative[by_position[i]] == representative[by_position[i - 1]] ? merged[by_position[i - 1]]
                                                                                       : by_position[i];

  // Triangles over three distinct, non-collinear representatives; the first of any repeat.
  std::vector<std::array<std::uint32_t, 3>> kept;
  for (const Triangle& triangle : mesh.triangles) {
    const std::array<std::uint32_t, 3> t = {merged[cluster_of[triangle[0]]], merged[cluster_of[triangle[1]]],
                                            merged[cluster_of[triangle[2]]]};
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) continue;
    if (exactly_collinear(representative[t[0]], representative[t[1]], representative[t[2]])) continue;
    kept.push_back(t);
  }
  std::vector<std::array<std::uint32_t, 3>> sorted_corners(kept.size());
  for (std::size_t t = 0; t < kept.size(); ++t) {
    sorted_corners[t] = kept[t];
    std::sort(sorted_corners[t].begin(), sorted_corners[t].end());
  }
  std::vector<std::uint32_t> order(kept.size());
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&sorted_corners](std::uint32_t a, std::uint32_t b) {
    return sorted_corners[a] != sorted_corners[b] ? sorted_corners[a] < sorted_corners[b] : a < b;
  });
  std::vector<std::uint8_t> repeat(kept.size(), 0);
  for (std::size_t i = 1; i < order.size(); ++i)
    if (sorted_corners[order[i]] == sorted_corners[order[i - 1]]) repeat[order[i]] = 1;

  constexpr std::uint32_t kUnused = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> output_index(clusters.size(), kUnused);
  for (std::size_t t = 0; t < kept.size(); ++t) {
    if (repeat[t]) continue;
    Triangle out;
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t cluster = kept[t][c];
      if (output_index[cluster] == kUnused) {
        output_index[cluster] = static_cast<std::uint32_t>(result.mesh.positions.size());
        result.mesh.positions.push_back(representative[cluster]);
      }
      out[c] = output_index[cluster];
    }
    result.mesh.triangles.push_back(out);
  }
  return result;
}

}  // namespace visproxy
