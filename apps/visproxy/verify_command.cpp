// visproxy verify MESH DIR [--hausdorff-samples N] [--seed S]

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>

#include "commands.h"
#include "progress.h"
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

}  // namespace

void add_verify_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<VerifyCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "verify",
      "Check every proxy in DIR against MESH: an outside proxy must contain the mesh, an inside proxy must lie within "
      "it (exact tests); general proxies get their sampled Hausdorff distance. Records `verify` in DIR/manifest.json, "
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
    nlohmann::json manifest = read_manifest(options->folder);
    const TriangleMesh mesh = read_manifest_mesh(options->mesh, manifest, print_warning);
    std::size_t failures = 0;
    std::printf("visproxy verify: %zu proxies in %s against %s (%zu triangles)\n", manifest["proxies"].size(),
                options->folder.string().c_str(), options->mesh.string().c_str(), mesh.triangles.size());
    std::printf("%-22s %-8s %-22s %-7s %12s %9s  %s\n", "name", "kind", "claim", "holds", "margin", "seconds",
                "counterexample / note");
    Progress progress("visproxy verify", manifest["proxies"].size(), options->progress);
    for (nlohmann::json& entry : manifest["proxies"]) {
      const std::string name = entry["name"].get<std::string>();
      progress.step("verifying " + name);
      const ProxyGeometry geometry = read_proxy_geometry(options->folder, entry);
      nlohmann::json verify = verify_proxy(mesh, manifest, entry, geometry,
                                           {.hausdorff_samples = options->hausdorff_samples, .seed = options->seed});
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
        std::cerr << "visproxy verify: " << name << " (" << entry["kind"].get<std::string>() << ") fails: " << note << "\n";
      }
      entry["verify"] = std::move(verify);
    }
    write_manifest(options->folder, manifest);
    std::printf("margin: smallest distance between the contained surface's vertices and the container's surface, in "
                "mesh units (negative: how far the counterexample is outside). %zu of %zu claims hold. Recorded in %s\n",
                manifest["proxies"].size() - failures, manifest["proxies"].size(),
                (options->folder / "manifest.json").string().c_str());
    exit_code = failures == 0 ? kSuccess : kCheckFailed;
  });
}

}  // namespace visproxy::cli
