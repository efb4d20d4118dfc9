// visproxy compare SCENE [-o DIR] [--seconds T] [--reference REF.pfm|REF.exr] ...

#include <unistd.h>

#include <algorithm>
#include <array>
#include <map>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "commands.h"
#include "visproxy/core/errors.h"
#include "visproxy/core/files.h"
#include "visproxy/core/json_input.h"
#include "visproxy/evaluate/plot.h"
#include "visproxy/measure/proxy_measurement.h"
#include "visproxy/render/scene_proxies.h"
#include "visproxy/render/renderer.h"

namespace visproxy::cli {
namespace {

struct CompareOptions {
  std::filesystem::path scene, folder, reference, cache;
  std::vector<std::string> proxies;
  double seconds = 10;
  int reference_spp = 4096;
  int shadow_rays = 1;
  std::uint64_t seed = 1;
  int width = 0, height = 0;
  int convergence_points = 4;
  int rounds = 8;
  std::string equal = "time";
  std::vector<std::string> only_modes;  // --mode: the modes' names without their proxy spec; empty: all
  IntegratorKind integrator = IntegratorKind::direct;
  int vpls = 1024, bounces = 1;
  std::uint64_t vpl_seed = 1;
  int count_passes = 4;
  bool no_count = false;
};

struct Mode {
  std::string name;
  std::string proxy;  ///< the stochastic proxy spec; empty for exact and bounds
  RenderOptions options;
};

// The stochastic proxy specs to compare: --proxy, else every spec the instances name, in
// the order they first appear.
std::vector<std::string> stochastic_specs(const Scene& scene, const CompareOptions& o) {
  if (!o.proxies.empty()) return o.proxies;
  std::vector<std::string> specs;
  for (const SceneInstance& instance : scene.instances)
    for (const std::string& spec : instance.proxies)
      if (std::find(specs.begin(), specs.end(), spec) == specs.end()) specs.push_back(spec);
  return specs;
}

std::vector<Mode> modes(const std::vector<std::string>& specs, const CompareOptions& o) {
  auto base = [&](VisibilityMode v) {
    RenderOptions r;
    r.visibility = v;
    r.spp = 1 << 24;
    r.shadow_rays = o.shadow_rays;
    r.seed = o.seed;
    r.integrator = o.integrator;
    r.vpls = o.vpls;
    r.bounces = o.bounces;
    r.vpl_seed = o.vpl_seed;
    // As visproxy render: with VPLs, hundreds of connections per shading point share the
    // variance, and fewer corrections pay.
    if (o.integrator == IntegratorKind::vpl) r.correction_scale = 0.25;
    return r;
  };
  std::vector<Mode> out{{"exact", "", base(VisibilityMode::exact)}, {"bounds", "", base(VisibilityMode::bounds)}};
  for (const std::string& spec : specs) {
    RenderOptions equal = base(VisibilityMode::stochastic);
    out.push_back({spec + " eq8 equal", spec, equal});
    RenderOptions adaptive = equal;
    adaptive.probabilities = ProbabilityMode::adaptive;
    out.push_back({spec + " eq8 adaptive", spec, adaptive});
    adaptive.cost_heuristic = true;
    out.push_back({spec + " eq8 adaptive + cost heuristic", spec, adaptive});
    RenderOptions optimal = equal;
    optimal.probabilities = ProbabilityMode::optimal;
    out.push_back({spec + " eq8 optimal", spec, optimal});
    RenderOptions control = equal;
    control.estimator = StochasticEstimator::control_variate;
    out.push_back({spec + " control variate equal", spec, control});
    control.probabilities = ProbabilityMode::learned;
    out.push_back({spec + " control variate learned", spec, control});
    // Sphere sets with VPLs: the occluder disks themselves (biased by design).
    if (o.integrator == IntegratorKind::vpl && spec.starts_with("spheres:"))
      out.push_back({spec + " occluder disks", spec, base(VisibilityMode::spheres)});
  }
  if (o.only_modes.empty()) return out;
  // --mode: exact (every ratio's reference) and the modes named, by their name without the spec.
  std::vector<Mode> kept;
  for (Mode& mode : out) {
    const std::string bare = mode.proxy.empty() ? mode.name : mode.name.substr(mode.proxy.size() + 1);
    if (mode.name == "exact" || std::find(o.only_modes.begin(), o.only_modes.end(), bare) != o.only_modes.end())
      kept.push_back(std::move(mode));
  }
  return kept;
}

// The names --mode accepts.
const std::vector<std::string>& mode_names() {
  static const std::vector<std::string> names = {"exact",
                                                 "bounds",
                                                 "eq8 equal",
                                                 "eq8 adaptive",
                                                 "eq8 adaptive + cost heuristic",
                                                 "eq8 optimal",
                                                 "control variate equal",
                                                 "control variate learned",
                                                 "occluder disks"};
  return names;
}

std::string format_number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", value);
  return buffer;
}

std::string file_stem(const std::string& name) {
  std::string stem;
  for (char c : name) {
    const bool keep = std::isalnum(static_cast<unsigned char>(c)) != 0;
    if (keep || (!stem.empty() && stem.back() != '-')) stem += keep ? c : '-';
  }
  while (!stem.empty() && stem.back() == '-') stem.pop_back();
  return stem;
}

// One line redrawn in place on a terminal: the mode, its budget and how far it got.
void draw_progress(const std::string& label, double fraction, int passes, double seconds) {
  const int filled = static_cast<int>(30 * std::clamp(fraction, 0.0, 1.0));
  std::fprintf(stderr, "\r\033[Kvisproxy compare: %s [%s%s] %3.0f%% %d spp %.1f s", label.c_str(),
               std::string(static_cast<std::size_t>(filled), '#').c_str(), std::string(static_cast<std::size_t>(30 - filled), '.').c_str(),
               100 * std::clamp(fraction, 0.0, 1.0), passes, seconds);
}

// Per pixel root of the squared error (mean over channels), white at `white`.
void write_error_png(const std::filesystem::path& path, const Image& image, const Image& reference, double white) {
  Image map = squared_error_map(image, reference);
  for (Color& c : map.pixels) c = c.cwiseSqrt();
  write_png(path, map, white > 0 ? 1.0 / white : 1.0);
}

}  // namespace

