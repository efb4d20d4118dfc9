#include "visproxy/render/world/render_world.h"

#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "visproxy/core/errors.h"
#include "visproxy/proxy/convex_hull.h"
#include "visproxy/render/world/box_tree.h"
#include "visproxy/trace/convex_polytope.h"
#include "visproxy/trace/embree_support.h"
#include "visproxy/trace/ray_scene.h"
#include "visproxy/verify/containment.h"

namespace visproxy {
namespace {

// Instance i carries mask bit i % 31; lights carry bit 31. A query that skips or keeps one
// instance clears or keeps its bit, so Embree never visits what it must ignore; only when
// other instances share that bit (more than 31 instances), or the device has no ray masks,
// does the filter function decide.
constexpr unsigned kLightMask = 1u << 31;
constexpr unsigned kAllInstances = kLightMask - 1;
unsigned instance_mask(std::size_t instance) { return 1u << (instance % 31); }

// kFloatRoundingBound (ray_scene.h), relative to the magnitude of the coordinates Embree
// sees, both for the padding of each proxy (so two surfaces proved apart stay apart by 16
// ulps less 6) and for the offsets of points off their surfaces.
constexpr double kFloatPadding = kFloatRoundingBound;
constexpr double kSurfaceOffset = kFloatRoundingBound;

// For each triangle of a small mesh: whether every vertex lies behind its plane (against
// the normal of its winding), and whether every vertex lies in front of it.
struct TangentSides {
  std::vector<std::uint8_t> behind, in_front;
  double tolerance = 0;  // object units: how far a vertex may lie on the wrong side
};

TangentSides tangent_sides(const TriangleMesh& mesh) {
  TangentSides sides;
  if (mesh.triangles.size() > 4096) return sides;
  const std::vector<Vertex> points = used_positions(mesh);
  const double tolerance = 1e-9 * bounding_box(mesh).diagonal();
  sides.tolerance = tolerance;
  for (const Triangle& t : mesh.triangles) {
    const Vertex& p0 = mesh.positions[t[0]];
    const Vertex n = (mesh.positions[t[1]] - p0).cross(mesh.positions[t[2]] - p0);
    bool behind = n.squaredNorm() > 0, in_front = behind;
    const Vertex unit = behind ? n.normalized() : n;
    for (const Vertex& v : points) {
      const double height = unit.dot(v - p0);
      behind = behind && height <= tolerance;
      in_front = in_front && height >= -tolerance;
    }
    sides.behind.push_back(behind);
    sides.in_front.push_back(in_front);
  }
  return sides;
}

// An intersect context that carries which instances a query sees; the scenes' context
// filter function reads it (Embree passes the context to every hit it considers).
struct FilterContext {
  RTCIntersectContext context;
  InstanceFilter filter;
};

bool filter_passes(std::size_t instance, const InstanceFilter& filter) {
  return static_cast<int>(instance) != filter.skip && (filter.only < 0 || static_cast<int>(instance) == filter.only) &&
         (filter.bits & instance_mask(instance)) != 0;
}

// Shadow queries: hits on lights (the only geometry outside an instance) and on instances
// the filter drops are ignored.
void instance_filter(const RTCFilterFunctionNArguments* args) {
  const auto* context = reinterpret_cast<const FilterContext*>(args->context);
  for (unsigned lane = 0; lane < args->N; ++lane) {
    if (args->valid[lane] == 0) continue;
    const unsigned instance = RTCHitN_instID(args->hit, args->N, lane, 0);
    if (instance == RTC_INVALID_GEOMETRY_ID || !filter_passes(instance, context->filter)) args->valid[lane] = 0;
  }
}

// A split scene's query (RenderWorld::split_blocks): a hit on the own mesh ends it, a hit on
// another instance's proxy is noted and passed over, so that one traversal tells the own
// mesh blocking from a proxy blocking.
// Hits on instances outside `bits` (which ray masks leave out already, where the device has
// them) are passed over unnoted.
struct SplitContext {
  RTCIntersectContext context;
  unsigned own = 0;
  unsigned bits = 0;
  bool proxy_hit = false;
};

void split_filter(const RTCFilterFunctionNArguments* args) {
  auto* context = reinterpret_cast<SplitContext*>(args->context);
  for (unsigned lane = 0; lane < args->N; ++lane) {
    const unsigned instance = RTCHitN_instID(args->hit, args->N, lane, 0);
    if (args->valid[lane] == 0 || instance == context->own) continue;
    if ((instance_mask(instance) & context->bits) != 0) context->proxy_hit = true;
    args->valid[lane] = 0;
  }
}

thread_local TraversalCounts g_thread_counts;

// One instance of an object BVH for counted queries.
struct CountedInstance {
  const CountingBvh* object = nullptr;
  Eigen::Affine3d to_object;
  BoundingBox world;
};


// A convex proxy of one instance, in world space, tested by clipping instead of Embree.
struct ConvexInstance {
  unsigned id = 0;
  ConvexPolytope world;
};

double largest_magnitude(const BoundingBox& box, const Vertex& center) {
  return box.empty() ? 0.0 : std::max((box.max - center).cwiseAbs().maxCoeff(), (box.min - center).cwiseAbs().maxCoeff());
}

std::string kind_text(ProxyKind kind) {
  return kind == ProxyKind::outside ? "outside" : kind == ProxyKind::inside ? "inside" : "general";
}

// One proxy of one mesh, made ready for the world: the geometry that is traced or
// clipped, in the mesh's frame, and the kind it can still claim after the proof and the
// rounding checks.
struct PreparedProxy {
  ProxyKind kind = ProxyKind::general;
  std::string spec;
  std::optional<ConvexPolytope> polytope;  ///< closed convex, at most 64 planes: clipped
  TriangleMesh mesh;                       ///< traced by Embree (unless polytope or spheres)
  std::vector<Sphere> spheres;
  std::string note;  ///< why the kind was given up, if it was
};

}  // namespace

struct RenderWorld::Impl {
  EmbreeDevice device;
  bool counting = false;
  bool masks = true;
  Vertex origin = Vertex::Zero();  // world points are handed to Embree relative to it
  double scene_magnitude = 0;      // largest |coordinate - origin| of instances and lights
  std::map<RTCScene, std::unique_ptr<CountingBvh>> counting_bvhs;  // per object scene
  std::map<RTCScene, std::vector<std::optional<CountedInstance>>> counted;  // per top scene, per instance
  std::vector<RTCScene> owned;  // released at the end
  std::vector<std::vector<Sphere>> sphere_storage;  // moved vectors keep their buffers
  RTCScene camera = nullptr, proxy = nullptr, outside = nullptr, inside = nullptr;
  // Per instance (RenderWorldOptions::split_scenes): its own mesh and the other instances'
  // stochastic (outside) proxies as traced in `proxy` (`outside`); their clipped convex
  // proxies stay there.
  std::vector<RTCScene> split_scenes, split_outside_scenes;
  std::vector<Eigen::Matrix3d> normal_matrices;  // per instance, object to world normals
  std::vector<Eigen::Affine3d> instance_transforms;  // per instance, object to world points
  std::vector<int> light_of_triangle;
  std::vector<Vertex> light_normals;  // per light triangle, unit, world
  TriangleMesh lights_world;          // every light triangle, world space
  std::vector<ProxyKind> stochastic_kinds;  // per instance; outside for exact (mesh itself)
  std::vector<bool> is_exact;  // per instance: no stochastic proxy (traced exactly)
  std::vector<InstancePrimitives> primitives;  // per instance
  std::size_t instance_count = 0;
  bool has_inside = false;
  std::vector<BoundingBox> instance_bounds;
  std::vector<Sphere> instance_spheres;
  std::vector<const TangentSides*> instance_sides;
  std::vector<double> instance_pads;  // per instance: its bound on Embree's float rounding, world units
  std::vector<const TriangleMesh*> instance_meshes;
  std::map<std::string, TangentSides> mesh_sides;
  std::map<RTCScene, std::vector<ConvexInstance>> convex;  // per top scene
  // The same over their bounding balls, where there are many: a segment visits only the
  // solids whose ball's box it meets, in place of every one.
  std::map<RTCScene, BoxTree> convex_trees;
  BoxTree instance_tree;
  static constexpr std::size_t kConvexTreeFrom = 16;

