#include "visproxy/evaluate/measure_proxies.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/folder/proxy_folder.h"
#include "visproxy/folder/verdict.h"
#include "visproxy/measure/cost_model.h"
#include "visproxy/measure/random_lines.h"
#include "visproxy/render/renderer.h"

namespace visproxy {
namespace {

using nlohmann::json;

json interval(const Proportion& p) { return {{"value", p.fraction()}, {"lower", p.lower()}, {"upper", p.upper()}}; }

// Isotropic lines are lines. They are drawn as chords of the mesh's bounding sphere, but
// a proxy may reach beyond that sphere (a coarse outer hull, a box's corners), and a chord
// that starts inside the proxy's solid need not cross its surface. Such a proxy is traced
// on the same lines' chords of a concentric sphere of radius `radius` that holds it; the
// mesh, within the first sphere, meets the longer chords where it met the first ones.
std::vector<Segment> lengthen_chords(std::span<const Segment> chords, const Vertex& center, double radius) {
  std::vector<Segment> lines(chords.size());
  for (std::size_t i = 0; i < chords.size(); ++i) {
    const Vertex d = chords[i].to - chords[i].from, m = chords[i].from - center;
    const double a = d.squaredNorm(), b = d.dot(m), c = m.squaredNorm() - radius * radius;
    if (!(a > 0)) {
      lines[i] = chords[i];
      continue;
    }
    const double root = std::sqrt(std::max(0.0, b * b - a * c));
    const double t0 = std::min(0.0, (-b - root) / a), t1 = std::max(1.0, (-b + root) / a);
    lines[i] = {chords[i].from + t0 * d, chords[i].from + t1 * d};
  }
  return lines;
}

// The radius of a sphere about `center` that holds `geometry`, with a margin of 2^-20 of
// it for the rounding of the chords' ends.
double reach(const ProxyGeometry& geometry, const Vertex& center) {
  double r = 0;
  for (const Sphere& s : geometry.spheres) r = std::max(r, (s.center - center).norm() + s.radius);
  for (const Vertex& p : geometry.mesh.positions) r = std::max(r, (p - center).norm());
  return r * (1 + std::ldexp(1.0, -20));
}

}  // namespace

json ray_set_json(const TriangleMesh& mesh, const MeasureOptions& options) {
  const Sphere sphere = bounding_sphere(mesh);
  return {
      {"kind", "isotropic lines"},
      {"description", "chords between two independent uniform points on the mesh's bounding sphere"},
      {"count", options.rays},
      {"seed", options.seed},
      {"sphere", {{"center", {sphere.center.x(), sphere.center.y(), sphere.center.z()}}, {"radius", sphere.radius}}},
      {"timed_rays", std::min(options.rays, options.timing.rays)}};
}

namespace {

json work_json(const WorkPerRay& work) {
  return {{"nodes", work.nodes}, {"triangles", work.triangles}, {"balls", work.balls}};
}

// The cost model of the run (cost_model.h), fitted to the proxies' timings, and each
// proxy's cost over the mesh's predicted from its counted work. The mesh is left out of the
// fit and enters by its timed cost alone: it is timed in every block of every proxy, and
// its BVH, unlike the proxies', does not stay in the caches, so the same constants do not
// hold for it.
//
// The interval of a proxy's cost ratio is the prediction scaled by the model's error over
// the run's proxies (the least and greatest timed / predicted ratio), joined with the
// proxy's own block range: the cost of a geometry moves with the machine's state between
// runs by more than between the blocks of one run, and how far the run's timings stray
// from what their work predicts is a measure of that, taken from every proxy at once.
// The point stays the proxy's timed median. Without enough timed proxies for a fit, the
// manifest says why and the entries keep their block ranges alone.
void add_cost_model(json& manifest, const WorkPerRay& mesh_work, const std::vector<WorkPerRay>& proxy_work) {
  std::vector<CostObservation> observations;
  std::vector<double> mesh_ns;
  json& proxies = manifest.at("proxies");
  for (std::size_t i = 0; i < proxies.size(); ++i) {
    const json& cost = proxies[i]["measure"]["cost_ns_per_ray"];
    if (cost.value("proxy", 0.0) > 0) observations.push_back({proxy_work[i], cost.value("proxy", 0.0)});
    if (cost.value("mesh", 0.0) > 0) mesh_ns.push_back(cost.value("mesh", 0.0));
  }
  const std::optional<CostModel> model = mesh_ns.empty() ? std::nullopt : fit_cost_model(observations);
  if (!model) {
    manifest["cost_model"] = {{"fitted", false},
                              {"why_not", "fewer than " + std::to_string(kCostModelMinimumObservations) +
                                              " timed proxies to fit four constants"}};
    return;
  }
  std::sort(mesh_ns.begin(), mesh_ns.end());
  const double mesh = mesh_ns[mesh_ns.size() / 2];
  double low = std::numeric_limits<double>::infinity(), high = 0;
  std::vector<double> predicted(proxies.size(), 0);
  for (std::size_t i = 0; i < proxies.size(); ++i) {
    const json& cost = proxies[i]["measure"]["cost_ns_per_ray"];
    predicted[i] = model->predict(proxy_work[i]) / mesh;
    if (const double timed = cost.value("proxy_over_mesh", 0.0); timed > 0 && predicted[i] > 0) {
      low = std::min(low, timed / predicted[i]);
      high = std::max(high, timed / predicted[i]);
    }
  }
  if (!(high > 0)) low = high = 1;
  for (std::size_t i = 0; i < proxies.size(); ++i) {
    json& cost = proxies[i]["measure"]["cost_ns_per_ray"];
    double range_low = predicted[i] * low, range_high = predicted[i] * high;
    if (const auto blocks = cost.find("proxy_over_mesh_range"); blocks != cost.end() && blocks->size() == 2) {
      range_low = std::min(range_low, blocks->at(0).get<double>());
      range_high = std::max(range_high, blocks->at(1).get<double>());
    }
    cost["predicted"] = {{"proxy_over_mesh", predicted[i]}, {"interval", {range_low, range_high}}};
  }
  manifest["cost_model"] = {
      {"fitted", true},
      {"description",
       "ns per ray = per_ray + per_node nodes + per_triangle triangles + per_ball balls, the work counted on the "
       "timed rays (a binary BVH of the same primitives), fitted to this run's timings of the proxies by non-negative "
       "least squares on relative errors; each proxy's cost_ns_per_ray.predicted is its prediction over the mesh's "
       "timed cost, and the interval that prediction scaled by ratio_timed_over_predicted, joined with its block "
       "range"},
      {"ns",
       {{"per_ray", model->per_ray},
        {"per_node", model->per_node},
        {"per_triangle", model->per_triangle},
        {"per_ball", model->per_ball}}},
      {"observations", model->observations},
      {"timed_over_predicted", {model->residual_low, model->residual_high}},
      {"ratio_timed_over_predicted", {low, high}},
      {"mesh_ns_per_ray", mesh},
      {"mesh_work", work_json(mesh_work)},
      {"mesh_over_predicted", mesh / model->predict(mesh_work)}};
}

// The scene's camera made at most 128 pixels on the longer side for timed renders, and
// given back when this goes out of scope (the scene's meshes are not copied).
class SmallCamera {
 public:
  explicit SmallCamera(Scene& scene) : scene_(scene), camera_(scene.camera) {
    const double scale = std::min(1.0, 128.0 / std::max(scene.camera.width, scene.camera.height));
    scene.camera.width = std::max(1, static_cast<int>(std::lround(scene.camera.width * scale)));
    scene.camera.height = std::max(1, static_cast<int>(std::lround(scene.camera.height * scale)));
  }
  ~SmallCamera() { scene_.camera = camera_; }
  SmallCamera(const SmallCamera&) = delete;
  SmallCamera& operator=(const SmallCamera&) = delete;

