// visproxy report DIR [--mesh MESH] [--no-pictures]

#include <chrono>
#include <cstdio>
#include <filesystem>

#include "commands.h"
#include "visproxy/core/errors.h"
#include "visproxy/evaluate/asset_report.h"
#include "visproxy/evaluate/report.h"
#include "visproxy/folder/asset_folder.h"
#include "visproxy/folder/proxy_folder.h"

namespace visproxy::cli {
namespace {

struct ReportCommandOptions {
  std::filesystem::path folder;
  std::filesystem::path mesh;
  bool no_pictures = false;
  int picture_size = 192;
  std::size_t budget = 0;
};

}  // namespace

void add_report_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<ReportCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "report",
      "Write DIR/report.html (self-contained: opens from a file URL) and DIR/report.md from DIR/manifest.json: at the "
      "top, for each use (control variate, eq. 8, bounds) the proxy with the best predicted efficiency against tracing "
      "the mesh, with its 95 % interval (all figures in DIR/recommendation.json); a table sortable by any column "
      "(kind, "
      "primitives, build time, verdict, f_hit, f_miss, V_avg, GSSA ratio, p1/p2/p3, variance, cost ratio); each proxy "
      "drawn over the mesh and the shadow it casts on a ground plane beside the mesh's, with their difference "
      "(DIR/pictures/*.png); plots of f_miss (DIR/f_miss.svg) and of predicted efficiency (DIR/efficiency.svg) against "
      "primitive count. Run 'verify' and 'measure' first to fill them in: bounds use only proxies whose claim 'verify' "
      "proved for these very files.");
  command
      ->add_option(
          "dir", options->folder,
          "Proxy folder written by 'visproxy build'; a per-mesh folder gets each mesh's report and DIR/report.md, "
          "one row per mesh and a total")
      ->required();
  command->add_option("--mesh", options->mesh,
                      "The mesh the proxies were built from [default: the path DIR/manifest.json records]");
  command->add_flag("--no-pictures", options->no_pictures,
                    "Leave out the pictures (the recommendation still needs the mesh)");
  command->add_option("--picture-size", options->picture_size, "Pixels on a side of each picture [default: 192]")
      ->check(CLI::Range(32, 1024));
  command
      ->add_option(
          "--budget", options->budget,
          "Recommend only proxies of at most N primitives (triangles, boxes or spheres); the others keep their "
          "rows [default: any]")
      ->check(CLI::Range(std::size_t{1}, std::size_t{1'000'000'000}));
  command->callback([options, &exit_code] {
    const auto start = std::chrono::steady_clock::now();
    if (is_asset_folder(options->folder)) {
      // A per-mesh folder: each mesh's report, and one table over the asset.
      const nlohmann::json summary = write_asset_report(options->folder, options->mesh,
                                                        {.pictures = !options->no_pictures,
                                                         .picture_options = {.size = options->picture_size},
                                                         .budget = options->budget});
      std::printf("visproxy report: %zu meshes of %s in %.2f s\n", summary["parts"].size(),
                  summary["source"].get<std::string>().c_str(),
                  std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      for (const auto& [use, shipped] : summary["total"]["shipped_triangles"].items())
        std::printf("  %s: ship %zu triangles in all for the asset's %zu\n", use.c_str(), shipped.get<std::size_t>(),
                    summary["total"]["triangles"].get<std::size_t>());
      for (const char* file : {"report.md", "recommendation.json"})
        std::printf("  %s\n", (options->folder / file).string().c_str());
      exit_code = kSuccess;
      return;
    }
    const nlohmann::json manifest = read_manifest(options->folder);
    std::filesystem::path mesh_path = options->mesh;
    if (mesh_path.empty()) {
      mesh_path = manifest["mesh"]["path"].get<std::string>();
      std::error_code error;
      if (!std::filesystem::is_regular_file(mesh_path, error))
        throw IOError(mesh_path, "the mesh " + (options->folder / "manifest.json").string() +
                                     " names is not here (run from where it was built, or give it with --mesh)");
    }
    const TriangleMesh mesh = read_manifest_mesh(mesh_path, manifest, print_warning);
    const ReportFigures figures = report_figures(mesh, options->folder, manifest,
                                                 {.pictures = !options->no_pictures,
                                                  .picture_options = {.size = options->picture_size},
                                                  .budget = options->budget});
    write_report(options->folder, manifest, figures);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("visproxy report: %zu proxies of %s in %.2f s\n", manifest["proxies"].size(),
                mesh_path.string().c_str(), seconds);
    if (!figures.recommendation.choices[0].sentence.empty())
      for (const ShippingLine& line : shipping_lines(figures, manifest)) std::printf("  %s\n", line.text.c_str());
    for (const UseChoice& choice : figures.recommendation.choices)
      if (!choice.sentence.empty()) std::printf("  %s\n", choice.sentence.c_str());
    for (const ProxyFlag& flag : figures.flags) std::printf("  check: %s\n", flag.text.c_str());
    for (const char* file : {"report.html", "report.md", "recommendation.json", "f_miss.svg", "efficiency.svg"})
      std::printf("  %s\n", (options->folder / file).string().c_str());
    if (figures.pictured)
      std::printf("  %s (%zu proxies, %d x %d pixels each)\n", (options->folder / "pictures").string().c_str(),
                  figures.pictures.size(), options->picture_size, options->picture_size);
    exit_code = kSuccess;
  });
}

}  // namespace visproxy::cli
