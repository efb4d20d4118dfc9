// Speed and tightness of the convex outside proxies: build_convex_hull against CGAL's
// convex_hull_3 called directly (the peer), and build_bounded_hull at 64, 32, 18 and 6 faces.
//
//   visproxy-bench-hull [--benchmark_* flags]
//
// Timed on bunny00.off and on bunny00 Loop-subdivided twice (OpenMesh), whose hull has
// many more facets. After Google Benchmark's report, a table gives the volume each bounded
// hull adds over the exact hull on the libcgal-demo meshes, next to the axis-aligned
// bounding box's, for comparison with Jacobson (arXiv:2604.14468): under 5 % at 18 faces
// on his shapes.

// OpenMesh wants its IO header before the mesh kernel.
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Subdivider/Uniform/LoopT.hh>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>

#include <benchmark/benchmark.h>

#include <array>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/core/process.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/proxy/bounded_hull.h"
#include "visproxy/proxy/convex_hull.h"

#ifndef VISPROXY_MESH_DIR
#error "VISPROXY_MESH_DIR must name the folder of the extracted libcgal-demo meshes"
#endif

namespace {

using visproxy::TriangleMesh;
using CgalPoint = CGAL::Exact_predicates_inexact_constructions_kernel::Point_3;

std::filesystem::path cgal_mesh(const std::string& name) { return std::filesystem::path(VISPROXY_MESH_DIR) / name; }

// `mesh` after `steps` rounds of Loop subdivision (which moves vertices, so the hull grows
// more facets).
TriangleMesh loop_subdivided(const TriangleMesh& mesh, std::size_t steps) {
  struct DoubleTraits : OpenMesh::DefaultTraits {
    using Point = OpenMesh::Vec3d;
  };
  using OpenMeshMesh = OpenMesh::TriMesh_ArrayKernelT<DoubleTraits>;
  OpenMeshMesh om;
  std::vector<OpenMeshMesh::VertexHandle> handles;
  for (const visproxy::Vertex& p : mesh.positions) handles.push_back(om.add_vertex(OpenMeshMesh::Point(p.x(), p.y(), p.z())));
  for (const visproxy::Triangle& t : mesh.triangles) om.add_face(handles[t[0]], handles[t[1]], handles[t[2]]);
  OpenMesh::Subdivider::Uniform::LoopT<OpenMeshMesh> loop;
  loop.attach(om);
  loop(steps);
  loop.detach();
  TriangleMesh result;
  for (const auto vertex : om.vertices()) {
    const auto& p = om.point(vertex);
    result.positions.emplace_back(p[0], p[1], p[2]);
  }
  for (const auto face : om.faces()) {
    visproxy::Triangle triangle{};
    int corner = 0;
    for (const auto vertex : om.fv_range(face)) triangle[corner++] = static_cast<visproxy::VertexIndex>(vertex.idx());
    result.triangles.push_back(triangle);
  }
  return result;
}

void register_benchmarks(const std::string& name, const TriangleMesh& mesh) {
  std::vector<CgalPoint> points;
  for (const visproxy::Vertex& p : mesh.positions) points.emplace_back(p.x(), p.y(), p.z());
  const visproxy::ConvexHullResult hull = visproxy::build_convex_hull(mesh);
  const double hull_facets = static_cast<double>(hull.faces);

  benchmark::RegisterBenchmark(("convex_hull/visproxy/" + name).c_str(), [mesh, hull_facets](benchmark::State& state) {
    for (auto _ : state) benchmark::DoNotOptimize(visproxy::build_convex_hull(mesh));
    state.counters["hull_faces"] = hull_facets;
  })->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark(("convex_hull/cgal/" + name).c_str(), [points](benchmark::State& state) {
    for (auto _ : state) {
      CGAL::Surface_mesh<CgalPoint> cgal_hull;
      CGAL::convex_hull_3(points.begin(), points.end(), cgal_hull);
      benchmark::DoNotOptimize(cgal_hull.number_of_faces());
    }
  })->Unit(benchmark::kMillisecond);
  for (const std::size_t max_faces : {64u, 32u, 18u, 6u})
    benchmark::RegisterBenchmark(("bounded_hull/" + std::to_string(max_faces) + "/" + name).c_str(),
                                 [mesh, max_faces](benchmark::State& state) {
                                   visproxy::BoundedHullResult result;
                                   for (auto _ : state) result = visproxy::build_bounded_hull(mesh, {.max_faces = max_faces});
                                   state.counters["faces"] = static_cast<double>(result.faces);
                                   state.counters["added_volume_%"] = 100.0 * result.added_volume_fraction();
                                 })
        ->Unit(benchmark::kMillisecond);
}

void print_added_volume_table() {
  std::printf("\nVolume added over the exact convex hull (%%); AABB = axis-aligned bounding box\n");
  std::printf("%-26s %7s %9s %9s %9s %9s %9s\n", "mesh", "facets", "64", "32", "18", "6", "AABB");
  for (const char* name : {"bunny00.off", "armadillo.off", "knot1.off", "knot2.off", "ChineseDragon-10kv.off",
                           "elephant-with-holes.off", "sphere.ply"}) {
    const TriangleMesh mesh = visproxy::read_mesh(cgal_mesh(name));
    const visproxy::ConvexHullResult hull = visproxy::build_convex_hull(mesh);
    std::printf("%-26s %7zu", name, hull.faces);
    for (const std::size_t max_faces : {64u, 32u, 18u, 6u})
      std::printf(" %9.2f", 100.0 * visproxy::build_bounded_hull(mesh, {.max_faces = max_faces}).added_volume_fraction());
    const visproxy::BoundingBox box = visproxy::bounding_box(mesh);
    std::printf(" %9.2f\n", 100.0 * ((box.max - box.min).prod() / hull.volume - 1.0));
  }
  std::printf("Jacobson (arXiv:2604.14468), on his shapes: under 5 %% at 18 faces; 1.61x the hull at 6 faces on his teaser.\n");
}

}  // namespace

int main(int argc, char** argv) {
  visproxy::disable_transparent_huge_pages();  // see visproxy/core/process.h
  try {
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    const TriangleMesh bunny = visproxy::read_mesh(cgal_mesh("bunny00.off"));
    register_benchmarks("bunny00", bunny);
    register_benchmarks("bunny00_loop2", loop_subdivided(bunny, 2));
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    print_added_volume_table();
  } catch (const std::exception& error) {
    std::fprintf(stderr, "visproxy-bench-hull: %s\n", error.what());
    return 2;
  }
  return 0;
}
