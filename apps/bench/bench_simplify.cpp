// Speed and accuracy of visproxy's general proxy builders against meshoptimizer, OpenMesh
// and CGAL, all in this process, on the same inputs and triangle budget.
//
//   visproxy-bench-simplify [--skip-slow] [--meshopt-only] [--repetitions N] [--budget N] [--loop-to T]... [MESH...]
//
// Without MESH arguments it uses four closed meshes of Debian's libcgal-demo from
// VISPROXY_MESH_DIR (armadillo, camel, cow, knot1); each --loop-to T adds every input
// Loop-subdivided (CGAL) until it has at least T triangles. Each method simplifies to
// `--budget` triangles (512), in repetitions (5, or 3 on inputs over 500 K triangles) that
// run the methods one after the other, so that a repetition's ratios to meshoptimizer
// compare runs made at one state of the machine; the table gives the median and the range
// of the seconds and of those ratios. Only the simplification is timed: copying the input
// into each library's own mesh type is done before the clock starts. The error is the
// sampled two-sided Hausdorff distance to the input (visproxy::sampled_hausdorff_distance,
// 20 000 samples a side plus every vertex) divided by the input's bounding-box diagonal.
// --skip-slow leaves out OpenMesh and CGAL on inputs over 500 K triangles (they take
// minutes there), --meshopt-only on every input.
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
#include <CGAL/Subdivision_method_3/subdivision_methods_3.h>

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

#include "surface_mesh.h"
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
  std::vector<double> seconds;                // one per repetition
  std::vector<double> ratios;                 // seconds / meshoptimizer's in the same repetition
  std::optional<double> hausdorff_relative;
  bool skipped = false;
};

std::size_t parse_count(const char* text, const char* option) {
  char* end = nullptr;
  const unsigned long long value = std::strtoull(text, &end, 10);
  if (end == text || *end != '\0' || value == 0) die(std::string(option) + " needs a positive whole number, not '" + text + "'");
  return static_cast<std::size_t>(value);
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

// Loop subdivision (CGAL) until the mesh has at least `triangles`; the levels it took.
std::pair<TriangleMesh, int> loop_subdivided(const TriangleMesh& mesh, std::size_t triangles) {
  auto cgal = visproxy::bench::to_surface_mesh<CgalKernel::Point_3>(mesh);
  int levels = 0;
  while (cgal.number_of_faces() < triangles) {
    CGAL::Subdivision_method_3::Loop_subdivision(cgal, CGAL::parameters::number_of_iterations(1));
    ++levels;
  }
  return {visproxy::bench::from_surface_mesh<CgalKernel::Point_3>(cgal), levels};
}

constexpr const char* kUsage =
    "usage: visproxy-bench-simplify [--skip-slow] [--meshopt-only] [--repetitions N] [--budget N] [--loop-to T]... "
    "[MESH...]";

}  // namespace

