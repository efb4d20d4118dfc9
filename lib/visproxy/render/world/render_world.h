#pragma once
// The scene as Embree sees it when rendering: every instance's mesh, and for each instance
// the proxies the visibility modes use, in one device with shared per-mesh BVHs.

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "visproxy/core/proxy_kind.h"
#include "visproxy/mesh/sphere_set.h"
#include "visproxy/scene/scene.h"
#include "visproxy/trace/counting_bvh.h"

namespace visproxy {

/// One proxy's geometry for one scene mesh: triangles or spheres, in the mesh's own frame.
struct InstanceProxy {
  ProxyKind kind = ProxyKind::general;
  std::string spec;
  TriangleMesh mesh;
  std::vector<Sphere> spheres;  ///< sphere proxies (mesh empty)
  /// The claim of `kind` is proved for this mesh: `visproxy verify` (verify_proxy) found it
  /// to hold, checked against these very files. Outside and inside proxies that are not
  /// proved are used as general proxies: no shortcut and no zero probability rests on them.
  bool proved = false;
};

/// The proxies of one instance by role (in its mesh's frame). Any may be missing: an
/// instance without a stochastic proxy stands in for itself (traced exactly, V' = V);
/// without an outside proxy its mesh is its own outside proxy; without an inside proxy
/// nothing is proved occluded.
struct MeshProxies {
  std::optional<InstanceProxy> stochastic;  ///< the proxy `--visibility stochastic` uses
  std::optional<InstanceProxy> outside;     ///< `--visibility bounds`: certainly-unoccluded test
  std::optional<InstanceProxy> inside;      ///< `--visibility bounds`: certainly-occluded test
};

struct SurfaceHit {
  Vertex position;
  double distance = 0;  ///< along the ray, world units (the ray's direction is a unit vector)
  Vertex normal;      ///< unit geometric normal, world space, facing the incoming ray
  int instance = -1;  ///< scene instance, or -1 for a light
  int light = -1;     ///< light index when a light was hit
  bool light_front = false;
  /// The instance's own mesh lies entirely behind the hit triangle's own plane (or in it,
  /// up to `own_plane.reach`), seen from the side the camera ray came from. Known for meshes
  /// of up to 4096 triangles (walls, floors, boxes), false otherwise. Not a test of a
  /// segment by itself: use own_mesh_clear_of().
  bool own_mesh_behind = false;
  /// The hit triangle's plane, exactly as the mesh's double-precision vertices and the
  /// instance's transform give it (never Embree's float normal, which a sliver triangle
  /// can tilt far off), in world space.
  struct OwnPlane {
    Vertex normal = Vertex::Zero();  ///< unit, towards the side the camera ray came from
    Vertex anchor = Vertex::Zero();  ///< a vertex of the triangle
    double reach = 0;        ///< how far in front of the plane the mesh's vertices may lie (world units)
    double near_margin = 0;  ///< how far in front a segment's start must lie: reach, a quarter of the surface offset, rounding
    double far_margin = 0;   ///< how far in front its end must lie: reach, the instance's float rounding bound, rounding
    double height(const Vertex& p) const { return normal.dot(p - anchor); }
  } own_plane;
  /// Whether the segment from `from` (the shading point moved off this surface) to `to`
  /// certainly misses the instance's own mesh, exactly and in Embree's float tests: the
  /// mesh lies behind the exact plane, and both ends lie in front of it by the margins.
  bool own_mesh_clear_of(const Vertex& from, const Vertex& to) const {
    return own_mesh_behind && own_plane.height(from) > own_plane.near_margin && own_plane.height(to) > own_plane.far_margin;
  }
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

/// How RenderWorld clusters an instance's occluder balls (cluster_spheres): clusters of at
/// most 32, headed 4 at a time by a bound of theirs (measured on the armadillo room with 100
/// and 1000 balls: faster than one level of 16, 32 or 64, and than clusters of 8 headed 4
/// at a time).
inline constexpr std::size_t kOccluderClusterSize = 32, kOccluderClusterGroup = 4;

struct RenderWorldOptions {
  /// Shadow queries run through CountingBvh (our traversal of Embree-built BVHs,
  /// double-precision primitive tests) and add their work to thread_counts(); camera rays
  /// still use Embree.
  bool counting = false;
  /// Use Embree's ray masks to skip instances, when the device supports them (Debian's
  /// Embree does); otherwise, or with false, a filter function decides every hit.
  bool ray_masks = true;
  /// Keep each instance's geometry in world space for proofs about whole shafts and cones
  /// (instance_solids(): lightcuts' cluster bounds). Off by default: it copies every mesh.
  bool keep_solids = false;
  /// For scenes of at most kSplitScenesUpTo instances: per instance, top scenes of its own
  /// mesh and every other instance's stochastic (and outside) proxy, so that split_blocks()
  /// answers most segments with one traversal (split_blocks() answers the same without
  /// them). Not built for counting worlds.
  bool split_scenes = true;
};

/// The most instances for which RenderWorld builds split scenes (one per instance, each
/// holding every instance once).
inline constexpr std::size_t kSplitScenesUpTo = 31;

/// What blocks a shadow segment from a point on an instance, when the instance's own mesh
/// is traced exactly and the rest of the scene through its stochastic proxies (visibility
/// splitting, eq. 27 of Billen et al.).
enum class SplitAnswer {
  clear,         ///< neither the own mesh nor another instance's proxy
  own_blocks,    ///< the own mesh (whatever the proxies answer)
  proxy_blocks,  ///< another instance's proxy, and not the own mesh
};

/// Which proxies of the other instances split_blocks() asks: their stochastic proxies (as
/// proxy_blocks), or their outside proxies (as outside_blocks).
enum class SplitProxies { stochastic, outside };

/// What proofs about a shaft or a cone of segments (rather than one segment) may use of an
/// instance, in world space, after the same checks the segment proofs make. Every
/// separation or crossing proved against these must hold by `pad`, the instance's bound on
/// Embree's float rounding, so that the proof also holds for the rays Embree traces.
struct InstanceSolids {
  double pad = 0;      ///< world units
  TriangleMesh mesh;   ///< the instance's own triangles
  /// Triangles whose solid holds the mesh: its outside proxy (proved, and usable by bounds);
  /// empty when the mesh is its own outside solid (`outside_is_mesh`: use `mesh`). A shaft that meets none of them misses the
  /// mesh only if the shaft holds a point outside that solid: a convex solid (`outside_planes`
  /// not empty: its face planes, outward unit normals) shows it by a plane, a traced proxy
  /// by a point on a light (`lights_outside_outside`: every light lies outside its solid).
  TriangleMesh outside;
  bool outside_is_mesh = true;
  std::vector<std::pair<Vertex, double>> outside_planes;
  bool lights_outside_outside = false;
  /// Proved inside proxies, usable because every light lies outside the mesh's solid: balls
  /// (shrunk by the rounding bound, radius scaled by the transform's least stretch) and
  /// triangles (kept clear of the mesh by the rounding bound). A segment from a point on a
  /// light that enters one is blocked by the mesh.
  std::vector<Sphere> inside_spheres;
  TriangleMesh inside;
};

/// The scene as shadow and camera rays see it, with every proof the visibility modes rely
/// on checked before it is used:
///  - Every proxy is a solid. Closed convex proxies of at most 64 face planes are clipped
///    as solids (ConvexPolytope); proxies Embree traces as surfaces answer "miss" only when
///    the segment crosses none of their faces, which proves the segment outside the solid
///    only because one end, the light's, is: a proxy is used as an outside (or, for its
///    mesh, inside) proxy only when every light lies outside its solid (outside proxies) or
///    outside the mesh's solid (inside proxies), by a rounding margin. Shadow segments must
///    therefore end on a light.
///  - Only proved proxies (InstanceProxy::proved) keep their kind.
///  - The proofs are made in double; Embree works in float. Every point is handed to Embree
///    relative to the scene's centre and every mesh relative to its own, so that rounding
///    is relative to the scene's and the object's extent, not to their distance from the
///    origin; proxies are then padded by a bound on that rounding: convex outside proxies
///    pushed out (clipped ones) or scaled about their centre (traced ones), other outside
///    proxies required to keep that distance from the mesh, inside spheres shrunk.
/// A proxy that fails a condition is used as a general proxy (and not by bounds), and
/// notes() says why.
class RenderWorld {
 public:
  /// `proxies` has one entry per scene instance (same order), possibly empty. Proxies with
  /// the same spec on instances of the same mesh share one BVH.
  RenderWorld(const Scene& scene, const std::vector<MeshProxies>& proxies, const RenderWorldOptions& options = {});

