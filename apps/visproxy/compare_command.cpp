// visproxy compare SCENE [-o DIR] [--seconds T] [--reference REF.pfm] ...

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <cmath>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "core/errors.h"
#include "core/files.h"
#include "evaluate/plot.h"
#include "evaluate/scene_proxies.h"
#include "render/renderer.h"

namespace visproxy::cli {
namespace {

struct CompareOptions {
  std::filesystem::path scene, folder, reference, cache;
  double seconds = 10;
  int reference_spp = 4096;
  int shadow_rays = 1;
  std::uint64_t seed = 1;
  int width = 0, height = 0;
  int convergence_points = 4;
  bool no_count = false;
};

struct Mode {
  std::string name;
  RenderOptions options;
};

std::vector<Mode> modes(const CompareOptions& o) {
  auto base = [&](VisibilityMode v) {
    RenderOptions r;
    r.visibility = v;
    r.spp = 1 << 24;
    r.shadow_rays = o.shadow_rays;
    r.seed = o.seed;
    return r;
  };
  std::vector<Mode> out{{"exact", base(VisibilityMode::exact)}, {"bounds", base(VisibilityMode::bounds)}};
  RenderOptions equal = base(VisibilityMode::stochastic);
  out.push_back({"stochastic equal", equal});
  RenderOptions adaptive = equal;
  adaptive.probabilities = ProbabilityMode::adaptive;
  out.push_back({"stochastic adaptive", adaptive});
  adaptive.cost_heuristic = true;
  out.push_back({"stochastic adaptive + cost heuristic", adaptive});
  return out;
}

std::string format_number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", value);
  return buffer;
}

std::string file_stem(const std::string& name) {
  std::string stem;
  for (char c : name) stem += std::isalnum(static_cast<unsigned char>(c)) ? c : '-';
  return stem;
}

}  // namespace

