// Time of every proxy builder of `visproxy build` on one mesh, as the build command runs
// them (the build alone, without the Hausdorff error that the command also measures).
//
//   visproxy-bench-build [--subdivide LEVELS] [--proxy SPEC]... [MESH]
//   visproxy-bench-build --scaling [--levels 0,1,2,3] [--proxy SPEC]... [--seed S]
//                        [--time-limit SECONDS] [--memory-limit GIB] [--out PREFIX] [MESH]
//
// Without MESH it uses bunny00.off from VISPROXY_MESH_DIR. --subdivide splits every
// triangle into 4, LEVELS times (bunny00 twice: 1.2 M triangles). Prints one row per
// proxy: primitives reached, seconds, and throughput in input triangles per second.
//
// --scaling: the mesh subdivided 0, 1, 2, 3 times (bunny00: 75 K, 300 K, 1.2 M and 4.8 M
// triangles) and each time displaced along its normals by seeded smooth bumps of a quarter
// of an edge (displace.h), so that the finer meshes are finer surfaces, not flat
// subdivisions. Each mesh is written to PREFIX-LEVEL.ply, and each builder runs on it in a
// fresh process of this program (fork and exec) that reads the file and builds: its wall
// time, its peak resident memory (reading the mesh and holding it included, as `visproxy
// build` with that one proxy would; getrusage of the child), and the time over n log2 n
// (n input triangles), which stays flat for a builder that scales as n log n. A builder that runs out of time or memory is named with what it
// ran out of. Prints the table and the default set's sum of times and largest peak per
// size, and writes PREFIX.csv and PREFIX.svg (seconds against triangles, log-log).

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <map>
#include <new>
#include <sstream>
#include <string>
#include <vector>

#include "child_process.h"
#include "visproxy/core/errors.h"
#include "visproxy/core/files.h"
#include "visproxy/core/process.h"
#include "visproxy/evaluate/plot.h"
#include "visproxy/mesh/displace.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/mesh/subdivide.h"
#include "visproxy/mesh/write_mesh.h"
#include "visproxy/proxy/build_proxies.h"

#ifndef VISPROXY_MESH_DIR
#error "VISPROXY_MESH_DIR must name the folder of the extracted libcgal-demo meshes"
#endif