  /// The work of this thread's shadow queries so far (counting worlds only): one node per
  /// instance whose world box is tested, plus the nodes and primitives of its BVH.
  static TraversalCounts& thread_counts();
  bool counting() const;
  ~RenderWorld();
  RenderWorld(const RenderWorld&) = delete;
  RenderWorld& operator=(const RenderWorld&) = delete;

  /// The nearest surface or light along the ray (unit direction), if any.
  std::optional<SurfaceHit> intersect(const Vertex& origin, const Vertex& direction) const;

  /// How far to move a point off the surface it was found on, along the normal, so that
  /// rays leaving it do not meet that surface again through float rounding: 8 float ulps of
  /// the point's coordinates (relative to the scene's centre) plus of the distance the ray
  /// that found it travelled (pbrt's approach, with Embree's single precision). World units.
  double surface_offset(const Vertex& point, double distance) const;

  /// Whether the open segment is blocked by the exact geometry of the instances the filter
  /// lets through (lights never block).
  bool mesh_blocks(const Vertex& from, const Vertex& to, InstanceFilter filter = {}) const;
  /// mesh_blocks for a group of segments from one origin: blocked[i] for from to ends[i]
  /// (blocked.size() == ends.size()). Traced as packets of 8 (or 4) rays where Embree has
  /// them natively; the answers equal those of single queries.
  /// `lane_bits`, if given, narrows the instances each segment sees (lane_bits[i] & filter.bits).
  void mesh_blocks(const Vertex& from, std::span<const Vertex> ends, std::span<std::uint8_t> blocked, InstanceFilter filter = {},
                   std::span<const unsigned> lane_bits = {}) const;
  /// The packet width mesh_blocks of a group uses (1: single rays).
  int packet_width() const;
  /// The same against each instance's stochastic proxy (its mesh where it has none). The
  /// segment must end on a light (`to`) for the proxies' kinds to hold.
  bool proxy_blocks(const Vertex& from, const Vertex& to, InstanceFilter filter = {}) const;
  /// The same against the instances' outside (inside) proxies; instances without a usable
  /// one are their own outside proxy (exact) or have no inside proxy, so both tests stay
  /// conservative for segments that end on a light.
  bool outside_blocks(const Vertex& from, const Vertex& to, InstanceFilter filter = {}) const;
  bool inside_blocks(const Vertex& from, const Vertex& to, InstanceFilter filter = {}) const;
  /// The segment from a point on instance `own` against its own mesh (unless `trace_own` is
  /// false: the caller knows the mesh cannot block it) and the other instances' proxies of
  /// `proxies` among `rest_bits` (instance_bit()s). The answer is that of mesh_blocks(own
  /// only) followed, if clear, by proxy_blocks or outside_blocks with {skip own, rest_bits};
  /// with split scenes it takes one traversal in place of two (a hit on the own mesh ends
  /// it, the proxies' hits are only noted). `exact_queries` and `proxy_queries` count the
  /// queries made (the joint one as a proxy query).
  SplitAnswer split_blocks(const Vertex& from, const Vertex& to, int own, bool trace_own, std::uint64_t& exact_queries,
                           std::uint64_t& proxy_queries, SplitProxies proxies = SplitProxies::stochastic,
                           unsigned rest_bits = 0x7FFFFFFFu) const;
  /// Whether split_blocks() has a split scene for instance `own`.
  bool has_split_scene(int own) const;

