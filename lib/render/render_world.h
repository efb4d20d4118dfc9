#pragma once
// The scene as Embree sees it when rendering: every instance's mesh, and for each instance
// the proxies the visibility modes use, in one device with shared per-mesh BVHs.

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "core/proxy_kind.h"
#include "mesh/sphere_set.h"
#include "scene/scene.h"
#include "trace/counting_bvh.h"

namespace visproxy {

/// One proxy's geometry for one scene mesh: triangles or spheres, in the mesh's own frame.
struct InstanceProxy {
  ProxyKind kind = ProxyKind::general;
  std::string spec;
  TriangleMesh mesh;
  std::vector<Sphere> spheres;  ///< sphere proxies (mesh empty)
};

/// The proxies of one instance by role (in its mesh's frame). Any may be missing: an
/// instance without a stochastic proxy stands in for itself; without an outside proxy its
/// mesh is its own outside proxy; without an inside proxy nothing is proved occluded.
struct MeshProxies {
  std::optional<InstanceProxy> stochastic;  ///< the proxy `--visibility stochastic` uses
  std::optional<InstanceProxy> outside;     ///< `--visibility bounds`: certainly-unoccluded test
  std::optional<InstanceProxy> inside;      ///< `--visibility bounds`: certainly-occluded test
};

struct SurfaceHit {
  Vertex position;
  Vertex normal;      ///< unit geometric normal, world space, facing the incoming ray
  int instance = -1;  ///< scene instance, or -1 for a light
  int light = -1;     ///< light index when a light was hit
  bool light_front = false;
  /// The instance's own mesh lies entirely on the far side of the tangent plane here (or
  /// in it): a shadow segment that leaves towards `normal` cannot meet it again. Known for
  /// meshes of up to 4096 triangles (walls, floors, boxes), false otherwise.
  bool own_mesh_behind = false;
};

/// What a shadow query should see of the instances.
struct InstanceFilter {
  int skip = -1;  ///< ignore this instance (-1: none)
  int only = -1;  ///< see only this instance (-1: all)
  /// Only instances whose bit (instance_bit) is set; instances sharing a bit (beyond 31)
  /// may be seen too, which keeps every use conservative.
  unsigned bits = 0x7FFFFFFFu;
};

/// The mask bit of an instance (bit i % 31).
unsigned instance_bit(std::size_t instance);

class RenderWorld {
 public:
  /// `proxies` has one entry per scene instance (same order), possibly empty. Proxies with
  /// the same spec on instances of the same mesh share one BVH. With `counting`, shadow
  /// queries run through CountingBvh (our traversal of Embree-built BVHs, double-precision
  /// primitive tests) and add their work to thread_counts(); camera rays still use Embree.
  RenderWorld(const Scene& scene, const std::vector<MeshProxies>& proxies, bool counting = false);

  /// The work of this thread's shadow queries so far (counting worlds only): one node per
  /// instance whose world box is tested, plus the nodes and primitives of its BVH.
  static TraversalCounts& thread_counts();
  bool counting() const;
  ~RenderWorld();
  RenderWorld(const RenderWorld&) = delete;
  RenderWorld& operator=(const RenderWorld&) = delete;

  /// The nearest surface or light along the ray, if any.
  std::optional<SurfaceHit> intersect(const Vertex& origin, const Vertex& direction) const;

  /// Whether the open segment is blocked by the exact geometry of the instances the filter
  /// lets through (lights never block).
  bool mesh_blocks(const Vertex& from, const Vertex& to, InstanceFilter filter = {}) const;
  /// The same against each instance's stochastic proxy (its mesh where it has none).
  bool proxy_blocks(const Vertex& from, const Vertex& to, InstanceFilter filter = {}) const;
  /// The same against the instances' outside (inside) proxies; instances without one are
  /// treated as blocking (outside) or as empty (inside), so both tests stay conservative.
  bool outside_blocks(const Vertex& from, const Vertex& to, InstanceFilter filter = {}) const;
  bool inside_blocks(const Vertex& from, const Vertex& to, InstanceFilter filter = {}) const;

  /// The kind of the union of every instance's stochastic proxy except `skip`'s: outside
  /// (inside) when each is outside (inside) or exact, general otherwise.
  ProxyKind stochastic_kind(int skip) const;
  /// World-space bounding box of an instance's mesh, and the sphere around its centre that
  /// holds every vertex (tighter than the box's for round meshes).
  const BoundingBox& instance_bounds(std::size_t instance) const;
  const Sphere& instance_sphere(std::size_t instance) const;

  /// Whether any instance has an inside proxy (else inside_blocks is always false).
  bool has_inside_proxies() const;
  /// Whether every instance other than `skip` has an outside proxy.
  bool outside_complete(int skip) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace visproxy