namespace {

using namespace visproxy;

// What a builder's process reports through its pipe.
struct ChildReport {
  int ok = 0;
  std::size_t primitives = 0;
  double seconds = 0;
  double read_mb = 0;  // resident after reading the mesh
  char message[400] = {};
};

struct Run {
  std::size_t triangles = 0;
  std::string proxy;
  std::string status = "ok";  // ok, out of time, out of memory, failed: ..., crashed: ...
  std::size_t primitives = 0;
  double seconds = std::nan("");
  double peak_mb = std::nan("");
  double read_mb = std::nan("");
  double ns_per_n_log_n() const {
    const double n = static_cast<double>(triangles);
    return seconds * 1e9 / (n * std::log2(n));
  }
};

// This process's resident memory now (VmRSS), MiB.
double resident_mb() {
  std::FILE* status = std::fopen("/proc/self/status", "r");
  if (!status) return std::nan("");
  char line[256];
  double kib = std::nan("");
  while (std::fgets(line, sizeof line, status))
    if (std::strncmp(line, "VmRSS:", 6) == 0) kib = std::atof(line + 6);
  std::fclose(status);
  return kib / 1024.0;
}

// The hidden --one mode: read FILE, build SPEC, write a ChildReport to descriptor 3.
int build_one(const std::string& spec_text, const std::filesystem::path& file) {
  ChildReport report;
  return bench::report_to_parent(report, [&] {
    const TriangleMesh mesh = read_mesh(file, {.weld = Weld::never, .on_warning = {}});
    report.read_mb = resident_mb();
    const std::vector<ProxySpec> specs = parse_proxy_specs({spec_text});
    BuildOptions options;
    options.hausdorff_samples = 100;  // the error is not what is timed here
    const BuiltProxy proxy = build_proxies(mesh, file, specs, options).front();
    report.ok = 1, report.primitives = proxy.primitives, report.seconds = proxy.build_seconds;
  });
}

Run run_builder(const std::filesystem::path& file, std::size_t triangles, const ProxySpec& spec, int time_limit,
                double memory_limit_gib) {
  Run run;
  run.triangles = triangles;
  run.proxy = spec.name();
  ChildReport report;
  const bench::ChildRun child = bench::run_self({"visproxy-bench-build", "--one", spec.text, file.string()}, &report,
                                                sizeof report, time_limit, memory_limit_gib);
  run.peak_mb = child.peak_mb;
  if (child.reported) run.read_mb = report.read_mb;
  if (child.reported && report.ok) {
    run.primitives = report.primitives, run.seconds = report.seconds;
  } else if (child.reported) {
    run.status = report.message;
  } else {
    run.status = bench::child_failure(child, time_limit);
  }
  return run;
}

std::vector<int> parse_levels(const std::string& text) {
  std::vector<int> levels;
  std::stringstream stream(text);
  for (std::string item; std::getline(stream, item, ',');) levels.push_back(std::stoi(item));
  return levels;
}

std::string csv_text(const std::vector<Run>& runs) {
  std::string csv = "input_triangles,proxy,status,primitives,seconds,peak_mb,mesh_read_mb,ns_per_n_log2_n\n";
  char line[512];
  for (const Run& r : runs) {
    std::snprintf(line, sizeof line, "%zu,%s,\"%s\",%zu,%.4f,%.1f,%.1f,%.3f\n", r.triangles, r.proxy.c_str(),
                  r.status.c_str(), r.primitives, r.seconds, r.peak_mb, r.read_mb, r.ns_per_n_log_n());
    csv += line;
  }
  return csv;
}

int scaling(const std::filesystem::path& path, const std::vector<int>& levels, const std::vector<ProxySpec>& specs,
            std::uint64_t seed, int time_limit, double memory_limit_gib, const std::string& prefix) {
  const TriangleMesh base = read_mesh(path);
  std::printf("Scaling of every builder on %s subdivided 0..N times and displaced by seeded bumps (a quarter of an edge, "
              "seed %llu). Each builder in its own process: wall time, peak resident memory (its input mesh included), "
              "resident memory once the mesh is read, time / (n log2 n) for n input triangles. %ld cores.\n",
              path.filename().c_str(), static_cast<unsigned long long>(seed), ::sysconf(_SC_NPROCESSORS_ONLN));
  std::printf("%12s  %-16s %12s %10s %10s %10s %14s  %s\n", "triangles", "proxy", "primitives", "seconds", "peak MB",
              "read MB", "ns/(n log2 n)", "status");
  std::vector<Run> runs;
  for (const int level : levels) {
    const std::filesystem::path file = prefix + "-" + std::to_string(level) + ".ply";
    std::size_t triangles = 0;
    {
      const TriangleMesh mesh = displace_along_normals(subdivide_midpoint(base, level), {.amplitude_relative = 0.25, .seed = seed});
      triangles = mesh.triangles.size();
      write_mesh(file, mesh);
    }
    double total = 0, peak = 0;
    bool complete = true;
    for (const ProxySpec& spec : specs) {
      const Run run = run_builder(file, triangles, spec, time_limit, memory_limit_gib);
      std::printf("%12zu  %-16s %12zu %10.3f %10.1f %10.1f %14.3f  %s\n", run.triangles, run.proxy.c_str(), run.primitives,
                  run.seconds, run.peak_mb, run.read_mb, run.ns_per_n_log_n(), run.status.c_str());
      std::fflush(stdout);
      if (run.status == "ok") total += run.seconds;
      complete = complete && run.status == "ok";
      peak = std::max(peak, run.peak_mb);
      runs.push_back(run);
    }
    std::printf("%12zu  %-16s %12s %10.3f %10.1f %10s %14s  %s\n", triangles, "(the set)", "", total, peak, "", "",
                complete ? "sum of the times, largest peak" : "sum of the builders that finished, largest peak");
  }
  std::vector<PlotSeries> series;
  std::map<std::string, std::size_t> index;
  for (const Run& r : runs) {
    if (r.status != "ok") continue;
    if (!index.count(r.proxy)) index[r.proxy] = series.size(), series.push_back({r.proxy, {}, {}});
    series[index[r.proxy]].x.push_back(static_cast<double>(r.triangles));
    series[index[r.proxy]].y.push_back(r.seconds);
  }
  write_file_atomically(prefix + ".csv", csv_text(runs));
  write_file_atomically(prefix + ".svg",
                        line_plot_svg(series, {.title = "Build time against input size: " + path.filename().string() +
                                                        " subdivided and displaced, " +
                                                        std::to_string(::sysconf(_SC_NPROCESSORS_ONLN)) + " cores",
                                               .x_label = "input triangles (log scale)",
                                               .y_label = "wall time of the build, seconds (log scale)",
                                               .log_x = true,
                                               .log_y = true}));
  std::printf("Wrote %s.csv and %s.svg (the meshes: %s-LEVEL.ply)\n", prefix.c_str(), prefix.c_str(), prefix.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  visproxy::disable_transparent_huge_pages();  // see visproxy/core/process.h
  std::filesystem::path path = std::filesystem::path(VISPROXY_MESH_DIR) / "bunny00.off";
  int levels = 0, time_limit = 600;
  bool scaling_mode = false;
  std::vector<int> scaling_levels{0, 1, 2, 3};
  std::uint64_t seed = 1;
  double memory_limit_gib = 0;
  std::string prefix = "build-scaling";
  std::vector<std::string> texts;
  for (int i = 1; i < argc; ++i) {
    const std::string argument = argv[i];
    if (argument == "--one" && i + 2 < argc) {
      return build_one(argv[i + 1], argv[i + 2]);
    } else if (argument == "--subdivide" && i + 1 < argc) {
      levels = std::atoi(argv[++i]);
    } else if (argument == "--proxy" && i + 1 < argc) {
      texts.emplace_back(argv[++i]);
    } else if (argument == "--scaling") {
      scaling_mode = true;
    } else if (argument == "--levels" && i + 1 < argc) {
      scaling_levels = parse_levels(argv[++i]);
    } else if (argument == "--seed" && i + 1 < argc) {
      seed = std::strtoull(argv[++i], nullptr, 10);
    } else if (argument == "--time-limit" && i + 1 < argc) {
      time_limit = std::atoi(argv[++i]);
    } else if (argument == "--memory-limit" && i + 1 < argc) {
      memory_limit_gib = std::atof(argv[++i]);
    } else if (argument == "--out" && i + 1 < argc) {
      prefix = argv[++i];
    } else if (argument == "--help" || argument == "-h") {
      std::printf(
          "usage: visproxy-bench-build [--subdivide LEVELS] [--proxy SPEC]... [MESH]\n"
          "       visproxy-bench-build --scaling [--levels 0,1,2,3] [--proxy SPEC]... [--seed S] [--time-limit SECONDS]\n"
          "                            [--memory-limit GIB] [--out PREFIX] [MESH]\n");
      return 0;
    } else {
      path = argument;
    }
  }
  try {
    const std::vector<ProxySpec> specs = texts.empty() ? default_proxy_specs() : parse_proxy_specs(texts);
    if (scaling_mode) return scaling(path, scaling_levels, specs, seed, time_limit, memory_limit_gib, prefix);
    TriangleMesh mesh = read_mesh(path);
    if (levels > 0) mesh = subdivide_midpoint(mesh, levels);
    std::printf("builders on %s%s: %zu vertices, %zu triangles (1 run each, wall time, %s)\n", path.filename().c_str(),
                levels > 0 ? (" subdivided " + std::to_string(levels) + "x").c_str() : "", mesh.positions.size(),
                mesh.triangles.size(), "Hausdorff error not included");
    std::printf("%-28s %12s %12s %16s\n", "proxy", "primitives", "seconds", "input tris/s");
    for (const ProxySpec& spec : specs) {
      BuildOptions options;
      options.hausdorff_samples = 100;  // the error is not what is timed here
      const BuiltProxy proxy = build_proxies(mesh, path, {&spec, 1}, options).front();
      std::printf("%-28s %12zu %12.3f %16.0f\n", spec.name().c_str(), proxy.primitives, proxy.build_seconds,
                  static_cast<double>(mesh.triangles.size()) / proxy.build_seconds);
      std::fflush(stdout);
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "visproxy-bench-build: %s\n", error.what());
    return 2;
  }
  return 0;
}
