// The integrator a render asks for.

#include "visproxy/render/integrators/integrator.h"

namespace visproxy {

std::unique_ptr<Integrator> make_integrator(const IntegratorContext& context) {
  switch (context.options.integrator) {
    case IntegratorKind::direct: return make_direct_integrator(context);
    case IntegratorKind::vpl: return make_vpl_integrator(context);
    case IntegratorKind::lightcuts: return make_lightcuts_integrator(context);
  }
  return make_direct_integrator(context);
}

}  // namespace visproxy