void add_compare_command(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<CompareOptions>();
  CLI::App* command = app.add_subcommand(
      "compare",
      "Render a scene with every visibility mode at equal time against a high-sample exact reference and write the "
      "comparison (Billen et al. Tables 5/6, Figure 8): DIR/table.md and table.csv (time, samples and shadow rays per "
      "pixel, exact and proxy tests per pixel, MSE, efficiency 1/(MSE x time)), DIR/convergence.csv and .svg (MSE "
      "against time), and every image.");
  command->add_option("scene", o->scene, "Scene file")->required();
  command->add_option("-o,--output", o->folder, "Output folder [default: compare-SCENENAME]");
  command->add_option("--seconds", o->seconds, "Time per mode for the table [default: 10]")->check(CLI::Range(0.01, 1e6));
  command->add_option("--reference", o->reference, "Reference image (.pfm); rendered exactly with --reference-spp when absent");
  command->add_option("--reference-spp", o->reference_spp, "Samples per pixel of the rendered reference [default: 4096]")
      ->check(CLI::Range(1, 1 << 20));
  command->add_option("--shadow-rays", o->shadow_rays, "Shadow rays per camera sample in every mode [default: 1]")->check(CLI::Range(1, 4096));
  command->add_option("--seed", o->seed, "Seed of the renders (the reference uses seed + 1000003) [default: 1]");
  command->add_option("--convergence-points", o->convergence_points,
                      "Time budgets per mode for the MSE-against-time curve, halving from --seconds [default: 4]")
      ->check(CLI::Range(1, 12));
  command->add_flag("--no-count", o->no_count,
                    "Skip the counted re-render of each mode (same samples and seed, visproxy's own BVH traversal) that "
                    "gives the table's traversal steps and primitive tests");
  command->add_option("--cache", o->cache, "Proxy cache folder [default: as for render]");
  command->add_option("--width", o->width, "Override the camera's image width")->check(CLI::Range(1, 16384));
  command->add_option("--height", o->height, "Override the camera's image height")->check(CLI::Range(1, 16384));

  command->callback([o, &exit_code] {
    Scene scene = load_scene(o->scene);
    if (o->width > 0) scene.camera.width = o->width;
    if (o->height > 0) scene.camera.height = o->height;
    const std::filesystem::path folder = o->folder.empty() ? std::filesystem::path("compare-" + o->scene.stem().string()) : o->folder;
    std::error_code error;
    std::filesystem::create_directories(folder, error);
    if (error) throw IOError(folder, "cannot create the output folder: " + error.message());
    const bool terminal = ::isatty(STDERR_FILENO);

    const std::vector<MeshProxies> proxies = prepare_scene_proxies(
        scene, {.cache = o->cache.empty() ? default_proxy_cache() : o->cache, .stochastic_spec = std::nullopt, .seed = o->seed,
                .on_proxy = [](std::string_view mesh, std::string_view spec, bool cached) {
                  if (!cached) std::cerr << "visproxy compare: building " << spec << " of " << mesh << "\n";
                }});
    const RenderWorld world(scene, proxies);
    std::unique_ptr<RenderWorld> counting;
    if (!o->no_count) counting = std::make_unique<RenderWorld>(scene, proxies, true);

    Image reference;
    std::string reference_note;
    if (!o->reference.empty()) {
      reference = read_pfm(o->reference);
      if (reference.width != scene.camera.width || reference.height != scene.camera.height)
        throw InvalidInputError(o->reference, "is " + std::to_string(reference.width) + "x" + std::to_string(reference.height) +
                                                  "; the scene renders " + std::to_string(scene.camera.width) + "x" +
                                                  std::to_string(scene.camera.height));
      reference_note = "reference " + o->reference.string();
    } else {
      std::cerr << "visproxy compare: rendering the exact reference (" << o->reference_spp << " spp x " << o->shadow_rays
                << " shadow rays)\n";
      RenderOptions r;
      r.spp = o->reference_spp;
      r.shadow_rays = o->shadow_rays;
      r.seed = o->seed + 1000003;
      const RenderResult result = render(scene, world, r);
      reference = result.image;
      write_pfm(folder / "reference.pfm", reference);
      write_png(folder / "reference.png", reference);
      reference_note = "reference rendered exactly with " + std::to_string(o->reference_spp) + " spp x " +
                       std::to_string(o->shadow_rays) + " shadow rays (seed " + std::to_string(o->seed + 1000003) + ", " +
                       format_number(result.stats.seconds) + " s)";
    }

    const double pixels = static_cast<double>(scene.camera.width) * scene.camera.height;
    std::string md = "# visproxy compare: " + o->scene.string() + "\n\n" + std::to_string(scene.camera.width) + "x" +
                     std::to_string(scene.camera.height) + " pixels, " + std::to_string(o->shadow_rays) +
                     " shadow ray(s) per camera sample, seed " + std::to_string(o->seed) + ", equal time " +
                     format_number(o->seconds) + " s per mode; " + reference_note + ".\n\n";
    md += "| mode | time (s) | samples per pixel | shadow rays per pixel | exact tests per pixel | proxy tests per pixel | "
          "traversal steps per pixel | primitive tests per pixel | MSE | efficiency 1/(MSE x s) |\n";
    md += "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n";
    std::string csv = "mode,seconds,samples_per_pixel,shadow_rays_per_pixel,exact_tests_per_pixel,proxy_tests_per_pixel,"
                      "traversal_steps_per_pixel,primitive_tests_per_pixel,mse,efficiency\n";
    std::string convergence = "mode,seconds_budget,seconds,samples_per_pixel,mse\n";
    std::vector<PlotSeries> curves;
    for (const Mode& mode : modes(*o)) {
      PlotSeries curve{mode.name, {}, {}};
      for (int point = o->convergence_points - 1; point >= 0; --point) {
        RenderOptions options = mode.options;
        options.seconds = o->seconds / std::pow(2.0, point);
        if (terminal) std::cerr << "visproxy compare: " << mode.name << ", " << options.seconds << " s\n";
        const RenderResult result = render(scene, world, options);
        const double mse = mean_squared_error(result.image, reference);
        char line[256];
        std::snprintf(line, sizeof line, "%s,%.6g,%.6g,%d,%.10g\n", mode.name.c_str(), options.seconds, result.stats.seconds,
                      result.stats.passes, mse);
        convergence += line;
        curve.x.push_back(result.stats.seconds);
        curve.y.push_back(mse);
        if (point != 0) continue;
        write_pfm(folder / (file_stem(mode.name) + ".pfm"), result.image);
        write_png(folder / (file_stem(mode.name) + ".png"), result.image);
        const RenderStats& s = result.stats;
        const double efficiency = mse > 0 ? 1.0 / (mse * s.seconds) : 0.0;
        // The same samples again through the counting traversal: deterministic work figures.
        double steps = std::nan(""), primitives = std::nan("");
        if (counting) {
          RenderOptions counted = mode.options;
          counted.spp = s.passes;
          counted.seconds = 0;
          if (terminal) std::cerr << "visproxy compare: " << mode.name << ", counting " << s.passes << " spp\n";
          const RenderResult c = render(scene, *counting, counted);
          steps = static_cast<double>(c.stats.traversal_steps) / pixels;
          primitives = static_cast<double>(c.stats.primitive_tests) / pixels;
        }
        std::snprintf(line, sizeof line, "| %s | %.2f | %d | %.1f | %.1f | %.1f | %.0f | %.0f | %.4g | %.4g |\n", mode.name.c_str(),
                      s.seconds, s.passes, static_cast<double>(s.shadow_rays) / pixels, static_cast<double>(s.exact_tests) / pixels,
                      static_cast<double>(s.proxy_tests) / pixels, steps, primitives, mse, efficiency);
        md += line;
        std::snprintf(line, sizeof line, "%s,%.6g,%d,%.6g,%.6g,%.6g,%.6g,%.6g,%.10g,%.10g\n", mode.name.c_str(), s.seconds, s.passes,
                      static_cast<double>(s.shadow_rays) / pixels, static_cast<double>(s.exact_tests) / pixels,
                      static_cast<double>(s.proxy_tests) / pixels, steps, primitives, mse, efficiency);
        csv += line;
      }
      curves.push_back(std::move(curve));
    }
    md += "\nMSE: mean over pixels and RGB channels of the squared difference to the reference (linear radiance). "
          "Exact and proxy tests: segment queries against meshes and against proxies; traversal steps and primitive tests: "
          "BVH nodes visited and triangles or balls tested by those queries, counted by re-rendering the same samples "
          "with visproxy's own traversal (nan with --no-count). Images: MODE.pfm / MODE.png; "
          "MSE against time: convergence.csv, convergence.svg.\n";
    write_file_atomically(folder / "table.md", md);
    write_file_atomically(folder / "table.csv", csv);
    write_file_atomically(folder / "convergence.csv", convergence);
    write_file_atomically(folder / "convergence.svg",
                          line_plot_svg(curves, {.title = "MSE against render time: " + o->scene.filename().string(),
                                                 .x_label = "render time (s, log scale)",
                                                 .y_label = "MSE against the reference (log scale)",
                                                 .log_x = true, .log_y = true, .width = 720, .height = 440}));
    std::fputs(md.c_str(), stdout);
    std::printf("Written to %s\n", folder.string().c_str());
    std::fflush(stdout);
    exit_code = kSuccess;
  });
}

}  // namespace visproxy::cli
