// visproxy render SCENE -o OUT.pfm [--visibility MODE] [--spp N] [--shadow-rays M] [--seed S] [--seconds T] ...

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <string>

#include "commands.h"
#include "visproxy/core/errors.h"
#include "visproxy/core/files.h"
#include "visproxy/evaluate/scene_proxies.h"
#include "visproxy/render/renderer.h"

namespace visproxy::cli {
namespace {

struct RenderCommandOptions {
  std::filesystem::path scene;
  std::filesystem::path output;
  VisibilityMode visibility = VisibilityMode::exact;
  IntegratorKind integrator = IntegratorKind::direct;
  int vpls = 1024;
  int bounces = 1;
  std::uint64_t vpl_seed = 1;
  double vpl_clamp = 0.05;
  SelfShadow self_shadow = SelfShadow::heuristic;
  bool single_rays = false;
  std::size_t disk_grid_from = 4096;
  bool no_disk_clusters = false;
  ProbabilityMode probabilities = ProbabilityMode::equal;
  StochasticEstimator estimator = StochasticEstimator::term_choice;
  int probe_passes = 0;
  bool cost_heuristic = false;
  bool no_split = false;
  int probe_rays = 16;
  double probability_floor = 0.05;
  double correction_scale = 0;  // 0: not given (2, or 0.25 with --integrator vpl)
  int spp = 16;
  int shadow_rays = 1;
  std::uint64_t seed = 1;
  double seconds = 0;
  std::string proxy;
  std::filesystem::path cache;
  double exposure = 1.0;
  bool maps = false;
  std::filesystem::path cut_reference;
  bool count = false;
  int light_points = 1024;
  double error = 0.02;
  int max_cut = 1000;
  VisibilityBounds visibility_bounds = VisibilityBounds::none;
  bool check_proofs = false;
  int width = 0, height = 0;
};

std::filesystem::path beside(const std::filesystem::path& output, const std::string& suffix) {
  std::filesystem::path path = output;
  path.replace_extension();
  return path.string() + suffix;
}

}  // namespace

void add_render_command(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<RenderCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "render",
      "Render a scene lit by its area lights (Lambertian surfaces): direct illumination with M shadow rays per camera "
      "sample, or with --integrator vpl also the indirect light of N virtual point lights, or with --integrator lightcuts K "
      "point lights per area light through lightcuts, whose clusters the proxies may prove free or occluded. Writes OUT.pfm (linear radiance), OUT.png (sRGB) and OUT.stats.json; builds the proxies the scene "
      "names that are not in the cache yet.");
  command->add_option("scene", o->scene, "Scene file: JSON (format in README.md, schema data/schemas/scene.schema.json), or a glTF 2.0 .gltf/.glb (or other Assimp file) whose nodes, emissive materials and camera make the scene")->required();
  command->add_option("-o,--output", o->output, "Output image: .pfm or .exr (linear radiance)")->required();
  const std::map<std::string, VisibilityMode> modes{{"exact", VisibilityMode::exact},
                                                    {"stochastic", VisibilityMode::stochastic},
                                                    {"bounds", VisibilityMode::bounds},
                                                    {"spheres", VisibilityMode::spheres}};
  command
      ->add_option("--visibility", o->visibility,
                   "exact: every shadow ray against the meshes; stochastic: the unbiased estimator with each instance's "
                   "proxy (own instance exact); bounds: exact answer, proxies only skip work (VPL connections are traced "
                   "exactly); spheres: each instance's sphere-set proxy as occluder disks, biased by design (instances "
                   "without one traced exactly) [default: exact]")
      ->transform(CLI::CheckedTransformer(modes, CLI::ignore_case));
  const std::map<std::string, IntegratorKind> integrators{
      {"direct", IntegratorKind::direct}, {"vpl", IntegratorKind::vpl}, {"lightcuts", IntegratorKind::lightcuts}};
  command
      ->add_option("--integrator", o->integrator,
                   "direct: M area-light samples per camera sample; vpl: those plus every virtual point light left by N "
                   "light paths of B bounces (instant radiosity); lightcuts: K point lights per area light (plus the VPLs "
                   "of --vpls, if given) shaded through a lightcut (Walter et al. 2005), each cluster by a representative "
                   "traced exactly, or by its central light where the proxies prove its visibility [default: direct]")
      ->transform(CLI::CheckedTransformer(integrators, CLI::ignore_case));
  CLI::Option* vpls_option =
      command->add_option("--vpls", o->vpls, "vpl: light paths traced from the area lights (N); lightcuts: add their VPLs to the point lights [default: 1024; lightcuts: none]")
          ->check(CLI::Range(1, 1 << 22));
  command->add_option("--light-points", o->light_points, "lightcuts: point lights per area light (K), stratified over its area [default: 1024]")
      ->check(CLI::Range(1, 1 << 22));
  command->add_option("--error", o->error,
                      "lightcuts: refine the cut until every cluster's error bound is at most this fraction of the cut's total "
                      "(0: the exact sum over every light, whatever --max-cut says) [default: 0.02]")
      ->check(CLI::Range(0.0, 1.0));
  command->add_option("--max-cut", o->max_cut, "lightcuts: most clusters in a cut with --error above 0; the stats count the cuts it stopped [default: 1000]")->check(CLI::Range(1, 1 << 24));
  const std::map<std::string, VisibilityBounds> bounds{{"none", VisibilityBounds::none},
                                                       {"lower", VisibilityBounds::lower},
                                                       {"upper", VisibilityBounds::upper},
                                                       {"both", VisibilityBounds::both}};
  command
      ->add_option("--visibility-bounds", o->visibility_bounds,
                   "lightcuts: prove clusters with the scene's proxies: lower (the shaft from the point to the cluster's "
                   "box misses every other instance's outside proxy and the own mesh: visibility 1), upper (every segment "
                   "to the box enters an inside proxy: visibility 0), both, or none. Proved clusters take no shadow ray; "
                   "their error bounds shrink [default: none]")
      ->transform(CLI::CheckedTransformer(bounds, CLI::ignore_case));
  command->add_flag("--check-proofs", o->check_proofs,
                    "lightcuts: also trace the light every proved cluster is shaded by and report how many disagreed with the "
                    "proof (proof_disagreements in the stats; expected 0)");
  command->add_option("--bounces", o->bounces, "vpl: diffuse hits per light path that leave a VPL (B) [default: 1]")->check(CLI::Range(1, 64));
  command->add_option("--vpl-seed", o->vpl_seed, "vpl: seed of the light paths, apart from --seed so that a reference can share the VPLs [default: 1]");
  command->add_option("--vpl-clamp", o->vpl_clamp,
                      "vpl: clamp each VPL's geometric term cos cos / d^2 to 1 / (C x D)^2, D the scene's diagonal; the energy "
                      "dropped is in the stats (0: no clamp) [default: 0.05]")
      ->check(CLI::Range(0.0, 1.0));
  const std::map<std::string, SelfShadow> self_shadows{
      {"heuristic", SelfShadow::heuristic}, {"exact", SelfShadow::exact}, {"none", SelfShadow::none}};
  command
      ->add_option("--self-shadow", o->self_shadow,
                   "spheres: heuristic skips the own instance's spheres closer than twice their radius (t < 2R); exact traces "
                   "the own instance's mesh instead of its spheres; none uses all its spheres [default: heuristic]")
      ->transform(CLI::CheckedTransformer(self_shadows, CLI::ignore_case));
  command->add_option("--disk-grid-from", o->disk_grid_from,
                      "Occluder disks: sort a shading point's disks into a grid over the directions when it has at least this "
                      "many (0: always) [default: 4096]");
  command->add_flag("--no-disk-clusters", o->no_disk_clusters,
                    "Occluder disks: compare every ball with every connection, instead of first the bound of each cluster of "
                    "an instance's balls (same answers, for timing)");
  command->add_flag("--single-rays", o->single_rays, "vpl: trace the connections of a shading point one ray at a time, not as packets");
  const std::map<std::string, ProbabilityMode> probability_modes{
      {"equal", ProbabilityMode::equal}, {"adaptive", ProbabilityMode::adaptive}, {"learned", ProbabilityMode::learned}};
  command
      ->add_option("--probabilities", o->probabilities,
                   "stochastic: equal; adaptive (for each shading point from K probe rays); learned (control-variate only: "
                   "from the corrections each pixel traced before, no probe rays) [default: equal]")
      ->transform(CLI::CheckedTransformer(probability_modes, CLI::ignore_case));
  const std::map<std::string, StochasticEstimator> estimators{{"eq8", StochasticEstimator::term_choice},
                                                              {"control-variate", StochasticEstimator::control_variate}};
  command
      ->add_option("--estimator", o->estimator,
                   "stochastic: eq8 (the paper: a term drawn with p1, p2, p3, then traced), or control-variate (the proxy "
                   "always traced, its answer corrected by the mesh with a probability its answer chooses; no exact query "
                   "after an outside proxy's miss or an inside proxy's hit) [default: eq8]")
      ->transform(CLI::CheckedTransformer(estimators, CLI::ignore_case));
  command->add_flag("--cost-heuristic", o->cost_heuristic, "stochastic eq8, adaptive: favour the proxy where it agrees with the mesh (eq. 22-24)");
  command->add_option("--probe-passes", o->probe_passes,
                      "adaptive: 0 probes every shading point; P > 0 probes only in each pixel's first P passes and "
                      "keeps the ray types seen per pixel for the later passes [default: 0]")
      ->check(CLI::Range(0, 1 << 24));
  command->add_flag("--no-split", o->no_split, "stochastic: estimate the shading point's own instance too, instead of tracing it exactly");
  command->add_option("--probe-rays", o->probe_rays, "adaptive: probe rays per shading point (K) [default: 16]")->check(CLI::Range(1, 4096));
  command->add_option("--probability-floor", o->probability_floor,
                      "adaptive or learned: least probability of each term the proxy kind needs, which keeps the estimate "
                      "unbiased when the probes or corrections miss a ray type; must be above 0 [default: 0.05]")
      ->check(CLI::Range(0.0, 0.33));
  command->add_option("--correction-scale", o->correction_scale,
                      "control-variate, adaptive or learned: trace the mesh with probability min(1, scale x sqrt(p)) where "
                      "the proxy's answer is wrong with probability p [default: 2; 0.25 with --integrator vpl, whose hundreds "
                      "of connections per shading point share the variance]")
      ->check(CLI::Range(0.01, 1000.0));
  command->add_option("--spp", o->spp, "Camera samples per pixel [default: 16]")->check(CLI::Range(1, 1 << 24));
  command->add_option("--shadow-rays", o->shadow_rays, "Shadow rays per camera sample (M) [default: 1]")->check(CLI::Range(1, 4096));
  command->add_option("--seed", o->seed, "Seed of the image's random streams and of proxy builds [default: 1]");
  command->add_option("--seconds", o->seconds, "Stop after the pass that crosses this wall time (0: render all --spp) [default: 0]")
      ->check(CLI::Range(0.0, 1e7));
  command->add_option("--proxy", o->proxy, "stochastic: use this spec for every instance that names proxies (default: its first)");
  command->add_option("--cache", o->cache, "Proxy cache folder [default: $XDG_CACHE_HOME/visproxy or ~/.cache/visproxy]");
  command->add_option("--exposure", o->exposure, "Scale applied before sRGB encoding of the PNG [default: 1]")->check(CLI::PositiveNumber);
  command->add_option("--width", o->width, "Override the camera's image width")->check(CLI::Range(1, 16384));
  command->add_option("--height", o->height, "Override the camera's image height")->check(CLI::Range(1, 16384));
  command->add_flag("--count", o->count,
                    "Trace shadow rays with visproxy's own traversal of Embree-built BVHs and count traversal steps and "
                    "primitive tests (deterministic cost; slower than Embree's traversal)");
  command->add_flag("--maps", o->maps, "Also write OUT.cost.png (per camera sample: traversal steps + primitive tests with --count, else segment queries; "
                    "white = the most) and, for stochastic, OUT.p1.png (the chance a shadow ray traces the proxy alone: p1 of eq. 8, "
                    "1 - q of the control variate; white = 1); for lightcuts OUT.cut.pfm and OUT.cut.png (mean clusters per cut; "
                    "white = the largest mean)");
  command->add_option("--cut-reference", o->cut_reference,
                      "lightcuts with --maps: a cut map (OUT.cut.pfm) of another run, e.g. without bounds; writes "
                      "OUT.cut-reduction.png, per pixel 1 - this cut / that cut (white = the whole cut saved, black = none "
                      "or larger)");

