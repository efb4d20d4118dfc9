// Direct illumination from area lights on Lambertian surfaces (Billen et al. eq. 21):
// M points on the lights by area, each segment's visibility from the strategy.

#include "visproxy/render/integrators/integrator.h"

namespace visproxy {
namespace {

class DirectIntegrator final : public Integrator {
 public:
  explicit DirectIntegrator(const IntegratorContext& context) : context_(context) {}

  Color shade(const ShadingPoint& point, const Color& brdf, PixelRandom& random, PointVisibility& visibility) const override {
    if (!visibility.wants_contributions())
      return brdf.cwiseProduct(direct_light(context_, point, random, visibility)) / context_.options.shadow_rays;
    thread_local std::vector<Color> worth;
    worth.clear();
    const Color radiance = brdf.cwiseProduct(direct_light(context_, point, random, visibility, &worth)) / context_.options.shadow_rays;
    thread_local std::vector<double> luminance;
    luminance.clear();
    for (const Color& w : worth) luminance.push_back(brdf.cwiseProduct(w).mean() / context_.options.shadow_rays);
    visibility.contributions(luminance);
    return radiance;
  }

 private:
  IntegratorContext context_;
};

}  // namespace

Color direct_light(const IntegratorContext& context, const ShadingPoint& point, PixelRandom& random, PointVisibility& visibility,
                   std::vector<Color>* worth) {
  const LightSampler& lights = context.lights;
  RenderStats& stats = *point.stats;
  const Vertex& x = point.position;
  Color radiance = Color::Zero();
  for (int s = 0; s < context.options.shadow_rays; ++s) {
    const LightSample y = lights.sample(random);
    const std::optional<LightGeometry> g = light_geometry(x, point.hit->normal, y);
    if (!g) continue;
    ++stats.shadow_rays;
    const double v = visibility.to_light(light_end(context.world, y, x));
    if (worth) worth->push_back((g->cos_x * g->cos_y / g->distance2 * lights.total_area()) * y.radiance);
    if (v != 0) radiance += (v * g->cos_x * g->cos_y / g->distance2 * lights.total_area()) * y.radiance;
  }
  return radiance;
}

std::unique_ptr<Integrator> make_direct_integrator(const IntegratorContext& context) {
  return std::make_unique<DirectIntegrator>(context);
}

}  // namespace visproxy
