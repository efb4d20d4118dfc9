// Instant radiosity: each shading point sums M area-light samples (as the direct
// integrator) and every virtual point light, with the VPLs' geometric term clamped.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "visproxy/render/integrators/integrator.h"
#include "visproxy/render/world/virtual_point_lights.h"

namespace visproxy {
namespace {

// Orders the lights along a Morton curve over their bounding box (ties kept in order), so
// that neighbours in the list lie near each other: a shading point's connections to a run
// of them leave in similar directions, which lets occluder disks reject clusters for whole
// chunks of connections at once. Only the order of a sum changes.
void sort_spatially(std::vector<VirtualPointLight>& lights) {
  if (lights.size() < 2) return;
  BoundingBox box;
  for (const VirtualPointLight& light : lights) box.extend(light.position);
  const Vertex extent = (box.max - box.min).cwiseMax(Vertex::Constant(std::numeric_limits<double>::min()));
  auto spread = [](std::uint64_t v) {  // 21 bits to every third of 63
    v &= 0x1FFFFF;
    v = (v | v << 32) & 0x1F00000000FFFF;
    v = (v | v << 16) & 0x1F0000FF0000FF;
    v = (v | v << 8) & 0x100F00F00F00F00F;
    v = (v | v << 4) & 0x10C30C30C30C30C3;
    v = (v | v << 2) & 0x1249249249249249;
    return v;
  };
  std::vector<std::pair<std::uint64_t, std::size_t>> keys;
  for (std::size_t i = 0; i < lights.size(); ++i) {
    std::uint64_t code = 0;
    for (int axis = 0; axis < 3; ++axis) {
      const double u = std::clamp((lights[i].position[axis] - box.min[axis]) / extent[axis], 0.0, 1.0);
      code |= spread(static_cast<std::uint64_t>(u * 2097151.0)) << axis;
    }
    keys.emplace_back(code, i);
  }
  std::sort(keys.begin(), keys.end());
  std::vector<VirtualPointLight> sorted;
  sorted.reserve(lights.size());
  for (const auto& key : keys) sorted.push_back(lights[key.second]);
  lights = std::move(sorted);
}

class VplIntegrator final : public Integrator {
 public:
  explicit VplIntegrator(const IntegratorContext& context) : context_(context) {
    const RenderOptions& options = context.options;
    lights_ = integrator_vpls(context);
    given_ = options.virtual_point_lights != nullptr;
    sort_spatially(lights_);
    arrays_ = VplArrays(lights_);
    for (const VirtualPointLight& light : lights_) {
      intensity_.push_back(light.power.cwiseProduct(light.brdf));
      intensity_luminance_.push_back(luminance(intensity_.back()));
      ends_.push_back(vpl_connection_end(context.world, light));
      end_shells_.push_back(context.world.convex_shells_holding(ends_.back()));
    }
    diagonal_ = scene_diagonal(context.scene, context.world);
    clamp_distance_ = options.vpl_clamp * diagonal_;
    max_geometric_ = vpl_max_geometric(clamp_distance_);
    const std::size_t pixels = static_cast<std::size_t>(context.scene.camera.width) * static_cast<std::size_t>(context.scene.camera.height);
    energy_.assign(pixels, 0.0);
    dropped_.assign(pixels, 0.0);
  }