  command->callback([o, vpls_option, &exit_code] {
    if (o->probabilities == ProbabilityMode::learned && o->estimator != StochasticEstimator::control_variate)
      throw CLI::ValidationError("--probabilities", "learned needs --estimator control-variate");
    if (!is_linear_image_path(o->output))
      throw InvalidInputError(o->output, "unsupported image format (use .pfm or .exr; a PNG is written beside it)");
    const bool terminal = ::isatty(STDERR_FILENO);
    Scene scene = load_scene(o->scene, print_warning);
    if (o->width > 0) scene.camera.width = o->width;
    if (o->height > 0) scene.camera.height = o->height;
    SceneProxyOptions proxy_options{.cache = o->cache.empty() ? default_proxy_cache() : o->cache,
                                    .stochastic_spec = std::nullopt,
                                    .seed = o->seed,
                                    .on_proxy = nullptr};
    if (!o->proxy.empty()) proxy_options.stochastic_spec = o->proxy;
    proxy_options.on_proxy = [&](std::string_view mesh, std::string_view spec, bool cached) {
      if (!cached) std::cerr << "visproxy render: building " << spec << " of " << mesh << " (cached in "
                             << proxy_options.cache.string() << ")\n";
    };
    proxy_options.on_verify = [](std::string_view mesh, std::string_view spec, bool holds, std::string_view counterexample) {
      std::cerr << "visproxy render: verified " << spec << " of " << mesh << ": "
                << (holds ? std::string("holds") : "does not hold (" + std::string(counterexample) + "): used as a general proxy")
                << "\n";
    };
    const bool cluster_bounds = o->integrator == IntegratorKind::lightcuts && o->visibility_bounds != VisibilityBounds::none;
    if (!o->cut_reference.empty() && (o->integrator != IntegratorKind::lightcuts || !o->maps))
      throw CLI::ValidationError("--cut-reference", "needs --integrator lightcuts and --maps");
    // Read before rendering, so that a bad reference fails at once.
    std::optional<Image> cut_reference;
    if (!o->cut_reference.empty()) cut_reference = read_linear_image(o->cut_reference);
    const std::vector<MeshProxies> proxies = o->visibility == VisibilityMode::exact && !cluster_bounds
                                                 ? std::vector<MeshProxies>(scene.instances.size())
                                                 : prepare_scene_proxies(scene, proxy_options);
    const RenderWorld world(scene, proxies, {.counting = o->count, .ray_masks = true, .keep_solids = cluster_bounds});
    if (cut_reference && (cut_reference->width != scene.camera.width || cut_reference->height != scene.camera.height))
      throw InvalidInputError(o->cut_reference, "the cut map is " + std::to_string(cut_reference->width) + "x" +
                                                    std::to_string(cut_reference->height) + ", the image " +
                                                    std::to_string(scene.camera.width) + "x" + std::to_string(scene.camera.height));
    for (const std::string& note : world.notes()) std::cerr << "visproxy render: note: " << note << "\n";
    if (o->correction_scale == 0) o->correction_scale = o->integrator == IntegratorKind::vpl ? 0.25 : 2.0;
    RenderOptions options{.integrator = o->integrator,
                          .visibility = o->visibility,
                          .probabilities = o->probabilities,
                          .estimator = o->estimator,
                          .cost_heuristic = o->cost_heuristic,
                          .probe_rays = o->probe_rays,
                          .probe_passes = o->probe_passes,
                          .probability_floor = o->probability_floor,
                          .correction_scale = o->correction_scale,
                          .split = !o->no_split,
                          .spp = o->spp,
                          .shadow_rays = o->shadow_rays,
                          .seed = o->seed,
                          .vpls = o->vpls,
                          .bounces = o->bounces,
                          .vpl_seed = o->vpl_seed,
                          .vpl_clamp = o->vpl_clamp,
                          .light_points = o->light_points,
                          .lightcut_vpls = vpls_option->count() > 0,
                          .lightcut = {.error = o->error, .max_cut = o->max_cut, .bounds = o->visibility_bounds, .check_proofs = o->check_proofs},
                          .virtual_point_lights = nullptr,
                          .group_connections = !o->single_rays,
                          .self_shadow = o->self_shadow,
                          .disk_grid_from = o->disk_grid_from,
                          .disk_clusters = !o->no_disk_clusters,
                          .seconds = o->seconds,
                          .on_pass = nullptr};
    if (terminal)
      options.on_pass = [&](int passes, double seconds) {
        const double fraction = o->seconds > 0 ? std::min(1.0, seconds / o->seconds) : double(passes) / o->spp;
        const int filled = static_cast<int>(40 * fraction);
        std::fprintf(stderr, "\rvisproxy render: [%s%s] %3.0f%% %d spp %.1f s", std::string(static_cast<std::size_t>(filled), '#').c_str(),
                     std::string(static_cast<std::size_t>(40 - filled), '.').c_str(), 100 * fraction, passes, seconds);
      };
    const RenderResult result = render(scene, world, options);
    if (terminal) std::fprintf(stderr, "\n");

    if (o->output.has_parent_path()) {
      std::error_code error;
      std::filesystem::create_directories(o->output.parent_path(), error);
      if (error) throw IOError(o->output.parent_path(), "cannot create the output folder: " + error.message());
    }
    write_linear_image(o->output, result.image);
    const std::filesystem::path png = beside(o->output, ".png"), stats = beside(o->output, ".stats.json");
    write_png(png, result.image, o->exposure);
    if (o->maps) {
      double most = 0;
      for (const Color& c : result.cost_map.pixels) most = std::max(most, c.x());
      write_png(beside(o->output, ".cost.png"), result.cost_map, most > 0 ? 1.0 / most : 1.0);
      if (!result.p1_map.pixels.empty()) write_png(beside(o->output, ".p1.png"), result.p1_map, 1.0);
      if (!result.cut_map.pixels.empty()) {
        double largest = 0;
        for (const Color& c : result.cut_map.pixels) largest = std::max(largest, c.x());
        write_linear_image(beside(o->output, ".cut.pfm"), result.cut_map);
        write_png(beside(o->output, ".cut.png"), result.cut_map, largest > 0 ? 1.0 / largest : 1.0);
        if (cut_reference) {
          Image reduction(scene.camera.width, scene.camera.height);
          for (std::size_t i = 0; i < reduction.pixels.size(); ++i) {
            const double before = cut_reference->pixels[i].x(), now = result.cut_map.pixels[i].x();
            reduction.pixels[i] = Color::Constant(before > 0 ? std::clamp(1 - now / before, 0.0, 1.0) : 0.0);
          }
          write_png(beside(o->output, ".cut-reduction.png"), reduction, 1.0);
        }
      }
    }
    nlohmann::json instances = nlohmann::json::array();
    for (std::size_t i = 0; i < scene.instances.size(); ++i)
      instances.push_back({{"mesh", scene.instances[i].mesh},
                           {"stochastic_proxy", proxies[i].stochastic ? nlohmann::json(proxies[i].stochastic->spec) : nlohmann::json(nullptr)},
                           {"outside_proxy", proxies[i].outside ? nlohmann::json(proxies[i].outside->spec) : nlohmann::json(nullptr)},
                           {"inside_proxy", proxies[i].inside ? nlohmann::json(proxies[i].inside->spec) : nlohmann::json(nullptr)},
                           {"stochastic_proxy_proved", proxies[i].stochastic && proxies[i].stochastic->proved}});
    const nlohmann::json document = {
        {"scene", o->scene.string()},
        {"image", o->output.string()},
        {"width", scene.camera.width},
        {"height", scene.camera.height},
        {"integrator", integrator_name(o->integrator)},
        {"visibility", visibility_mode_name(o->visibility)},
        {"self_shadow", self_shadow_name(o->self_shadow)},
        {"probabilities", probability_mode_name(o->probabilities)},
        {"estimator", stochastic_estimator_name(o->estimator)},
        {"cost_heuristic", o->cost_heuristic},
        {"probe_passes", o->probe_passes},
        {"split", !o->no_split},
        {"probe_rays", o->probe_rays},
        {"probability_floor", o->probability_floor},
        {"correction_scale", o->correction_scale},
        {"spp_requested", o->spp},
        {"shadow_rays_per_sample", o->shadow_rays},
        {"seed", o->seed},
        {"seconds_budget", o->seconds},
        {"visibility_bounds", o->integrator == IntegratorKind::lightcuts ? nlohmann::json(visibility_bounds_name(o->visibility_bounds)) : nlohmann::json(nullptr)},
        {"instances", instances},
        {"proxy_notes", world.notes()},
        {"stats", result.stats.to_json()}};
    write_file_atomically(stats, document.dump(2) + "\n");
    const double segments = static_cast<double>(std::max<std::uint64_t>(result.stats.shadow_rays + result.stats.vpl_connections, 1));
    std::string vpl_text;
    if (o->integrator == IntegratorKind::lightcuts) {
      const nlohmann::json& lc = result.stats.integrator;
      char text[400];
      std::snprintf(text, sizeof text,
                    ", %llu point lights, error %.3g, max cut %d, bounds %s: mean cut %.1f clusters, %.1f shadow rays per "
                    "shading point, clusters proved unoccluded %llu and occluded %llu",
                    static_cast<unsigned long long>(lc.value("point_lights", 0ull)), o->error, o->max_cut,
                    std::string(visibility_bounds_name(o->visibility_bounds)).c_str(), lc.value("cut_size_mean", 0.0),
                    lc.value("shadow_rays_per_shading_point", 0.0), static_cast<unsigned long long>(lc.value("clusters_proved_unoccluded", 0ull)),
                    static_cast<unsigned long long>(lc.value("clusters_proved_occluded", 0ull)));
      vpl_text = text;
      if (o->check_proofs) vpl_text += ", proofs checked: " + std::to_string(lc.value("proof_disagreements", 0ull)) + " disagreed";
    }
    if (o->integrator == IntegratorKind::vpl) {
      char text[200];
      std::snprintf(text, sizeof text, ", %llu VPLs (%llu connections; clamping dropped %.3f %% of their energy)",
                    static_cast<unsigned long long>(result.stats.integrator.value("virtual_point_lights", 0ull)),
                    static_cast<unsigned long long>(result.stats.vpl_connections),
                    100 * result.stats.integrator.value("clamped_energy_fraction", 0.0));
      vpl_text = text;
    }
    std::printf("visproxy render: %s, %dx%d, %s integrator, %s visibility, %d spp x %d shadow rays, seed %llu: %.2f s, %llu shadow rays "
                "(%.2f exact and %.2f proxy tests per %s)%s\n  %s\n  %s\n  %s\n",
                o->scene.string().c_str(), scene.camera.width, scene.camera.height,
                std::string(integrator_name(o->integrator)).c_str(),
                std::string(visibility_mode_name(o->visibility)).c_str(), result.stats.passes, o->shadow_rays,
                static_cast<unsigned long long>(o->seed), result.stats.seconds,
                static_cast<unsigned long long>(result.stats.shadow_rays),
                static_cast<double>(result.stats.exact_tests) / segments, static_cast<double>(result.stats.proxy_tests) / segments,
                o->integrator == IntegratorKind::vpl ? "segment: shadow ray or VPL connection" : "shadow ray", vpl_text.c_str(),
                o->output.string().c_str(),
                png.string().c_str(), stats.string().c_str());
    exit_code = all_finite(result.image) ? kSuccess : kInternalError;
    if (exit_code != kSuccess) std::cerr << "visproxy render: the image holds NaN or infinite values\n";
  });
}

}  // namespace visproxy::cli
