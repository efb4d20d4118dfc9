#include "visproxy/render/options/render_options.h"

#include <cmath>
#include <string>

namespace visproxy {

template <>
const std::vector<std::pair<std::string_view, VisibilityMode>>& choice_names<VisibilityMode>() {
  static const std::vector<std::pair<std::string_view, VisibilityMode>> names{
      {"exact", VisibilityMode::exact},
      {"stochastic", VisibilityMode::stochastic},
      {"bounds", VisibilityMode::bounds},
      {"spheres", VisibilityMode::spheres}};
  return names;
}
template <>
const std::vector<std::pair<std::string_view, IntegratorKind>>& choice_names<IntegratorKind>() {
  static const std::vector<std::pair<std::string_view, IntegratorKind>> names{
      {"direct", IntegratorKind::direct}, {"vpl", IntegratorKind::vpl}, {"lightcuts", IntegratorKind::lightcuts}};
  return names;
}
template <>
const std::vector<std::pair<std::string_view, SelfShadow>>& choice_names<SelfShadow>() {
  static const std::vector<std::pair<std::string_view, SelfShadow>> names{
      {"heuristic", SelfShadow::heuristic}, {"exact", SelfShadow::exact}, {"none", SelfShadow::none}};
  return names;
}
template <>
const std::vector<std::pair<std::string_view, ProbabilityMode>>& choice_names<ProbabilityMode>() {
  static const std::vector<std::pair<std::string_view, ProbabilityMode>> names{{"equal", ProbabilityMode::equal},
                                                                               {"adaptive", ProbabilityMode::adaptive},
                                                                               {"learned", ProbabilityMode::learned},
                                                                               {"optimal", ProbabilityMode::optimal}};
  return names;
}
template <>
const std::vector<std::pair<std::string_view, StochasticEstimator>>& choice_names<StochasticEstimator>() {
  static const std::vector<std::pair<std::string_view, StochasticEstimator>> names{
      {"eq8", StochasticEstimator::term_choice}, {"control-variate", StochasticEstimator::control_variate}};
  return names;
}
template <>
const std::vector<std::pair<std::string_view, VisibilityBounds>>& choice_names<VisibilityBounds>() {
  static const std::vector<std::pair<std::string_view, VisibilityBounds>> names{{"none", VisibilityBounds::none},
                                                                                {"lower", VisibilityBounds::lower},
                                                                                {"upper", VisibilityBounds::upper},
                                                                                {"both", VisibilityBounds::both}};
  return names;
}

void validate(const RenderOptions& options) {
  auto fail = [](const std::string& problem) { throw Error("render options: " + problem); };
  if (options.spp < 1) fail("spp (camera samples per pixel) must be at least 1, not " + std::to_string(options.spp));
  if (options.shadow_rays < 1) fail("shadow_rays must be at least 1, not " + std::to_string(options.shadow_rays));
  if (options.probe_passes < 0) fail("probe_passes must not be negative");
  if (!(options.seconds >= 0) || !std::isfinite(options.seconds)) fail("seconds must be a finite number, 0 or more");
  if (!(options.probability_floor >= 0 && options.probability_floor <= 1.0 / 3))
    fail("probability_floor must lie in [0, 1/3]");
  if (!(options.correction_scale > 0) || !std::isfinite(options.correction_scale))
    fail("correction_scale must be positive");
  if (options.integrator == IntegratorKind::lightcuts) {
    if (options.visibility != VisibilityMode::exact)
      fail("lightcuts traces its representatives exactly: use visibility exact (its proofs are the visibility bounds)");
    if (options.light_points < 1) fail("light_points must be at least 1, not " + std::to_string(options.light_points));
    if (!(options.lightcut.error >= 0) || !std::isfinite(options.lightcut.error))
      fail("the lightcut error must be a finite number, 0 or more");
    if (options.lightcut.max_cut < 1)
      fail("max_cut must be at least 1, not " + std::to_string(options.lightcut.max_cut));
  }
  if (options.integrator == IntegratorKind::vpl ||
      (options.integrator == IntegratorKind::lightcuts && options.lightcut_vpls)) {
    if (!options.virtual_point_lights && options.vpls < 1)
      fail("vpls (light paths) must be at least 1, not " + std::to_string(options.vpls));
    if (options.bounces < 1) fail("bounces must be at least 1, not " + std::to_string(options.bounces));
    if (!(options.vpl_clamp >= 0) || !std::isfinite(options.vpl_clamp))
      fail("vpl_clamp must be a finite number, 0 or more");
    if (options.virtual_point_lights)
      for (const VirtualPointLight& light : *options.virtual_point_lights)
        if (!light.position.allFinite() || !light.power.allFinite() || !light.brdf.allFinite() ||
            (light.power.array() < 0).any() || (light.brdf.array() < 0).any() ||
            !(std::abs(light.normal.norm() - 1) < 1e-6) || light.bounce < 1 || !(light.distance >= 0) ||
            !std::isfinite(light.distance))
          fail(
              "virtual point lights need finite positions, unit normals, finite, non-negative power and BRDF, a bounce "
              "of at least 1 and a finite, non-negative distance");
  }
  if (options.visibility != VisibilityMode::stochastic) return;
  const bool control_variate = options.estimator == StochasticEstimator::control_variate;
  if (options.probabilities == ProbabilityMode::learned && !control_variate)
    fail("learned probabilities need the control-variate estimator");
  if (options.probabilities == ProbabilityMode::optimal && control_variate)
    fail("optimal probabilities are eq. 8's; the control variate learns its own (learned)");
  if (options.probabilities == ProbabilityMode::adaptive && options.probe_rays < 1)
    fail("adaptive probabilities need at least one probe ray");
  if (options.probabilities != ProbabilityMode::equal && !(options.probability_floor > 0))
    fail(
        "probability_floor must be positive with adaptive, learned or optimal probabilities: a ray type the probes or a "
        "pixel's corrections have not seen would get probability 0, and the estimate would be biased wherever it "
        "occurs");
}

}  // namespace visproxy
