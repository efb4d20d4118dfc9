#include "visproxy/render/world/virtual_point_lights.h"

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

Vertex vpl_connection_end(const RenderWorld& world, const VirtualPointLight& light) {
  return segment_end(world, light.position, light.normal, light.position + light.normal, light.distance);
}

double scene_diagonal(const Scene& scene, const RenderWorld& world) {
  BoundingBox box;
  for (std::size_t i = 0; i < scene.instances.size(); ++i) {
    const BoundingBox& b = world.instance_bounds(i);
    if (!b.empty()) box.extend(b.min), box.extend(b.max);
  }
  for (const AreaLight& light : scene.lights)
    for (const auto& t : light.triangles)
      for (const Vertex& p : t) box.extend(p);
  return box.empty() ? 0 : (box.max - box.min).norm();
}

VplGeometry vpl_geometry(const Vertex& x, const Vertex& n, const VirtualPointLight& light) {
  // cos_x cos_v / d^2 = (n . w) (-n_v . w) / d^4: no square root.
  // Written out as in vpl_geometry_soa below, so that both forms round alike.
  const double w0 = light.position.x() - x.x(), w1 = light.position.y() - x.y(), w2 = light.position.z() - x.z();
  const double along_x = n.x() * w0 + n.y() * w1 + n.z() * w2;
  const double along_v = -(light.normal.x() * w0 + light.normal.y() * w1 + light.normal.z() * w2);
  if (!(along_x > 0 && along_v > 0)) return {};
  const double d2 = w0 * w0 + w1 * w1 + w2 * w2;
  return {true, along_x * along_v / (d2 * d2)};
}

VplArrays::VplArrays(const std::vector<VirtualPointLight>& lights) {
  for (const VirtualPointLight& light : lights) {
    px.push_back(light.position.x()), py.push_back(light.position.y()), pz.push_back(light.position.z());
    nx.push_back(light.normal.x()), ny.push_back(light.normal.y()), nz.push_back(light.normal.z());
  }
}

namespace {

__attribute__((target_clones("avx2", "default"))) void vpl_geometry_soa(
    double x0, double x1, double x2, double n0, double n1, double n2, const double* __restrict px, const double* __restrict py,
    const double* __restrict pz, const double* __restrict nx, const double* __restrict ny, const double* __restrict nz, std::size_t count,
    double* __restrict geometric, std::int64_t* __restrict faces) {
  // Selects rather than branches, so that the loop vectorises.
  for (std::size_t i = 0; i < count; ++i) {
    const double w0 = px[i] - x0, w1 = py[i] - x1, w2 = pz[i] - x2;
    const double along_x = n0 * w0 + n1 * w1 + n2 * w2;
    const double along_v = -(nx[i] * w0 + ny[i] * w1 + nz[i] * w2);
    const double d2 = w0 * w0 + w1 * w1 + w2 * w2;
    const double g = along_x * along_v / (d2 * d2);
    const std::int64_t facing = (along_x > 0 ? std::int64_t{-1} : 0) & (along_v > 0 ? std::int64_t{-1} : 0);
    faces[i] = facing;
    geometric[i] = facing != 0 ? g : 0.0;
  }
}

}  // namespace

void vpl_geometry(const Vertex& x, const Vertex& n, const VplArrays& lights, double* geometric, std::int64_t* faces) {
  vpl_geometry_soa(x.x(), x.y(), x.z(), n.x(), n.y(), n.z(), lights.px.data(), lights.py.data(), lights.pz.data(), lights.nx.data(),
                   lights.ny.data(), lights.nz.data(), lights.size(), geometric, faces);
}

}  // namespace visproxy
