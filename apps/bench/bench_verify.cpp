// How the proof of an outside claim scales with the mesh (n vertices) and the proxy (m
// faces): the convex hull of large closed meshes, proved to contain them as `visproxy
// verify` proves it (check_containment, then the margin), timed step by step over repeated
// runs, against CGAL's Side_of_triangle_mesh classifying the same vertices (a vertex test
// only, no surface proof) in the same process.
//
//   visproxy-bench-verify [--repetitions R] [--loop-to TRIANGLES] [--torus UxV]... [MESH...]
//
// Without arguments: two tori of 1 M triangles whose hulls have hundreds of thousands of
// faces, and four libcgal-demo meshes as they are and Loop-subdivided to at least
// --loop-to triangles (default 1 M).

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Subdivision_method_3/subdivision_methods_3.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "surface_mesh.h"
#include "visproxy/core/process.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/proxy/convex_hull.h"
#include "visproxy/verify/containment.h"

namespace {

using namespace visproxy;
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using CgalMesh = CGAL::Surface_mesh<Kernel::Point_3>;

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// A torus of u x v quads (2uv triangles), major radius 1, minor radius 0.35, outward.
TriangleMesh torus(int u, int v) {
  TriangleMesh mesh;
  const double two_pi = 2 * std::numbers::pi;
  for (int i = 0; i < u; ++i)
    for (int j = 0; j < v; ++j) {
      const double a = two_pi * i / u, b = two_pi * j / v;
      const double r = 1 + 0.35 * std::cos(b);
      mesh.positions.emplace_back(r * std::cos(a), r * std::sin(a), 0.35 * std::sin(b));
    }
  auto at = [&](int i, int j) { return static_cast<VertexIndex>((i % u) * v + (j % v)); };
  for (int i = 0; i < u; ++i)
    for (int j = 0; j < v; ++j) {
      mesh.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      mesh.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  return mesh;
}

CgalMesh to_cgal(const TriangleMesh& mesh) { return bench::to_surface_mesh<Kernel::Point_3>(mesh); }
TriangleMesh from_cgal(const CgalMesh& mesh) { return bench::from_surface_mesh(mesh); }

struct Range {
  double low = 1e300, high = 0;
  void add(double x) { low = std::min(low, x), high = std::max(high, x); }
};

void run(const std::string& name, const TriangleMesh& mesh, int repetitions) {
  auto start = std::chrono::steady_clock::now();
  const TriangleMesh hull = build_convex_hull(mesh).mesh;
  const double hull_seconds = seconds_since(start);
  const CgalMesh cgal_hull = to_cgal(hull);
  Range locate, crossing, proof, margin, peer;
  bool contained = true;
  for (int r = 0; r < repetitions; ++r) {
    start = std::chrono::steady_clock::now();
    locate_points(hull, mesh.positions);
    locate.add(seconds_since(start));
    start = std::chrono::steady_clock::now();
    find_crossing_triangles(hull, mesh);
    crossing.add(seconds_since(start));
    start = std::chrono::steady_clock::now();
    const Containment containment = check_containment(hull, mesh);
    contained = contained && containment.contained();
    proof.add(seconds_since(start));
    // As `visproxy verify`: the margin is 0 when a vertex lies on the surface, measured otherwise.
    start = std::chrono::steady_clock::now();
    if (containment.vertices_on_boundary == 0) closest_distance_to_surface(hull, mesh.positions);
    margin.add(seconds_since(start));
    start = std::chrono::steady_clock::now();
    const CGAL::Side_of_triangle_mesh<CgalMesh, Kernel> side(cgal_hull);
    std::size_t outside = 0;
    for (const Vertex& p : mesh.positions) outside += side({p.x(), p.y(), p.z()}) == CGAL::ON_UNBOUNDED_SIDE;
    peer.add(seconds_since(start));
    contained = contained && outside == 0;
  }
  std::printf("%-24s %9zu %9zu %8zu %7.2f  %6.2f-%-6.2f %6.2f-%-6.2f %6.2f-%-6.2f %6.2f-%-6.2f %6.2f-%-6.2f %6.2f-%-6.2f  %.2f-%.2f  %s\n",
              name.c_str(), mesh.positions.size(), mesh.triangles.size(), hull.triangles.size(), hull_seconds,
              locate.low, locate.high, crossing.low, crossing.high, proof.low, proof.high, margin.low, margin.high,
              proof.low + margin.low, proof.high + margin.high, peer.low, peer.high, (proof.low + margin.low) / peer.high,
              (proof.high + margin.high) / peer.low, contained ? "holds" : "DOES NOT HOLD");
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  visproxy::disable_transparent_huge_pages();  // see visproxy/core/process.h
  int repetitions = 3;
  std::size_t loop_to = 1000000;
  std::vector<std::pair<int, int>> tori;
  std::vector<std::string> meshes;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--repetitions" && i + 1 < argc) {
      repetitions = std::max(1, std::stoi(argv[++i]));
    } else if (arg == "--loop-to" && i + 1 < argc) {
      loop_to = std::stoul(argv[++i]);
    } else if (arg == "--torus" && i + 1 < argc) {
      int u = 0, v = 0;
      if (std::sscanf(argv[++i], "%dx%d", &u, &v) != 2 || u < 3 || v < 3) {
        std::fprintf(stderr, "visproxy-bench-verify: --torus takes UxV, two counts of at least 3 (e.g. 1000x500)\n");
        return 2;
      }
      tori.emplace_back(u, v);
    } else if (arg == "--help" || arg == "-h") {
      std::printf("usage: visproxy-bench-verify [--repetitions R] [--loop-to TRIANGLES] [--torus UxV]... [MESH...]\n");
      return 0;
    } else {
      meshes.push_back(arg);
    }
  }
  if (tori.empty() && meshes.empty()) {
    tori = {{1000, 500}, {250, 2000}};
    for (const char* name : {"armadillo.off", "camel.off", "cow.off", "knot1.off"})
      meshes.push_back(std::string(VISPROXY_MESH_DIR) + "/" + name);
  }
  std::printf("Proof that the convex hull contains the mesh, as `visproxy verify` runs it (check_containment on all\n"
              "threads, then the margin unless a vertex lies on the hull); seconds, lowest-highest of %d runs.\n"
              "rays s and pairs s: the two steps of the general proof (winding numbers along rays; triangle pairs that\n"
              "meet), which a convex container no longer needs, for comparison. Peer: CGAL's Side_of_triangle_mesh on\n"
              "the hull, one thread, classifying the vertices only (no surface proof). n = vertices, m = hull triangles.\n\n",
              repetitions);
  std::printf("%-24s %9s %9s %8s %7s  %-13s %-13s %-13s %-13s %-13s %-13s  %s\n", "mesh", "n", "triangles", "m", "hull s",
              "rays s", "pairs s", "proof s", "margin s", "verify s", "peer s", "verify/peer");
  try {
    for (const auto& [u, v] : tori) run("torus-" + std::to_string(u) + "x" + std::to_string(v), torus(u, v), repetitions);
    for (const std::string& path : meshes) {
      const TriangleMesh mesh = read_mesh(path);
      const std::string name = path.substr(path.find_last_of('/') + 1);
      run(name, mesh, repetitions);
      if (loop_to > mesh.triangles.size()) {
        CgalMesh cgal = to_cgal(mesh);
        int levels = 0;
        while (cgal.number_of_faces() < loop_to) {
          CGAL::Subdivision_method_3::Loop_subdivision(cgal, CGAL::parameters::number_of_iterations(1));
          ++levels;
        }
        run(name + " loop" + std::to_string(levels), from_cgal(cgal), repetitions);
      }
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "visproxy-bench-verify: %s\n", error.what());
    return 1;
  }
  return 0;
}
