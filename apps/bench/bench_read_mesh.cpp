// Reading speed of visproxy::read_mesh against the generic readers of CGAL and OpenMesh.
//
//   visproxy-bench-read-mesh [--benchmark_* flags] [MESH...]
//
// Without MESH arguments it reads bunny00.off and armadillo.off from VISPROXY_MESH_DIR
// (extracted by the `cgal_meshes` target). Each reader's result is checked against the
// vertex and triangle counts visproxy reports before anything is timed, and again on every
// timed read, so a reader that fails cannot pass for a fast one. After Google Benchmark's
// own report, a table gives each reader's time per file and how many times faster
// visproxy is.

// OpenMesh wants its IO header before the mesh kernel.
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/polygon_soup_io.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/IO/polygon_mesh_io.h>

#include <benchmark/benchmark.h>

#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <functional>
#include <iterator>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/core/process.h"
#include "visproxy/mesh/read_mesh.h"

#ifndef VISPROXY_MESH_DIR
#error "VISPROXY_MESH_DIR must name the folder of the extracted libcgal-demo meshes"
#endif

namespace {

namespace fs = std::filesystem;

using CgalPoint = CGAL::Exact_predicates_inexact_constructions_kernel::Point_3;
using CgalMesh = CGAL::Surface_mesh<CgalPoint>;
using OpenMeshMesh = OpenMesh::TriMesh_ArrayKernelT<>;

// What a reader produced: the counts checked on every timed read (`faces` as the reader
// stores them, polygons included), and the triangles those faces make.
struct Counts {
  std::size_t vertices = 0;
  std::size_t faces = 0;
  std::size_t triangles = 0;
  bool operator==(const Counts&) const = default;
};

// A reader: reads the whole file into its library's mesh type and returns what it holds.
// The triangle count is only filled in when `count_triangles` is set (it walks the faces);
// nullopt means the reader reported failure (or threw).
struct Reader {
  const char* name;   // benchmark name prefix
  const char* title;  // table column
  std::optional<Counts> (*read)(const fs::path& path, bool count_triangles);
};

std::size_t triangles_of_polygon(std::size_t corners) { return corners >= 3 ? corners - 2 : 0; }

std::optional<Counts> read_visproxy(const fs::path& path, bool /*count_triangles*/) {
  try {
    const visproxy::TriangleMesh mesh = visproxy::read_mesh(path);
    return Counts{mesh.positions.size(), mesh.triangles.size(), mesh.triangles.size()};
  } catch (const visproxy::Error& error) {
    std::fprintf(stderr, "visproxy::read_mesh: %s\n", error.what());
    return std::nullopt;
  }
}

std::optional<Counts> read_cgal_polygon_mesh(const fs::path& path, bool count_triangles) {
  CgalMesh mesh;
  if (!CGAL::IO::read_polygon_mesh(path.string(), mesh)) return std::nullopt;
  Counts counts{mesh.number_of_vertices(), mesh.number_of_faces(), 0};
  if (count_triangles)
    for (const CgalMesh::Face_index face : mesh.faces())
      counts.triangles += triangles_of_polygon(mesh.degree(face));
  return counts;
}

std::optional<Counts> read_cgal_polygon_soup(const fs::path& path, bool count_triangles) {
  std::vector<CgalPoint> points;
  std::vector<std::vector<std::size_t>> polygons;
  if (!CGAL::IO::read_polygon_soup(path.string(), points, polygons)) return std::nullopt;
  Counts counts{points.size(), polygons.size(), 0};
  if (count_triangles)
    for (const std::vector<std::size_t>& polygon : polygons) counts.triangles += triangles_of_polygon(polygon.size());
  return counts;
}

std::optional<Counts> read_openmesh(const fs::path& path, bool /*count_triangles*/) {
  OpenMeshMesh mesh;
  if (!OpenMesh::IO::read_mesh(mesh, path.string())) return std::nullopt;
  // TriMesh triangulates polygons as it reads them: every face is a triangle.
  return Counts{mesh.n_vertices(), mesh.n_faces(), mesh.n_faces()};
}

constexpr Reader kReaders[] = {
    {"visproxy", "visproxy", read_visproxy},
    {"cgal_polygon_mesh", "CGAL mesh", read_cgal_polygon_mesh},
    {"cgal_polygon_soup", "CGAL soup", read_cgal_polygon_soup},
    {"openmesh", "OpenMesh", read_openmesh},
};
constexpr std::size_t kReaderCount = std::size(kReaders);

[[noreturn]] void die(const std::string& message) {
  std::fprintf(stderr, "visproxy-bench-read-mesh: %s\n", message.c_str());
  std::exit(EXIT_FAILURE);
}

std::string describe(const Counts& counts) {
  return std::to_string(counts.vertices) + " vertices, " + std::to_string(counts.faces) + " faces (" +
         std::to_string(counts.triangles) + " triangles)";
}

// Reads `path` once with every reader; all must agree on vertices and triangles with
// visproxy, else the program stops. Returns what each reader holds after a read.
std::vector<Counts> verify_readers(const fs::path& path) {
  std::vector<Counts> counts;
  for (const Reader& reader : kReaders) {
    std::optional<Counts> read;
    try {
      read = reader.read(path, true);
    } catch (const std::exception& error) {
      die(std::string(reader.title) + " threw reading " + path.string() + ": " + error.what());
    }
    if (!read) die(std::string(reader.title) + " failed to read " + path.string());
    counts.push_back(*read);
  }
  const Counts& expected = counts.front();
  if (expected.triangles == 0) die(path.string() + " has no triangles");
  bool agree = true;
  for (const Counts& c : counts) agree = agree && c.vertices == expected.vertices && c.triangles == expected.triangles;
  if (!agree) {
    std::string message = "the readers disagree on " + path.string() + ":";
    for (std::size_t r = 0; r < kReaderCount; ++r) message += std::string("\n  ") + kReaders[r].title + ": " + describe(counts[r]);
    die(message);
  }
  return counts;
}

// One timed read; any read that does not give the verified counts stops the benchmark.
void bench_read(benchmark::State& state, const Reader& reader, const fs::path& path, Counts expected) {
  for (auto _ : state) {
    const std::optional<Counts> read = reader.read(path, false);
    if (!read || read->vertices != expected.vertices || read->faces != expected.faces) {
      state.SkipWithError((std::string(reader.title) + " did not read " + path.string() + " as before").c_str());
      break;
    }
  }
  state.SetLabel(std::to_string(expected.triangles) + " triangles");
}

std::string benchmark_name(const Reader& reader, const fs::path& path) {
  return std::string(reader.name) + "/" + path.filename().string();
}

// Passes everything on to Google Benchmark's usual display reporter (so --benchmark_format
// still works) and keeps the real time per read of every benchmark, in milliseconds.
class RecordingReporter : public benchmark::BenchmarkReporter {
 public:
  explicit RecordingReporter(benchmark::BenchmarkReporter* display) : display_(display) {}

