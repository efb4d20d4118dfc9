#include "visproxy/render/render_job.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <system_error>
#include <type_traits>

#include "visproxy/core/errors.h"
#include "visproxy/core/files.h"
#include "visproxy/image/image.h"

namespace visproxy {
namespace {

using Type = RenderOption::Type;
using nlohmann::json;

template <class Number>
Number parse_number(std::string_view flag, std::string_view text, double least, double most) {
  Number value{};
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size() || text.empty())
    throw OptionError(flag, "'" + std::string(text) + "' is not a number");
  if (!(static_cast<double>(value) >= least && static_cast<double>(value) <= most)) {
    char range[96];
    std::snprintf(range, sizeof range, "[%g, %g]", least, most);
    throw OptionError(flag, std::string(text) + " is not in " + range);
  }
  return value;
}

// An option whose value is a whole number in [least, most], stored through `field`.
template <class Field>
RenderOption integer(std::string_view name, std::string_view flag, std::string help, double least, double most,
                     Field field) {
  RenderOption option{name, flag, Type::integer, std::move(help), "", nullptr, nullptr};
  option.set = [flag, least, most, field](RenderJob& job, std::string_view text) {
    auto& target = field(job);
    target = parse_number<std::remove_reference_t<decltype(target)>>(flag, text, least, most);
  };
  return option;
}

template <class Field>
RenderOption real(std::string_view name, std::string_view flag, std::string help, double least, double most,
                  Field field) {
  RenderOption option{name, flag, Type::real, std::move(help), "", nullptr, nullptr};
  option.set = [flag, least, most, field](RenderJob& job, std::string_view text) {
    field(job) = parse_number<double>(flag, text, least, most);
  };
  return option;
}

template <class Enum, class Field>
RenderOption choice(std::string_view name, std::string_view flag, std::string help, Field field) {
  RenderOption option{name, flag, Type::choice, std::move(help), choice_list<Enum>(), nullptr, nullptr};
  option.set = [flag, field](RenderJob& job, std::string_view text) { field(job) = parse_choice<Enum>(flag, text); };
  return option;
}

template <class Field>
RenderOption text(std::string_view name, std::string_view flag, std::string help, Field field) {
  RenderOption option{name, flag, Type::text, std::move(help), "", nullptr, nullptr};
  option.set = [field](RenderJob& job, std::string_view value) { field(job) = std::string(value); };
  return option;
}

template <class Field>
RenderOption path(std::string_view name, std::string_view flag, std::string help, Field field) {
  RenderOption option{name, flag, Type::text, std::move(help), "", nullptr, nullptr};
  option.set = [field](RenderJob& job, std::string_view value) {
    field(job) = std::filesystem::path(std::string(value));
  };
  return option;
}

// A flag that turns `field` to `when_given` (its help says what giving it does).
template <class Field>
RenderOption flag(std::string_view name, std::string_view flag_name, std::string help, bool when_given, Field field) {
  RenderOption option{name, flag_name, Type::flag, std::move(help), "", nullptr, nullptr};
  option.set_flag = [field](RenderJob& job, bool on) { field(job) = on; };
  option.set = [flag_name, when_given, field](RenderJob& job, std::string_view) { field(job) = when_given; };
  return option;
}

std::vector<RenderOption> make_options() {
  std::vector<RenderOption> o;
  o.push_back(choice<VisibilityMode>(
      "visibility", "--visibility",
      "exact: every shadow ray against the meshes; stochastic: the unbiased estimator with each instance's proxy (own "
      "instance exact); bounds: exact answer, proxies only skip work (VPL connections are traced exactly); spheres: "
      "each "
      "instance's sphere-set proxy as occluder disks, biased by design (instances without one traced exactly) "
      "[default: exact]",
      [](RenderJob& j) -> VisibilityMode& { return j.options.visibility; }));
  o.push_back(choice<IntegratorKind>("integrator", "--integrator",
                                     "direct: M area-light samples per camera sample; vpl: those plus every virtual "
                                     "point light left by N light paths of B "
                                     "bounces (instant radiosity); lightcuts: K point lights per area light (plus the "
                                     "VPLs of --vpls, if given) shaded "
                                     "through a lightcut (Walter et al. 2005), each cluster by a representative traced "
                                     "exactly, or by its central light "
                                     "where the proxies prove its visibility [default: direct]",
                                     [](RenderJob& j) -> IntegratorKind& { return j.options.integrator; }));
  RenderOption vpls = integer("vpls", "--vpls",
                              "vpl: light paths traced from the area lights (N); lightcuts: add their VPLs to the "
                              "point lights [default: 1024; lightcuts: none]",
                              1, 1 << 22, [](RenderJob& j) -> int& { return j.options.vpls; });
  vpls.set = [inner = vpls.set](RenderJob& job, std::string_view value) {
    inner(job, value);
    job.options.lightcut_vpls = true;
  };
  o.push_back(std::move(vpls));
  o.push_back(integer("light_points", "--light-points",
                      "lightcuts: point lights per area light (K), stratified over its area [default: 1024]", 1,
                      1 << 22, [](RenderJob& j) -> int& { return j.options.light_points; }));
  o.push_back(real(
      "error", "--error",
      "lightcuts: refine the cut until every cluster's error bound is at most this fraction of the cut's total (0: "
      "the exact sum over every light, whatever --max-cut says) [default: 0.02]",
      0, 1, [](RenderJob& j) -> double& { return j.options.lightcut.error; }));
  o.push_back(integer(
      "max_cut", "--max-cut",
      "lightcuts: most clusters in a cut with --error above 0; the stats count the cuts it stopped [default: 1000]", 1,
      1 << 24, [](RenderJob& j) -> int& { return j.options.lightcut.max_cut; }));
  o.push_back(choice<VisibilityBounds>("visibility_bounds", "--visibility-bounds",
                                       "lightcuts: prove clusters with the scene's proxies: lower (the shaft from the "
                                       "point to the cluster's box misses every "
                                       "other instance's outside proxy and the own mesh: visibility 1), upper (every "
                                       "segment to the box enters an inside "
                                       "proxy: visibility 0), both, or none. Proved clusters take no shadow ray; their "
                                       "error bounds shrink [default: none]",
                                       [](RenderJob& j) -> VisibilityBounds& { return j.options.lightcut.bounds; }));
  o.push_back(flag(
      "check_proofs", "--check-proofs",
      "lightcuts: also trace the light every proved cluster is shaded by and report how many disagreed with the proof "
      "(proof_disagreements in the stats; expected 0)",
      true, [](RenderJob& j) -> bool& { return j.options.lightcut.check_proofs; }));
  o.push_back(integer("bounces", "--bounces", "vpl: diffuse hits per light path that leave a VPL (B) [default: 1]", 1,
                      64, [](RenderJob& j) -> int& { return j.options.bounces; }));
  o.push_back(
      integer("vpl_seed", "--vpl-seed",
              "vpl: seed of the light paths, apart from --seed so that a reference can share the VPLs [default: 1]", 0,
              1.8e19, [](RenderJob& j) -> std::uint64_t& { return j.options.vpl_seed; }));
  o.push_back(real(
      "vpl_clamp", "--vpl-clamp",
      "vpl: clamp each VPL's geometric term cos cos / d^2 to 1 / (C x D)^2, D the scene's diagonal; the energy dropped "
      "is in the stats (0: no clamp) [default: 0.05]",
      0, 1, [](RenderJob& j) -> double& { return j.options.vpl_clamp; }));
  o.push_back(
      choice<SelfShadow>("self_shadow", "--self-shadow",
                         "spheres: heuristic skips the own instance's spheres closer than twice their radius (t < 2R); "
                         "exact traces the own "
                         "instance's mesh instead of its spheres; none uses all its spheres [default: heuristic]",
                         [](RenderJob& j) -> SelfShadow& { return j.options.self_shadow; }));
  o.push_back(integer(
      "disk_grid_from", "--disk-grid-from",
      "Occluder disks: sort a shading point's disks into a grid over the directions when it has at least this many (0: "
      "always) [default: 4096]",
      0, 1e15, [](RenderJob& j) -> std::size_t& { return j.options.disk_grid_from; }));
  o.push_back(
      flag("disk_clusters", "--no-disk-clusters",
           "Occluder disks: compare every ball with every connection, instead of first the bound of each cluster of an "
           "instance's balls (same answers, for timing)",
           false, [](RenderJob& j) -> bool& { return j.options.disk_clusters; }));
  o.push_back(flag("group_connections", "--single-rays",
                   "vpl: trace the connections of a shading point one ray at a time, not as packets", false,
                   [](RenderJob& j) -> bool& { return j.options.group_connections; }));
  o.push_back(choice<ProbabilityMode>(
      "probabilities", "--probabilities",
      "stochastic: equal; adaptive (for each shading point from K probe rays); learned (control-variate only: from the "
      "corrections each pixel traced before, no probe rays; with direct light it weighs them against the proxy's and "
      "the mesh's modelled cost and the render's noise, and traces a pixel's segments exactly where the proxy does not "
      "pay); optimal (eq8 only: one set for the image, eq. 8's optimum "
      "for the ray types of 20 000 of the scene's shadow segments traced before the render, as 'measure --scene' "
      "predicts with) [default: equal]",
      [](RenderJob& j) -> ProbabilityMode& { return j.options.probabilities; }));
  o.push_back(choice<StochasticEstimator>("estimator", "--estimator",
                                          "stochastic: eq8 (the paper: a term drawn with p1, p2, p3, then traced), or "
                                          "control-variate (the proxy always traced, "
                                          "its answer corrected by the mesh with a probability its answer chooses; no "
                                          "exact query after an outside proxy's miss "
                                          "or an inside proxy's hit) [default: eq8]",
                                          [](RenderJob& j) -> StochasticEstimator& { return j.options.estimator; }));
  o.push_back(flag("cost_heuristic", "--cost-heuristic",
                   "stochastic eq8, adaptive: favour the proxy where it agrees with the mesh (eq. 22-24)", true,
                   [](RenderJob& j) -> bool& { return j.options.cost_heuristic; }));
  o.push_back(flag("gate", "--no-gate",
                   "stochastic: render the estimator everywhere, even where the gate before the render finds that it "
                   "cannot beat exact visibility (adaptive eq8, for each instance's points; the learned control variate "
                   "with VPLs and occluder disks, for the scene), as the paper's estimators are",
                   false, [](RenderJob& j) -> bool& { return j.options.gate; }));
  o.push_back(integer(
      "probe_passes", "--probe-passes",
      "adaptive: 0 probes every shading point; P > 0 probes only in each pixel's first P passes and keeps the ray "
      "types seen per pixel for the later passes [default: 0]",
      0, 1 << 24, [](RenderJob& j) -> int& { return j.options.probe_passes; }));
  o.push_back(flag("split", "--no-split",
                   "stochastic: estimate the shading point's own instance too, instead of tracing it exactly", false,
                   [](RenderJob& j) -> bool& { return j.options.split; }));
  o.push_back(integer("probe_rays", "--probe-rays", "adaptive: probe rays per shading point (K) [default: 16]", 1, 4096,
                      [](RenderJob& j) -> int& { return j.options.probe_rays; }));
  o.push_back(real(
      "probability_floor", "--probability-floor",
      "adaptive or learned: least probability of each term the proxy kind needs, which keeps the estimate unbiased "
      "when the probes or corrections miss a ray type; must be above 0 [default: 0.05]",
      0, 0.33, [](RenderJob& j) -> double& { return j.options.probability_floor; }));
  RenderOption scale =
      real("correction_scale", "--correction-scale",
           "control-variate, adaptive or learned: trace the mesh with probability min(1, scale x sqrt(p)) where the "
           "proxy's answer is wrong with probability p (learned with direct light: scale / 2 times the cost-optimal "
           "probability) [default: 2; 0.25 with --integrator vpl, whose hundreds of connections per shading point share "
           "the variance]",
           0.01, 1000, [](RenderJob& j) -> double& { return j.options.correction_scale; });
  scale.set = [flag = scale.flag](RenderJob& job, std::string_view value) {
    job.correction_scale = parse_number<double>(flag, value, 0.01, 1000);
  };
  o.push_back(std::move(scale));
  o.push_back(integer("spp", "--spp", "Camera samples per pixel [default: 16]", 1, 1 << 24,
                      [](RenderJob& j) -> int& { return j.options.spp; }));
  o.push_back(integer("shadow_rays", "--shadow-rays", "Shadow rays per camera sample (M) [default: 1]", 1, 4096,
                      [](RenderJob& j) -> int& { return j.options.shadow_rays; }));
  o.push_back(integer("seed", "--seed", "Seed of the image's random streams and of proxy builds [default: 1]", 0,
                      1.8e19, [](RenderJob& j) -> std::uint64_t& { return j.options.seed; }));
  o.push_back(real("seconds", "--seconds",
                   "Stop after the pass that crosses this wall time (0: render all --spp) [default: 0]", 0, 1e7,
                   [](RenderJob& j) -> double& { return j.options.seconds; }));
  o.push_back(text("proxy", "--proxy",
                   "stochastic: use this spec for every instance that names proxies (default: its first)",
                   [](RenderJob& j) -> std::string& { return j.proxy; }));
  o.push_back(path("cache", "--cache", "Proxy cache folder [default: $XDG_CACHE_HOME/visproxy or ~/.cache/visproxy]",
                   [](RenderJob& j) -> std::filesystem::path& { return j.cache; }));
  o.push_back(real("exposure", "--exposure", "Scale applied before sRGB encoding of the PNG [default: 1]", 1e-30, 1e30,
                   [](RenderJob& j) -> double& { return j.exposure; }));
  o.push_back(integer("width", "--width", "Override the camera's image width", 1, 16384,
                      [](RenderJob& j) -> int& { return j.width; }));
  o.push_back(integer("height", "--height", "Override the camera's image height", 1, 16384,
                      [](RenderJob& j) -> int& { return j.height; }));
  o.push_back(flag(
      "count", "--count",
      "Trace shadow rays with visproxy's own traversal of Embree-built BVHs and count traversal steps and primitive "
      "tests (deterministic cost; slower than Embree's traversal)",
      true, [](RenderJob& j) -> bool& { return j.count; }));
  o.push_back(flag(
      "maps", "--maps",
      "Also write OUT.cost.png (per camera sample: traversal steps + primitive tests with --count, else segment "
      "queries; white = the most) and, for stochastic, OUT.p1.png (the chance a shadow ray traces the proxy alone: p1 "
      "of eq. 8, 1 - q of the control variate; white = 1); for lightcuts OUT.cut.pfm and OUT.cut.png (mean clusters "
      "per cut; white = the largest mean)",
      true, [](RenderJob& j) -> bool& { return j.maps; }));
  o.push_back(path(
      "cut_reference", "--cut-reference",
      "lightcuts with --maps: a cut map (OUT.cut.pfm) of another run, e.g. without bounds; writes "
      "OUT.cut-reduction.png, per pixel 1 - this cut / that cut (white = the whole cut saved, black = none or larger)",
      [](RenderJob& j) -> std::filesystem::path& { return j.cut_reference; }));
  for (RenderOption& option : o)
    if (option.type == Type::choice) option.help = option.help + " " + option.choices;
  return o;
}

std::filesystem::path beside(const std::filesystem::path& output, const std::string& suffix) {
  std::filesystem::path path = output;
  path.replace_extension();
  return path.string() + suffix;
}

json proxy_name(const std::optional<InstanceProxy>& proxy) { return proxy ? json(proxy->spec) : json(nullptr); }

}  // namespace