void add_compare_command(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<CompareOptions>();
  CLI::App* command = app.add_subcommand(
      "compare",
      "Render a scene with every visibility mode at equal time against a high-sample exact reference and write the "
      "comparison (Billen et al. Tables 5/6, Figure 8): DIR/table.md and table.csv (time, samples and shadow rays per "
      "pixel, exact and proxy tests, traversal steps and primitive tests per pixel, MSE, efficiency 1/(MSE x time) and "
      "its ratio to exact), DIR/convergence.csv and .svg (MSE against time), and every image with its error map.");
  command->add_option("scene", o->scene, "Scene file: JSON, or a glTF 2.0 .gltf/.glb (as for render)")->required();
  command->add_option("-o,--output", o->folder, "Output folder [default: compare-SCENENAME]");
  command->add_option("--proxy", o->proxies,
                      "Stochastic proxy spec to compare (repeatable) [default: every spec the scene's instances name]");
  command->add_option("--seconds", o->seconds, "Time per mode for the table, over all rounds [default: 10]")->check(CLI::Range(0.01, 1e6));
  command->add_option("--reference", o->reference,
                      "Reference image (.pfm or .exr); rendered exactly with --reference-spp when absent");
  command->add_option("--reference-spp", o->reference_spp, "Samples per pixel of the rendered reference [default: 4096]")
      ->check(CLI::Range(1, 1 << 20));
  command->add_option("--shadow-rays", o->shadow_rays, "Shadow rays per camera sample in every mode [default: 1]")->check(CLI::Range(1, 4096));
  command->add_option("--seed", o->seed, "Seed of the renders (the reference's two halves use seed + 1000003 and seed + 2000003) [default: 1]");
  command->add_option("--rounds", o->rounds,
                      "Turns the modes take: each renders --seconds / rounds per round, forwards and backwards in turn, "
                      "so that the machine's drifting speed slows every mode alike [default: 8]")
      ->check(CLI::Range(1, 1 << 16));
  command->add_option("--mode", o->only_modes,
                      "Render only this mode (repeatable; exact is always rendered): exact, bounds, 'eq8 equal', 'eq8 "
                      "adaptive', 'eq8 adaptive + cost heuristic', 'eq8 optimal', 'control variate equal', 'control variate "
                      "learned', 'occluder disks' (each stochastic one for every --proxy) [default: every mode]")
      ->check(CLI::IsMember(mode_names()));
  command->add_option("--equal", o->equal,
                      "time: every turn lasts --seconds / rounds; samples: every mode renders in each turn the passes "
                      "exact rendered in its first turn, and a mode's time is its set-up plus exact's render time x the "
                      "median over the rounds of its turn's time over exact's (common samples make the MSE ratios "
                      "precise, and the median leaves out the machine's pauses) [default: time]")
      ->check(CLI::IsMember({"time", "samples"}));
  command->add_option("--convergence-points", o->convergence_points,
                      "Points per mode of the MSE-against-time curve, read from the same renders at the end of rounds "
                      "K, K/2, K/4, ... (K: --rounds) [default: 4]")
      ->check(CLI::Range(1, 12));
  command->add_option("--count-passes", o->count_passes,
                      "Passes of each mode re-rendered with visproxy's own BVH traversal (same seed) to count traversal "
                      "steps and primitive tests; the table scales them to the passes the mode reached (modes with learned "
                      "probabilities are counted in full) [default: 4]")
      ->check(CLI::Range(1, 1 << 20));
  command->add_flag("--no-count", o->no_count, "Skip the counted re-renders (traversal steps and primitive tests: nan)");
  command->add_option("--cache", o->cache, "Proxy cache folder [default: as for render]");
  as_choice<IntegratorKind>(
      command->add_option("--integrator", o->integrator,
                          "direct, or vpl (virtual point lights; adds occluder-disk modes for sphere sets) [default: direct]"),
      {IntegratorKind::direct, IntegratorKind::vpl});
  command->add_option("--vpls", o->vpls, "vpl: light paths [default: 1024]")->check(CLI::Range(1, 1 << 22));
  command->add_option("--bounces", o->bounces, "vpl: VPLs per light path [default: 1]")->check(CLI::Range(1, 64));
  command->add_option("--vpl-seed", o->vpl_seed, "vpl: seed of the light paths, shared by the reference and every mode [default: 1]");
  command->add_option("--width", o->width, "Override the camera's image width")->check(CLI::Range(1, 16384));
  command->add_option("--height", o->height, "Override the camera's image height")->check(CLI::Range(1, 16384));

  command->callback([o, &exit_code] {
    if (!o->reference.empty() && !is_linear_image_path(o->reference))
      throw InvalidInputError(o->reference, "unsupported image format (use .pfm or .exr)");
    Scene scene = load_scene(o->scene, print_warning);
    if (o->width > 0) scene.camera.width = o->width;
    if (o->height > 0) scene.camera.height = o->height;
    const std::filesystem::path folder = o->folder.empty() ? std::filesystem::path("compare-" + o->scene.stem().string()) : o->folder;
    Image reference;
    // The reference's own noise: its variance per pixel and channel, which adds to every
    // mode's MSE against it (the two are independent). Known when compare rendered it (from
    // its two halves) or when a reference it wrote is given back with its REF.noise.json.
    std::optional<double> reference_noise;
    if (!o->reference.empty()) {
      reference = read_linear_image(o->reference);
      const std::filesystem::path noise_path = std::filesystem::path(o->reference).replace_extension(".noise.json");
      if (std::filesystem::exists(noise_path)) {
        const JsonInput input(noise_path);
        const nlohmann::json noise = input.parse(read_file(noise_path));
        const double value = input.number(input.member(input.object(noise, ""), "noise_per_pixel", ""), "noise_per_pixel");
        if (value < 0) input.fail("noise_per_pixel", "must not be negative");
        reference_noise = value;
      }
      if (reference.width != scene.camera.width || reference.height != scene.camera.height)
        throw InvalidInputError(o->reference, "is " + std::to_string(reference.width) + "x" + std::to_string(reference.height) +
                                                  "; the scene renders " + std::to_string(scene.camera.width) + "x" +
                                                  std::to_string(scene.camera.height));
    }
    std::error_code error;
    std::filesystem::create_directories(folder, error);
    if (error) throw IOError(folder, "cannot create the output folder: " + error.message());
    const bool terminal = ::isatty(STDERR_FILENO);

    SceneProxyOptions proxy_options{.cache = o->cache.empty() ? default_proxy_cache() : o->cache,
                                    .stochastic_spec = std::nullopt,
                                    .seed = o->seed,
                                    .on_proxy = [](std::string_view mesh, std::string_view spec, bool cached) {
                                      if (!cached) std::cerr << "visproxy compare: building " << spec << " of " << mesh << "\n";
                                    },
                                    .on_verify = [](std::string_view mesh, std::string_view spec, bool holds, std::string_view counterexample) {
                                      std::cerr << "visproxy compare: verified " << spec << " of " << mesh << ": "
                                                << (holds ? std::string("holds") : "does not hold (" + std::string(counterexample) + "): used as a general proxy")
                                                << "\n";
                                    }};
    const std::vector<std::string> specs = stochastic_specs(scene, *o);
    const std::vector<Mode> all_modes = modes(specs, *o);

    // One world per stochastic proxy spec (exact and bounds use the scene's first), all kept
    // while the modes take turns; with its counting twin unless --no-count.
    struct Worlds {
      std::unique_ptr<RenderWorld> world, counting;
    };
    std::map<std::string, Worlds> worlds;
    auto worlds_of = [&](const std::string& spec) -> const Worlds& {
      if (const auto found = worlds.find(spec); found != worlds.end()) return found->second;
      proxy_options.stochastic_spec = spec.empty() ? std::nullopt : std::optional<std::string>(spec);
      const std::vector<MeshProxies> proxies = prepare_scene_proxies(scene, proxy_options);
      Worlds w;
      w.world = std::make_unique<RenderWorld>(scene, proxies);
      for (const std::string& note : w.world->notes()) std::cerr << "visproxy compare: note: " << note << "\n";
      if (!o->no_count) w.counting = std::make_unique<RenderWorld>(scene, proxies, RenderWorldOptions{.counting = true});
      return worlds.emplace(spec, std::move(w)).first->second;
    };
    const RenderWorld* world = worlds_of("").world.get();

    std::string reference_note;
    if (!o->reference.empty()) {
      reference_note = "reference " + o->reference.string();
    } else {
      RenderOptions r;
      r.spp = o->reference_spp;
      r.shadow_rays = o->shadow_rays;
      r.seed = o->seed + 1000003;
      // The same VPLs as every mode, so that their clamping cancels out of the errors.
      r.integrator = o->integrator;
      r.vpls = o->vpls;
      r.bounces = o->bounces;
      r.vpl_seed = o->vpl_seed;
      const std::string label = "exact reference, " + std::to_string(o->reference_spp) + " spp";
      if (terminal) r.on_pass = [&](int passes, double seconds) { draw_progress(label, double(passes) / r.spp, passes, seconds); };
      else std::cerr << "visproxy compare: rendering the " << label << "\n";
      // In two halves of independent samples: their difference shows the reference's noise
      // (a reference of 1 spp has no halves, and its noise stays unknown).
      const int first_half = o->reference_spp > 1 ? o->reference_spp / 2 : 1, second_half = o->reference_spp - first_half;
      r.spp = first_half;
      const RenderResult a = render(scene, *world, r);
      std::optional<RenderResult> b;
      if (second_half > 0) {
        r.spp = second_half;
        r.seed = o->seed + 2000003;
        b = render(scene, *world, r);
      }
      if (terminal) std::fprintf(stderr, "\n");
      const double total = o->reference_spp;
      reference = a.image;
      if (b) {
        for (std::size_t i = 0; i < reference.pixels.size(); ++i)
          reference.pixels[i] = (first_half * a.image.pixels[i] + second_half * b->image.pixels[i]) / total;
        // Var(half) = per-sample variance / half's spp; E[MSE(a, b)] = Var(a) + Var(b), and
        // the reference's variance is per-sample variance / total spp.
        reference_noise = mean_squared_error(a.image, b->image) / (1.0 / first_half + 1.0 / second_half) / total;
      }
      write_pfm(folder / "reference.pfm", reference);
      write_png(folder / "reference.png", reference);
      if (reference_noise)
        write_file_atomically(folder / "reference.noise.json",
                            nlohmann::json{{"description", "the reference's noise: its variance per pixel and channel, from the "
                                                           "difference of its two halves; compare subtracts it from every MSE"},
                                           {"spp", o->reference_spp},
                                           {"noise_per_pixel", *reference_noise}}
                                    .dump(2) + "\n");
      reference_note = "reference rendered exactly with " + std::to_string(o->reference_spp) + " spp x " +
                       std::to_string(o->shadow_rays) + " shadow rays (seeds " + std::to_string(o->seed + 1000003) +
                       (b ? " and " + std::to_string(o->seed + 2000003) : std::string()) + ", " +
                       format_number(a.stats.seconds + (b ? b->stats.seconds : 0.0)) + " s)";
    }

    reference_note += reference_noise ? "; its own noise, " + format_number(*reference_noise) + " per pixel, is subtracted from every MSE"
                                      : "; its own noise is not known (no REF.noise.json beside it, or 1 spp) and is left in every MSE";
    const double pixels = static_cast<double>(scene.camera.width) * scene.camera.height;
    std::string md = "# visproxy compare: " + o->scene.string() + "\n\n" + std::to_string(scene.camera.width) + "x" +
                     std::to_string(scene.camera.height) + " pixels, " + std::to_string(o->shadow_rays) +
                     " shadow ray(s) per camera sample, seed " + std::to_string(o->seed) + ", equal time " +
                     format_number(o->seconds) + " s per mode in " + std::to_string(o->rounds) + " rounds" +
                     (o->equal == "samples" ? std::string(", equal samples per round") : std::string()) + "; " + reference_note + ".\n\n";
    md += "| mode | time (s) | samples per pixel | shadow rays per pixel | exact tests per pixel | proxy tests per pixel | "
          "traversal steps per pixel | primitive tests per pixel | pass time / exact's, median (range) over rounds | MSE | "
          "efficiency 1/(MSE x s) | efficiency / exact |\n";
    md += "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n";
    std::string csv = "mode,proxy,seconds,samples_per_pixel,shadow_rays_per_pixel,exact_tests_per_pixel,proxy_tests_per_pixel,"
                      "traversal_steps_per_pixel,primitive_tests_per_pixel,pass_time_over_exact,pass_time_over_exact_low,"
                      "pass_time_over_exact_high,mse,efficiency,efficiency_over_exact\n";
    std::string convergence = "mode,seconds_budget,seconds,samples_per_pixel,mse\n";
    double exact_efficiency = 0, error_white = 0;
    // The modes take turns: --rounds rounds of --seconds / rounds each, in turn forwards and
    // backwards, so that a machine whose speed drifts during the comparison slows every mode
    // alike. Each mode is one render continued from round to round (RenderSession), timed
    // over its own runs; the MSE-against-time curve reads it at the end of rounds K, K/2, ...
    const int rounds = o->rounds;
    std::vector<int> checkpoints;
    for (int k = 0; k < o->convergence_points; ++k)
      if (const int r = std::max(1, rounds >> k); std::find(checkpoints.begin(), checkpoints.end(), r) == checkpoints.end())
        checkpoints.push_back(r);
    std::vector<RenderSession> sessions;
    sessions.reserve(all_modes.size());
    std::vector<double> setup_seconds;
    for (const Mode& mode : all_modes) {
      sessions.emplace_back(scene, *worlds_of(mode.proxy).world, mode.options);
      setup_seconds.push_back(sessions.back().seconds());
    }
    // Per mode and round: the turn's seconds and passes.
    std::vector<std::vector<double>> turn_seconds(all_modes.size());
    std::vector<std::vector<int>> turn_passes(all_modes.size());
    const bool equal_samples = o->equal == "samples";
    int passes_per_turn = 0;  // equal samples: exact's passes in its first turn (the first turn of all)
    std::vector<PlotSeries> curves;
    std::vector<std::string> convergence_rows(all_modes.size());
    for (const Mode& mode : all_modes) curves.push_back({mode.name, {}, {}});
    for (int round = 1; round <= rounds; ++round) {
      if (!terminal) std::cerr << "visproxy compare: round " << round << " of " << rounds << "\n";
      for (std::size_t k = 0; k < all_modes.size(); ++k) {
        const std::size_t m = round % 2 == 1 ? k : all_modes.size() - 1 - k;
        const std::string label = "round " + std::to_string(round) + "/" + std::to_string(rounds) + " mode " + std::to_string(m + 1) +
                                  "/" + std::to_string(all_modes.size()) + " " + all_modes[m].name;
        RenderSession& session = sessions[m];
        const double before = session.seconds(), budget = o->seconds / rounds;
        const int passes_before = session.passes();
        if (equal_samples && passes_per_turn > 0) session.run(passes_per_turn);
        else session.run(1 << 24, budget);
        if (equal_samples && passes_per_turn == 0) passes_per_turn = session.passes() - passes_before;
        turn_seconds[m].push_back(session.seconds() - before);
        turn_passes[m].push_back(session.passes() - passes_before);
        if (terminal) {
          draw_progress(label, (session.seconds() - before) / budget, session.passes() - passes_before, session.seconds());
          std::fprintf(stderr, "\n");
        }
        if (std::find(checkpoints.begin(), checkpoints.end(), round) == checkpoints.end()) continue;
        const RenderResult result = session.result();
        const double mse = mean_squared_error(result.image, reference);
        char line[512];
        std::snprintf(line, sizeof line, "%s,%.6g,%.6g,%d,%.10g\n", all_modes[m].name.c_str(), o->seconds * round / rounds,
                      result.stats.seconds, result.stats.passes, mse);
        convergence_rows[m] += line;
        curves[m].x.push_back(result.stats.seconds);
        curves[m].y.push_back(mse);
      }
    }
    for (const std::string& rows : convergence_rows) convergence += rows;
    // Per mode: a pass's time over exact's in the same round, median and range over the rounds.
    std::vector<std::array<double, 3>> pass_time_ratio;
    for (std::size_t m = 0; m < all_modes.size(); ++m) {
      std::vector<double> ratios;
      for (std::size_t r = 0; r < turn_seconds[m].size(); ++r)
        if (turn_passes[m][r] > 0 && turn_passes[0][r] > 0 && turn_seconds[0][r] > 0)
          ratios.push_back(turn_seconds[m][r] / turn_passes[m][r] / (turn_seconds[0][r] / turn_passes[0][r]));
      if (ratios.empty()) {
        pass_time_ratio.push_back({std::nan(""), std::nan(""), std::nan("")});
        continue;
      }
      const auto [least, most] = std::minmax_element(ratios.begin(), ratios.end());
      pass_time_ratio.push_back({median(ratios), *least, *most});
    }
    double exact_turns = 0;
    for (const double t : turn_seconds[0]) exact_turns += t;
    for (std::size_t m = 0; m < all_modes.size(); ++m) {
      const Mode& mode = all_modes[m];
      const RenderResult result = sessions[m].result();
      const double mse = mean_squared_error(result.image, reference);
      char line[512];
      const RenderStats& s = result.stats;
      // Equal samples: the mode's set-up, then exact's render time scaled by the median
      // round's ratio (every turn renders the same passes).
      const double mode_seconds =
          equal_samples ? setup_seconds[m] + exact_turns * (m == 0 ? 1.0 : pass_time_ratio[m][0]) : s.seconds;
      if (m == 0) error_white = 4 * std::sqrt(mse);  // error maps: white at 4x exact's RMS error
      write_pfm(folder / (file_stem(mode.name) + ".pfm"), result.image);
      write_png(folder / (file_stem(mode.name) + ".png"), result.image);
      write_error_png(folder / (file_stem(mode.name) + ".error.png"), result.image, reference, error_white);
      // The mode's own error: the MSE less the reference's noise. When that noise is most
      // of the MSE, the reference cannot measure the mode, and efficiency is not given.
      const double own_mse = mse - reference_noise.value_or(0.0);
      if (reference_noise && own_mse < mse / 4)
        std::cerr << "visproxy compare: warning: the reference's noise is " << format_number(*reference_noise / mse * 100)
                  << " % of " << mode.name << "'s MSE: render the reference with more --reference-spp\n";
      const double efficiency = own_mse > 0 && own_mse >= mse / 4 ? 1.0 / (own_mse * mode_seconds) : std::nan("");
      if (m == 0) exact_efficiency = efficiency;
      // The first passes again through the counting traversal: deterministic work figures,
      // scaled to the passes reached (every pass draws the same distribution of samples).
      double steps = std::nan(""), primitives = std::nan("");
      if (const RenderWorld* counting = worlds_of(mode.proxy).counting.get()) {
        RenderOptions counted = mode.options;
        // Learned probabilities change from pass to pass: those modes are counted in full.
        const bool stationary = mode.options.probabilities != ProbabilityMode::learned && mode.options.probe_passes == 0;
        counted.spp = stationary ? std::min(s.passes, o->count_passes) : s.passes;
        counted.seconds = 0;
        const std::string count_label = "mode " + std::to_string(m + 1) + "/" + std::to_string(all_modes.size()) + " " + mode.name +
                                        ", counting " + std::to_string(counted.spp) + " spp";
        if (terminal) counted.on_pass = [&](int passes, double seconds) { draw_progress(count_label, double(passes) / counted.spp, passes, seconds); };
        const RenderResult c = render(scene, *counting, counted);
        if (terminal) std::fprintf(stderr, "\n");
        const double scale = static_cast<double>(s.passes) / counted.spp / pixels;
        steps = static_cast<double>(c.stats.traversal_steps) * scale;
        primitives = static_cast<double>(c.stats.primitive_tests) * scale;
      }
      const double relative = exact_efficiency > 0 ? efficiency / exact_efficiency : std::nan("");
      // Probe rays trace both the mesh and the proxy.
      const double exact_tests = static_cast<double>(s.exact_tests + s.probe_rays) / pixels;
      const double proxy_tests = static_cast<double>(s.proxy_tests + s.probe_rays) / pixels;
      const std::array<double, 3>& ratio = pass_time_ratio[m];
      std::snprintf(line, sizeof line, "| %s | %.2f | %d | %.1f | %.1f | %.1f | %.0f | %.0f | %.3f (%.3f-%.3f) | %.4g | %.4g | %.2f |\n",
                    mode.name.c_str(), mode_seconds, s.passes, static_cast<double>(s.shadow_rays) / pixels, exact_tests, proxy_tests,
                    steps, primitives, ratio[0], ratio[1], ratio[2], mse, efficiency, relative);
      md += line;
      std::snprintf(line, sizeof line, "\"%s\",%s,%.6g,%d,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.10g,%.10g,%.6g\n",
                    mode.name.c_str(), mode.proxy.c_str(), mode_seconds, s.passes, static_cast<double>(s.shadow_rays) / pixels,
                    exact_tests, proxy_tests, steps, primitives, ratio[0], ratio[1], ratio[2], mse, efficiency, relative);
      csv += line;
    }
    md += equal_samples
              ? "\nTime: the modes took " + std::to_string(rounds) + " turns, forwards and backwards in turn, each of the " +
                    std::to_string(passes_per_turn) + " passes exact rendered in its first turn of " + format_number(o->seconds / rounds) +
                    " s; a mode's time is its set-up plus exact's render time times the median over the rounds of its turn's time "
                    "over exact's. Pass time / exact's: a pass's time over exact's in the same round. "
              : "\nTime: each mode's own render time (its set-up and its turns), the modes having taken " + std::to_string(rounds) +
                    " turns of " + format_number(o->seconds / rounds) + " s each, forwards and backwards in turn. Pass time / "
                    "exact's: a pass's time over exact's in the same round. ";
    md += "MSE: mean over pixels and RGB channels of the squared difference to the reference (linear radiance); "
          "efficiency takes the MSE less the reference's own noise (the two add), where it is known. "
          "Exact and proxy tests: segment queries against meshes and against proxies (adaptive modes include their probe "
          "rays). Traversal steps and primitive tests: BVH nodes visited and triangles or balls tested by the shadow "
          "queries (one by one: a split segment's own mesh and the rest's proxies as two queries, where the timed "
          "render joins them in one), counted by re-rendering the first " + std::to_string(o->count_passes) +
          " passes with visproxy's own traversal and scaled to the passes reached (learned modes: every pass; nan with "
          "--no-count). eq8: the "
          "paper's estimator (a term drawn with p1, p2, p3); control variate: the proxy's answer corrected by the mesh "
          "under Russian roulette (learned: its probabilities from the corrections each pixel traced before). Images: MODE.pfm / MODE.png; "
          "error maps MODE.error.png, per-pixel RMS error over the channels, white at " + format_number(error_white) +
          " (4x the exact mode's RMS error); MSE against time: convergence.csv, convergence.svg.\n";
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
