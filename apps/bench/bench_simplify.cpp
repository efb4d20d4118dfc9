// Speed and accuracy of visproxy's general proxy builders against meshoptimizer, OpenMesh
// and CGAL, all in this process, on the same inputs and triangle budget.
//
//   visproxy-bench-simplify [--skip-slow] [--repetitions N] [--budget N] [MESH...]
//
// Without MESH arguments it uses bunny00.off from VISPROXY_MESH_DIR and the same bunny
// subdivided twice (1.2 M triangles, made here with subdivide_midpoint). Each method
// simplifies to `--budget` triangles (512); the time is the fastest of the repetitions
// (5, or 2 on inputs over 500 K triangles), counting the simplification only: copying the
// input into each library's own mesh type is done before the clock starts. The error is the
// sampled two-sided Hausdorff distance to the input (visproxy::sampled_hausdorff_distance,
// 20 000 samples a side plus every vertex) divided by the input's bounding-box diagonal.
// --skip-slow leaves out OpenMesh and CGAL on inputs over 500 K triangles (they take
// minutes there).
//
// The methods:
//   visproxy quadric   visproxy::simplify_quadric
//   meshoptimizer      meshopt_simplify (0.18), target 3 x budget indices, target_error 1
//                      (100 % of the extent, so that only the count stops it)
//   OpenMesh           Decimater with ModQuadric, decimate_to_faces(0, budget)
//   CGAL GH plane      Surface_mesh_simplification::edge_collapse with
//                      GarlandHeckbert_plane_policies, Count_stop_predicate at 3/2 x budget
//                      edges (the edge count of a closed mesh of `budget` triangles)
//   visproxy cluster   visproxy::cluster_vertices at 3 % of the largest extent (its count is
//                      whatever that cell size gives, not the budget)

// OpenMesh wants its IO-free kernel headers before the decimater.
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>

#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Count_stop_predicate.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/GarlandHeckbert_plane_policies.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>

#include <meshoptimizer.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/core/process.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/mesh/subdivide.h"
#include "visproxy/proxy/quadric_simplify.h"
#include "visproxy/proxy/surface_distance.h"
#include "visproxy/proxy/vertex_clustering.h"

#ifndef VISPROXY_MESH_DIR
#error "VISPROXY_MESH_DIR must name the folder of the extracted libcgal-demo meshes"
#endif

namespace {

namespace fs = std::filesystem;
using visproxy::TriangleMesh;
using Clock = std::chrono::steady_clock;

constexpr std::size_t kLargeInput = 500'000;

[[noreturn]] void die(const std::string& message) {
  std::fprintf(stderr, "visproxy-bench-simplify: %s\n", message.c_str());
  std::exit(EXIT_FAILURE);
}

// One method on one input: made from the input (copied into the library's own types,
// untimed), then simplify() is timed, then result() gives the simplified mesh.
class Run {
 public:
  virtual ~Run() = default;
  virtual void simplify() = 0;
  virtual TriangleMesh result() const = 0;
};

struct Method {
  const char* name;
  bool slow;  // skipped on large inputs with --skip-slow
  std::unique_ptr<Run> (*start)(const TriangleMesh& input, std::size_t budget);
};

class VisproxyQuadric : public Run {
 public:
  VisproxyQuadric(const TriangleMesh& input, std::size_t budget) : input_(input), budget_(budget) {}
  void simplify() override { output_ = visproxy::simplify_quadric(input_, {.max_triangles = budget_}).mesh; }
  TriangleMesh result() const override { return output_; }

 private:
  const TriangleMesh& input_;
  std::size_t budget_;
  TriangleMesh output_;
};

class VisproxyCluster : public Run {
 public:
  explicit VisproxyCluster(const TriangleMesh& input) : input_(input) {}
  void simplify() override { output_ = visproxy::cluster_vertices(input_, {.cell_size_relative = 0.03}).mesh; }
  TriangleMesh result() const override { return output_; }

 private:
  const TriangleMesh& input_;
  TriangleMesh output_;
};

class Meshoptimizer : public Run {
 public:
  Meshoptimizer(const TriangleMesh& input, std::size_t budget) : input_(input), budget_(budget) {
    for (const visproxy::Vertex& p : input.positions)
      for (int axis = 0; axis < 3; ++axis) positions_.push_back(static_cast<float>(p[axis]));
    for (const visproxy::Triangle& t : input.triangles) indices_.insert(indices_.end(), t.begin(), t.end());
    destination_.resize(indices_.size());
  }
  void simplify() override {
    float reached_error = 0;
    count_ = meshopt_simplify(destination_.data(), indices_.data(), indices_.size(), positions_.data(),
                              input_.positions.size(), 3 * sizeof(float), 3 * budget_, 1.0f, 0, &reached_error);
  }
  TriangleMesh result() const override {
    TriangleMesh mesh;
    mesh.positions = input_.positions;
    for (std::size_t i = 0; i + 2 < count_; i += 3) mesh.triangles.push_back({destination_[i], destination_[i + 1], destination_[i + 2]});
    return mesh;
  }

