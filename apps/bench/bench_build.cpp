// Time of every proxy builder of `visproxy build` on one mesh, as the build command runs
// them (the build alone, without the Hausdorff error that the command also measures).
//
//   visproxy-bench-build [--subdivide LEVELS] [--proxy SPEC]... [MESH]
//
// Without MESH it uses bunny00.off from VISPROXY_MESH_DIR. --subdivide splits every
// triangle into 4, LEVELS times (bunny00 twice: 1.2 M triangles). Prints one row per
// proxy: primitives reached, seconds, and throughput in input triangles per second.

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/mesh/subdivide.h"
#include "visproxy/proxy/build_proxies.h"

#ifndef VISPROXY_MESH_DIR
#error "VISPROXY_MESH_DIR must name the folder of the extracted libcgal-demo meshes"
#endif

int main(int argc, char** argv) {
  std::filesystem::path path = std::filesystem::path(VISPROXY_MESH_DIR) / "bunny00.off";
  int levels = 0;
  std::vector<std::string> texts;
  for (int i = 1; i < argc; ++i) {
    const std::string argument = argv[i];
    if (argument == "--subdivide" && i + 1 < argc) {
      levels = std::atoi(argv[++i]);
    } else if (argument == "--proxy" && i + 1 < argc) {
      texts.emplace_back(argv[++i]);
    } else if (argument == "--help" || argument == "-h") {
      std::printf("usage: visproxy-bench-build [--subdivide LEVELS] [--proxy SPEC]... [MESH]\n");
      return 0;
    } else {
      path = argument;
    }
  }
  try {
    visproxy::TriangleMesh mesh = visproxy::read_mesh(path);
    if (levels > 0) mesh = visproxy::subdivide_midpoint(mesh, levels);
    const std::vector<visproxy::ProxySpec> specs =
        texts.empty() ? visproxy::default_proxy_specs() : visproxy::parse_proxy_specs(texts);
    std::printf("builders on %s%s: %zu vertices, %zu triangles (1 run each, wall time, %s)\n", path.filename().c_str(),
                levels > 0 ? (" subdivided " + std::to_string(levels) + "x").c_str() : "", mesh.positions.size(),
                mesh.triangles.size(), "Hausdorff error not included");
    std::printf("%-28s %12s %12s %16s\n", "proxy", "primitives", "seconds", "input tris/s");
    for (const visproxy::ProxySpec& spec : specs) {
      visproxy::BuildOptions options;
      options.hausdorff_samples = 100;  // the error is not what is timed here
      const visproxy::BuiltProxy proxy = visproxy::build_proxies(mesh, path, {&spec, 1}, options).front();
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
