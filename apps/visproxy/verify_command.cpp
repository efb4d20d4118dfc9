// visproxy verify MESH DIR [--hausdorff-samples N] [--seed S]

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>

#include "commands.h"
#include "progress.h"
#include "visproxy/folder/asset_folder.h"
#include "visproxy/folder/proxy_folder.h"
#include "visproxy/folder/verdict.h"

namespace visproxy::cli {
namespace {

struct VerifyCommandOptions {
  ProgressMode progress = ProgressMode::automatic;
  std::filesystem::path mesh;
  std::filesystem::path folder;
  std::size_t hausdorff_samples = 20000;
  std::uint64_t seed = 1;
};

std::string margin_text(const nlohmann::json& verify) {
  if (!verify.contains("margin") || verify["margin"].is_null()) return "-";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.4g", verify["margin"].get<double>());
  return buffer;
}

struct Tally {
  std::size_t proxies = 0, failures = 0;
};

// Verifies every proxy of one proxy folder against `mesh_path`, prints its table and
// records the verdicts in its manifest.
// `read`: the mesh, read and checked against the manifest already (read_built_parts), or
// null to read it from `mesh_path`.
Tally verify_folder(const std::filesystem::path& mesh_path, const std::filesystem::path& folder,
                    const VerifyCommandOptions& options, const TriangleMesh* read = nullptr) {
  nlohmann::json manifest = read_manifest(folder);
  TriangleMesh own;
  if (read == nullptr) own = read_manifest_mesh(mesh_path, manifest, print_warning);
  const TriangleMesh& mesh = read == nullptr ? own : *read;
  std::size_t failures = 0;
  std::printf("visproxy verify: %zu proxies in %s against %s (%zu triangles)\n", manifest["proxies"].size(),
              folder.string().c_str(), mesh_path.string().c_str(), mesh.triangles.size());
  std::printf("%-22s %-8s %-22s %-7s %12s %9s  %s\n", "name", "kind", "claim", "holds", "margin", "seconds",
              "counterexample / note");
  Progress progress("visproxy verify", manifest["proxies"].size(), options.progress);
  for (nlohmann::json& entry : manifest["proxies"]) {
    const std::string name = entry["name"].get<std::string>();
    progress.step("verifying " + name);
    const ProxyGeometry geometry = read_proxy_geometry(folder, entry);
    nlohmann::json verify = verify_proxy(mesh, manifest, entry, geometry,
                                         {.hausdorff_samples = options.hausdorff_samples, .seed = options.seed});
    const bool holds = verify["holds"].get<bool>();
    std::string note = verify["counterexample"].is_null() ? "" : verify["counterexample"].get<std::string>();
    if (verify["claim"] == "none") {
      char buffer[96];
      std::snprintf(buffer, sizeof buffer, "Hausdorff %.4g (%.4f %% of the diagonal)",
                    verify["hausdorff_world"].get<double>(), 100 * verify["hausdorff_relative"].get<double>());
      note = buffer;
    }
    progress.clear();
    std::printf("%-22s %-8s %-22s %-7s %12s %9.3f  %s\n", name.c_str(), entry["kind"].get<std::string>().c_str(),
                verify["claim"].get<std::string>().c_str(), holds ? "yes" : "NO", margin_text(verify).c_str(),
                verify["seconds"].get<double>(), note.c_str());
    if (!holds) {
      ++failures;
      std::cerr << "visproxy verify: " << name << " (" << entry["kind"].get<std::string>() << ") fails: " << note
                << "\n";
    }
    entry["verify"] = std::move(verify);
  }
  write_manifest(folder, manifest);
  std::printf(
      "margin: smallest distance between the contained surface's vertices and the container's surface, in "
      "mesh units (negative: how far the counterexample is outside). %zu of %zu claims hold. Recorded in %s\n",
      manifest["proxies"].size() - failures, manifest["proxies"].size(), (folder / "manifest.json").string().c_str());
  return {manifest["proxies"].size(), failures};
}

}  // namespace

void add_verify_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<VerifyCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "verify",
      "Check every proxy in DIR against MESH: an outside proxy must contain the mesh, an inside proxy must lie within "
      "it (exact tests); general proxies get their sampled Hausdorff distance. A per-mesh DIR (build --per-mesh) is "
      "checked mesh by mesh against MESH's own meshes, with a total. Records `verify` in DIR/manifest.json, "
      "prints a table, and exits 0 when every claim holds, 1 when one fails (naming the proxy and the first "
      "counterexample).");
  command->add_option("mesh", options->mesh, "The mesh the proxies were built from")->required();
  command->add_option("dir", options->folder, "Proxy folder written by 'visproxy build'")->required();
  command
      ->add_option("--hausdorff-samples", options->hausdorff_samples,
                   "General proxies: area-uniform samples per surface for the Hausdorff distance [default: 20000]")
      ->check(CLI::Range(std::size_t{100}, std::size_t{100'000'000}));
  command->add_option("--seed", options->seed, "Seed of the Hausdorff samples [default: 1]");
  add_progress_option(command, options->progress);

  command->callback([options, &exit_code] {
    if (is_asset_folder(options->folder)) {
      // A per-mesh folder: each built mesh's folder against ASSET:MESH, then the total.
      Tally total;
      std::size_t meshes = 0;
      for (const BuiltPart& part : read_built_parts(options->folder, options->mesh).parts) {
        const Tally tally = verify_folder(part.mesh_path, part.folder, *options, &part.mesh);
        total.proxies += tally.proxies;
        total.failures += tally.failures;
        ++meshes;
        std::printf("\n");
      }
      std::printf("visproxy verify: %zu of %zu claims hold over %zu meshes of %s\n", total.proxies - total.failures,
                  total.proxies, meshes, options->mesh.string().c_str());
      exit_code = total.failures == 0 ? kSuccess : kCheckFailed;
      return;
    }
    const Tally tally = verify_folder(options->mesh, options->folder, *options);
    exit_code = tally.failures == 0 ? kSuccess : kCheckFailed;
  });
}

}  // namespace visproxy::cli