  Color shade(const ShadingPoint& point, const Color& brdf, PixelRandom& random, PointVisibility& visibility) const override {
    Color radiance = Color::Zero();
    // What each segment is worth, only for a strategy that asks (PointVisibility::contributions).
    const bool report = visibility.wants_contributions();
    std::vector<Color>* direct_worth = nullptr;
    if (report) {
      thread_local std::vector<Color> buffer;
      buffer.clear();
      direct_worth = &buffer;
    }
    if (!context_.lights.empty()) radiance = direct_light(context_, point, random, visibility, direct_worth) / context_.options.shadow_rays;
    // Per-thread buffers, read through plain pointers in the loops (a thread_local vector's
    // fields would be reloaded on every iteration).
    thread_local std::vector<Vertex> ends;
    thread_local std::vector<unsigned> shells;
    thread_local std::vector<std::uint32_t> which;
    thread_local std::vector<std::int64_t> faces;
    thread_local std::vector<double> geometric, answers;
    const std::size_t count = lights_.size();
    geometric.resize(count), faces.resize(count), which.resize(count);
    double* const g = geometric.data();
    std::uint32_t* const w = which.data();
    vpl_geometry(point.position, point.hit->normal, arrays_, g, faces.data());
    std::size_t facing = 0;
    const std::int64_t* const f = faces.data();
    for (std::size_t i = 0; i < count; ++i) {
      w[facing] = static_cast<std::uint32_t>(i);
      facing += static_cast<std::size_t>(f[i] & 1);
    }
    ends.resize(facing), shells.resize(facing), answers.resize(facing);
    {
      Vertex* const e = ends.data();
      unsigned* const sh = shells.data();
      const Vertex* const from = ends_.data();
      const unsigned* const from_shells = end_shells_.data();
      for (std::size_t k = 0; k < facing; ++k) e[k] = from[w[k]], sh[k] = from_shells[w[k]];
    }
    point.stats->vpl_connections += facing;
    visibility.connections(ends, shells, answers);
    double energy = 0, dropped = 0;
    double r0 = radiance.x(), r1 = radiance.y(), r2 = radiance.z();
    const double* const a = answers.data();
    const Color* const intensity = intensity_.data();
    const double* const intensity_luminance = intensity_luminance_.data();
    const double max_geometric = max_geometric_;
    for (std::size_t k = 0; k < facing; ++k) {
      if (a[k] == 0) continue;
      const std::size_t i = w[k];
      const double clamped = std::min(g[i], max_geometric), weight = a[k] * clamped;
      r0 += weight * intensity[i].x(), r1 += weight * intensity[i].y(), r2 += weight * intensity[i].z();
      const double l = intensity_luminance[i] * a[k];
      energy += l * g[i];
      dropped += l * (g[i] - clamped);
    }
    radiance = Color(r0, r1, r2);
    if (report) {
      thread_local std::vector<double> worth;
      worth.clear();
      for (const Color& d : *direct_worth) worth.push_back(brdf.cwiseProduct(d).mean() / context_.options.shadow_rays);
      for (std::size_t k = 0; k < facing; ++k)
        worth.push_back(brdf.cwiseProduct(intensity[w[k]]).mean() * std::min(g[w[k]], max_geometric));
      visibility.contributions(worth);
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
  VplArrays arrays_{{}};
  std::vector<Color> intensity_;          // per VPL: power x BRDF
  std::vector<double> intensity_luminance_;
  bool given_ = false;
  double diagonal_ = 0, clamp_distance_ = 0, max_geometric_ = 0;
  // Per pixel, what the VPLs gave before clamping and what clamping dropped (luminance of
  // BRDF x intensity x G x visibility), summed in pixel order for a thread-independent figure.
  mutable std::vector<double> energy_, dropped_;
};

}  // namespace

std::vector<VirtualPointLight> integrator_vpls(const IntegratorContext& context) {
  const RenderOptions& options = context.options;
  if (options.virtual_point_lights) return *options.virtual_point_lights;
  return trace_virtual_point_lights(context.scene, context.world, {.paths = options.vpls, .bounces = options.bounces, .seed = options.vpl_seed});
}

double vpl_max_geometric(double clamp_distance) {
  return clamp_distance > 0 ? 1 / (clamp_distance * clamp_distance) : std::numeric_limits<double>::infinity();
}

std::unique_ptr<Integrator> make_vpl_integrator(const IntegratorContext& context) {
  return std::make_unique<VplIntegrator>(context);
}

}  // namespace visproxy
