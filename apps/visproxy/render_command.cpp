// visproxy render SCENE -o OUT.pfm [options]: the job render_scene() does (render/render_job.h),
// its options made into flags from the one table of render options.

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <string>

#include "commands.h"
#include "visproxy/core/errors.h"
#include "visproxy/image/image.h"
#include "visproxy/render/render_job.h"

namespace visproxy::cli {
namespace {

// What the CLI prints of a render: the scene, the modes, the time, the work per segment, the files.
void print_render_summary(const RenderJob& job, const RenderedScene& rendered) {
  const RenderResult& result = rendered.result;
  const RenderOptions& o = job.options;
  const std::filesystem::path png = std::filesystem::path(job.output).replace_extension(".png");
  std::filesystem::path stats = job.output;
  stats.replace_extension();
  stats += ".stats.json";
  const double segments =
      static_cast<double>(std::max<std::uint64_t>(result.stats.shadow_rays + result.stats.vpl_connections, 1));
  std::string vpl_text;
  if (o.integrator == IntegratorKind::lightcuts) {
    const nlohmann::json& lc = result.stats.integrator;
    char text[400];
    std::snprintf(
        text, sizeof text,
        ", %llu point lights, error %.3g, max cut %d, bounds %s: mean cut %.1f clusters, %.1f shadow rays per "
        "shading point, clusters proved unoccluded %llu and occluded %llu",
        static_cast<unsigned long long>(lc.value("point_lights", 0ull)), o.lightcut.error, o.lightcut.max_cut,
        std::string(name_of(o.lightcut.bounds)).c_str(), lc.value("cut_size_mean", 0.0),
        lc.value("shadow_rays_per_shading_point", 0.0),
        static_cast<unsigned long long>(lc.value("clusters_proved_unoccluded", 0ull)),
        static_cast<unsigned long long>(lc.value("clusters_proved_occluded", 0ull)));
    vpl_text = text;
    if (o.lightcut.check_proofs)
      vpl_text += ", proofs checked: " + std::to_string(lc.value("proof_disagreements", 0ull)) + " disagreed";
  }
  if (o.integrator == IntegratorKind::vpl) {
    char text[200];
    std::snprintf(text, sizeof text, ", %llu VPLs (%llu connections; clamping dropped %.3f %% of their energy)",
                  static_cast<unsigned long long>(result.stats.integrator.value("virtual_point_lights", 0ull)),
                  static_cast<unsigned long long>(result.stats.vpl_connections),
                  100 * result.stats.integrator.value("clamped_energy_fraction", 0.0));
    vpl_text = text;
  }
  std::printf(
      "visproxy render: %s, %dx%d, %s integrator, %s visibility, %d spp x %d shadow rays, seed %llu: %.2f s, %llu "
      "shadow rays "
      "(%.2f exact and %.2f proxy tests per %s)%s\n  %s\n  %s\n  %s\n",
      job.scene.string().c_str(), rendered.scene.camera.width, rendered.scene.camera.height,
      std::string(name_of(o.integrator)).c_str(), std::string(name_of(o.visibility)).c_str(), result.stats.passes,
      o.shadow_rays, static_cast<unsigned long long>(o.seed), result.stats.seconds,
      static_cast<unsigned long long>(result.stats.shadow_rays),
      static_cast<double>(result.stats.exact_tests) / segments,
      static_cast<double>(result.stats.proxy_tests) / segments,
      o.integrator == IntegratorKind::vpl ? "segment: shadow ray or VPL connection" : "shadow ray", vpl_text.c_str(),
      job.output.string().c_str(), png.string().c_str(), stats.string().c_str());
}

}  // namespace

void add_render_command(CLI::App& app, int& exit_code) {
  struct Given {
    RenderJob job;
    std::map<std::string_view, std::string> values;  // option name -> text, for the options given
    std::map<std::string_view, CLI::Option*> flags;
  };
  auto given = std::make_shared<Given>();
  CLI::App* command = app.add_subcommand(
      "render",
      "Render a scene lit by its area lights (Lambertian surfaces): direct illumination with M shadow rays per camera "
      "sample, or with --integrator vpl also the indirect light of N virtual point lights, or with --integrator "
      "lightcuts K "
      "point lights per area light through lightcuts, whose clusters the proxies may prove free or occluded. Writes "
      "OUT.pfm "
      "(linear radiance), OUT.png (sRGB) and OUT.stats.json; builds the proxies the scene names that are not in the "
      "cache yet.");
  command
      ->add_option(
          "scene", given->job.scene,
          "Scene file: JSON (format in apps/visproxy/README.md, schema data/schemas/scene.schema.json), or a glTF 2.0 .gltf/.glb "
          "(or other Assimp file) whose nodes, emissive materials and camera make the scene")
      ->required();
  command->add_option("-o,--output", given->job.output, "Output image: .pfm or .exr (linear radiance)")->required();
  for (const RenderOption& option : render_options()) {
    if (option.type == RenderOption::Type::flag) {
      given->flags[option.name] = command->add_flag(std::string(option.flag), option.help);
      continue;
    }
    CLI::Option* added = command->add_option(std::string(option.flag), given->values[option.name], option.help);
    added->type_name(option.type == RenderOption::Type::choice    ? option.choices
                     : option.type == RenderOption::Type::integer ? "INT"
                     : option.type == RenderOption::Type::real    ? "NUMBER"
                                                                  : "TEXT");
  }

  command->callback([given, command, &exit_code] {
    RenderJob job = given->job;
    for (const RenderOption& option : render_options()) {
      if (option.type == RenderOption::Type::flag) {
        if (given->flags.at(option.name)->count() > 0) option.set(job, "");
      } else if (command->get_option(std::string(option.flag))->count() > 0) {
        option.set(job, given->values.at(option.name));
      }
    }
    const bool terminal = ::isatty(STDERR_FILENO);
    RenderCallbacks callbacks;
    callbacks.on_warning = print_warning;
    const std::filesystem::path cache = job.cache;
    callbacks.on_proxy = [&](std::string_view mesh, std::string_view spec, bool cached) {
      if (!cached)
        std::cerr << "visproxy render: building " << spec << " of " << mesh << " (cached in "
                  << (cache.empty() ? default_proxy_cache() : cache).string() << ")\n";
    };
    callbacks.on_verify = [](std::string_view mesh, std::string_view spec, bool holds,
                             std::string_view counterexample) {
      std::cerr << "visproxy render: verified " << spec << " of " << mesh << ": "
                << (holds ? std::string("holds")
                          : "does not hold (" + std::string(counterexample) + "): used as a general proxy")
                << "\n";
    };
    if (terminal)
      callbacks.on_pass = [&](int passes, double seconds) {
        const double fraction =
            job.options.seconds > 0 ? std::min(1.0, seconds / job.options.seconds) : double(passes) / job.options.spp;
        const int filled = static_cast<int>(40 * fraction);
        std::fprintf(stderr, "\rvisproxy render: [%s%s] %3.0f%% %d spp %.1f s",
                     std::string(static_cast<std::size_t>(filled), '#').c_str(),
                     std::string(static_cast<std::size_t>(40 - filled), '.').c_str(), 100 * fraction, passes, seconds);
      };
    const RenderedScene rendered = render_scene(job, callbacks);
    if (terminal) std::fprintf(stderr, "\n");
    for (const std::string& note : rendered.notes) std::cerr << "visproxy render: note: " << note << "\n";
    write_render_outputs(job, rendered);
    print_render_summary(job, rendered);
    exit_code = all_finite(rendered.result.image) ? kSuccess : kInternalError;
    if (exit_code != kSuccess) std::cerr << "visproxy render: the image holds NaN or infinite values\n";
  });
}

}  // namespace visproxy::cli
