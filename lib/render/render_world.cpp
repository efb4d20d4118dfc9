#include "render/render_world.h"

#include <limits>
#include <map>

#include "core/errors.h"
#include "trace/convex_polytope.h"
#include "trace/embree_support.h"

namespace visproxy {
namespace {

// Instance i carries mask bit i % 31; lights carry bit 31. A query that skips or keeps one
// instance clears or keeps its bit, so Embree never visits what it must ignore; only when
// other instances share that bit (more than 31 instances) does the filter function decide.
constexpr unsigned kLightMask = 1u << 31;
constexpr unsigned kAllInstances = kLightMask - 1;
unsigned instance_mask(std::size_t instance) { return 1u << (instance % 31); }

// For each triangle of a small mesh: whether every vertex lies behind its plane (against
// the normal of its winding), and whether every vertex lies in front of it.
struct TangentSides {
  std::vector<std::uint8_t> behind, in_front;
};

TangentSides tangent_sides(const TriangleMesh& mesh) {
  TangentSides sides;
  if (mesh.triangles.size() > 4096) return sides;
  const std::vector<Vertex> points = used_positions(mesh);
  const double tolerance = 1e-9 * bounding_box(mesh).diagonal();
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

void instance_filter(const RTCFilterFunctionNArguments* args) {
  const auto* context = reinterpret_cast<const FilterContext*>(args->context);
  for (unsigned lane = 0; lane < args->N; ++lane) {
    if (args->valid[lane] == 0) continue;
    const auto instance = static_cast<int>(RTCHitN_instID(args->hit, args->N, lane, 0));
    if ((context->filter.skip >= 0 && instance == context->filter.skip) ||
        (context->filter.only >= 0 && instance != context->filter.only))
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

bool segment_meets_box(const Vertex& from, const Vertex& to, const BoundingBox& box) {
  double t0 = 0, t1 = 1;
  const Vertex d = to - from;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0) {
      if (from[a] < box.min[a] || from[a] > box.max[a]) return false;
      continue;
    }
    double near = (box.min[a] - from[a]) / d[a], far = (box.max[a] - from[a]) / d[a];
    if (near > far) std::swap(near, far);
    t0 = std::max(t0, near), t1 = std::min(t1, far);
  }
  return t0 <= t1;
}

// A convex proxy of one instance, in world space, tested by clipping instead of Embree.
struct ConvexInstance {
  unsigned id = 0;
  ConvexPolytope world;
};

bool filter_passes(std::size_t instance, const InstanceFilter& filter) {
  return static_cast<int>(instance) != filter.skip && (filter.only < 0 || static_cast<int>(instance) == filter.only) &&
         (filter.bits & instance_mask(instance)) != 0;
}

}  // namespace

struct RenderWorld::Impl {
  EmbreeDevice device;
  bool counting = false;
  std::map<RTCScene, std::unique_ptr<CountingBvh>> counting_bvhs;  // per object scene
  std::map<RTCScene, std::vector<std::optional<CountedInstance>>> counted;  // per top scene, per instance
  std::vector<RTCScene> owned;  // released at the end
  std::vector<std::vector<Sphere>> sphere_storage;
  RTCScene camera = nullptr, proxy = nullptr, outside = nullptr, inside = nullptr;
  std::vector<Eigen::Matrix3d> normal_matrices;  // per instance, object to world normals
  std::vector<int> light_of_triangle;
  std::vector<Vertex> light_normals;  // per light triangle, unit, world
  std::vector<ProxyKind> stochastic_kinds;  // per instance; outside for exact (mesh itself)
  std::vector<bool> has_outside;
  std::vector<bool> is_exact;  // per instance: no stochastic proxy (traced exactly)
  std::size_t instance_count = 0;
  bool has_inside = false;
  std::vector<BoundingBox> instance_bounds;
  std::vector<Sphere> instance_spheres;
  std::vector<const TangentSides*> instance_sides;
  std::vector<const TriangleMesh*> instance_meshes;
  std::map<std::string, TangentSides> mesh_sides;
  std::map<RTCScene, std::vector<ConvexInstance>> convex;  // per top scene
  std::map<RTCScene, unsigned> embree_masks;  // per top scene: the mask bits of the instances Embree traces

  ~Impl() {
    for (RTCScene scene : owned) rtcReleaseScene(scene);
  }