const std::vector<RenderOption>& render_options() {
  static const std::vector<RenderOption> options = make_options();
  return options;
}

const RenderOption* find_render_option(std::string_view name) {
  for (const RenderOption& option : render_options())
    if (option.name == name || option.flag == name) return &option;
  return nullptr;
}

RenderedScene render_scene(const RenderJob& job, const RenderCallbacks& callbacks) {
  if (!job.output.empty() && !is_linear_image_path(job.output))
    throw InvalidInputError(job.output, "unsupported image format (use .pfm or .exr; a PNG is written beside it)");
  RenderOptions options = job.options;
  options.correction_scale = job.correction_scale.value_or(options.integrator == IntegratorKind::vpl ? 0.25 : 2.0);
  options.on_pass = callbacks.on_pass;
  if (options.probabilities == ProbabilityMode::learned && options.estimator != StochasticEstimator::control_variate)
    throw OptionError("--probabilities", "learned needs --estimator control-variate");
  if (options.probabilities == ProbabilityMode::optimal && options.estimator != StochasticEstimator::term_choice)
    throw OptionError("--probabilities", "optimal needs --estimator eq8");
  if (!job.cut_reference.empty() && (options.integrator != IntegratorKind::lightcuts || !job.maps))
    throw OptionError("--cut-reference", "needs --integrator lightcuts and --maps");
  validate(options);
  // Read before rendering, so that a bad reference fails at once.
  std::optional<Image> cut_reference;
  if (!job.cut_reference.empty()) cut_reference = read_linear_image(job.cut_reference);

  RenderedScene rendered;
  Scene& scene = rendered.scene;
  scene = load_scene(job.scene, callbacks.on_warning);
  if (job.width > 0) scene.camera.width = job.width;
  if (job.height > 0) scene.camera.height = job.height;
  if (cut_reference && (cut_reference->width != scene.camera.width || cut_reference->height != scene.camera.height))
    throw InvalidInputError(job.cut_reference, "the cut map is " + std::to_string(cut_reference->width) + "x" +
                                                   std::to_string(cut_reference->height) + ", the image " +
                                                   std::to_string(scene.camera.width) + "x" +
                                                   std::to_string(scene.camera.height));
  const bool cluster_bounds =
      options.integrator == IntegratorKind::lightcuts && options.lightcut.bounds != VisibilityBounds::none;
  SceneProxyOptions proxy_options{.cache = job.cache.empty() ? default_proxy_cache() : job.cache,
                                  .stochastic_spec = std::nullopt,
                                  .seed = options.seed,
                                  .on_proxy = callbacks.on_proxy,
                                  .on_verify = callbacks.on_verify};
  if (!job.proxy.empty()) proxy_options.stochastic_spec = job.proxy;
  rendered.proxies = options.visibility == VisibilityMode::exact && !cluster_bounds
                         ? std::vector<MeshProxies>(scene.instances.size())
                         : prepare_scene_proxies(scene, proxy_options);
  const RenderWorld world(scene, rendered.proxies,
                          {.counting = job.count, .ray_masks = true, .keep_solids = cluster_bounds});
  rendered.notes = world.notes();
  rendered.result = render(scene, world, options);

  json instances = json::array();
  for (std::size_t i = 0; i < scene.instances.size(); ++i) {
    const MeshProxies& p = rendered.proxies[i];
    instances.push_back({{"mesh", scene.instances[i].mesh},
                         {"stochastic_proxy", proxy_name(p.stochastic)},
                         {"outside_proxy", proxy_name(p.outside)},
                         {"inside_proxy", proxy_name(p.inside)},
                         {"stochastic_proxy_proved", p.stochastic && p.stochastic->proved}});
  }
  rendered.document = {
      {"scene", job.scene.string()},
      {"image", job.output.string()},
      {"width", scene.camera.width},
      {"height", scene.camera.height},
      {"integrator", name_of(options.integrator)},
      {"visibility", name_of(options.visibility)},
      {"self_shadow", name_of(options.self_shadow)},
      {"probabilities", name_of(options.probabilities)},
      {"estimator", name_of(options.estimator)},
      {"cost_heuristic", options.cost_heuristic},
      {"gate", options.gate},
      {"probe_passes", options.probe_passes},
      {"split", options.split},
      {"probe_rays", options.probe_rays},
      {"probability_floor", options.probability_floor},
      {"correction_scale", options.correction_scale},
      {"spp_requested", options.spp},
      {"shadow_rays_per_sample", options.shadow_rays},
      {"seed", options.seed},
      {"seconds_budget", options.seconds},
      {"visibility_bounds",
       options.integrator == IntegratorKind::lightcuts ? json(name_of(options.lightcut.bounds)) : json(nullptr)},
      {"instances", instances},
      {"proxy_notes", rendered.notes},
      {"stats", rendered.result.stats.to_json()}};
  return rendered;
}