  /// The kind of the union of every instance's stochastic proxy except `skip`'s: outside
  /// (inside) when each is a usable outside (inside) proxy or exact, general otherwise.
  ProxyKind stochastic_kind(int skip) const;
  /// World-space bounding box of an instance's mesh, and a sphere around its centre that
  /// holds every vertex (tighter than the box's for round meshes), both padded by the
  /// rounding bound of Embree's tests.
  const BoundingBox& instance_bounds(std::size_t instance) const;
  const Sphere& instance_sphere(std::size_t instance) const;
  /// What a segment that enters the instance's world box may test (render/world/query_costs.h
  /// models its cost): the mesh's triangles, and the stochastic proxy's primitives
  /// (triangles Embree traces, or balls and a clipped solid's planes, which visproxy's own
  /// code tests; the mesh when it has none).
  struct InstancePrimitives {
    std::size_t mesh = 0, proxy = 0;
    bool proxy_triangles = true;
  };
  const InstancePrimitives& instance_primitives(std::size_t instance) const;
  /// The instances i for which meets(instance_bounds(i), instance_sphere(i)) holds, in
  /// increasing order, found through a tree over the instances' bounds: `meets` must be
  /// monotone (false for a box and a ball means false for every box and ball they hold), as
  /// a conservative "may this region meet that volume" test is. Logarithmic in the instances
  /// for a region that meets few.
  void instances_where(const std::function<bool(const BoundingBox&, const Sphere&)>& meets,
                       std::vector<std::size_t>& out) const;

  /// The instances (as instance_bit()s) whose mesh lies on the boundary of its own convex
  /// hull (every triangle in a supporting plane of the mesh's vertices: a box room, a wall,
  /// a floor) and whose hull holds `point` strictly, by a margin of double rounding. A
  /// segment between two points both held by an instance's hull cannot meet its mesh: for
  /// such pairs the instance need not be traced. Empty (0) beyond 31 instances, where bits
  /// are shared. Checked in double: the answer is exact, not Embree's float one.
  unsigned convex_shells_holding(const Vertex& point) const;

  /// World-space balls of the instance's stochastic proxy when it is a sphere set (each
  /// radius scaled by the transform's largest stretch, so it holds its transformed ball),
  /// else empty: the occluders of `spheres` visibility.
  const std::vector<Sphere>& occluder_spheres(std::size_t instance) const;
  /// occluder_spheres() in clusters of nearby balls (cluster_spheres() with
  /// kOccluderClusterSize and kOccluderClusterGroup), each with a ball holding them:
  /// occluder disks reject a cluster's balls at once for segments outside its bound's cone.
  const std::vector<SphereCluster>& occluder_clusters(std::size_t instance) const;

  /// The instance's geometry for shaft and cone proofs (RenderWorldOptions::keep_solids; Error
  /// otherwise).
  const InstanceSolids& instance_solids(std::size_t instance) const;
  bool keeps_solids() const;

  /// Whether any instance has a usable inside proxy (else inside_blocks is always false).
  bool has_inside_proxies() const;

  /// One line for each proxy that is not used with its kind's guarantees, and why.
  const std::vector<std::string>& notes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace visproxy
