#pragma once
// Integrators: the light a shading point reflects towards the camera, with every shadow
// segment answered by a visibility strategy (render/visibility).

#include <memory>
#include <vector>

#include "visproxy/image/image.h"
#include "visproxy/render/visibility/visibility.h"

namespace visproxy {

class Integrator {
 public:
  virtual ~Integrator() = default;
  /// Reflected radiance at `point` (a surface, not a light) towards the camera, for a
  /// Lambertian BRDF `brdf` (albedo / pi). Light samples come from `random`; the
  /// visibility strategy has been begun at `point`.
  virtual Color shade(const ShadingPoint& point, const Color& brdf, PixelRandom& random, PointVisibility& visibility) const = 0;
  /// One line per fact a reader of the image needs (the VPLs made, the energy clamped), for
  /// the stats.
  virtual nlohmann::json describe() const { return nlohmann::json::object(); }
  /// The integrator's own map after `passes` camera samples per pixel (lightcuts: the mean
  /// cut size per pixel), or an empty image.
  virtual Image cut_map(int passes) const {
    (void)passes;
    return {};
  }
};

struct IntegratorContext {
  const Scene& scene;
  const RenderWorld& world;
  const RenderOptions& options;
  const LightSampler& lights;
};

/// The sum over M light samples (context.options.shadow_rays) of Le V cos_x cos_y / d^2
/// times the lights' total area: divided by M, an unbiased estimate of the irradiance the
/// area lights give `point`. With `worth`, appends each segment's term at V = 1, in the
/// order the segments were asked.
Color direct_light(const IntegratorContext& context, const ShadingPoint& point, PixelRandom& random, PointVisibility& visibility,
                   std::vector<Color>* worth = nullptr);

/// The VPLs an integrator shades: context.options.virtual_point_lights when given, else
/// those its light paths leave (vpls, bounces, vpl_seed).
std::vector<VirtualPointLight> integrator_vpls(const IntegratorContext& context);
/// The clamp of the VPLs' geometric term for a clamp distance: 1 / distance^2, or no clamp
/// (infinity) for 0.
double vpl_max_geometric(double clamp_distance);

/// The integrator `context.options` asks for (as make_visibility chooses the strategy).
std::unique_ptr<Integrator> make_integrator(const IntegratorContext& context);

/// Direct illumination from the area lights (Billen et al. eq. 21): M light samples by area.
std::unique_ptr<Integrator> make_direct_integrator(const IntegratorContext& context);
/// Instant radiosity: M light samples plus every virtual point light.
std::unique_ptr<Integrator> make_vpl_integrator(const IntegratorContext& context);
/// Lightcuts over K points per area light (and the VPLs), with optional visibility bounds.
std::unique_ptr<Integrator> make_lightcuts_integrator(const IntegratorContext& context);

}  // namespace visproxy
