#pragma once
// `visproxy verify`: does each proxy keep the promise its kind makes?

#include <nlohmann/json.hpp>

#include "evaluate/proxy_folder.h"
#include "mesh/triangle_mesh.h"

namespace visproxy {

struct VerifyOptions {
  std::size_t hausdorff_samples = 20000;  ///< general proxies: area-uniform samples per surface
  std::uint64_t seed = 1;
};

/// Checks one proxy against the mesh it was built from, exactly:
///  - outside (contains the mesh): every vertex of the mesh inside or on the proxy by exact
///    winding numbers; for proxies that are not convex, also no mesh triangle touching the
///    proxy's surface; for convex proxies built per component, every mesh triangle inside
///    one convex part;
///  - inside, meshes (lies within the mesh): the same with the roles swapped, which needs a
///    closed mesh; spheres: each centre strictly inside and each radius at most the exact
///    distance from the centre to the surface;
///  - general: no claim; the sampled two-sided Hausdorff distance is recorded.
/// Returns the manifest's `verify` object:
///   {"claim", "holds", "margin", "seconds", "checked", "counterexample", ...}
/// where `margin` is the smallest distance between the contained surface's vertices and
/// the container's surface in world units (null for general proxies), and
/// `counterexample` is null or one line naming the first vertex, triangle or sphere that
/// breaks the claim.
nlohmann::json verify_proxy(const TriangleMesh& mesh, const nlohmann::json& manifest, const nlohmann::json& entry,
                            const ProxyGeometry& proxy, const VerifyOptions& options = {});

}  // namespace visproxy
