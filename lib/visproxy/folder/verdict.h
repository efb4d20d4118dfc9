#pragma once
// `visproxy verify`: does each proxy keep the promise its kind makes?

#include <nlohmann/json.hpp>

#include "visproxy/folder/proxy_folder.h"
#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy {

struct VerifyOptions {
  std::size_t hausdorff_samples = 20000;  ///< general proxies: area-uniform samples per surface
  std::uint64_t seed = 1;
};

/// Checks one proxy against the mesh it was built from, exactly, from the files alone:
/// nothing but the entry's kind is read from the manifest (not the spec, the method or
/// what the builder reported), so a proxy file edited by hand is judged as it is.
///  - outside (contains the mesh), check_containment(proxy, mesh): the proxy closed (every
///    edge used as often in each direction), every mesh vertex inside or on it by exact
///    winding numbers, and every mesh triangle either touching no proxy triangle or lying
///    in one convex part of the proxy (convexity tested with exact predicates);
///  - inside, meshes (lies within the mesh): the mesh closed, and the proxy's solid within
///    the mesh's (proxy closed, its vertices inside, no triangles touching, no mesh vertex
///    inside the proxy); spheres: each centre strictly inside and each radius at most the
///    exact distance from the centre to the surface. A closed mesh may self-intersect or
///    have non-manifold edges: its solid is where the winding number is not zero;
///  - general: no claim; the sampled two-sided Hausdorff distance is recorded.
/// Returns the manifest's `verify` object:
///   {"claim", "holds", "margin", "seconds", "checked", "counterexample", ...}
/// where `margin` is the smallest distance between the contained surface's vertices and
/// the container's surface in world units (null for general proxies), and
/// `counterexample` is null or one line naming the first vertex, triangle or sphere that
/// breaks the claim.
/// The object also records what the verdict is about: the entry's `kind`, its `file` and
/// `files`, and `mesh_hash` and `proxy_hash` (content_hash of the mesh and
/// proxy_content_hash of the proxy). A proxy whose other files do not hold its geometry
/// (ProxyGeometry::files_problem) does not hold, whatever its kind: the folder ships them.
nlohmann::json verify_proxy(const TriangleMesh& mesh, const nlohmann::json& manifest, const nlohmann::json& entry,
                            const ProxyGeometry& proxy, const VerifyOptions& options = {});

/// content_hash of a proxy's geometry: its triangles, and its spheres' bytes mixed in.
std::string proxy_content_hash(const ProxyGeometry& proxy);

/// The claim a kind makes, as verify_proxy records it: "contains the mesh", "lies within
/// the mesh", "none".
std::string_view kind_claim(ProxyKind kind);

/// Whether a recorded `verify` object (verify_proxy's) is a proof of the entry's claim, as
/// the entry states it now, for these very files: it holds; it was made for the entry's
/// kind (its claim is that kind's), file and files; its mesh and proxy hashes are those of
/// `mesh` and `proxy`; and the proxy's other files hold its geometry. False for a general
/// entry, a verdict for another kind (a manifest whose kinds were swapped by hand), for
/// other files (a proxy edited or swapped since, a verdict copied from another proxy) or
/// none.
bool verdict_proves(const nlohmann::json& verify, const nlohmann::json& entry, const TriangleMesh& mesh,
                    const ProxyGeometry& proxy);

}  // namespace visproxy