  bool ReportContext(const Context& context) override { return display_->ReportContext(context); }

  void ReportRuns(const std::vector<Run>& runs) override {
    display_->ReportRuns(runs);
    for (const Run& run : runs) {
      Result& result = results_[run.run_name.function_name];
      if (run.error_occurred) {
        result.error = run.error_message;
        continue;
      }
      const double milliseconds = run.GetAdjustedRealTime() / benchmark::GetTimeUnitMultiplier(run.time_unit) * 1e3;
      if (run.run_type == Run::RT_Iteration) {
        result.sum_ms += milliseconds;
        ++result.runs;
      } else if (run.aggregate_name == "median") {
        result.median_ms = milliseconds;
      }
    }
  }

  void Finalize() override { display_->Finalize(); }

  // Time per read in ms: the median over repetitions if there were several, else the
  // mean; nullopt if the benchmark did not run (filtered out) or failed.
  std::optional<double> milliseconds(const std::string& name) const {
    const auto it = results_.find(name);
    if (it == results_.end() || !it->second.error.empty()) return std::nullopt;
    if (it->second.median_ms) return it->second.median_ms;
    if (it->second.runs == 0) return std::nullopt;
    return it->second.sum_ms / static_cast<double>(it->second.runs);
  }

  std::vector<std::string> errors() const {
    std::vector<std::string> found;
    for (const auto& [name, result] : results_)
      if (!result.error.empty()) found.push_back(name + ": " + result.error);
    return found;
  }