void write_render_outputs(const RenderJob& job, const RenderedScene& rendered) {
  if (job.output.empty()) return;
  const RenderResult& result = rendered.result;
  if (job.output.has_parent_path()) {
    std::error_code error;
    std::filesystem::create_directories(job.output.parent_path(), error);
    if (error) throw IOError(job.output.parent_path(), "cannot create the output folder: " + error.message());
  }
  write_linear_image(job.output, result.image);
  write_png(beside(job.output, ".png"), result.image, job.exposure);
  if (job.maps) {
    double most = 0;
    for (const Color& c : result.cost_map.pixels) most = std::max(most, c.x());
    write_png(beside(job.output, ".cost.png"), result.cost_map, most > 0 ? 1.0 / most : 1.0);
    if (!result.p1_map.pixels.empty()) write_png(beside(job.output, ".p1.png"), result.p1_map, 1.0);
    if (!result.cut_map.pixels.empty()) {
      double largest = 0;
      for (const Color& c : result.cut_map.pixels) largest = std::max(largest, c.x());
      write_linear_image(beside(job.output, ".cut.pfm"), result.cut_map);
      write_png(beside(job.output, ".cut.png"), result.cut_map, largest > 0 ? 1.0 / largest : 1.0);
      if (!job.cut_reference.empty()) {
        const Image reference = read_linear_image(job.cut_reference);
        Image reduction(result.cut_map.width, result.cut_map.height);
        for (std::size_t i = 0; i < reduction.pixels.size(); ++i) {
          const double before = reference.pixels[i].x(), now = result.cut_map.pixels[i].x();
          reduction.pixels[i] = Color::Constant(before > 0 ? std::clamp(1 - now / before, 0.0, 1.0) : 0.0);
        }
        write_png(beside(job.output, ".cut-reduction.png"), reduction, 1.0);
      }
    }
  }
  write_file_atomically(beside(job.output, ".stats.json"), rendered.document.dump(2) + "\n");
}

}  // namespace visproxy
