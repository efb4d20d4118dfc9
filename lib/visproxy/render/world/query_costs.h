#pragma once
// A deterministic model of what the renderer's queries cost, for choices that weigh a
// proxy's cost against the mesh's (the learned control variate): timings would make the
// image depend on the machine's load, counted traversals need a second world.
//
// A query pays kQueryWork, and for each instance whose world box the segment meets,
// log2(2 + n) for the n primitives (triangles, balls, clipping planes) of the geometry it
// meets there: the depth of a BVH over them, which a ray that enters the box descends.
// A camera sample pays for its camera ray the same way, and kShadingWork for shading.
// The unit is about one BVH level.

#include "visproxy/render/world/render_world.h"

namespace visproxy {

inline constexpr double kQueryWork = 2;    ///< a query's own work: the ray's setup and the top level
inline constexpr double kShadingWork = 10;  ///< a camera sample's shading and light sampling

/// The modelled work of one shadow segment from a point on instance `own`.
struct SegmentQueryCosts {
  double camera = 0;      ///< the camera ray that found the point, and its shading
  double exact = 0;       ///< the segment against every instance's mesh
  double proxy = 0;       ///< the proxy query: the own mesh and the others' stochastic proxies (split), or every proxy
  double correction = 0;  ///< a correction: the meshes the proxies stood for
};

/// `camera` is the camera's position; the segment runs from `from` (a point found by the
/// camera ray, on instance `own`) to `to`. `split`: visibility splitting (the own instance
/// traced exactly as part of the proxy query; a correction traces only the others).
SegmentQueryCosts segment_query_costs(const RenderWorld& world, const Vertex& camera, const Vertex& from, const Vertex& to, int own,
                                      bool split);

}  // namespace visproxy
