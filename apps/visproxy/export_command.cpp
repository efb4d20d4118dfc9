// visproxy export DIR -o OUT.{glb,gltf,obj,ply} [--mesh MESH] [--proxy NAME]...

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "commands.h"
#include "progress.h"
#include "visproxy/asset/export_proxies.h"
#include "visproxy/folder/asset_folder.h"
#include "visproxy/folder/proxy_folder.h"
#include "visproxy/folder/verdict.h"

namespace visproxy::cli {
namespace {

struct ExportCommandOptions {
  std::filesystem::path folder;
  std::filesystem::path out;
  std::filesystem::path mesh;
  std::vector<std::string> proxies;
  ProgressMode progress = ProgressMode::automatic;
};

}  // namespace

void add_export_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<ExportCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "export",
      "Write the proxies of DIR back beside the asset they stand for, as OUT's extension says: .glb or .gltf (the "
      "source asset kept whole, a glTF source with its nodes, materials and textures; each proxy a node of its own "
      "with extras.visproxy = {shadow_only, kind, claim, proved, hashes}), .obj (the source and each proxy as `o` "
      "objects) or .ply (one proxy). Positions are float32: an outside or inside claim is proved again on the rounded "
      "coordinates, after moving vertices outward (inward) by a few float ulps where rounding to nearest broke it; a "
      "claim that cannot be kept is exported as general and named. Sphere proxies are written as icospheres inside "
      "their spheres. Exits 0 when every claim of the folder is kept, 1 when one was dropped.");
  command->add_option("dir", options->folder, "Proxy folder written by 'visproxy build' (with --per-mesh or without)")
      ->required();
  command->add_option("-o,--output", options->out, "The file to write: .glb, .gltf, .obj or .ply")->required();
  command->add_option("--mesh", options->mesh,
                      "The asset the proxies were built from [default: the path DIR/manifest.json records]");
  command->add_option("--proxy", options->proxies,
                      "Export only this proxy (its manifest name; repeat for more) [default: all]");
  add_progress_option(command, options->progress);

  command->callback([options, &exit_code] {
    // The proxies to round and prove, for the progress display: each part's of a per-mesh folder.
    std::size_t count = 0;
    const auto add = [&](const nlohmann::json& names) {
      for (const nlohmann::json& name : names)
        count += options->proxies.empty() || std::find(options->proxies.begin(), options->proxies.end(),
                                                       name.get<std::string>()) != options->proxies.end();
    };
    if (is_asset_folder(options->folder)) {
      const nlohmann::json listing = read_asset_manifest(options->folder);
      for (const nlohmann::json& part : listing["parts"]) add(part["proxies"]);
    } else {
      nlohmann::json names = nlohmann::json::array();
      const nlohmann::json manifest = read_manifest(options->folder);
      for (const nlohmann::json& entry : manifest["proxies"]) names.push_back(entry["name"]);
      add(names);
    }
    Progress progress("visproxy export", count, options->progress);
    const ExportResult result = export_proxies(
        options->folder, options->out,
        {.proxies = options->proxies,
         .source = options->mesh,
         .on_proxy = [&progress](std::string_view name) { progress.step("rounding and proving " + std::string(name)); },
         .on_warning = print_warning});
    progress.clear();
    std::printf("visproxy export: %zu proxies of %s written to %s (float32 positions)\n", result.proxies.size(),
                result.source.string().c_str(), result.path.string().c_str());
    std::printf("%-34s %-8s %-19s %-7s %10s %12s  %s\n", "object", "kind", "claim", "proved", "triangles", "moved",
                "note");
    std::size_t dropped = 0;
    for (const ExportedProxy& proxy : result.proxies) {
      const FloatProxy& g = proxy.geometry;
      char moved[32];
      std::snprintf(moved, sizeof moved, "%.3g", g.moved);
      std::printf("%-34s %-8s %-19s %-7s %10zu %12s  %s\n", proxy.node.c_str(), std::string(kind_name(g.kind)).c_str(),
                  std::string(kind_claim(g.kind)).c_str(), g.kind == ProxyKind::general ? "-" : "yes",
                  g.indices.size() / 3, moved, g.note.c_str());
      if (g.kind != g.claimed) {
        ++dropped;
        std::cerr << "visproxy export: " << proxy.name << ": " << g.note << "\n";
      }
    }
    std::printf(
        "moved: how far each vertex was moved along its normal (mesh units) before rounding outward (outside "
        "claims) or inward (inside claims); 0: rounded to nearest. %zu of %zu claims kept.\n",
        result.proxies.size() - dropped, result.proxies.size());
    exit_code = dropped == 0 ? kSuccess : kCheckFailed;
  });
}

}  // namespace visproxy::cli
