#include "render/virtual_point_lights.h"

#include <cmath>
#include <numbers>

namespace visproxy {

std::vector<VirtualPointLight> trace_virtual_point_lights(const Scene& scene, const RenderWorld& world, const VplOptions& options) {
  std::vector<VirtualPointLight> lights;
  const LightSampler sampler(scene);
  if (sampler.empty() || options.paths <= 0 || options.bounces <= 0) return lights;
  for (int i = 0; i < options.paths; ++i) {
    PixelRandom random(options.seed ^ kLightPathStream, static_cast<std::uint64_t>(i), 0);
    const LightSample y = sampler.sample(random);
    // Lights emit to the side their winding's normal points to (two-sided ones to both).
    Vertex emit = y.normal;
    double sides = 1;
    if (y.two_sided) {
      sides = 2;
      if (random.uniform() < 0.5) emit = -y.normal;
    }
    Color power = y.radiance * (sampler.total_area() * std::numbers::pi * sides / options.paths);
    const double u1 = random.uniform(), u2 = random.uniform();
    Vertex direction = cosine_direction(emit, u1, u2);
    Vertex origin = y.position + world.surface_offset(y.position, 0.0) * emit;
    for (int bounce = 1; bounce <= options.bounces;) {
      std::optional<SurfaceHit> hit = world.intersect(origin, direction);
      // Through lights: they emit, but neither reflect nor block.
      for (int pass_through = 0; hit && hit->light >= 0 && pass_through < 64; ++pass_through) {
        origin = hit->position + world.surface_offset(hit->position, hit->distance) * direction;
        hit = world.intersect(origin, direction);
      }
      if (!hit || hit->light >= 0) break;
      const Color albedo = scene.instances[static_cast<std::size_t>(hit->instance)].albedo;
      lights.push_back({hit->position, hit->normal, power, albedo / std::numbers::pi, hit->instance, bounce, hit->distance});
      if (++bounce > options.bounces) break;
      power = power.cwiseProduct(albedo);
      if (power.maxCoeff() <= 0) break;
      origin = hit->position + world.surface_offset(hit->position, hit->distance) * hit->normal;
      const double v1 = random.uniform(), v2 = random.uniform();
      direction = cosine_direction(hit->normal, v1, v2);
    }
  }
  return lights;
}

VplGeometry vpl_geometry(const Vertex& x, const Vertex& n, const VirtualPointLight& light) {
  // cos_x cos_v / d^2 = (n . w) (-n_v . w) / d^4: no square root.
  const Vertex w = light.position - x;
  const double along_x = n.dot(w), along_v = -light.normal.dot(w);
  if (!(along_x > 0 && along_v > 0)) return {};
  const double d2 = w.squaredNorm();
  return {true, along_x * along_v / (d2 * d2)};
}

}  // namespace visproxy
