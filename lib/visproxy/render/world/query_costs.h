#pragma once
// A deterministic model of what the renderer's queries cost, for choices that weigh a
// proxy's cost against the mesh's (the learned control variate): timings would make the
// image depend on the machine's load, counted traversals need a second world.
//
// A query pays kQueryWork, and for each instance whose world box the segment meets,
// log2(2 + n) for the n primitives (triangles, balls, clipping planes) of the geometry it
// meets there: the depth of a BVH over them, which a ray that enters the box descends;
// balls and clipped solids, which visproxy's own code tests outside Embree's SIMD kernels,
// add kOwnTestWork. A camera sample pays for its camera ray the same way, and kShadingWork
// for shading. The unit is about one BVH level.
//
// The constants were fit to renders of the prediction scenes (apps/bench/README.md): exact
// renders at 1 and 4 shadow rays per sample put a segment at 0.31-0.69 of the rest of a
// sample (the model: 0.59-0.68), and the oriented boxes of cow-field, which `--count`
// shows doing 0.6x the mesh's traversal work, cost as much time as the meshes.

#include "visproxy/render/world/render_world.h"

namespace visproxy {

/// The modelled work of a segment that enters an instance's box: of its mesh, and of its
/// stochastic proxy.
struct InstanceWork {
  double mesh = 0, proxy = 0;
};
InstanceWork instance_work(const RenderWorld& world, std::size_t instance);

inline constexpr double kQueryWork = 2;    ///< a query's own work: the ray's setup and the top level
inline constexpr double kShadingWork = 10;  ///< a camera sample's shading and light sampling
inline constexpr double kOwnTestWork = 8;   ///< balls and clipped solids: tested outside Embree

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
/// The same without the camera ray's and shading's part (camera = 0): for many segments
/// from one point.
SegmentQueryCosts shadow_segment_costs(const RenderWorld& world, const Vertex& from, const Vertex& to, int own, bool split);
/// That part alone: the camera ray from `camera` that found `from`, and its shading.
double camera_sample_work(const RenderWorld& world, const Vertex& camera, const Vertex& from);

}  // namespace visproxy
