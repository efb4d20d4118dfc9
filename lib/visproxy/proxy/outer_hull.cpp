// Outer hull: an alpha wrap decimated by conservative edge collapses (conservative_decimation.cpp).
//
//   C. Portaneri et al., "Alpha Wrapping with an Offset", 2022: the starting surface.

#include "visproxy/proxy/outer_hull.h"

#include <cmath>
#include <string>

#include "visproxy/core/errors.h"
#include "visproxy/proxy/alpha_wrap_shared.h"
#include "visproxy/proxy/detail/conservative_decimation.h"

namespace visproxy {
namespace {

void require_positive(double value, const char* name) {
  if (!(std::isfinite(value) && value > 0))
    throw InvalidInputError("", std::string("outer hull: ") + name + " must be a positive finite number, got " +
                                    std::to_string(value));
}

}  // namespace

OuterHullResult build_outer_hull(const TriangleMesh& input, const OuterHullOptions& options) {
  if (options.max_triangles < 4)
    throw InvalidInputError("", "outer hull: max_triangles must be at least 4 (a closed surface), got " +
                                    std::to_string(options.max_triangles));
  require_positive(options.wrap_alpha_relative, "wrap_alpha_relative");
  require_positive(options.wrap_offset_relative, "wrap_offset_relative");
  if (!(options.clearance_relative >= 0 && options.clearance_relative < 0.1))
    throw InvalidInputError("", "outer hull: clearance_relative must be in [0, 0.1), got " +
                                    std::to_string(options.clearance_relative));

  AlphaWrapOptions wrap_options{.alpha_relative = options.wrap_alpha_relative,
                                .offset_relative = options.wrap_offset_relative};
  detail::check_alpha_wrap_input(input, wrap_options);
  // The input's BVH serves the wrap's queries and then the decimation's checks.
  const detail::ConservativeInput geometry(input);
  AlphaWrapResult wrap = detail::build_alpha_wrap(input, wrap_options, geometry.triangles(), geometry.degenerate());
  for (int attempt = 1; !geometry.starts_conservative(wrap.mesh, detail::InputSide::inside); ++attempt) {
    if (attempt == 4)
      throw Error("outer hull: the alpha wrap is not a closed, embedded surface clear of the input, even with 8 "
                  "times the offset");
    wrap_options.offset_relative *= 2;
    wrap = detail::build_alpha_wrap(input, wrap_options, geometry.triangles(), geometry.degenerate());
  }

  OuterHullResult result;
  result.wrap_triangles = wrap.mesh.triangles.size();
  result.wrap_alpha_world = wrap.alpha_world;
  result.wrap_offset_world = wrap.offset_world;
  const double diagonal = bounding_box(input).diagonal();
  result.clearance_world = options.clearance_relative * diagonal;
  if (wrap.mesh.triangles.size() <= options.max_triangles) {
    result.mesh = std::move(wrap.mesh);
  } else {
    auto decimate = [&](double clearance) {
      detail::ConservativeDecimator decimator(wrap.mesh, geometry);
      decimator.keep_clear_by(clearance);
      decimator.collapse_edges(options.max_triangles);
      for (int stage = 0; stage < 3 && decimator.triangle_count() > options.max_triangles; ++stage) {
        decimator.move_towards_input();
        decimator.collapse_edges(options.max_triangles);
      }
      decimator.move_towards_input();
      return decimator.result();
    };
    // With the clearance asked of every new triangle first; if that leaves the budget
    // unreached, again with none (only the exact checks).
    result.mesh = decimate(result.clearance_world);
    if (result.mesh.triangles.size() > options.max_triangles && result.clearance_world > 0) result.mesh = decimate(0);
  }
  result.clearance_kept = geometry.keeps_clear(result.mesh, result.clearance_world);
  result.reached_target = result.mesh.triangles.size() <= options.max_triangles;
  result.max_distance_to_input_world = geometry.distance_bound(result.mesh, diagonal / 100);
  return result;
}

}  // namespace visproxy
