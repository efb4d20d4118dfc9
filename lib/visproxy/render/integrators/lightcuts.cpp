// Lightcuts (Walter et al. 2005): every shading point shades K points per area light (and
// the VPLs, if asked) through a cut of the light tree, each cluster by its representative
// traced exactly; with visibility bounds, clusters that proxies prove unoccluded or occluded
// are shaded without a ray (render/lightcuts.h, render/cluster_visibility.h).

#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <optional>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/render/integrators/integrator.h"
#include "visproxy/render/integrators/light_tree.h"
#include "visproxy/render/world/virtual_point_lights.h"

namespace visproxy {
namespace {

// Cut sizes in bins 1, 2-3, 4-7, ..., 512-1023, 1024 and more.
constexpr int kHistogramBins = 11;
int histogram_bin(int size) { return std::min(kHistogramBins - 1, static_cast<int>(std::bit_width(static_cast<unsigned>(std::max(size, 1)))) - 1); }

struct CutCounts {
  std::uint64_t cuts = 0, clusters = 0, rays = 0, proved_unoccluded = 0, proved_occluded = 0, proofs_tried = 0, disagreements = 0;
  std::uint64_t stopped_at_max_cut = 0;  // cuts whose refinement max_cut stopped
  std::array<std::uint64_t, kHistogramBins> histogram{};
  int largest = 0;
};

std::vector<PointLight> lightcut_lights(const IntegratorContext& context, std::size_t& area_points, std::size_t& vpls,
                                        double& clamp_distance) {
  const RenderOptions& options = context.options;
  std::vector<PointLight> lights = area_light_points(context.scene, context.world, options.light_points, options.seed);
  area_points = lights.size();
  vpls = 0;
  clamp_distance = 0;
  if (options.lightcut_vpls) {
    const std::vector<VirtualPointLight> traced = integrator_vpls(context);
    clamp_distance = options.vpl_clamp * scene_diagonal(context.scene, context.world);
    for (PointLight& light : vpl_point_lights(context.world, traced, vpl_max_geometric(clamp_distance))) lights.push_back(light);
    vpls = traced.size();
  }
  return lights;
}

class LightcutsIntegrator final : public Integrator {
 public:
  explicit LightcutsIntegrator(const IntegratorContext& context)
      : context_(context), tree_(lightcut_lights(context, area_points_, vpls_, clamp_distance_)) {
    if (context.options.lightcut.bounds != VisibilityBounds::none) {
      if (!context.world.keeps_solids())
        throw Error("lightcuts: visibility bounds need a render world made with keep_solids (RenderWorldOptions)");
      proofs_.emplace(context.world, context.scene.instances.size());
    }
    const std::size_t pixels = static_cast<std::size_t>(context.scene.camera.width) * static_cast<std::size_t>(context.scene.camera.height);
    cut_sum_.assign(pixels, 0.0);
  }

  Color shade(const ShadingPoint& point, const Color& brdf, PixelRandom& random, PointVisibility& visibility) const override {
    (void)random;
    (void)visibility;
    const RenderWorld& world = context_.world;
    CutEvaluator& evaluator = evaluators_.local();
    const Vertex& x = point.position;
    const std::vector<PointLight>& lights = tree_.lights();
    auto blocked = [&](std::uint32_t index) {
      const PointLight& light = lights[index];
      const Vertex end = light.on_light ? segment_end(world, light.position, light.normal, x) : light.end;
      return world.mesh_blocks(x, end);
    };
    const double offset = world.surface_offset(point.hit->position, point.hit->distance);
    const CutResult cut = evaluator.evaluate(x, *point.hit, offset, brdf, context_.options.lightcut, blocked);
    point.stats->shadow_rays += static_cast<std::uint64_t>(cut.shadow_rays);
    point.stats->exact_tests += static_cast<std::uint64_t>(cut.shadow_rays);
    point.stats->bounds.unoccluded += static_cast<std::uint64_t>(cut.proved_unoccluded);
    point.stats->bounds.occluded += static_cast<std::uint64_t>(cut.proved_occluded);
    CutCounts& counts = counts_.local();
    ++counts.cuts;
    counts.clusters += static_cast<std::uint64_t>(cut.size);
    counts.rays += static_cast<std::uint64_t>(cut.shadow_rays);
    counts.proved_unoccluded += static_cast<std::uint64_t>(cut.proved_unoccluded);
    counts.proved_occluded += static_cast<std::uint64_t>(cut.proved_occluded);
    counts.proofs_tried += static_cast<std::uint64_t>(cut.proofs_tried);
    counts.disagreements += static_cast<std::uint64_t>(cut.disagreements);
    counts.stopped_at_max_cut += cut.stopped_at_max_cut ? 1 : 0;
    ++counts.histogram[static_cast<std::size_t>(histogram_bin(cut.size))];
    counts.largest = std::max(counts.largest, cut.size);
    cut_sum_[point.pixel] += cut.size;
    return cut.radiance;
  }