  // Calls meets(instance) for the convex solids of `scene` a segment from `from` to `to`
  // may meet, until one returns true.
  template <class Meets>
  bool any_convex(RTCScene scene, const Vertex& from, const Vertex& to, Meets&& meets) const {
    const auto it = convex.find(scene);
    if (it == convex.end()) return false;
    if (const auto tree = convex_trees.find(scene); tree != convex_trees.end())
      return tree->second.any_along(to - from, [&](const BoundingBox& box, const Sphere&) { return segment_meets_box(from, to, box); },
                              [&](std::uint32_t k) { return meets(it->second[k]); });
    for (const ConvexInstance& instance : it->second)
      if (meets(instance)) return true;
    return false;
  }
  std::map<RTCScene, unsigned> embree_masks;  // per top scene: the mask bits of the instances Embree traces
  std::vector<std::string> notes;
  std::vector<std::vector<Sphere>> occluder_spheres;  // per instance, world space
  std::vector<std::vector<SphereCluster>> occluder_clusters;  // per instance, over occluder_spheres
  // Instances whose mesh lies on its convex hull's boundary: the hull's planes (outward
  // normal, offset) in world space, and the margin a point must keep inside them.
  struct ConvexShell {
    unsigned bit = 0;
    std::vector<std::pair<Vertex, double>> planes;
    double margin = 0;
    bool holds(const Vertex& p) const {
      for (const auto& [normal, offset] : planes)
        if (!(normal.dot(p) - offset < -margin)) return false;
      return true;
    }
  };
  std::vector<ConvexShell> shells;
  bool keep_solids = false;
  std::vector<InstanceSolids> solids;  // per instance, when keep_solids
  static std::optional<ConvexShell> convex_shell(const TriangleMesh& mesh, const Eigen::Affine3d& transform);
  int packet = 1;  // width of the packets grouped queries use

  ~Impl() {
    for (RTCScene scene : owned) rtcReleaseScene(scene);
  }

  void note(const std::string& text) {
    if (std::find(notes.begin(), notes.end(), text) == notes.end()) notes.push_back(text);
  }

  // An object scene of triangles or balls, given in the mesh's frame and stored relative
  // to `center` (the mesh's own centre).
  RTCScene object_scene(const TriangleMesh& mesh, const std::vector<Sphere>& spheres, const Vertex& center) {
    RTCScene scene = device.new_scene();
    owned.push_back(scene);
    // Hits inside instances go through the context filter too: Embree needs the flag on
    // the instanced scenes as well as on the top scenes.
    rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
    if (!spheres.empty()) {
      std::vector<Sphere> local = spheres;
      for (Sphere& s : local) s.center -= center;
      sphere_storage.push_back(std::move(local));
      attach_spheres(device, scene, sphere_storage.back());
      if (counting) counting_bvhs.emplace(scene, std::make_unique<CountingBvh>(std::span<const Sphere>(sphere_storage.back())));
    } else {
      TriangleMesh local = mesh;
      for (Vertex& p : local.positions) p -= center;
      if (!local.triangles.empty()) attach_triangles(device, scene, local);
      if (counting) counting_bvhs.emplace(scene, std::make_unique<CountingBvh>(local));
    }
    rtcCommitScene(scene);
    device.throw_if_failed();
    return scene;
  }

  RTCScene top_scene() {
    RTCScene scene = device.new_scene();
    owned.push_back(scene);
    rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
    return scene;
  }

  // `object_to_world` maps the object scene's (centred) frame to world space; Embree gets
  // it relative to the world's origin.
  void add_instance(RTCScene top, RTCScene object, const Eigen::Affine3d& object_to_world, unsigned id, unsigned mask) {
    embree_masks[top] |= mask;
    if (counting) {
      auto& list = counted[top];
      list.resize(std::max<std::size_t>(list.size(), id + 1));
      const CountingBvh* bvh = counting_bvhs.at(object).get();
      CountedInstance instance{bvh, object_to_world.inverse(), {}};
      const BoundingBox& local = bvh->bounds();
      if (!local.empty())
        for (int corner = 0; corner < 8; ++corner)
          instance.world.extend(object_to_world * Vertex(corner & 1 ? local.max.x() : local.min.x(), corner & 2 ? local.max.y() : local.min.y(),
                                                         corner & 4 ? local.max.z() : local.min.z()));
      list[id] = instance;
    }
    const Eigen::Affine3d transform = Eigen::Translation3d(-origin) * object_to_world;
    RTCGeometry geometry = rtcNewGeometry(device.get(), RTC_GEOMETRY_TYPE_INSTANCE);
    device.throw_if_failed();
    rtcSetGeometryInstancedScene(geometry, object);
    float matrix[12];
    for (int column = 0; column < 4; ++column)
      for (int row = 0; row < 3; ++row) matrix[3 * column + row] = static_cast<float>(transform.matrix()(row, column));
    rtcSetGeometryTransform(geometry, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, matrix);
    rtcSetGeometryMask(geometry, mask);
    rtcCommitGeometry(geometry);
    rtcAttachGeometryByID(top, geometry, id);
    rtcReleaseGeometry(geometry);
    device.throw_if_failed();
  }