int main(int argc, char** argv) {
  visproxy::disable_transparent_huge_pages();  // see visproxy/core/process.h
  bool skip_slow = false, meshopt_only = false;
  std::size_t repetitions = 0, budget = 512;
  std::vector<std::size_t> loop_to;
  std::vector<fs::path> paths;
  for (int i = 1; i < argc; ++i) {
    const std::string_view argument = argv[i];
    if (argument == "--skip-slow") {
      skip_slow = true;
    } else if (argument == "--meshopt-only") {
      meshopt_only = true;
    } else if ((argument == "--repetitions" || argument == "--budget" || argument == "--loop-to") && i + 1 < argc) {
      const std::size_t value = parse_count(argv[i + 1], argv[i]);
      if (argument == "--loop-to") loop_to.push_back(value);
      else (argument == "--budget" ? budget : repetitions) = value;
      ++i;
    } else if (argument.starts_with("-")) {
      die("unknown option '" + std::string(argument) + "'\n" + kUsage);
    } else {
      paths.emplace_back(argument);
    }
  }

  // Inputs: named by file, or four closed meshes of Debian's libcgal-demo; each as it is
  // and Loop-subdivided to each --loop-to count.
  std::vector<std::pair<std::string, TriangleMesh>> inputs;
  try {
    if (paths.empty())
      for (const char* name : {"armadillo.off", "camel.off", "cow.off", "knot1.off"}) {
        const fs::path path = fs::path(VISPROXY_MESH_DIR) / name;
        if (!fs::is_regular_file(path)) die("no mesh file " + path.string() + " (build the 'cgal_meshes' target)");
        paths.push_back(path);
      }
    for (const fs::path& path : paths) {
      const TriangleMesh mesh = visproxy::read_mesh(path);
      inputs.emplace_back(path.filename().string(), mesh);
      for (const std::size_t triangles : loop_to)
        if (triangles > mesh.triangles.size()) {
          auto [subdivided, levels] = loop_subdivided(mesh, triangles);
          inputs.emplace_back(path.filename().string() + " loop" + std::to_string(levels), std::move(subdivided));
        }
    }
  } catch (const visproxy::Error& error) {
    die(error.what());
  }

  std::vector<std::pair<std::string, std::vector<Row>>> tables;
  for (const auto& [name, input] : inputs) {
    const bool large = input.triangles.size() > kLargeInput;
    const std::size_t runs = repetitions > 0 ? repetitions : large ? 3 : 5;
    const double diagonal = visproxy::bounding_box(input).diagonal();
    std::vector<Row> rows;
    for (const Method& method : kMethods) {
      Row row{method.name, input.triangles.size(), 0, {}, {}, std::nullopt, false};
      row.skipped = method.slow && (meshopt_only || (skip_slow && large));
      rows.push_back(row);
    }
    // Repetitions interleave the methods, so that each repetition's ratios compare runs made
    // at the same state of the machine.
    std::fprintf(stderr, "%s (%zu triangles): %zu repetitions ...\n", name.c_str(), input.triangles.size(), runs);
    std::vector<std::unique_ptr<Run>> last(rows.size());
    for (std::size_t r = 0; r < runs; ++r)
      for (std::size_t m = 0; m < rows.size(); ++m) {
        if (rows[m].skipped) continue;
        std::unique_ptr<Run> run = kMethods[m].start(input, budget);
        const Clock::time_point start = Clock::now();
        run->simplify();
        rows[m].seconds.push_back(std::chrono::duration<double>(Clock::now() - start).count());
        last[m] = std::move(run);
      }
    for (std::size_t m = 0; m < rows.size(); ++m) {
      if (rows[m].skipped) continue;
      for (std::size_t r = 0; r < runs; ++r) rows[m].ratios.push_back(rows[m].seconds[r] / rows[1].seconds[r]);
      const TriangleMesh output = last[m]->result();
      rows[m].output_triangles = output.triangles.size();
      try {
        rows[m].hausdorff_relative = visproxy::sampled_hausdorff_distance(input, output).hausdorff_world() / diagonal;
      } catch (const visproxy::Error& error) {
        std::fprintf(stderr, "%s on %s: no distance: %s\n", kMethods[m].name, name.c_str(), error.what());
      }
    }
    tables.emplace_back(name, rows);
  }

  std::printf("\nSimplification to %zu triangles. seconds: the median of the repetitions and their range; ratio: "
              "seconds / meshoptimizer's in the same repetition, median and range over the repetitions (the methods "
              "run interleaved); Hausdorff: sampled two-sided distance to the input / bounding-box diagonal.\n",
              budget);
  for (const auto& [name, rows] : tables) {
    std::printf("\n%-24s %-20s %9s %7s %9s %-17s %6s %-13s %10s\n", name.c_str(), "method", "input", "output", "seconds",
                "(range)", "ratio", "(range)", "Hausdorff");
    for (const Row& row : rows) {
      std::printf("%-24s %-20s %9zu ", "", row.method.c_str(), row.input_triangles);
      if (row.skipped || row.seconds.empty()) {
        std::printf("%7s %9s\n", "-", "skipped");
        continue;
      }
      const auto [least, most] = std::minmax_element(row.seconds.begin(), row.seconds.end());
      const auto [low, high] = std::minmax_element(row.ratios.begin(), row.ratios.end());
      char seconds_range[32], ratio_range[32];
      std::snprintf(seconds_range, sizeof seconds_range, "(%.4f-%.4f)", *least, *most);
      std::snprintf(ratio_range, sizeof ratio_range, "(%.2f-%.2f)", *low, *high);
      std::printf("%7zu %9.4f %-17s %5.2fx %-13s ", row.output_triangles, median(row.seconds), seconds_range,
                  median(row.ratios), ratio_range);
      if (row.hausdorff_relative) std::printf("%10.5f\n", *row.hausdorff_relative);
      else std::printf("%10s\n", "-");
    }
  }
  return EXIT_SUCCESS;
}