 private:
  const TriangleMesh& input_;
  std::size_t budget_;
  std::vector<float> positions_;
  std::vector<unsigned int> indices_, destination_;
  std::size_t count_ = 0;
};

using OpenMeshMesh = OpenMesh::TriMesh_ArrayKernelT<>;

class OpenMeshDecimater : public Run {
 public:
  OpenMeshDecimater(const TriangleMesh& input, std::size_t budget) : budget_(budget) {
    std::vector<OpenMeshMesh::VertexHandle> handles;
    for (const visproxy::Vertex& p : input.positions)
      handles.push_back(mesh_.add_vertex(OpenMeshMesh::Point(static_cast<float>(p.x()), static_cast<float>(p.y()),
                                                             static_cast<float>(p.z()))));
    for (const visproxy::Triangle& t : input.triangles) mesh_.add_face(handles[t[0]], handles[t[1]], handles[t[2]]);
  }
  void simplify() override {
    OpenMesh::Decimater::DecimaterT<OpenMeshMesh> decimater(mesh_);
    OpenMesh::Decimater::ModQuadricT<OpenMeshMesh>::Handle quadric;
    decimater.add(quadric);
    decimater.module(quadric).unset_max_err();
    decimater.initialize();
    decimater.decimate_to_faces(0, budget_);
    mesh_.garbage_collection();
  }
  TriangleMesh result() const override {
    TriangleMesh mesh;
    for (const OpenMeshMesh::VertexHandle v : mesh_.vertices()) {
      const OpenMeshMesh::Point& p = mesh_.point(v);
      mesh.positions.emplace_back(p[0], p[1], p[2]);
    }
    for (const OpenMeshMesh::FaceHandle f : mesh_.faces()) {
      visproxy::Triangle triangle{};
      std::size_t c = 0;
      for (const OpenMeshMesh::VertexHandle v : mesh_.fv_range(f))
        if (c < 3) triangle[c++] = static_cast<visproxy::VertexIndex>(v.idx());
      mesh.triangles.push_back(triangle);
    }
    return mesh;
  }

 private:
  OpenMeshMesh mesh_;
  std::size_t budget_;
};

using CgalKernel = CGAL::Simple_cartesian<double>;
using CgalMesh = CGAL::Surface_mesh<CgalKernel::Point_3>;

class CgalGarlandHeckbert : public Run {
 public:
  CgalGarlandHeckbert(const TriangleMesh& input, std::size_t budget) : budget_(budget) {
    std::vector<CgalMesh::Vertex_index> handles;
    for (const visproxy::Vertex& p : input.positions) handles.push_back(mesh_.add_vertex({p.x(), p.y(), p.z()}));
    for (const visproxy::Triangle& t : input.triangles) mesh_.add_face(handles[t[0]], handles[t[1]], handles[t[2]]);
  }
  void simplify() override {
    namespace SMS = CGAL::Surface_mesh_simplification;
    SMS::GarlandHeckbert_plane_policies<CgalMesh, CgalKernel> policies(mesh_);
    const SMS::Count_stop_predicate<CgalMesh> stop(3 * budget_ / 2);
    SMS::edge_collapse(mesh_, stop,
                       CGAL::parameters::get_cost(policies.get_cost()).get_placement(policies.get_placement()));
    mesh_.collect_garbage();
  }
  TriangleMesh result() const override {
    TriangleMesh mesh;
    for (const CgalMesh::Vertex_index v : mesh_.vertices()) {
      const CgalKernel::Point_3& p = mesh_.point(v);
      mesh.positions.emplace_back(p.x(), p.y(), p.z());
    }
    for (const CgalMesh::Face_index f : mesh_.faces()) {
      visproxy::Triangle triangle{};
      std::size_t c = 0;
      for (const CgalMesh::Vertex_index v : CGAL::vertices_around_face(mesh_.halfedge(f), mesh_))
        if (c < 3) triangle[c++] = static_cast<visproxy::VertexIndex>(v.idx());
      mesh.triangles.push_back(triangle);
    }
    return mesh;
  }

 private:
  CgalMesh mesh_;
  std::size_t budget_;
};

const Method kMethods[] = {
    {"visproxy quadric", false,
     [](const TriangleMesh& input, std::size_t budget) -> std::unique_ptr<Run> { return std::make_unique<VisproxyQuadric>(input, budget); }},
    {"meshoptimizer", false,
     [](const TriangleMesh& input, std::size_t budget) -> std::unique_ptr<Run> { return std::make_unique<Meshoptimizer>(input, budget); }},
    {"OpenMesh ModQuadric", true,
     [](const TriangleMesh& input, std::size_t budget) -> std::unique_ptr<Run> { return std::make_unique<OpenMeshDecimater>(input, budget); }},
    {"CGAL GH plane", true,
     [](const TriangleMesh& input, std::size_t budget) -> std::unique_ptr<Run> { return std::make_unique<CgalGarlandHeckbert>(input, budget); }},
    {"visproxy cluster 3%", false,
     [](const TriangleMesh& input, std::size_t) -> std::unique_ptr<Run> { return std::make_unique<VisproxyCluster>(input); }},
};

struct Row {
  std::string method;
  std::size_t input_triangles = 0, output_triangles = 0;
  std::optional<double> seconds, hausdorff_relative;
};

std::size_t parse_count(const char* text, const char* option) {
  char* end = nullptr;
  const unsigned long long value = std::strtoull(text, &end, 10);
  if (end == text || *end != '\0' || value == 0) die(std::string(option) + " wants a positive whole number, not '" + text + "'");
  return static_cast<std::size_t>(value);
}

}  // namespace