  // The instance bits a query may see. With more than 31 instances a skipped instance's bit
  // is shared and stays set (the filter function then decides).
  unsigned query_mask(const InstanceFilter& filter) const {
    unsigned mask = kAllInstances & filter.bits;
    if (filter.only >= 0) mask &= instance_mask(static_cast<std::size_t>(filter.only));
    if (filter.skip >= 0 && instance_count <= 31) mask &= ~instance_mask(static_cast<std::size_t>(filter.skip));
    return mask;
  }

  bool blocked(RTCScene scene, const Vertex& from, const Vertex& to, InstanceFilter filter) const {
    if (any_convex(scene, from, to, [&](const ConvexInstance& instance) {
          if (!filter_passes(instance.id, filter)) return false;
          if (counting) ++g_thread_counts.nodes, ++g_thread_counts.primitives;  // one solid, clipped
          return instance.world.meets_segment(from, to);
        }))
      return true;
    // No Embree call when every instance Embree holds here is filtered out (e.g. the only
    // instance without a convex proxy is the one the query skips).
    const auto masks_here = embree_masks.find(scene);
    if (masks_here == embree_masks.end() || (masks_here->second & query_mask(filter)) == 0) return false;
    if (counting) {
      const auto it = counted.find(scene);
      if (it == counted.end()) return false;
      TraversalCounts& counts = g_thread_counts;
      for (std::size_t i = 0; i < it->second.size(); ++i) {
        const auto& instance = it->second[i];
        if (!instance || !filter_passes(i, filter)) continue;
        ++counts.nodes;
        if (instance->world.empty() || !segment_meets_box(from, to, instance->world)) continue;
        if (instance->object->segment_blocked(instance->to_object * from, instance->to_object * to, counts)) return true;
      }
      return false;
    }
    FilterContext context;
    rtcInitIntersectContext(&context.context);
    context.filter = filter;
    RTCRay ray = segment_ray(from - origin, to - origin);
    ray.mask = query_mask(filter);
    const bool shared_bit = (filter.only >= 0 || filter.skip >= 0) && instance_count > 31;
    context.context.filter = shared_bit || !masks ? instance_filter : nullptr;
    rtcOccluded1(scene, &context.context, &ray);
    return ray.tfar == -std::numeric_limits<float>::infinity();
  }

  // blocked() for segments from one origin, `packet` rays at a time (the same answers: each
  // lane is one segment ray with the same mask and filter).
  template <typename RayN, int N>
  void blocked_packets(RTCScene scene, const Vertex& from, std::span<const Vertex> ends, std::span<std::uint8_t> out,
                       const InstanceFilter& filter, std::span<const unsigned> lane_bits,
                       void (*occluded)(const int*, RTCScene, RTCIntersectContext*, RayN*)) const {
    FilterContext context;
    rtcInitIntersectContext(&context.context);
    context.filter = filter;
    const bool shared_bit = (filter.only >= 0 || filter.skip >= 0) && instance_count > 31;
    context.context.filter = shared_bit || !masks ? instance_filter : nullptr;
    const unsigned mask = query_mask(filter);
    const Vertex origin_here = from - origin;
    const float ox = static_cast<float>(origin_here.x()), oy = static_cast<float>(origin_here.y()), oz = static_cast<float>(origin_here.z());
    for (std::size_t base = 0; base < ends.size(); base += N) {
      alignas(64) int valid[N];
      alignas(64) RayN rays;
      bool any = false;
      for (int lane = 0; lane < N; ++lane) {
        const std::size_t i = base + static_cast<std::size_t>(lane);
        valid[lane] = i < ends.size() && out[i] == 0 ? -1 : 0;
        if (valid[lane] == 0) continue;
        any = true;
        const Vertex direction = (ends[i] - origin) - origin_here;
        rays.org_x[lane] = ox, rays.org_y[lane] = oy, rays.org_z[lane] = oz;
        rays.dir_x[lane] = static_cast<float>(direction.x());
        rays.dir_y[lane] = static_cast<float>(direction.y());
        rays.dir_z[lane] = static_cast<float>(direction.z());
        rays.tnear[lane] = 0.0f, rays.tfar[lane] = 1.0f, rays.time[lane] = 0.0f;
        rays.mask[lane] = lane_bits.empty() ? mask : mask & lane_bits[i];
        rays.id[lane] = 0, rays.flags[lane] = 0;
      }
      if (!any) continue;
      occluded(valid, scene, &context.context, &rays);
      for (int lane = 0; lane < N; ++lane)
        if (valid[lane] != 0 && rays.tfar[lane] == -std::numeric_limits<float>::infinity()) out[base + static_cast<std::size_t>(lane)] = 1;
    }
  }

  void blocked_group(RTCScene scene, const Vertex& from, std::span<const Vertex> ends, std::span<std::uint8_t> out,
                     const InstanceFilter& filter, std::span<const unsigned> lane_bits) const {
    std::fill(out.begin(), out.end(), std::uint8_t{0});
    auto lane_filter = [&](std::size_t i) {
      InstanceFilter f = filter;
      if (!lane_bits.empty()) f.bits &= lane_bits[i];
      return f;
    };
    // Without ray masks the filter function would need a filter per lane: single rays.
    if (counting || packet == 1 || (!lane_bits.empty() && !masks)) {
      for (std::size_t i = 0; i < ends.size(); ++i) out[i] = blocked(scene, from, ends[i], lane_filter(i)) ? 1 : 0;
      return;
    }
    for (std::size_t i = 0; i < ends.size(); ++i)
      if (any_convex(scene, from, ends[i], [&](const ConvexInstance& instance) {
            return filter_passes(instance.id, lane_filter(i)) && instance.world.meets_segment(from, ends[i]);
          }))
        out[i] = 1;
    const auto masks_here = embree_masks.find(scene);
    if (masks_here == embree_masks.end() || (masks_here->second & query_mask(filter)) == 0) return;
    if (packet == 8)
      blocked_packets<RTCRay8, 8>(scene, from, ends, out, filter, lane_bits, &rtcOccluded8);
    else
      blocked_packets<RTCRay4, 4>(scene, from, ends, out, filter, lane_bits, &rtcOccluded4);
  }

