// Instant radiosity: each shading point sums M area-light samples (as the direct
// integrator) and every virtual point light, with the VPLs' geometric term clamped.

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "render/integrators/integrator.h"
#include "render/virtual_point_lights.h"

namespace visproxy {
namespace {

double luminance(const Color& c) { return (c.x() + c.y() + c.z()) / 3; }

class VplIntegrator final : public Integrator {
 public:
  explicit VplIntegrator(const IntegratorContext& context) : context_(context) {
    const RenderOptions& options = context.options;
    if (options.virtual_point_lights) {
      lights_ = *options.virtual_point_lights;
      given_ = true;
    } else {
      lights_ = trace_virtual_point_lights(context.scene, context.world,
                                           {.paths = options.vpls, .bounces = options.bounces, .seed = options.vpl_seed});
    }
    // A connection reaches a VPL from the side its normal faces (vpl_geometry), so its end,
    // moved off the surface towards that side, is the same for every shading point.
    for (const VirtualPointLight& light : lights_) {
      ends_.push_back(segment_end(context.world, light.position, light.normal, light.position + light.normal, light.distance));
      end_shells_.push_back(context.world.convex_shells_holding(ends_.back()));
    }
    BoundingBox box;
    for (std::size_t i = 0; i < context.scene.instances.size(); ++i) {
      const BoundingBox& b = context.world.instance_bounds(i);
      if (!b.empty()) box.extend(b.min), box.extend(b.max);
    }
    for (const AreaLight& light : context.scene.lights)
      for (const auto& t : light.triangles)
        for (const Vertex& p : t) box.extend(p);
    diagonal_ = box.empty() ? 0 : (box.max - box.min).norm();
    clamp_distance_ = options.vpl_clamp * diagonal_;
    max_geometric_ = clamp_distance_ > 0 ? 1 / (clamp_distance_ * clamp_distance_) : std::numeric_limits<double>::infinity();
    const std::size_t pixels = static_cast<std::size_t>(context.scene.camera.width) * static_cast<std::size_t>(context.scene.camera.height);
    energy_.assign(pixels, 0.0);
    dropped_.assign(pixels, 0.0);
  }

  Color shade(const ShadingPoint& point, const Color& brdf, PixelRandom& random, PointVisibility& visibility) const override {
    Color radiance = Color::Zero();
    if (!context_.lights.empty()) radiance = direct_light(context_, point, random, visibility) / context_.options.shadow_rays;
    thread_local std::vector<Vertex> ends;
    thread_local std::vector<unsigned> shells;
    thread_local std::vector<std::size_t> which;
    thread_local std::vector<double> geometric, answers;
    ends.clear(), shells.clear(), which.clear(), geometric.clear();
    const Vertex& x = point.position;
    for (std::size_t i = 0; i < lights_.size(); ++i) {
      const VplGeometry g = vpl_geometry(x, point.hit->normal, lights_[i]);
      if (!g.faces) continue;
      which.push_back(i);
      geometric.push_back(g.geometric);
      ends.push_back(ends_[i]);
      shells.push_back(end_shells_[i]);
    }
    point.stats->vpl_connections += ends.size();
    answers.resize(ends.size());
    visibility.connections(ends, shells, answers);
    double energy = 0, dropped = 0;
    for (std::size_t k = 0; k < which.size(); ++k) {
      if (answers[k] == 0) continue;
      const VirtualPointLight& light = lights_[which[k]];
      const Color intensity = light.power.cwiseProduct(light.brdf);
      const double g = std::min(geometric[k], max_geometric_);
      radiance += (answers[k] * g) * intensity;
      const double l = luminance(intensity) * answers[k];
      energy += l * geometric[k];
      dropped += l * (geometric[k] - g);
    }
    energy_[point.pixel] += luminance(brdf) * energy;
    dropped_[point.pixel] += luminance(brdf) * dropped;
    return brdf.cwiseProduct(radiance);
  }

  nlohmann::json describe() const override {
    double energy = 0, dropped = 0;
    for (std::size_t i = 0; i < energy_.size(); ++i) energy += energy_[i], dropped += dropped_[i];
    std::size_t by_bounce[8] = {};
    for (const VirtualPointLight& light : lights_) ++by_bounce[std::clamp(light.bounce, 1, 7)];
    nlohmann::json bounces = nlohmann::json::array();
    for (int b = 1; b < 8; ++b)
      if (by_bounce[b] > 0) bounces.push_back(by_bounce[b]);
    return {{"integrator", "vpl"},
            {"virtual_point_lights", lights_.size()},
            {"virtual_point_lights_given", given_},
            {"light_paths", given_ ? 0 : context_.options.vpls},
            {"bounces", context_.options.bounces},
            {"vpl_seed", context_.options.vpl_seed},
            {"virtual_point_lights_by_bounce", bounces},
            {"clamp_distance", clamp_distance_},
            {"clamp_distance_fraction_of_scene_diagonal", context_.options.vpl_clamp},
            {"max_geometric_term", std::isfinite(max_geometric_) ? nlohmann::json(max_geometric_) : nlohmann::json(nullptr)},
            {"clamped_energy_fraction", energy > 0 ? dropped / energy : 0.0}};
  }

 private:
  IntegratorContext context_;
  std::vector<VirtualPointLight> lights_;
  std::vector<Vertex> ends_;         // per VPL: the end of its connections
  std::vector<unsigned> end_shells_;  // per VPL: RenderWorld::convex_shells_holding(its end)
  bool given_ = false;
  double diagonal_ = 0, clamp_distance_ = 0, max_geometric_ = 0;
  // Per pixel, what the VPLs gave before clamping and what clamping dropped (luminance of
  // BRDF x intensity x G x visibility), summed in pixel order for a thread-independent figure.
  mutable std::vector<double> energy_, dropped_;
};

}  // namespace

std::unique_ptr<Integrator> make_vpl_integrator(const IntegratorContext& context) {
  return std::make_unique<VplIntegrator>(context);
}

}  // namespace visproxy