int main(int argc, char** argv) {
  visproxy::disable_transparent_huge_pages();  // see visproxy/core/process.h
  bool skip_slow = false;
  std::size_t repetitions = 0, budget = 512;
  std::vector<fs::path> paths;
  for (int i = 1; i < argc; ++i) {
    const std::string_view argument = argv[i];
    if (argument == "--skip-slow") {
      skip_slow = true;
    } else if ((argument == "--repetitions" || argument == "--budget") && i + 1 < argc) {
      (argument == "--budget" ? budget : repetitions) = parse_count(argv[i + 1], argv[i]);
      ++i;
    } else if (argument.starts_with("-")) {
      die("unknown option '" + std::string(argument) +
          "'\nusage: visproxy-bench-simplify [--skip-slow] [--repetitions N] [--budget N] [MESH...]");
    } else {
      paths.emplace_back(argument);
    }
  }

  // Inputs: named by file, or the bunny and the bunny subdivided twice.
  std::vector<std::pair<std::string, TriangleMesh>> inputs;
  try {
    if (paths.empty()) {
      const fs::path bunny = fs::path(VISPROXY_MESH_DIR) / "bunny00.off";
      if (!fs::is_regular_file(bunny)) die("no mesh file " + bunny.string() + " (build the 'cgal_meshes' target)");
      inputs.emplace_back("bunny00.off", visproxy::read_mesh(bunny));
      inputs.emplace_back("bunny00.off subdiv. x2", visproxy::subdivide_midpoint(inputs.front().second, 2));
    }
    for (const fs::path& path : paths) inputs.emplace_back(path.filename().string(), visproxy::read_mesh(path));
  } catch (const visproxy::Error& error) {
    die(error.what());
  }

  std::vector<std::pair<std::string, std::vector<Row>>> tables;
  for (const auto& [name, input] : inputs) {
    const bool large = input.triangles.size() > kLargeInput;
    const std::size_t runs = repetitions > 0 ? repetitions : large ? 2 : 5;
    const double diagonal = visproxy::bounding_box(input).diagonal();
    std::vector<Row> rows;
    for (const Method& method : kMethods) {
      Row row{method.name, input.triangles.size(), 0, std::nullopt, std::nullopt};
      if (skip_slow && large && method.slow) {
        rows.push_back(row);
        continue;
      }
      std::fprintf(stderr, "%s: %s ...\n", name.c_str(), method.name);
      std::unique_ptr<Run> last;
      for (std::size_t r = 0; r < runs; ++r) {
        std::unique_ptr<Run> run = method.start(input, budget);
        const Clock::time_point start = Clock::now();
        run->simplify();
        const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
        row.seconds = row.seconds ? std::min(*row.seconds, seconds) : seconds;
        last = std::move(run);
      }
      const TriangleMesh output = last->result();
      row.output_triangles = output.triangles.size();
      try {
        row.hausdorff_relative = visproxy::sampled_hausdorff_distance(input, output).hausdorff_world() / diagonal;
      } catch (const visproxy::Error& error) {
        std::fprintf(stderr, "%s on %s: no distance: %s\n", method.name, name.c_str(), error.what());
      }
      rows.push_back(row);
    }
    tables.emplace_back(name, rows);
  }

  std::printf("\nSimplification to %zu triangles; time = fastest of the repetitions (s); ratio = time / "
              "meshoptimizer's;\nHausdorff = sampled two-sided distance to the input / bounding-box diagonal.\n",
              budget);
  for (const auto& [name, rows] : tables) {
    std::printf("\n%-22s %-20s %10s %10s %10s %8s %10s\n", name.c_str(), "method", "input", "output", "seconds",
                "ratio", "Hausdorff");
    const std::optional<double> reference = rows[1].seconds;  // meshoptimizer
    for (const Row& row : rows) {
      std::printf("%-22s %-20s %10zu ", "", row.method.c_str(), row.input_triangles);
      if (!row.seconds) {
        std::printf("%10s %10s %8s %10s\n", "-", "skipped", "-", "-");
        continue;
      }
      std::printf("%10zu %10.4f ", row.output_triangles, *row.seconds);
      if (reference && *reference > 0) std::printf("%7.2fx ", *row.seconds / *reference);
      else std::printf("%8s ", "-");
      if (row.hausdorff_relative) std::printf("%10.5f\n", *row.hausdorff_relative);
      else std::printf("%10s\n", "-");
    }
  }
  return EXIT_SUCCESS;
}