  RTCScene scene_of(const InstanceProxy& p) {
    RTCScene scene = device.new_scene();
    if (counting)
      counting_bvhs.emplace(scene, p.spheres.empty() ? std::make_unique<CountingBvh>(p.mesh)
                                                     : std::make_unique<CountingBvh>(std::span<const Sphere>(p.spheres)));
    owned.push_back(scene);
    // Hits inside instances go through the context filter too: Embree needs the flag on
    // the instanced scenes as well as on the top scenes.
    rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
    if (!p.spheres.empty()) {
      sphere_storage.push_back(p.spheres);
      attach_spheres(device, scene, sphere_storage.back());
    } else if (!p.mesh.triangles.empty()) {
      attach_triangles(device, scene, p.mesh);
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

  void add_instance(RTCScene top, RTCScene object, const Eigen::Affine3d& transform, unsigned id, unsigned mask) {
    embree_masks[top] |= mask;
    if (counting) {
      auto& list = counted[top];
      list.resize(std::max<std::size_t>(list.size(), id + 1));
      const CountingBvh* bvh = counting_bvhs.at(object).get();
      CountedInstance instance{bvh, transform.inverse(), {}};
      const BoundingBox& local = bvh->bounds();
      if (!local.empty())
        for (int corner = 0; corner < 8; ++corner)
          instance.world.extend(transform * Vertex(corner & 1 ? local.max.x() : local.min.x(), corner & 2 ? local.max.y() : local.min.y(),
                                                   corner & 4 ? local.max.z() : local.min.z()));
      list[id] = instance;
    }
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
    if (const auto it = convex.find(scene); it != convex.end())
      for (const ConvexInstance& instance : it->second) {
        if (!filter_passes(instance.id, filter)) continue;
        if (counting) ++g_thread_counts.nodes, ++g_thread_counts.primitives;  // one solid, clipped
        if (instance.world.meets_segment(from, to)) return true;
      }
    // No Embree call when every instance Embree holds here is filtered out (e.g. the only
    // instance without a convex proxy is the one the query skips).
    const auto masks = embree_masks.find(scene);
    if (masks == embree_masks.end() || (masks->second & query_mask(filter)) == 0) return false;
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
    RTCRay ray = segment_ray(from, to);
    ray.mask = query_mask(filter);
    const bool shared_bit = (filter.only >= 0 || filter.skip >= 0) && instance_count > 31;
    context.context.filter = shared_bit ? instance_filter : nullptr;
    rtcOccluded1(scene, &context.context, &ray);
    return ray.tfar == -std::numeric_limits<float>::infinity();
  }
};

RenderWorld::RenderWorld(const Scene& scene, const std::vector<MeshProxies>& proxies, bool counting)
    : impl_(std::make_unique<Impl>()) {
  Impl& w = *impl_;
  w.counting = counting;
  if (proxies.size() != scene.instances.size()) throw Error("render: one proxy set per scene instance expected");
  std::map<std::string, RTCScene> shared;  // "mesh\nspec" -> scene
  auto scene_for = [&](const std::string& mesh, const std::optional<InstanceProxy>& proxy) -> RTCScene {
    const std::string key = mesh + "\n" + (proxy ? proxy->spec : std::string("mesh"));
    if (auto it = shared.find(key); it != shared.end()) return it->second;
    const TriangleMesh& triangles = scene.mesh(mesh).mesh;
    RTCScene object = proxy ? w.scene_of(*proxy) : w.scene_of({ProxyKind::outside, "mesh", triangles, {}});
    shared.emplace(key, object);
    return object;
  };
  // Closed convex proxies (boxes, bounded hulls) of few faces are clipped against instead.
  std::map<std::string, std::optional<ConvexPolytope>> polytopes;  // "mesh\nspec"
  auto polytope_for = [&](const std::string& mesh, const std::optional<InstanceProxy>& proxy) -> const std::optional<ConvexPolytope>& {
    const std::string key = mesh + "\n" + (proxy ? proxy->spec : std::string("mesh"));
    if (auto it = polytopes.find(key); it != polytopes.end()) return it->second;
    const TriangleMesh& triangles = proxy ? proxy->mesh : scene.mesh(mesh).mesh;
    const bool spheres = proxy && !proxy->spheres.empty();
    return polytopes.emplace(key, spheres ? std::nullopt : ConvexPolytope::from_mesh(triangles)).first->second;
  };
  w.instance_count = scene.instances.size();
  w.has_inside = false;
  for (const MeshProxies& p : proxies) w.has_inside = w.has_inside || p.inside.has_value();
  w.camera = w.top_scene();
  w.proxy = w.top_scene();
  w.outside = w.top_scene();
  w.inside = w.top_scene();
  for (std::size_t i = 0; i < scene.instances.size(); ++i) {
    const SceneInstance& instance = scene.instances[i];
    const MeshProxies& p = proxies[i];
    const auto id = static_cast<unsigned>(i);
    const unsigned mask = instance_mask(i);
    w.add_instance(w.camera, scene_for(instance.mesh, std::nullopt), instance.transform, id, mask);
    // A proxy scene holds each instance's proxy clipped as a convex solid, or else traced by
    // Embree (whose object scene is only built then).
    auto add_proxy = [&](RTCScene top, const std::optional<InstanceProxy>& proxy) {
      if (const std::optional<ConvexPolytope>& polytope = polytope_for(instance.mesh, proxy))
        w.convex[top].push_back({id, polytope->transformed(instance.transform)});
      else
        w.add_instance(top, scene_for(instance.mesh, proxy), instance.transform, id, mask);
    };
    add_proxy(w.proxy, p.stochastic);
    add_proxy(w.outside, p.outside);
    if (p.inside) add_proxy(w.inside, p.inside);
    w.normal_matrices.push_back(instance.transform.linear().inverse().transpose());
    auto sides = w.mesh_sides.find(instance.mesh);
    if (sides == w.mesh_sides.end()) sides = w.mesh_sides.emplace(instance.mesh, tangent_sides(scene.mesh(instance.mesh).mesh)).first;
    w.instance_sides.push_back(&sides->second);
    w.instance_meshes.push_back(&scene.mesh(instance.mesh).mesh);
    BoundingBox world;
    const std::vector<Vertex> points = used_positions(scene.mesh(instance.mesh).mesh);
    for (const Vertex& v : points) world.extend(instance.transform * v);
    Sphere sphere{0.5 * (world.min + world.max), 0.0};
    for (const Vertex& v : points) sphere.radius = std::max(sphere.radius, (instance.transform * v - sphere.center).norm());
    sphere.radius *= 1 + 1e-6;  // beyond float rounding of Embree's triangle tests
    w.instance_bounds.push_back(world);
    w.instance_spheres.push_back(sphere);
    w.is_exact.push_back(!p.stochastic.has_value());
    w.stochastic_kinds.push_back(p.stochastic ? p.stochastic->kind : ProxyKind::outside);
    w.has_outside.push_back(p.outside.has_value());
  }
  // Lights: visible to camera rays only (mask), one geometry after the instances.
  TriangleMesh lights;
  for (std::size_t l = 0; l < scene.lights.size(); ++l)
    for (const auto& t : scene.lights[l].triangles) {
      const auto base = static_cast<VertexIndex>(lights.positions.size());
      lights.positions.insert(lights.positions.end(), t.begin(), t.end());
      lights.triangles.push_back({base, base + 1, base + 2});
      w.light_of_triangle.push_back(static_cast<int>(l));
      w.light_normals.push_back((t[1] - t[0]).cross(t[2] - t[0]).normalized());
    }
  if (!lights.triangles.empty()) {
    const unsigned id = attach_triangles(w.device, w.camera, lights, kLightMask);
    if (id != static_cast<unsigned>(scene.instances.size())) throw Error("render: unexpected light geometry id");
  }
  for (RTCScene top : {w.camera, w.proxy, w.outside, w.inside}) rtcCommitScene(top);
  w.device.throw_if_failed();
}

RenderWorld::~RenderWorld() = default;

std::optional<SurfaceHit> RenderWorld::intersect(const Vertex& origin, const Vertex& direction) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rayhit{};
  rayhit.ray = segment_ray(origin, origin + direction);
  rayhit.ray.tfar = std::numeric_limits<float>::infinity();
  rayhit.ray.mask = kAllInstances | kLightMask;
  rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rayhit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(impl_->camera, &context, &rayhit);
  if (rayhit.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
  SurfaceHit hit;
  hit.position = origin + static_cast<double>(rayhit.ray.tfar) * direction;
  Vertex normal(rayhit.hit.Ng_x, rayhit.hit.Ng_y, rayhit.hit.Ng_z);
  if (rayhit.hit.instID[0] != RTC_INVALID_GEOMETRY_ID) {
    hit.instance = static_cast<int>(rayhit.hit.instID[0]);
    normal = impl_->normal_matrices[static_cast<std::size_t>(hit.instance)] * normal;  // Embree gives it in object space
    const TangentSides& sides = *impl_->instance_sides[static_cast<std::size_t>(hit.instance)];
    if (!sides.behind.empty()) {
      // The winding's normal in world space; the shading normal faces the camera ray.
      const TriangleMesh& mesh = *impl_->instance_meshes[static_cast<std::size_t>(hit.instance)];
      const Triangle& t = mesh.triangles[rayhit.hit.primID];
      const Vertex winding = impl_->normal_matrices[static_cast<std::size_t>(hit.instance)] *
                             (mesh.positions[t[1]] - mesh.positions[t[0]]).cross(mesh.positions[t[2]] - mesh.positions[t[0]]);
      const bool along = winding.dot(direction) < 0;
      hit.own_mesh_behind = along ? sides.behind[rayhit.hit.primID] != 0 : sides.in_front[rayhit.hit.primID] != 0;
    }
  } else {
    hit.light = impl_->light_of_triangle[rayhit.hit.primID];
    hit.light_front = impl_->light_normals[rayhit.hit.primID].dot(direction) < 0;
  }
  normal.normalize();
  hit.normal = normal.dot(direction) > 0 ? -normal : normal;
  return hit;
}

bool RenderWorld::mesh_blocks(const Vertex& from, const Vertex& to, InstanceFilter filter) const {
  return impl_->blocked(impl_->camera, from, to, filter);
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
const Sphere& RenderWorld::instance_sphere(std::size_t instance) const { return impl_->instance_spheres[instance]; }

TraversalCounts& RenderWorld::thread_counts() { return g_thread_counts; }
bool RenderWorld::counting() const { return impl_->counting; }

bool RenderWorld::has_inside_proxies() const { return impl_->has_inside; }

bool RenderWorld::outside_complete(int skip) const {
  for (std::size_t i = 0; i < impl_->has_outside.size(); ++i)
    if (static_cast<int>(i) != skip && !impl_->has_outside[i]) return false;
  return true;
}

}  // namespace visproxy
