// visproxy measure MESH DIR [--rays N] [--seed S] [--timed-rays N]

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>

#include "commands.h"
#include "progress.h"
#include "visproxy/evaluate/measure_proxies.h"
#include "visproxy/folder/asset_folder.h"
#include "visproxy/folder/proxy_folder.h"

namespace visproxy::cli {
namespace {

struct MeasureCommandOptions {
  ProgressMode progress = ProgressMode::automatic;
  std::filesystem::path mesh;
  std::filesystem::path folder;
  std::size_t rays = 1'000'000;
  std::uint64_t seed = 1;
  std::size_t timed_rays = 100'000;
  std::filesystem::path scene;
};

double value(const nlohmann::json& m, const char* key) { return m[key]["value"].get<double>(); }

// Measures every proxy of one proxy folder against the mesh at `mesh_path` (or `read`, an
// asset's part read and checked already by read_built_parts), records it in the folder's manifest and prints the table.
void measure_folder(const std::filesystem::path& mesh_path, const std::filesystem::path& folder,
                    const MeasureCommandOptions& options, const TriangleMesh* read = nullptr) {
  const auto start = std::chrono::steady_clock::now();
  nlohmann::json manifest = read_manifest(folder);
  TriangleMesh own;
  if (read == nullptr) own = read_manifest_mesh(mesh_path, manifest, print_warning);
  const TriangleMesh& mesh = read == nullptr ? own : *read;
  MeasureOptions measure{.rays = options.rays,
                         .seed = options.seed,
                         .scene = options.scene,
                         .timing = {.rays = options.timed_rays},
                         .on_start = {},
                         .on_warning = print_warning};
  {
    Progress progress("visproxy measure", manifest["proxies"].size(), options.progress);
    measure.on_start = [&progress](std::string_view name) { progress.step("measuring " + std::string(name)); };
    manifest = measure_proxies(mesh, folder, std::move(manifest), measure);
  }
  write_manifest(folder, manifest);

  const nlohmann::json& ray_set =
      manifest["proxies"].empty() ? nlohmann::json::object() : manifest["proxies"][0]["measure"]["rays"];
  if (options.scene.empty())
    std::printf("visproxy measure: %zu proxies of %s on %zu isotropic lines (seed %llu) through its bounding sphere\n",
                manifest["proxies"].size(), mesh_path.string().c_str(), options.rays,
                static_cast<unsigned long long>(options.seed));
  else
    std::printf("visproxy measure: %zu proxies of %s on %zu shadow segments of %s (seed %llu)\n",
                manifest["proxies"].size(), mesh_path.string().c_str(), ray_set.value("count", std::size_t{0}),
                options.scene.string().c_str(), static_cast<unsigned long long>(options.seed));
  std::printf("%-22s %-8s %8s %8s %8s %8s %-20s %9s %9s %9s %7s %-13s\n", "name", "kind", "f_hit", "f_miss", "V_avg",
              "GSSA", "p1/p2/p3", "variance", "proxy ns", "mesh ns", "ratio", "ratio interval");
  for (const nlohmann::json& entry : manifest["proxies"]) {
    const nlohmann::json& m = entry["measure"];
    char probabilities[32];
    std::snprintf(probabilities, sizeof probabilities, "%.3f/%.3f/%.3f", m["probabilities"]["p1"].get<double>(),
                  m["probabilities"]["p2"].get<double>(), m["probabilities"]["p3"].get<double>());
    const nlohmann::json& cost = m["cost_ns_per_ray"];
    char range[40] = "-";
    if (const auto interval = cost_ratio_interval(m))
      std::snprintf(range, sizeof range, "%.3f-%.3f", (*interval)[0], (*interval)[1]);
    std::printf("%-22s %-8s %8.4f %8.4f %8.4f %8.4f %-20s %9.4f %9.1f %9.1f %7.3f %-13s\n",
                entry["name"].get<std::string>().c_str(), entry["kind"].get<std::string>().c_str(), value(m, "f_hit"),
                value(m, "f_miss"), value(m, "v_avg"), value(m, "gssa_ratio"), probabilities,
                m["variance"]["optimal"].get<double>(), cost["proxy"].get<double>(), cost["mesh"].get<double>(),
                cost["proxy_over_mesh"].get<double>(), range);
    if (m["rays_contradicting_claim"].get<std::uint64_t>() > 0)
      std::printf("  note: %llu rays contradict the %s claim; probabilities use the general form\n",
                  static_cast<unsigned long long>(m["rays_contradicting_claim"].get<std::uint64_t>()),
                  entry["kind"].get<std::string>().c_str());
  }
  if (const auto model = manifest.find("cost_model"); model != manifest.end() && model->value("fitted", false)) {
    const nlohmann::json& ns = (*model)["ns"];
    std::printf(
        "cost model of this run: %.1f ns per ray + %.2f per BVH node + %.2f per triangle + %.2f per ball, fitted to %zu "
        "proxies' timings from their counted work; timed / predicted ratios %.3f-%.3f, which the ratio intervals "
        "carry\n",
        ns["per_ray"].get<double>(), ns["per_node"].get<double>(), ns["per_triangle"].get<double>(),
        ns["per_ball"].get<double>(), (*model)["observations"].get<std::size_t>(),
        (*model)["ratio_timed_over_predicted"][0].get<double>(), (*model)["ratio_timed_over_predicted"][1].get<double>());
  } else if (model != manifest.end()) {
    std::printf("cost model: not fitted (%s); the ratio intervals are the blocks' ranges\n",
                model->value("why_not", std::string()).c_str());
  }
  if (const auto share = manifest.find("render_share"); share != manifest.end())
    std::printf(
        "render: testing shadow rays against the mesh takes %.1f %% (%.1f-%.1f %% over %d timed rounds) of a camera "
        "sample's time in %s (%.2f shadow rays of %.1f ns per sample of %.0f ns, one thread, %dx%d pixels); 'visproxy "
        "report' predicts each use's render gain from it\n",
        100 * (*share)["share"].get<double>(), 100 * (*share)["share_range"][0].get<double>(),
        100 * (*share)["share_range"][1].get<double>(), (*share)["rounds"].get<int>(), options.scene.string().c_str(),
        (*share)["shadow_rays_per_camera_sample"].get<double>(), (*share)["mesh_ns_per_shadow_ray"].get<double>(),
        (*share)["ns_per_camera_sample"].get<double>(), (*share)["width"].get<int>(), (*share)["height"].get<int>());
  std::printf(
      "f_hit: blocked-by-mesh rays the proxy blocks; f_miss: free rays the proxy lets through; V_avg: free "
      "rays; GSSA: proxy-blocked over mesh-blocked rays; p1/p2/p3 and variance: the estimator's optimal "
      "probabilities and its variance per ray (Billen et al. eq. 16); ns: time per ray on one core over %zu "
      "lines, the median of %d blocks that time the mesh and the proxy back to back; ratio: the median of "
      "the blocks' proxy ns over mesh ns, and its interval (the cost model's, else the blocks' range). Intervals in "
      "%s. (%.2f s in all)\n",
      std::min(options.rays, options.timed_rays), TimingOptions{}.blocks, (folder / "manifest.json").string().c_str(),
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
}

}  // namespace

void add_measure_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<MeasureCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "measure",
      "Trace seeded isotropic lines through MESH's bounding sphere against the mesh and every proxy in DIR (Embree, "
      "all cores) and record per proxy, under `measure` in DIR/manifest.json: ray-type counts, f_hit, f_miss, V_avg "
      "and the GSSA ratio with 95 % intervals, the estimator's optimal probabilities and variance, and the cost per "
      "ray of proxy and mesh on one core, with a model of that cost fitted to the proxies' counted work (BVH nodes, "
      "triangles, balls) whose error widens the cost intervals. With --scene, the rays are the scene's shadow segments "
      "instead, and the share of a render sample's time that shadow tests against the mesh take is measured, with "
      "the render's noise per pixel and each proxy's part in it, from which 'report' predicts the gain over the whole "
      "render.");
  command->add_option("mesh", options->mesh, "The mesh the proxies were built from")->required();
  command
      ->add_option("dir", options->folder, "Proxy folder written by 'visproxy build' (a per-mesh folder: each mesh's)")
      ->required();
  command->add_option("--rays", options->rays, "Isotropic lines [default: 1000000]")
      ->check(CLI::Range(std::size_t{1}, std::size_t{1'000'000'000}));
  command->add_option("--seed", options->seed, "Seed of the lines [default: 1]");
  command->add_option("--scene", options->scene,
                      "Measure on a scene's shadow segments instead: from points its camera sees on other instances to "
                      "its lights, against every instance of MESH in it (--rays of them)");
  add_progress_option(command, options->progress);
  command
      ->add_option("--timed-rays", options->timed_rays,
                   "Lines timed on one core for the cost per ray, in 6 blocks that time the mesh and the proxy back to "
                   "back [default: 100000]")
      ->check(CLI::Range(std::size_t{1}, std::size_t{1'000'000'000}));

  command->callback([options, &exit_code] {
    if (is_asset_folder(options->folder)) {
      // A per-mesh folder: each built mesh's folder against ASSET:MESH, each mesh read once.
      if (!options->scene.empty())
        throw OptionError("--scene", "measures the folder of one mesh, not a per-mesh folder");
      std::size_t meshes = 0;
      for (const BuiltPart& part : read_built_parts(options->folder, options->mesh).parts) {
        measure_folder(part.mesh_path, part.folder, *options, &part.mesh);
        ++meshes;
        std::printf("\n");
      }
      std::printf("visproxy measure: the proxies of %zu meshes of %s measured\n", meshes,
                  options->mesh.string().c_str());
      exit_code = kSuccess;
      return;
    }
    measure_folder(options->mesh, options->folder, *options);
    exit_code = kSuccess;
  });
}

}  // namespace visproxy::cli