  // Whether every light lies outside the solid of `solid` (a closed mesh, placed in the
  // world by `transform`) by more than `margin`: no light triangle comes within the margin
  // of its surface, so each stays in one region of constant winding number, and every
  // light vertex has winding number 0. Lights beyond the solid's box need no more.
  bool lights_outside(const TriangleMesh& solid, const Eigen::Affine3d& transform, double margin) const {
    if (lights_world.triangles.empty()) return true;
    const BoundingBox local = bounding_box(solid), lights_box = bounding_box(lights_world);
    BoundingBox solid_box;
    for (int corner = 0; corner < 8 && !local.empty(); ++corner)
      solid_box.extend(transform * Vertex(corner & 1 ? local.max.x() : local.min.x(), corner & 2 ? local.max.y() : local.min.y(),
                                          corner & 4 ? local.max.z() : local.min.z()));
    if (solid_box.empty() || (lights_box.max.array() + margin < solid_box.min.array()).any() ||
        (lights_box.min.array() - margin > solid_box.max.array()).any())
      return true;
    const TriangleMesh solid_world = transformed_mesh(solid, transform);
    if (!check_edge_balance(solid_world).balanced()) return false;
    if (!surfaces_clear_by(lights_world, solid_world, margin)) return false;
    const std::vector<PointLocation> locations = locate_points(solid_world, lights_world.positions);
    return std::all_of(locations.begin(), locations.end(), [](PointLocation l) { return l == PointLocation::outside; });
  }
};

namespace {

// The stochastic, outside or inside use of a proxy (notes name it).
PreparedProxy prepare_proxy(const InstanceProxy& p, const SceneMesh& mesh, double pad) {
  PreparedProxy prepared;
  prepared.spec = p.spec;
  prepared.kind = p.proved ? p.kind : ProxyKind::general;
  prepared.mesh = p.mesh;
  prepared.spheres = p.spheres;
  const std::string name = "proxy " + p.spec + " of mesh \"" + mesh.name + "\"";
  if (!p.proved && p.kind != ProxyKind::general)
    prepared.note = name + ": its " + kind_text(p.kind) + " claim is not proved for this mesh (visproxy verify): used as a general proxy";
  if (!p.spheres.empty()) {
    if (prepared.kind == ProxyKind::inside) {
      // Shrunk by the rounding bound, so that the exact proof survives Embree's float rays.
      std::erase_if(prepared.spheres, [&](const Sphere& s) { return s.radius <= pad; });
      for (Sphere& s : prepared.spheres) s.radius -= pad;
    } else if (prepared.kind == ProxyKind::outside) {
      prepared.kind = ProxyKind::general;
      prepared.note = name + ": outside sphere sets are not supported: used as a general proxy";
    }
    return prepared;
  }
  if (prepared.kind != ProxyKind::inside) prepared.polytope = ConvexPolytope::from_mesh(p.mesh);
  if (prepared.polytope || prepared.kind == ProxyKind::general) return prepared;
  // Convex with many planes (up to 16 384 triangles: the plane test is quadratic): grown
  // to hold the whole proxy pushed out by twice `pad`.
  if (prepared.kind == ProxyKind::outside && p.mesh.triangles.size() <= 16384 &&
      grow_convex_mesh(prepared.mesh, 2 * pad, p.mesh.triangles.size()))
    return prepared;
  // Otherwise the proxy must keep the rounding bound away from the mesh.
  if (!surfaces_clear_by(p.mesh, mesh.mesh, 2 * pad)) {
    prepared.note = name + ": it comes within float rounding (" + std::to_string(2 * pad) +
                    " mesh units) of the mesh, so its " + kind_text(prepared.kind) +
                    " claim may not survive single-precision ray tests: used as a general proxy";
    prepared.kind = ProxyKind::general;
  }
  return prepared;
}

}  // namespace

// The convex shell of a small mesh (at most 4096 triangles, none degenerate) whose every
// triangle lies in a supporting plane of its vertices, placed by `transform`; nullopt
// otherwise. Coplanar triangles share a plane. The tolerance for "in the plane" is 2^-40
// of the mesh's magnitude; points must keep 2^-36 of it inside every plane.
std::optional<RenderWorld::Impl::ConvexShell> RenderWorld::Impl::convex_shell(const TriangleMesh& mesh, const Eigen::Affine3d& transform) {
  if (mesh.triangles.empty() || mesh.triangles.size() > 4096) return std::nullopt;
  std::vector<Vertex> points;
  for (const Vertex& p : used_positions(mesh)) points.push_back(transform * p);
  double magnitude = 0;
  for (const Vertex& p : points) magnitude = std::max(magnitude, p.cwiseAbs().maxCoeff());
  const double tolerance = 0x1.0p-40 * magnitude;
  ConvexShell shell;
  shell.margin = 0x1.0p-36 * magnitude;
  for (const Triangle& t : mesh.triangles) {
    const Vertex a = transform * mesh.positions[t[0]], b = transform * mesh.positions[t[1]], c = transform * mesh.positions[t[2]];
    Vertex normal = (b - a).cross(c - a);
    const double length = normal.norm();
    if (!(length > 0x1.0p-30 * magnitude * magnitude)) return std::nullopt;  // degenerate: no plane to lie in
    normal /= length;
    double offset = normal.dot(a);
    // Outward: the other vertices behind the plane, or (the other side) in front of it.
    double lowest = 0, highest = 0;
    for (const Vertex& p : points) {
      const double side = normal.dot(p) - offset;
      lowest = std::min(lowest, side), highest = std::max(highest, side);
    }
    if (highest > tolerance && lowest < -tolerance) return std::nullopt;  // vertices on both sides: not a supporting plane
    if (highest > tolerance) normal = -normal, offset = -offset;
    for (const Vertex& p : {a, b, c})
      if (std::abs(normal.dot(p) - offset) > tolerance) return std::nullopt;
    bool known = false;
    for (const auto& [n, d] : shell.planes) known = known || ((n - normal).norm() < 1e-12 && std::abs(d - offset) <= tolerance);
    if (!known) shell.planes.emplace_back(normal, offset);
  }
  return shell;
}

RenderWorld::RenderWorld(const Scene& scene, const std::vector<MeshProxies>& proxies, const RenderWorldOptions& options)
    : impl_(std::make_unique<Impl>()) {
  Impl& w = *impl_;
  w.counting = options.counting;
  w.keep_solids = options.keep_solids;
  w.masks = options.ray_masks && rtcGetDeviceProperty(w.device.get(), RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED) != 0;
  w.packet = rtcGetDeviceProperty(w.device.get(), RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED) != 0   ? 8
             : rtcGetDeviceProperty(w.device.get(), RTC_DEVICE_PROPERTY_NATIVE_RAY4_SUPPORTED) != 0 ? 4
                                                                                                   : 1;
  if (proxies.size() != scene.instances.size()) throw Error("render: one proxy set per scene instance expected");
  w.instance_count = scene.instances.size();

  // Lights in world space; the scene's centre and extent.
  for (std::size_t l = 0; l < scene.lights.size(); ++l)
    for (const auto& t : scene.lights[l].triangles) {
      const auto base = static_cast<VertexIndex>(w.lights_world.positions.size());
      w.lights_world.positions.insert(w.lights_world.positions.end(), t.begin(), t.end());
      w.lights_world.triangles.push_back({base, base + 1, base + 2});
      w.light_of_triangle.push_back(static_cast<int>(l));
      w.light_normals.push_back((t[1] - t[0]).cross(t[2] - t[0]).normalized());
    }
  std::map<std::string, Vertex> mesh_center;        // each mesh's box centre: its objects are stored relative to it
  std::map<std::string, double> object_magnitude;   // largest |coordinate - centre| of a mesh and its proxies
  std::map<std::string, double> least_scale;        // smallest singular value of its instances' transforms
  BoundingBox scene_box = bounding_box(w.lights_world);
  std::vector<BoundingBox> world_boxes;
  // Each mesh's convex hull corners, once: an instance's world box and bounding ball reach
  // their extent at a corner (a linear function and a distance from a point are greatest
  // at a vertex of the hull), so instances of a large mesh need only these.
  std::map<std::string, std::vector<Vertex>> mesh_corners;
  auto corners_of = [&](const std::string& name, const TriangleMesh& mesh) -> const std::vector<Vertex>& {
    auto found = mesh_corners.find(name);
    if (found != mesh_corners.end()) return found->second;
    std::vector<Vertex> corners;
    try {
      corners = mesh.triangles.size() > 64 ? build_convex_hull(mesh).mesh.positions : used_positions(mesh);
    } catch (const InvalidInputError&) {  // flat to a line or a point: every vertex
      corners = used_positions(mesh);
    }
    return mesh_corners.emplace(name, std::move(corners)).first->second;
  };
  for (std::size_t i = 0; i < scene.instances.size(); ++i) {
    const SceneInstance& instance = scene.instances[i];
    const TriangleMesh& mesh = scene.mesh(instance.mesh).mesh;
    if (!mesh_center.contains(instance.mesh)) {
      const BoundingBox box = bounding_box(mesh);
      const Vertex center = box.empty() ? Vertex::Zero() : Vertex(0.5 * (box.min + box.max));
      mesh_center[instance.mesh] = center;
      object_magnitude[instance.mesh] = largest_magnitude(box, center);
    }
    double& magnitude = object_magnitude[instance.mesh];
    const Vertex& center = mesh_center[instance.mesh];
    for (const auto* proxy : {&proxies[i].stochastic, &proxies[i].outside, &proxies[i].inside}) {
      if (!*proxy) continue;
      magnitude = std::max(magnitude, largest_magnitude(bounding_box((*proxy)->mesh), center));
      for (const Sphere& s : (*proxy)->spheres) magnitude = std::max(magnitude, (s.center - center).cwiseAbs().maxCoeff() + s.radius);
    }
    const double smallest = Eigen::JacobiSVD<Eigen::Matrix3d>(instance.transform.linear()).singularValues()(2);
    least_scale[instance.mesh] = std::min(least_scale.contains(instance.mesh) ? least_scale[instance.mesh] : smallest, smallest);
    BoundingBox world;
    for (const Vertex& v : corners_of(instance.mesh, mesh)) world.extend(instance.transform * v);
    world_boxes.push_back(world);
    if (!world.empty()) scene_box.extend(world.min), scene_box.extend(world.max);
  }
  w.origin = scene_box.empty() ? Vertex::Zero() : Vertex(0.5 * (scene_box.min + scene_box.max));
  w.scene_magnitude = std::max(largest_magnitude(scene_box, w.origin), std::numeric_limits<double>::min());
  // The rounding bound of an object: its own extent and the longest segment of the scene,
  // both in object units (Embree's errors grow with the distance of a ray's origin).
  auto object_pad = [&](const std::string& mesh) {
    return kFloatPadding * (object_magnitude[mesh] + 2 * w.scene_magnitude / std::max(least_scale[mesh], 1e-300));
  };

  w.camera = w.top_scene();
  w.proxy = w.top_scene();
  w.outside = w.top_scene();
  w.inside = w.top_scene();
  std::map<std::string, RTCScene> mesh_scenes;            // mesh name -> its triangles
  std::map<std::string, PreparedProxy> prepared_proxies;  // "mesh\nspec"
  std::map<std::string, RTCScene> proxy_scenes;           // "mesh\nspec"
  std::map<std::string, std::optional<ConvexPolytope>> mesh_polytopes;
  auto mesh_scene = [&](const std::string& name) {
    if (auto it = mesh_scenes.find(name); it != mesh_scenes.end()) return it->second;
    return mesh_scenes.emplace(name, w.object_scene(scene.mesh(name).mesh, {}, mesh_center[name])).first->second;
  };
  auto prepared_for = [&](const std::string& name, const InstanceProxy& p) -> const PreparedProxy& {
    const std::string key = name + "\n" + p.spec;
    if (auto it = prepared_proxies.find(key); it != prepared_proxies.end()) return it->second;
    PreparedProxy prepared = prepare_proxy(p, scene.mesh(name), object_pad(name));
    if (!prepared.note.empty()) w.note(prepared.note);
    return prepared_proxies.emplace(key, std::move(prepared)).first->second;
  };
  auto proxy_scene = [&](const std::string& name, const PreparedProxy& p) {
    const std::string key = name + "\n" + p.spec;
    if (auto it = proxy_scenes.find(key); it != proxy_scenes.end()) return it->second;
    return proxy_scenes.emplace(key, w.object_scene(p.mesh, p.spheres, mesh_center[name])).first->second;
  };

  // Per instance: its mesh's object scene, what `proxy` and `outside` trace of it (null:
  // clipped), and where they are placed.
  struct SplitPart {
    RTCScene mesh = nullptr, proxy = nullptr, outside = nullptr;
    Eigen::Affine3d object_to_world;
  };
  std::vector<SplitPart> split_parts;
  for (std::size_t i = 0; i < scene.instances.size(); ++i) {
    const SceneInstance& instance = scene.instances[i];
    const SceneMesh& mesh = scene.mesh(instance.mesh);
    const MeshProxies& p = proxies[i];
    const auto id = static_cast<unsigned>(i);
    const unsigned mask = instance_mask(i);
    const Eigen::Affine3d object_to_world = instance.transform * Eigen::Translation3d(mesh_center[instance.mesh]);
    const Eigen::Vector3d scales = Eigen::JacobiSVD<Eigen::Matrix3d>(instance.transform.linear()).singularValues();
    // World units: rays as long as the scene, whose errors in object space the most
    // anisotropic direction of the transform brings back, and the object's own extent.
    const double pad_world = kFloatPadding * (2 * w.scene_magnitude * scales(0) / std::max(scales(2), 1e-300) +
                                              scales(0) * object_magnitude[instance.mesh]);
    const std::string instance_name = "instance " + std::to_string(i) + " (mesh \"" + instance.mesh + "\")";
    w.add_instance(w.camera, mesh_scene(instance.mesh), object_to_world, id, mask);

    // Adds a prepared proxy to a top scene: clipped as a world-space solid, or traced.
    auto add_proxy = [&](RTCScene top, const PreparedProxy& prepared) {
      if (prepared.polytope)
        w.convex[top].push_back({id, prepared.polytope->transformed(instance.transform).grown(pad_world)});
      else
        w.add_instance(top, proxy_scene(instance.mesh, prepared), object_to_world, id, mask);
    };
    // An outside proxy traced as a surface proves a miss only with every light outside it.
    auto traced_outside_usable = [&](const PreparedProxy& prepared) {
      return prepared.polytope || w.lights_outside(prepared.mesh, instance.transform, pad_world);
    };
    // An inside proxy proves a hit only with every light outside the mesh's solid.
    std::optional<bool> lights_outside_mesh;
    auto inside_usable = [&]() {
      if (!lights_outside_mesh) lights_outside_mesh = w.lights_outside(mesh.mesh, instance.transform, pad_world);
      return *lights_outside_mesh;
    };

    // Stochastic: the proxy, or the mesh itself (V' = V exactly: traced, never clipped).
    ProxyKind kind = ProxyKind::outside;
    if (p.stochastic) {
      const PreparedProxy& prepared = prepared_for(instance.mesh, *p.stochastic);
      kind = prepared.kind;
      if (kind == ProxyKind::outside && !traced_outside_usable(prepared)) {
        w.note(instance_name + ": a light lies inside (or within rounding of) its outside proxy " + prepared.spec +
               ", which a traced surface cannot prove: used as a general proxy");
        kind = ProxyKind::general;
      }
      if (kind == ProxyKind::inside && !inside_usable()) {
        w.note(instance_name + ": a light lies inside (or within rounding of) the mesh's solid, so its inside proxy " +
               prepared.spec + " proves nothing: used as a general proxy");
        kind = ProxyKind::general;
      }
      add_proxy(w.proxy, prepared);
      split_parts.push_back({mesh_scene(instance.mesh), prepared.polytope ? nullptr : proxy_scene(instance.mesh, prepared),
                             nullptr, object_to_world});
    } else {
      w.add_instance(w.proxy, mesh_scene(instance.mesh), object_to_world, id, mask);
      split_parts.push_back({mesh_scene(instance.mesh), mesh_scene(instance.mesh), nullptr, object_to_world});
    }
    w.is_exact.push_back(!p.stochastic.has_value());
    {
      InstancePrimitives primitives{.mesh = mesh.mesh.triangles.size(), .proxy = mesh.mesh.triangles.size()};
      if (p.stochastic) {
        const PreparedProxy& prepared = prepared_for(instance.mesh, *p.stochastic);
        primitives.proxy = prepared.polytope          ? prepared.polytope->planes().size()
                           : !prepared.spheres.empty() ? prepared.spheres.size()
                                                       : prepared.mesh.triangles.size();
        primitives.proxy_triangles = !prepared.polytope && prepared.spheres.empty();
      }
      w.primitives.push_back(primitives);
    }
    std::vector<Sphere> occluders;
    if (p.stochastic)
      for (const Sphere& ball : p.stochastic->spheres) occluders.push_back({instance.transform * ball.center, ball.radius * scales(0)});
    w.occluder_clusters.push_back(cluster_spheres(occluders, kOccluderClusterSize, kOccluderClusterGroup));
    w.occluder_spheres.push_back(std::move(occluders));
    w.stochastic_kinds.push_back(kind);

    // Outside (bounds): a usable outside proxy, else the mesh itself (a clipped solid when
    // it is closed and convex, which holds it).
    bool outside_added = false;
    InstanceSolids solids;
    if (w.keep_solids) {
      solids.pad = pad_world;
      solids.mesh = transformed_mesh(mesh.mesh, instance.transform);
    }
    auto keep_planes = [&](const ConvexPolytope& local) {
      const ConvexPolytope world_polytope = local.transformed(instance.transform);
      for (const ConvexPolytope::Plane& plane : world_polytope.planes())
        solids.outside_planes.emplace_back(plane.normal, plane.offset);
    };
    if (p.outside) {
      const PreparedProxy& prepared = prepared_for(instance.mesh, *p.outside);
      if (prepared.kind == ProxyKind::outside && traced_outside_usable(prepared)) {
        add_proxy(w.outside, prepared);
        if (!prepared.polytope) split_parts.back().outside = proxy_scene(instance.mesh, prepared);
        outside_added = true;
        if (w.keep_solids) {
          solids.outside = transformed_mesh(prepared.mesh, instance.transform);
          solids.outside_is_mesh = false;
          if (prepared.polytope) keep_planes(*prepared.polytope);
          else solids.lights_outside_outside = true;
        }
      } else if (prepared.kind == ProxyKind::outside) {
        w.note(instance_name + ": a light lies inside (or within rounding of) its outside proxy " + prepared.spec +
               ": bounds traces the mesh instead");
      }
    }
    if (!outside_added) {
      auto it = mesh_polytopes.find(instance.mesh);
      if (it == mesh_polytopes.end()) it = mesh_polytopes.emplace(instance.mesh, ConvexPolytope::from_mesh(mesh.mesh)).first;
      if (it->second)
        w.convex[w.outside].push_back({id, it->second->transformed(instance.transform).grown(pad_world)});
      else
        w.add_instance(w.outside, mesh_scene(instance.mesh), object_to_world, id, mask), split_parts.back().outside = mesh_scene(instance.mesh);
      if (w.keep_solids && it->second) keep_planes(*it->second);
    }

    // Inside (bounds): only a usable one; traced (balls are solids), never clipped.
    if (p.inside) {
      const PreparedProxy& prepared = prepared_for(instance.mesh, *p.inside);
      if (prepared.kind == ProxyKind::inside && inside_usable() && (!prepared.spheres.empty() || !prepared.mesh.triangles.empty())) {
        w.add_instance(w.inside, proxy_scene(instance.mesh, prepared), object_to_world, id, mask);
        w.has_inside = true;
        if (w.keep_solids) {
          for (const Sphere& ball : prepared.spheres) solids.inside_spheres.push_back({instance.transform * ball.center, ball.radius * scales(2)});
          if (prepared.spheres.empty()) solids.inside = transformed_mesh(prepared.mesh, instance.transform);
        }
      } else if (prepared.kind == ProxyKind::inside) {
        w.note(instance_name + ": a light lies inside (or within rounding of) the mesh's solid, so its inside proxy " +
               prepared.spec + " proves nothing: bounds does not use it");
      }
    }

    if (w.keep_solids) w.solids.push_back(std::move(solids));
    w.normal_matrices.push_back(instance.transform.linear().inverse().transpose());
    w.instance_transforms.push_back(instance.transform);
    auto sides = w.mesh_sides.find(instance.mesh);
    if (sides == w.mesh_sides.end()) sides = w.mesh_sides.emplace(instance.mesh, tangent_sides(mesh.mesh)).first;
    w.instance_sides.push_back(&sides->second);
    w.instance_pads.push_back(pad_world);
    w.instance_meshes.push_back(&mesh.mesh);
    BoundingBox world = world_boxes[i];
    Sphere sphere{world.empty() ? Vertex::Zero() : Vertex(0.5 * (world.min + world.max)), 0.0};
    for (const Vertex& v : corners_of(instance.mesh, mesh.mesh))
      sphere.radius = std::max(sphere.radius, (instance.transform * v - sphere.center).norm());
    if (!world.empty()) {
      world.min.array() -= pad_world;
      world.max.array() += pad_world;
    }
    sphere.radius += pad_world;
    w.instance_bounds.push_back(world);
    w.instance_spheres.push_back(sphere);
    if (scene.instances.size() <= 31)
      if (std::optional<Impl::ConvexShell> shell = Impl::convex_shell(mesh.mesh, instance.transform)) {
        shell->bit = instance_mask(i);
        w.shells.push_back(std::move(*shell));
      }
  }

  // Lights: visible to camera rays only (mask, or the filter function), one geometry after the instances.
  if (!w.lights_world.triangles.empty()) {
    TriangleMesh local = w.lights_world;
    for (Vertex& v : local.positions) v -= w.origin;
    const unsigned id = attach_triangles(w.device, w.camera, local, kLightMask);
    if (id != static_cast<unsigned>(scene.instances.size())) throw Error("render: unexpected light geometry id");
  }
  for (RTCScene top : {w.camera, w.proxy, w.outside, w.inside}) rtcCommitScene(top);
  // Split scenes: instance `own` as its mesh, every other as in `proxy` (`outside`). They
  // share the object scenes; only their top levels are new.
  if (options.split_scenes && !w.counting && scene.instances.size() <= kSplitScenesUpTo)
    for (std::size_t own = 0; own < scene.instances.size(); ++own)
      for (const SplitProxies role : {SplitProxies::stochastic, SplitProxies::outside}) {
        RTCScene top = w.top_scene();
        for (std::size_t j = 0; j < scene.instances.size(); ++j) {
          const SplitPart& part = split_parts[j];
          RTCScene object = j == own ? part.mesh : role == SplitProxies::stochastic ? part.proxy : part.outside;
          if (object) w.add_instance(top, object, part.object_to_world, static_cast<unsigned>(j), instance_mask(j));
        }
        rtcCommitScene(top);
        (role == SplitProxies::stochastic ? w.split_scenes : w.split_outside_scenes).push_back(top);
      }
  w.device.throw_if_failed();
  for (const auto& [top, solids] : w.convex) {
    if (solids.size() < Impl::kConvexTreeFrom) continue;
    std::vector<BoundingBox> boxes;
    std::vector<Sphere> balls;
    for (const ConvexInstance& solid : solids) {
      const Sphere ball = solid.world.bounding_ball();
      balls.push_back(ball);
      BoundingBox box;
      box.extend(ball.center - Vertex::Constant(ball.radius));
      box.extend(ball.center + Vertex::Constant(ball.radius));
      boxes.push_back(box);
    }
    w.convex_trees.emplace(top, BoxTree(boxes, balls));
  }
  // The instances' world bounds, for queries over whole light shafts.
  w.instance_tree = BoxTree(w.instance_bounds, w.instance_spheres);
}

RenderWorld::~RenderWorld() = default;

std::optional<SurfaceHit> RenderWorld::intersect(const Vertex& origin, const Vertex& direction) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rayhit{};
  rayhit.ray = segment_ray(origin - impl_->origin, origin - impl_->origin + direction);
  rayhit.ray.tfar = std::numeric_limits<float>::infinity();
  rayhit.ray.mask = kAllInstances | kLightMask;
  rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rayhit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(impl_->camera, &context, &rayhit);
  if (rayhit.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
  SurfaceHit hit;
  hit.distance = static_cast<double>(rayhit.ray.tfar);
  hit.position = origin + hit.distance * direction;
  Vertex normal(rayhit.hit.Ng_x, rayhit.hit.Ng_y, rayhit.hit.Ng_z);
  if (rayhit.hit.instID[0] != RTC_INVALID_GEOMETRY_ID) {
    hit.instance = static_cast<int>(rayhit.hit.instID[0]);
    normal = impl_->normal_matrices[static_cast<std::size_t>(hit.instance)] * normal;  // Embree gives it in object space
    const TangentSides& sides = *impl_->instance_sides[static_cast<std::size_t>(hit.instance)];
    if (!sides.behind.empty()) {
      // The winding's normal in world space; the shading normal faces the camera ray.
      const std::size_t instance = static_cast<std::size_t>(hit.instance);
      const TriangleMesh& mesh = *impl_->instance_meshes[instance];
      const Triangle& t = mesh.triangles[rayhit.hit.primID];
      const Vertex object_normal = (mesh.positions[t[1]] - mesh.positions[t[0]]).cross(mesh.positions[t[2]] - mesh.positions[t[0]]);
      const Vertex winding = impl_->normal_matrices[instance] * object_normal;
      const bool along = winding.dot(direction) < 0;
      hit.own_mesh_behind = along ? sides.behind[rayhit.hit.primID] != 0 : sides.in_front[rayhit.hit.primID] != 0;
      if (hit.own_mesh_behind) {
        // The exact plane in world space. The normal matrix keeps heights: the unit object
        // normal through it gives, at a world point, the object-unit height of its preimage,
        // so the mesh's reach in front of the plane is its tolerance over that normal's length.
        const double length = winding.norm(), stretch = length / object_normal.norm();
        SurfaceHit::OwnPlane& plane = hit.own_plane;
        plane.normal = (along ? winding : Vertex(-winding)) / length;
        plane.anchor = impl_->instance_transforms[instance] * mesh.positions[t[0]];
        plane.reach = sides.tolerance / stretch;
        // Double rounding of the anchor (a transformed vertex) and of the heights: below 2^-48
        // of the coordinates involved, the anchor's absolute ones and the scene's extent.
        const double rounding = 0x1.0p-48 * (plane.anchor.cwiseAbs().maxCoeff() + 4 * impl_->scene_magnitude);
        plane.near_margin = plane.reach + surface_offset(hit.position, hit.distance) / 4 + rounding;
        plane.far_margin = plane.reach + impl_->instance_pads[instance] + rounding;
        hit.own_mesh_behind = plane.normal.allFinite() && std::isfinite(plane.reach) && std::isfinite(plane.far_margin);
      }
    }
  } else {
    hit.light = impl_->light_of_triangle[rayhit.hit.primID];
    hit.light_front = impl_->light_normals[rayhit.hit.primID].dot(direction) < 0;
  }
  normal.normalize();
  hit.normal = normal.dot(direction) > 0 ? -normal : normal;
  return hit;
}

double RenderWorld::surface_offset(const Vertex& point, double distance) const {
  return kSurfaceOffset * ((point - impl_->origin).cwiseAbs().maxCoeff() + std::abs(distance)) +
         std::numeric_limits<double>::min();
}

bool RenderWorld::mesh_blocks(const Vertex& from, const Vertex& to, InstanceFilter filter) const {
  return impl_->blocked(impl_->camera, from, to, filter);
}
void RenderWorld::mesh_blocks(const Vertex& from, std::span<const Vertex> ends, std::span<std::uint8_t> blocked,
                              InstanceFilter filter, std::span<const unsigned> lane_bits) const {
  if (blocked.size() != ends.size() || (!lane_bits.empty() && lane_bits.size() != ends.size()))
    throw Error("RenderWorld::mesh_blocks: one answer (and lane filter) per segment end is needed");
  impl_->blocked_group(impl_->camera, from, ends, blocked, filter, lane_bits);
}

unsigned RenderWorld::convex_shells_holding(const Vertex& point) const {
  unsigned bits = 0;
  for (const Impl::ConvexShell& shell : impl_->shells)
    if (shell.holds(point)) bits |= shell.bit;
  return bits;
}
int RenderWorld::packet_width() const { return impl_->counting ? 1 : impl_->packet; }
const std::vector<Sphere>& RenderWorld::occluder_spheres(std::size_t instance) const { return impl_->occluder_spheres[instance]; }

const std::vector<SphereCluster>& RenderWorld::occluder_clusters(std::size_t instance) const {
  return impl_->occluder_clusters[instance];
}


bool RenderWorld::proxy_blocks(const Vertex& from, const Vertex& to, InstanceFilter filter) const {
  return impl_->blocked(impl_->proxy, from, to, filter);
}
bool RenderWorld::outside_blocks(const Vertex& from, const Vertex& to, InstanceFilter filter) const {
  return impl_->blocked(impl_->outside, from, to, filter);
}
bool RenderWorld::inside_blocks(const Vertex& from, const Vertex& to, InstanceFilter filter) const {
  return impl_->has_inside && impl_->blocked(impl_->inside, from, to, filter);
}

bool RenderWorld::has_split_scene(int own) const {
  return own >= 0 && static_cast<std::size_t>(own) < impl_->split_scenes.size();
}

SplitAnswer RenderWorld::split_blocks(const Vertex& from, const Vertex& to, int own, bool trace_own, std::uint64_t& exact_queries,
                                      std::uint64_t& proxy_queries, SplitProxies proxies, unsigned rest_bits) const {
  const Impl& w = *impl_;
  RTCScene rest_scene = proxies == SplitProxies::stochastic ? w.proxy : w.outside;
  const InstanceFilter own_only{.skip = -1, .only = own}, rest{.skip = own, .only = -1, .bits = rest_bits};
  if (trace_own && has_split_scene(own)) {
    // One traversal of the own mesh and the others' traced proxies (the instance bits are
    // unique here): a hit on the own mesh ends it, the proxies' hits are only noted
    // (split_filter). Their clipped proxies are tested apart.
    ++proxy_queries;
    const auto index = static_cast<std::size_t>(own);
    RTCScene joint = proxies == SplitProxies::stochastic ? w.split_scenes[index] : w.split_outside_scenes[index];
    SplitContext context;
    rtcInitIntersectContext(&context.context);
    context.context.filter = split_filter;
    context.own = static_cast<unsigned>(own);
    context.bits = rest_bits;
    RTCRay ray = segment_ray(from - w.origin, to - w.origin);
    ray.mask = kAllInstances & (rest_bits | instance_mask(index));
    rtcOccluded1(joint, &context.context, &ray);
    if (ray.tfar == -std::numeric_limits<float>::infinity()) return SplitAnswer::own_blocks;
    if (context.proxy_hit || w.any_convex(rest_scene, from, to, [&](const ConvexInstance& instance) {
          return filter_passes(instance.id, rest) && instance.world.meets_segment(from, to);
        }))
      return SplitAnswer::proxy_blocks;
    return SplitAnswer::clear;
  }
  if (trace_own) {
    ++exact_queries;
    if (w.blocked(w.camera, from, to, own_only)) return SplitAnswer::own_blocks;
  }
  ++proxy_queries;
  return w.blocked(rest_scene, from, to, rest) ? SplitAnswer::proxy_blocks : SplitAnswer::clear;
}

ProxyKind RenderWorld::stochastic_kind(int skip) const {
  bool all_outside = true, all_inside = true;
  for (std::size_t i = 0; i < impl_->stochastic_kinds.size(); ++i) {
    if (static_cast<int>(i) == skip || impl_->is_exact[i]) continue;
    all_outside = all_outside && impl_->stochastic_kinds[i] == ProxyKind::outside;
    all_inside = all_inside && impl_->stochastic_kinds[i] == ProxyKind::inside;
  }
  return all_outside ? ProxyKind::outside : all_inside ? ProxyKind::inside : ProxyKind::general;
}

unsigned instance_bit(std::size_t instance) { return instance_mask(instance); }

const BoundingBox& RenderWorld::instance_bounds(std::size_t instance) const { return impl_->instance_bounds[instance]; }

void RenderWorld::instances_where(const std::function<bool(const BoundingBox&, const Sphere&)>& meets,
                                  std::vector<std::size_t>& out) const {
  out.clear();
  impl_->instance_tree.any(meets, [&](std::uint32_t i) {
    if (meets(impl_->instance_bounds[i], impl_->instance_spheres[i])) out.push_back(i);
    return false;
  });
  std::sort(out.begin(), out.end());
}
const Sphere& RenderWorld::instance_sphere(std::size_t instance) const { return impl_->instance_spheres[instance]; }

TraversalCounts& RenderWorld::thread_counts() { return g_thread_counts; }
bool RenderWorld::counting() const { return impl_->counting; }

const RenderWorld::InstancePrimitives& RenderWorld::instance_primitives(std::size_t instance) const {
  return impl_->primitives.at(instance);
}

bool RenderWorld::has_inside_proxies() const { return impl_->has_inside; }

bool RenderWorld::keeps_solids() const { return impl_->keep_solids; }
const InstanceSolids& RenderWorld::instance_solids(std::size_t instance) const {
  if (!impl_->keep_solids) throw Error("RenderWorld::instance_solids: the world was made without keep_solids");
  return impl_->solids.at(instance);
}

const std::vector<std::string>& RenderWorld::notes() const { return impl_->notes; }

}  // namespace visproxy
