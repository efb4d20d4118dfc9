// visproxy build MESH -o DIR [--proxy SPEC]... [--per-component] [--weld MODE] [--seed S]

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "commands.h"
#include "mesh/mesh_topology.h"
#include "mesh/read_mesh.h"
#include "proxy/build_proxies.h"
#include "proxy/manifest.h"

namespace visproxy::cli {
namespace {

struct BuildCommandOptions {
  std::filesystem::path mesh;
  std::filesystem::path folder;
  std::vector<std::string> proxies;
  bool per_component = false;
  Weld weld = Weld::automatic;
  std::uint64_t seed = 1;
  std::size_t hausdorff_samples = 20000;
};

void print_table(const BuildCommandOptions& options, const ManifestMesh& mesh, const std::vector<BuiltProxy>& proxies,
                 double total_seconds) {
  std::printf("visproxy build: %zu proxies of %s (%zu vertices, %zu triangles, %zu component%s, diagonal %.6g)\n",
              proxies.size(), options.mesh.string().c_str(), mesh.vertices, mesh.triangles, mesh.components,
              mesh.components == 1 ? "" : "s", mesh.bounds.diagonal());
  std::printf("%-28s %-8s %10s %-9s %9s %12s  %s\n", "name", "kind", "primitives", "type", "build s",
              "Hausdorff %", "file");
  for (const BuiltProxy& proxy : proxies) {
    const double hausdorff_percent = 100.0 * proxy.error.at("hausdorff_relative").get<double>();
    std::printf("%-28s %-8s %10zu %-9s %9.3f %12.4f  %s\n", proxy.spec.name().c_str(),
                std::string(kind_name(proxy.spec.kind())).c_str(), proxy.primitives,
                std::string(primitive_type_name(proxy.primitive_type)).c_str(), proxy.build_seconds, hausdorff_percent,
                (options.folder / (proxy.spec.name() + ".ply")).string().c_str());
  }
  std::printf("Hausdorff %%: sampled two-sided Hausdorff distance between proxy and mesh, in %% of the bounding-box\n"
              "diagonal (%zu samples per surface, seed %llu). Manifest: %s (%.2f s in all)\n",
              options.hausdorff_samples, static_cast<unsigned long long>(options.seed),
              (options.folder / "manifest.json").string().c_str(), total_seconds);
}

}  // namespace

void add_build_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<BuildCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "build",
      "Build visibility proxies of a mesh: one binary PLY and one OBJ per proxy in DIR, listed in DIR/manifest.json "
      "(schema: data/schemas/manifest.schema.json) with kind, parameters, primitive count, build time and error.");
  command->add_option("mesh", options->mesh, "Mesh file (.obj, .ply, .off, .stl)")->required();
  command->add_option("-o,--output", options->folder, "Output folder (created if missing)")->required();
  command->add_option("--proxy", options->proxies,
                      "Proxy to build (repeatable). aabb, obb, hull, hull:N (convex, at most N faces), wrap, "
                      "wrap:alpha=A,offset=O (relative to the bbox diagonal; defaults 0.05 and 1/600), outer:N "
                      "(non-convex outside mesh, at most N triangles), quadric:N (at most N triangles), cluster:F "
                      "(cell F x largest bbox extent). Default: aabb obb hull hull:32 wrap outer:512 quadric:512 "
                      "cluster:0.03");
  command->add_flag("--per-component", options->per_component,
                    "Build one proxy per connected component (N applies to each) and join them in one file");
  const std::map<std::string, Weld> weld_modes{{"auto", Weld::automatic}, {"never", Weld::never}, {"always", Weld::always}};
  command
      ->add_option("--weld", options->weld,
                   "Merge vertices with identical coordinates: auto (STL only), never, always [default: auto]")
      ->transform(CLI::CheckedTransformer(weld_modes, CLI::ignore_case));
  command->add_option("--seed", options->seed, "Seed of every random choice (error samples, box search) [default: 1]");
  command
      ->add_option("--hausdorff-samples", options->hausdorff_samples,
                   "Area-uniform samples per surface for the Hausdorff error [default: 20000]")
      ->check(CLI::Range(std::size_t{100}, std::size_t{100'000'000}));

  command->callback([options, &exit_code] {
    const auto start = std::chrono::steady_clock::now();
    // Specs are checked before anything is read or built.
    const std::vector<ProxySpec> specs =
        options->proxies.empty() ? default_proxy_specs() : parse_proxy_specs(options->proxies);
    const TriangleMesh mesh = read_mesh(options->mesh, {.weld = options->weld});
    ManifestMesh described{.path = options->mesh,
                           .weld = options->weld == Weld::never ? "never" : options->weld == Weld::always ? "always" : "auto",
                           .vertices = mesh.positions.size(),
                           .triangles = mesh.triangles.size(),
                           .components = analyze_topology(mesh).components,
                           .bounds = bounding_box(mesh)};
    BuildOptions build{.per_component = options->per_component,
                       .hausdorff_samples = options->hausdorff_samples,
                       .seed = options->seed,
                       .on_start = {}};
    if (::isatty(STDERR_FILENO))
      build.on_start = [](std::string_view name) { std::cerr << "visproxy build: " << name << " ...\n"; };
    const std::vector<BuiltProxy> proxies = build_proxies(mesh, options->mesh, specs, build);
    write_proxy_folder(options->folder, described, proxies, build);
    print_table(*options, described, proxies,
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    exit_code = kSuccess;
  });
}

}  // namespace visproxy::cli
