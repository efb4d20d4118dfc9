#include "render/render_world.h"

#include <limits>
#include <map>

#include "core/errors.h"
#include "trace/embree_support.h"

namespace visproxy {
namespace {

// Instance i carries mask bit i % 31; lights carry bit 31. A query that skips or keeps one
// instance clears or keeps its bit, so Embree never visits what it must ignore; only when
// other instances share that bit (more than 31 instances) does the filter function decide.
constexpr unsigned kLightMask = 1u << 31;
constexpr unsigned kAllInstances = kLightMask - 1;
unsigned instance_mask(std::size_t instance) { return 1u << (instance % 31); }

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

}  // namespace

struct RenderWorld::Impl {
  EmbreeDevice device;
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

  ~Impl() {
    for (RTCScene scene : owned) rtcReleaseScene(scene);
  }

  RTCScene scene_of(const InstanceProxy& p) {
    RTCScene scene = device.new_scene();
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

  bool blocked(RTCScene scene, const Vertex& from, const Vertex& to, InstanceFilter filter) const {
    FilterContext context;
    rtcInitIntersectContext(&context.context);
    context.filter = filter;
    RTCRay ray = segment_ray(from, to);
    ray.mask = kAllInstances;
    if (filter.only >= 0) ray.mask = instance_mask(static_cast<std::size_t>(filter.only));
    if (filter.skip >= 0) ray.mask &= ~instance_mask(static_cast<std::size_t>(filter.skip));
    const bool shared_bit = (filter.only >= 0 || filter.skip >= 0) && instance_count > 31;
    context.context.filter = shared_bit ? instance_filter : nullptr;
    rtcOccluded1(scene, &context.context, &ray);
    return ray.tfar == -std::numeric_limits<float>::infinity();
  }
};

RenderWorld::RenderWorld(const Scene& scene, const std::vector<MeshProxies>& proxies) : impl_(std::make_unique<Impl>()) {
  Impl& w = *impl_;
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
    w.add_instance(w.proxy, scene_for(instance.mesh, p.stochastic), instance.transform, id, mask);
    w.add_instance(w.outside, scene_for(instance.mesh, p.outside), instance.transform, id, mask);
    if (p.inside) w.add_instance(w.inside, scene_for(instance.mesh, p.inside), instance.transform, id, mask);
    w.normal_matrices.push_back(instance.transform.linear().inverse().transpose());
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
  RTCGeometry geometry = rtcNewGeometry(w.device.get(), RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                               3 * sizeof(float), lights.positions.size()));
  auto* indices = static_cast<std::uint32_t*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                      3 * sizeof(std::uint32_t), lights.triangles.size()));
  w.device.throw_if_failed();
  for (std::size_t i = 0; i < lights.positions.size(); ++i)
    for (int a = 0; a < 3; ++a) vertices[3 * i + a] = static_cast<float>(lights.positions[i][a]);
  for (std::size_t i = 0; i < lights.triangles.size(); ++i)
    for (int a = 0; a < 3; ++a) indices[3 * i + a] = lights.triangles[i][a];
  rtcSetGeometryMask(geometry, kLightMask);
  rtcCommitGeometry(geometry);
  rtcAttachGeometryByID(w.camera, geometry, static_cast<unsigned>(scene.instances.size()));
  rtcReleaseGeometry(geometry);
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

bool RenderWorld::has_inside_proxies() const { return impl_->has_inside; }

bool RenderWorld::outside_complete(int skip) const {
  for (std::size_t i = 0; i < impl_->has_outside.size(); ++i)
    if (static_cast<int>(i) != skip && !impl_->has_outside[i]) return false;
  return true;
}

}  // namespace visproxy