 private:
  struct Result {
    double sum_ms = 0;
    int runs = 0;
    std::optional<double> median_ms;
    std::string error;
  };
  benchmark::BenchmarkReporter* display_;
  std::map<std::string, Result> results_;
};

struct MeshCase {
  fs::path path;
  std::vector<Counts> counts;  // per reader, from verify_readers
};

void print_table(const std::vector<MeshCase>& cases, const RecordingReporter& reporter) {
  std::printf("\nTime to read a whole file into each library's mesh (ms, real time per read);\n"
              "x = how many times faster visproxy::read_mesh is.\n\n");
  std::printf("%-24s %9s %9s", "mesh", "vertices", "triangles");
  for (const Reader& reader : kReaders) std::printf(" %11s", reader.title);
  for (std::size_t r = 1; r < kReaderCount; ++r) std::printf(" %14s", (std::string(kReaders[r].title) + "/vp").c_str());
  std::printf("\n");
  for (const MeshCase& mesh : cases) {
    std::printf("%-24s %9zu %9zu", mesh.path.filename().string().c_str(), mesh.counts.front().vertices,
                mesh.counts.front().triangles);
    std::optional<double> times[kReaderCount];
    for (std::size_t r = 0; r < kReaderCount; ++r) {
      times[r] = reporter.milliseconds(benchmark_name(kReaders[r], mesh.path));
      if (times[r]) std::printf(" %11.2f", *times[r]);
      else std::printf(" %11s", "-");
    }
    for (std::size_t r = 1; r < kReaderCount; ++r) {
      if (times[0] && times[r] && *times[0] > 0) std::printf(" %13.1fx", *times[r] / *times[0]);
      else std::printf(" %14s", "-");
    }
    std::printf("\n");
  }
  std::printf("\nvp = visproxy; CGAL mesh = CGAL::IO::read_polygon_mesh into Surface_mesh<Epick::Point_3>;\n"
              "CGAL soup = CGAL::IO::read_polygon_soup into vectors; OpenMesh = OpenMesh::IO::read_mesh into\n"
              "TriMesh_ArrayKernelT<>.\n");
}

}  // namespace

int main(int argc, char** argv) {
  visproxy::disable_transparent_huge_pages();  // see visproxy/core/process.h
  benchmark::Initialize(&argc, argv);  // removes the --benchmark_* flags it knows

  std::vector<fs::path> paths;
  for (int i = 1; i < argc; ++i) {
    const std::string_view argument = argv[i];
    if (argument.starts_with("-")) {
      std::fprintf(stderr,
                   "visproxy-bench-read-mesh: unknown option '%s'\n"
                   "usage: visproxy-bench-read-mesh [--benchmark_* flags] [MESH...]\n",
                   argv[i]);
      return EXIT_FAILURE;
    }
    paths.emplace_back(argument);
  }
  if (paths.empty()) {
    for (const char* name : {"bunny00.off", "armadillo.off"}) paths.push_back(fs::path(VISPROXY_MESH_DIR) / name);
  }

  std::vector<MeshCase> cases;
  for (const fs::path& path : paths) {
    std::error_code error;
    if (!fs::is_regular_file(path, error))
      die("no mesh file " + path.string() + " (build the 'cgal_meshes' target to extract the default meshes)");
    cases.push_back({path, verify_readers(path)});
  }

  for (const MeshCase& mesh : cases) {
    for (std::size_t r = 0; r < kReaderCount; ++r) {
      const Reader& reader = kReaders[r];
      benchmark::RegisterBenchmark(benchmark_name(reader, mesh.path).c_str(), &bench_read, std::cref(reader),
                                   mesh.path, mesh.counts[r])
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime();
    }
  }

  RecordingReporter reporter(benchmark::CreateDefaultDisplayReporter());
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();

  print_table(cases, reporter);
  const std::vector<std::string> errors = reporter.errors();
  for (const std::string& error : errors) std::fprintf(stderr, "visproxy-bench-read-mesh: %s\n", error.c_str());
  return errors.empty() ? EXIT_SUCCESS : EXIT_FAILURE;
}