 private:
  Scene& scene_;
  const Camera camera_;
};

// The share of a camera sample's time that testing shadow rays against the mesh takes in
// `scene` (Amdahl's fraction for the render-level prediction): the scene rendered as
// `visproxy render` renders it by default (direct light, exact visibility, one shadow ray
// per sample), on one thread at no more than 128 x 128 pixels. The mesh's part of a sample
// is its shadow rays times the mesh's own cost per shadow ray on the scene's segments.
// Both are timed in turns, one render pass and one pass of the timed segments against the
// mesh per round (after a round that warms the caches), so that each round's share sees
// one state of the machine: the share is the median round's, and the least and greatest
// rounds' shares bound it (with 6 rounds, the median share lies between them with
// probability 1 - 2^-5 for any distribution of rounds).
json render_share(Scene& scene, const RenderWorld& world, const RayScene& mesh_scene, std::span<const Segment> rays,
                  const TimingOptions& timing, std::uint64_t seed) {
  const SmallCamera small(scene);
  const int rounds = std::max(timing.blocks, 1);
  RenderOptions options;
  options.spp = rounds + 1;
  options.seed = seed;
  const std::span<const Segment> timed = rays.first(std::min(rays.size(), timing.rays));
  std::vector<double> shares, sample_ns, mesh_ns;
  RenderStats stats;
  {
    const tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    RenderSession session(scene, world, options);
    for (int round = 0; round <= rounds; ++round) {
      const double before = session.seconds();
      session.run(1);
      const double pass_seconds = session.seconds() - before;
      const double ray_ns = nanoseconds_per_ray_once(mesh_scene, timed);
      const RenderStats so_far = session.result().stats;
      const double samples = static_cast<double>(so_far.camera_samples - stats.camera_samples);
      const double segments = static_cast<double>(so_far.shadow_rays - stats.shadow_rays);
      stats = so_far;
      if (round == 0 || !(samples > 0) || !(pass_seconds > 0)) continue;  // the first round warms the caches
      const double ns = 1e9 * pass_seconds / samples;
      sample_ns.push_back(ns);
      mesh_ns.push_back(ray_ns);
      shares.push_back(std::clamp(segments / samples * ray_ns / ns, 0.0, 1.0));
    }
  }
  const double shadow_rays_per_sample = static_cast<double>(stats.shadow_rays) / std::max(1.0, static_cast<double>(stats.camera_samples));
  const double share = median(shares);
  const double low = shares.empty() ? 0 : *std::min_element(shares.begin(), shares.end());
  const double high = shares.empty() ? 0 : *std::max_element(shares.begin(), shares.end());
  return {{"description",
           "share of a camera sample's time (direct light, exact visibility, one shadow ray per sample, one thread) "
           "spent testing shadow rays against the mesh: shadow rays per sample x the mesh's ns per shadow ray on "
           "the scene's segments, over the ns per sample, timed in turns (one render pass, then the segments against "
           "the mesh, per round); share is the median round's, share_range the least and greatest rounds'"},
          {"width", scene.camera.width},
          {"height", scene.camera.height},
          {"passes", stats.passes},
          {"rounds", shares.size()},
          {"ns_per_camera_sample", median(sample_ns)},
          {"shadow_rays_per_camera_sample", shadow_rays_per_sample},
          {"mesh_ns_per_shadow_ray", median(mesh_ns)},
          {"share", share},
          {"share_range", {low, high}}};
}

// The render's time per pass with each use of a proxy, over exact's: the mesh's instances
// given the proxy as their stochastic proxy, and as their outside or inside proxy when
// `proved` (verify proved that claim for these very files; else bounds is not timed, as
// the report cannot advise it); eq. 8 at its optimal probabilities and the learned control
// variate, as `render` runs them; the scene rendered as render_share renders it (one thread,
// at most 128 pixels on the longer side). Each round renders one pass of exact and one of
// each use, in turns, after a round that warms the caches; per use, the median round's
// ratio and the least and greatest rounds'. The work before a render's first pass (eq. 8's
// optimal probabilities, the learned control variate's costs) is not a sample's and is
// left out. What the renderer spends per sample beyond the shadow rays' cost (a second
// query where the proxies decide nothing, the point's set-up) is in these times, and not
// in render_share's model.
json use_render_times(Scene& scene, const std::vector<bool>& mesh_instance, const InstanceProxy& proxy, int rounds,
                      std::uint64_t seed) {
  const SmallCamera small(scene);
  std::vector<MeshProxies> proxies(scene.instances.size());
  const bool bounds = proxy.proved && proxy.kind != ProxyKind::general;
  for (std::size_t i = 0; i < proxies.size(); ++i) {
    if (!mesh_instance[i]) continue;
    proxies[i].stochastic = proxy;
    if (bounds) (proxy.kind == ProxyKind::outside ? proxies[i].outside : proxies[i].inside) = proxy;
  }
  const RenderWorld world(scene, proxies);
  RenderOptions exact;
  exact.spp = rounds + 1;
  exact.seed = seed;
  std::vector<std::pair<std::string, RenderOptions>> uses;
  if (bounds) {
    RenderOptions o = exact;
    o.visibility = VisibilityMode::bounds;
    uses.emplace_back("bounds", o);
  }
  {
    RenderOptions o = exact;
    o.visibility = VisibilityMode::stochastic;
    o.probabilities = ProbabilityMode::optimal;
    uses.emplace_back("eq8", o);
  }
  {
    RenderOptions o = exact;
    o.visibility = VisibilityMode::stochastic;
    o.estimator = StochasticEstimator::control_variate;
    o.probabilities = ProbabilityMode::learned;
    uses.emplace_back("control_variate", o);
  }
  // The learned control variate first learns: its first passes model each pixel's costs
  // and explore, which a render of hundreds of passes spends only at its start. It is
  // timed after kLearnedWarmUp passes, and the share of its timed segments it traced
  // exactly is kept (the report weighs its noise by it).
  constexpr int kLearnedWarmUp = 16;
  std::vector<std::vector<double>> ratios(uses.size());
  double traced_exactly_share = std::nan("");
  {
    const tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    RenderSession reference(scene, world, exact);
    std::vector<RenderSession> sessions;
    for (auto& [name, options] : uses) {
      if (name == "control_variate") options.spp += kLearnedWarmUp;
      sessions.emplace_back(scene, world, options);
    }
    std::vector<RenderStats> warm(uses.size());
    for (int round = 0; round <= rounds; ++round) {
      auto pass_seconds = [](RenderSession& session, int passes) {
        const double before = session.seconds();
        session.run(passes);
        return session.seconds() - before;
      };
      const double exact_seconds = pass_seconds(reference, 1);
      for (std::size_t u = 0; u < uses.size(); ++u) {
        const bool learned = uses[u].first == "control_variate";
        const double seconds = pass_seconds(sessions[u], round == 0 && learned ? kLearnedWarmUp : 1);
        if (round == 0) warm[u] = sessions[u].result().stats;
        if (round > 0 && exact_seconds > 0) ratios[u].push_back(seconds / exact_seconds);  // the first round warms the caches
      }
    }
    for (std::size_t u = 0; u < uses.size(); ++u)
      if (uses[u].first == "control_variate") {
        const RenderStats end = sessions[u].result().stats;
        const double segments = static_cast<double>(end.shadow_rays - warm[u].shadow_rays);
        if (segments > 0)
          traced_exactly_share =
              static_cast<double>(end.control_variate.traced_exactly - warm[u].control_variate.traced_exactly) / segments;
      }
  }
  json out = {{"description",
               "per use, a render pass's time over an exact pass's in the same round (one thread, the scene's camera at "
               "most 128 pixels on the longer side, direct light, one shadow ray per sample): the median round's, and the "
               "least and greatest rounds' (range); bounds only for a proxy whose claim verify proved"},
              {"rounds", rounds},
              {"width", scene.camera.width},
              {"height", scene.camera.height}};
  for (std::size_t u = 0; u < uses.size(); ++u) {
    const std::vector<double>& r = ratios[u];
    if (r.empty()) continue;
    const auto [least, most] = std::minmax_element(r.begin(), r.end());
    out[uses[u].first] = {{"pass_time_over_exact", median(r)}, {"range", {*least, *most}}};
    if (uses[u].first == "control_variate" && std::isfinite(traced_exactly_share)) {
      out[uses[u].first]["warm_up_passes"] = kLearnedWarmUp;
      out[uses[u].first]["traced_exactly_share"] = traced_exactly_share;
    }
  }
  return out;
}

// What the render's noise is made of, for predicting each use's noise over the whole
// render (efficiency.h, render_variance_ratio): pairs of camera samples in one pixel as a
// render takes them (scene_sample_pairs), the exact render's variance within a pixel from
// their differences, and the segments a use estimates with their squared contributions.
//  - Segments from other instances whose rest of the scene lets them through: the proxies
//    stand in for the mesh there, and their ray types are the proxy's (per proxy).
//  - Segments from the mesh's own instances: visibility splitting traces the own mesh
//    exactly (a segment it blocks is 0, without noise) and estimates the rest of the
//    scene, as of type 1 (blocked) or 4 (clear) when its estimate agrees with it. (Other
//    instances of the mesh are taken for their mesh there: what their proxies would add is
//    left out.) Eq. 8 still adds noise to type 4.
struct RenderNoise {
  std::size_t samples = 0;
  double exact_variance = 0, exact_variance_error = 0;  // mean per sample, and its standard error
  std::vector<Segment> segments;                        // from other instances, the rest of the scene clear
  std::vector<double> squared;                          // their squared contribution, mean over channels
  std::vector<std::uint8_t> mesh_blocked;
  // From the mesh's instances: per ray type, the mean over samples of the squared
  // contribution, and of its square.
  std::array<double, 4> own{}, own_squares{};
  std::array<std::uint64_t, 4> own_segments{};  // how many, by type
};

constexpr std::size_t kNoisePairs = 20000;

RenderNoise render_noise(const Scene& scene, const RenderWorld& world, const std::vector<bool>& mesh_instance,
                         const RayScene& mesh_scene, std::uint64_t seed) {
  // The rest of the scene: a world of the other instances only.
  Scene rest = scene;
  rest.instances.clear();
  for (std::size_t i = 0; i < scene.instances.size(); ++i)
    if (!mesh_instance[i]) rest.instances.push_back(scene.instances[i]);
  std::optional<RenderWorld> rest_world;
  if (!rest.instances.empty()) rest_world.emplace(rest, std::vector<MeshProxies>(rest.instances.size()));
  RenderNoise noise;
  double sum = 0, sum_squares = 0;
  for (const std::array<CameraSample, 2>& pair : scene_sample_pairs(scene, world, kNoisePairs, seed ^ 0x6E6F697365ULL)) {
    std::array<Color, 2> exact;
    for (std::size_t k = 0; k < 2; ++k) {
      const CameraSample& sample = pair[k];
      exact[k] = sample.emitted;
      if (!sample.has_segment) continue;
      const ShadowSegment& s = sample.segment;
      if (mesh_instance[static_cast<std::size_t>(s.instance)]) {
        // Typed by the rest of the scene, as the renderer's optimal mode counts it; where the
        // own mesh blocks, splitting answers 0 exactly and no use adds noise.
        const bool rest_blocks = world.mesh_blocks(s.from, s.to, {.skip = s.instance, .only = -1});
        const bool own_blocks = world.mesh_blocks(s.from, s.to, {.skip = -1, .only = s.instance});
        if (!rest_blocks && !own_blocks) exact[k] += sample.contribution;
        const std::size_t type = rest_blocks ? 0 : 3;
        ++noise.own_segments[type];
        if (own_blocks) continue;
        const double squared = sample.contribution.squaredNorm() / 3;
        noise.own[type] += squared, noise.own_squares[type] += squared * squared;
        continue;
      }
      if (!world.mesh_blocks(s.from, s.to)) exact[k] += sample.contribution;
      if (rest_world && rest_world->mesh_blocks(s.from, s.to)) continue;
      noise.segments.push_back({s.from, s.to});
      noise.squared.push_back(sample.contribution.squaredNorm() / 3);
    }
    const double variance = (exact[0] - exact[1]).squaredNorm() / 3 / 2;  // per channel, as mean_squared_error
    sum += variance, sum_squares += variance * variance;
  }
  noise.samples = 2 * kNoisePairs;
  for (std::size_t t = 0; t < 4; ++t)
    noise.own[t] /= static_cast<double>(noise.samples), noise.own_squares[t] /= static_cast<double>(noise.samples);
  const double n = static_cast<double>(kNoisePairs);
  noise.exact_variance = sum / n;
  noise.exact_variance_error = std::sqrt(std::max(0.0, sum_squares / n - noise.exact_variance * noise.exact_variance) / n);
  noise.mesh_blocked = mesh_scene.segments_blocked(noise.segments);
  return noise;
}

// A proxy's part of the render's noise: per ray type, the mean over the camera samples of
// the squared contributions of segments of that type, and the mean of their squares (for
// the prediction's interval).
json proxy_render_noise(const RenderNoise& noise, const RayScene& proxy_scene) {
  const std::vector<std::uint8_t> proxy_blocked = proxy_scene.segments_blocked(noise.segments);
  std::array<double, 4> weighted{}, weighted_squares{};
  std::array<std::uint64_t, 4> segments{};
  for (std::size_t i = 0; i < noise.segments.size(); ++i) {
    const bool mesh = noise.mesh_blocked[i] != 0, proxy = proxy_blocked[i] != 0;
    const std::size_t type = mesh ? (proxy ? 0 : 1) : (proxy ? 2 : 3);
    ++segments[type];
    weighted[type] += noise.squared[i];
    weighted_squares[type] += noise.squared[i] * noise.squared[i];
  }
  const double n = static_cast<double>(noise.samples);
  for (std::size_t t = 0; t < 4; ++t) weighted[t] /= n, weighted_squares[t] /= n;
  return {{"segments_by_type", segments},
          {"squared_contribution_by_type", weighted},
          {"squared_contribution_squares_by_type", weighted_squares}};
}

}  // namespace

std::optional<std::array<double, 2>> cost_ratio_interval(const json& measure) {
  if (!measure.is_object() || !measure.contains("cost_ns_per_ray")) return std::nullopt;
  const json& cost = measure["cost_ns_per_ray"];
  auto pair = [](const json& value) -> std::optional<std::array<double, 2>> {
    if (!value.is_array() || value.size() != 2 || !value[0].is_number() || !value[1].is_number()) return std::nullopt;
    return std::array<double, 2>{value[0].get<double>(), value[1].get<double>()};
  };
  if (cost.contains("predicted") && cost["predicted"].is_object() && cost["predicted"].contains("interval"))
    if (auto interval = pair(cost["predicted"]["interval"])) return interval;
  if (cost.contains("proxy_over_mesh_range")) return pair(cost["proxy_over_mesh_range"]);
  return std::nullopt;
}

json measurement_json(const ProxyMeasurement& m) {
  const bool bounded = std::isfinite(m.gssa_ratio_upper);
  return {{"counts", m.counts.counts},
          {"f_hit", interval(m.f_hit)},
          {"f_miss", interval(m.f_miss)},
          {"v_avg", interval(m.v_avg)},
          {"gssa_ratio",
           {{"value", m.gssa_ratio},
            {"lower", m.gssa_ratio_lower},
            {"upper", bounded ? json(m.gssa_ratio_upper) : json(nullptr)}}},
          {"probabilities",
           {{"form", kind_name(m.probability_form)}, {"p1", m.optimal.p1}, {"p2", m.optimal.p2}, {"p3", m.optimal.p3}}},
          {"variance", {{"optimal", m.variance_optimal}, {"equal", m.variance_equal}}},
          {"rays_contradicting_claim", m.rays_contradicting_claim},
          {"cost_ns_per_ray",
           {{"proxy", m.proxy_ns_per_ray},
            {"mesh", m.mesh_ns_per_ray},
            {"estimator", m.estimator_ns_per_ray},
            {"proxy_over_mesh", m.cost_ratio},
            {"proxy_over_mesh_range", {m.cost_ratio_low, m.cost_ratio_high}},
            {"timing_blocks", m.timing_blocks}}}};
}

json measure_proxies(const TriangleMesh& mesh, const std::filesystem::path& folder, json manifest,
                     const MeasureOptions& options) {
  return measure_proxies(
      mesh, std::move(manifest), [&](const json& entry, std::size_t) { return read_proxy_geometry(folder, entry); },
      options);
}

json measure_proxies(const TriangleMesh& mesh, json manifest, const ProxyGeometryReader& read,
                     const MeasureOptions& options) {
  // The mesh's instances in the scene (none: isotropic lines in the mesh's own frame).
  std::vector<Eigen::Affine3d> placements;
  std::vector<Segment> segments;
  json rays;
  std::optional<Scene> scene;
  std::unique_ptr<RenderWorld> world;
  std::vector<bool> mesh_instance;  // per scene instance: of the measured mesh
  const Sphere line_sphere = bounding_sphere(mesh);
  if (options.scene.empty()) {
    segments = isotropic_lines(line_sphere, options.rays, options.seed);
    rays = ray_set_json(mesh, options);
    placements.push_back(Eigen::Affine3d::Identity());
  } else {
    scene.emplace(load_scene(options.scene, options.on_warning));
    mesh_instance.assign(scene->instances.size(), false);
    for (std::size_t i = 0; i < scene->instances.size(); ++i)
      if (scene->mesh(scene->instances[i].mesh).mesh == mesh) {
        mesh_instance[i] = true;
        placements.push_back(scene->instances[i].transform);
      }
    if (placements.empty()) throw InvalidInputError(options.scene, "no instance of the scene uses the measured mesh");
    world = std::make_unique<RenderWorld>(*scene, std::vector<MeshProxies>(scene->instances.size()));
    for (const ShadowSegment& s : scene_shadow_segments(*scene, *world, options.rays, options.seed, mesh_instance))
      segments.push_back({s.from, s.to});
    if (segments.empty()) throw InvalidInputError(options.scene, "the camera sees no lit surface to measure from");
    rays = {{"kind", "scene shadow segments"},
            {"description", "from points the camera sees on other instances to area-uniform points on the lights"},
            {"scene", options.scene.string()},
            {"count", segments.size()},
            {"seed", options.seed},
            {"instances_of_mesh", placements.size()},
            {"timed_rays", std::min(segments.size(), options.timing.rays)}};
  }
  auto place_mesh = [&](const TriangleMesh& object) {
    TriangleMesh placed;
    for (const Eigen::Affine3d& t : placements) append_mesh(placed, transformed_mesh(object, t));
    return placed;
  };
  auto place_spheres = [&](const std::vector<Sphere>& object) {
    std::vector<Sphere> placed;
    for (const Eigen::Affine3d& t : placements) {
      const std::optional<std::vector<Sphere>> balls = transformed_spheres(object, t);
      if (!balls)
        throw InvalidInputError(options.scene, "sphere proxies need instances placed without shear or uneven scale");
      placed.insert(placed.end(), balls->begin(), balls->end());
    }
    return placed;
  };
  const TriangleMesh placed_mesh = placements.size() == 1 && options.scene.empty() ? mesh : place_mesh(mesh);
  // Mesh and proxies are traced relative to the placed mesh's centre: float rounding then
  // follows its extent, not its distance from the origin.
  const BoundingBox placed_box = bounding_box(placed_mesh);
  const Vertex center = placed_box.empty() ? Vertex::Zero() : Vertex(0.5 * (placed_box.min + placed_box.max));
  const RayScene mesh_scene(placed_mesh, center);
  const ReferenceRays reference = trace_reference(mesh_scene, std::move(segments), options.timing);
  std::optional<RenderNoise> noise;
  if (scene) noise = render_noise(*scene, *world, mesh_instance, mesh_scene, options.seed);
  const bool timed = options.timing.rays > 0 && options.timing.blocks > 0;
  const WorkPerRay mesh_work =
      timed ? count_work(CountingBvh(placed_mesh), false, reference.rays, options.timing.rays) : WorkPerRay{};
  std::vector<WorkPerRay> proxy_work;
  std::size_t index = 0;
  for (json& entry : manifest.at("proxies")) {
    if (options.on_start) options.on_start(entry.at("name").get<std::string>());
    const auto start = std::chrono::steady_clock::now();
    const ProxyGeometry geometry = read(entry, index++);
    // The proxy placed on every instance once: traced by Embree, and its work counted.
    const bool balls = geometry.type == PrimitiveType::sphere;
    const std::vector<Sphere> placed_balls = balls ? place_spheres(geometry.spheres) : std::vector<Sphere>{};
    const TriangleMesh placed_proxy = balls ? TriangleMesh{} : place_mesh(geometry.mesh);
    const RayScene proxy_scene = balls ? RayScene(placed_balls, center) : RayScene(placed_proxy, center);
    json proxy_rays = rays;
    ProxyMeasurement measurement;
    // The work of the timed rays, counted against the same placed geometry.
    auto work_on = [&](std::span<const Segment> traced) {
      if (!timed) return WorkPerRay{};
      if (balls) return count_work(CountingBvh(std::span<const Sphere>(placed_balls)), true, traced, options.timing.rays);
      return count_work(CountingBvh(placed_proxy), false, traced, options.timing.rays);
    };
    if (const double radius = options.scene.empty() ? reach(geometry, line_sphere.center) : 0;
        radius > line_sphere.radius) {
      const ReferenceRays lines{.rays = lengthen_chords(reference.rays, line_sphere.center, radius),
                                .mesh_blocked = reference.mesh_blocked,
                                .mesh_ns_per_ray = reference.mesh_ns_per_ray,
                                .mesh = reference.mesh};
      measurement = measure_proxy(lines, proxy_scene, entry_kind(entry), options.timing);
      proxy_work.push_back(work_on(lines.rays));
      proxy_rays["proxy_sphere_radius"] = radius;
    } else {
      measurement = measure_proxy(reference, proxy_scene, entry_kind(entry), options.timing);
      proxy_work.push_back(work_on(reference.rays));
    }
    json measured = measurement_json(measurement);
    measured["cost_ns_per_ray"]["work"] = work_json(proxy_work.back());
    if (noise) measured["render_noise"] = proxy_render_noise(*noise, proxy_scene);
    if (scene && timed) {
      const bool proved = entry.contains("verify") && verdict_proves(entry["verify"], entry, mesh, geometry);
      const InstanceProxy proxy{entry_kind(entry), entry.value("spec", std::string()), geometry.mesh, geometry.spheres, proved};
      measured["render_time"] = use_render_times(*scene, mesh_instance, proxy, std::max(options.timing.blocks, 1), options.seed);
    }
    measured["rays"] = std::move(proxy_rays);
    measured["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    entry["measure"] = std::move(measured);
  }
  if (timed) add_cost_model(manifest, mesh_work, proxy_work);
  if (timed && scene) {
    json share = render_share(*scene, *world, mesh_scene, reference.rays, options.timing, options.seed);
    share["scene"] = options.scene.string();
    share["noise"] = {{"description",
                       "the exact render's variance of one camera sample within its pixel (per colour channel, as the "
                       "mean squared error counts it), from pairs of samples in one pixel; each proxy's render_noise holds "
                       "the squared contributions of the segments whose estimate a use changes, by ray type"},
                      {"camera_samples", noise->samples},
                      {"exact_variance_per_sample", noise->exact_variance},
                      {"standard_error", noise->exact_variance_error},
                      {"own_instances_squared_contribution_by_type", noise->own},
                      {"own_instances_squared_contribution_squares_by_type", noise->own_squares},
                      {"own_instances_segments_by_type", noise->own_segments}};
    manifest["render_share"] = std::move(share);
  } else {
    manifest.erase("render_share");
  }
  return manifest;
}

}  // namespace visproxy