  Image cut_map(int passes) const override {
    Image map(context_.scene.camera.width, context_.scene.camera.height);
    for (std::size_t i = 0; i < cut_sum_.size(); ++i) map.pixels[i] = Color::Constant(cut_sum_[i] / passes);
    return map;
  }

  nlohmann::json describe() const override {
    CutCounts all;
    for (const CutCounts& c : counts_) {
      all.cuts += c.cuts, all.clusters += c.clusters, all.rays += c.rays, all.proved_unoccluded += c.proved_unoccluded;
      all.proved_occluded += c.proved_occluded, all.proofs_tried += c.proofs_tried, all.disagreements += c.disagreements;
      all.stopped_at_max_cut += c.stopped_at_max_cut;
      for (int b = 0; b < kHistogramBins; ++b) all.histogram[static_cast<std::size_t>(b)] += c.histogram[static_cast<std::size_t>(b)];
      all.largest = std::max(all.largest, c.largest);
    }
    const double cuts = static_cast<double>(std::max<std::uint64_t>(all.cuts, 1));
    nlohmann::json histogram = nlohmann::json::array();
    for (int b = 0; b < kHistogramBins; ++b)
      histogram.push_back({{"from", 1 << b}, {"to", b + 1 < kHistogramBins ? (2 << b) - 1 : -1}, {"cuts", all.histogram[static_cast<std::size_t>(b)]}});
    const CutOptions& cut = context_.options.lightcut;
    return {{"integrator", "lightcuts"},
            {"point_lights", tree_.lights().size()},
            {"area_light_points", area_points_},
            {"light_points_per_area_light", context_.options.light_points},
            {"virtual_point_lights", vpls_},
            {"vpl_clamp_distance", clamp_distance_},
            {"light_tree_nodes", tree_.nodes().size()},
            {"light_seed", context_.options.seed},
            {"error", cut.error},
            {"max_cut", cut.error == 0 ? nlohmann::json(nullptr) : nlohmann::json(cut.max_cut)},
            {"cuts_stopped_at_max_cut", all.stopped_at_max_cut},
            {"visibility_bounds", name_of(cut.bounds)},
            {"cuts", all.cuts},
            {"cut_size_mean", static_cast<double>(all.clusters) / cuts},
            {"cut_size_largest", all.largest},
            {"cut_size_histogram", histogram},
            {"shadow_rays_per_shading_point", static_cast<double>(all.rays) / cuts},
            {"clusters_proved_unoccluded", all.proved_unoccluded},
            {"clusters_proved_occluded", all.proved_occluded},
            {"proofs_tried", all.proofs_tried},
            {"proofs_checked", cut.check_proofs},
            {"proof_disagreements", cut.check_proofs ? nlohmann::json(all.disagreements) : nlohmann::json(nullptr)}};
  }

 private:
  IntegratorContext context_;
  std::size_t area_points_ = 0, vpls_ = 0;
  double clamp_distance_ = 0;
  LightTree tree_;
  std::optional<ClusterProofs> proofs_;
  mutable tbb::enumerable_thread_specific<CutEvaluator> evaluators_{[this] { return CutEvaluator(tree_, proofs_ ? &*proofs_ : nullptr); }};
  mutable tbb::enumerable_thread_specific<CutCounts> counts_;
  mutable std::vector<double> cut_sum_;  // per pixel, summed over passes (one thread per pixel at a time)
};

}  // namespace

std::unique_ptr<Integrator> make_lightcuts_integrator(const IntegratorContext& context) {
  return std::make_unique<LightcutsIntegrator>(context);
}

}  // namespace visproxy
