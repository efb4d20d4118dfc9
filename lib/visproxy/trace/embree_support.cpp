#include "visproxy/trace/embree_support.h"

#include <cmath>
#include <limits>
#include <new>
#include <utility>

#include "visproxy/core/errors.h"

namespace visproxy {
namespace {

void sphere_bounds(const RTCBoundsFunctionArguments* args) {
  const Sphere& sphere = static_cast<const Sphere*>(args->geometryUserPtr)[args->primID];
  RTCBounds* bounds = args->bounds_o;
  bounds->lower_x = round_down(sphere.center.x() - sphere.radius);
  bounds->lower_y = round_down(sphere.center.y() - sphere.radius);
  bounds->lower_z = round_down(sphere.center.z() - sphere.radius);
  bounds->upper_x = round_up(sphere.center.x() + sphere.radius);
  bounds->upper_y = round_up(sphere.center.y() + sphere.radius);
  bounds->upper_z = round_up(sphere.center.z() + sphere.radius);
}

void sphere_occluded(const RTCOccludedFunctionNArguments* args) {
  const Sphere& sphere = static_cast<const Sphere*>(args->geometryUserPtr)[args->primID];
  for (unsigned lane = 0; lane < args->N; ++lane) {
    if (args->valid[lane] == 0) continue;
    RTCRayN* ray = args->ray;
    const unsigned n = args->N;
    const Vertex origin(RTCRayN_org_x(ray, n, lane), RTCRayN_org_y(ray, n, lane), RTCRayN_org_z(ray, n, lane));
    const Vertex direction(RTCRayN_dir_x(ray, n, lane), RTCRayN_dir_y(ray, n, lane), RTCRayN_dir_z(ray, n, lane));
    float& tfar = RTCRayN_tfar(ray, n, lane);
    if (!segment_meets_ball(sphere, origin, direction, RTCRayN_tnear(ray, n, lane), tfar)) continue;
    // Hand the hit to the filter functions (the renderer's own-instance test), as
    // Embree does for its own geometry. Single rays only (rtcOccluded1): N is 1.
    if (n == 1) {
      RTCHit hit{};
      hit.Ng_x = 0, hit.Ng_y = 0, hit.Ng_z = 0;
      hit.geomID = args->geomID;
      hit.primID = args->primID;
      for (unsigned level = 0; level < RTC_MAX_INSTANCE_LEVEL_COUNT; ++level) hit.instID[level] = args->context->instID[level];
      int valid = -1;
      RTCFilterFunctionNArguments filter{};
      filter.valid = &valid;
      filter.geometryUserPtr = args->geometryUserPtr;
      filter.context = args->context;
      filter.ray = ray;
      filter.hit = reinterpret_cast<RTCHitN*>(&hit);
      filter.N = 1;
      rtcFilterOcclusion(args, &filter);
      if (valid == 0) continue;
    }
    tfar = -std::numeric_limits<float>::infinity();
  }
}

void sphere_intersect(const RTCIntersectFunctionNArguments*) {}

}  // namespace

namespace {

void* create_node(RTCThreadLocalAllocator allocator, unsigned int, void*) {
  void* memory = rtcThreadLocalAlloc(allocator, sizeof(BinaryBvhNode), 16);
  return new (memory) BinaryBvhNode();
}

void set_children(void* node, void** children, unsigned int count, void*) {
  for (unsigned i = 0; i < count && i < 2; ++i)
    static_cast<BinaryBvhNode*>(node)->children[i] = static_cast<BinaryBvhNode*>(children[i]);
}

void set_bounds(void* node, const RTCBounds** bounds, unsigned int count, void*) {
  auto* n = static_cast<BinaryBvhNode*>(node);
  for (unsigned i = 0; i < count && i < 2; ++i) {
    n->lower[i][0] = bounds[i]->lower_x, n->lower[i][1] = bounds[i]->lower_y, n->lower[i][2] = bounds[i]->lower_z;
    n->upper[i][0] = bounds[i]->upper_x, n->upper[i][1] = bounds[i]->upper_y, n->upper[i][2] = bounds[i]->upper_z;
  }
}

void* create_leaf(RTCThreadLocalAllocator allocator, const RTCBuildPrimitive* primitives, size_t count, void*) {
  auto* ids = static_cast<std::uint32_t*>(rtcThreadLocalAlloc(allocator, count * sizeof(std::uint32_t), 16));
  for (size_t i = 0; i < count; ++i) ids[i] = primitives[i].primID;
  void* memory = rtcThreadLocalAlloc(allocator, sizeof(BinaryBvhNode), 16);
  BinaryBvhNode* leaf = new (memory) BinaryBvhNode();
  leaf->leaf = true;
  leaf->count = static_cast<std::uint32_t>(count);
  leaf->ids = ids;
  return leaf;
}

}  // namespace

const BinaryBvhNode* build_binary_bvh(EmbreeDevice& device, RTCBVH bvh, std::vector<RTCBuildPrimitive> primitives,
                                      RTCBuildQuality quality) {
  if (primitives.empty()) return nullptr;
  RTCBuildArguments args = rtcDefaultBuildArguments();
  args.buildQuality = quality;
  args.maxBranchingFactor = 2;
  args.maxLeafSize = 4;
  args.bvh = bvh;
  args.primitiveCount = primitives.size();
  args.primitives = primitives.data();
  args.primitiveArrayCapacity = primitives.capacity();
  args.createNode = create_node;
  args.setNodeChildren = set_children;
  args.setNodeBounds = set_bounds;
  args.createLeaf = create_leaf;
  const auto* root = static_cast<const BinaryBvhNode*>(rtcBuildBVH(&args));
  device.throw_if_failed();
  if (!root) throw Error("Embree could not build a BVH");
  return root;
}

float round_down(double value) {
  const auto rounded = static_cast<float>(value);
  return static_cast<double>(rounded) <= value ? rounded : std::nextafter(rounded, -std::numeric_limits<float>::infinity());
}

float round_up(double value) {
  const auto rounded = static_cast<float>(value);
  return static_cast<double>(rounded) >= value ? rounded : std::nextafter(rounded, std::numeric_limits<float>::infinity());
}

bool segment_meets_ball(const Sphere& sphere, const Vertex& origin, const Vertex& direction, double tnear, double tfar) {
  const Vertex offset = origin - sphere.center;
  const double a = direction.squaredNorm();
  const double b = direction.dot(offset);
  const double c = offset.squaredNorm() - sphere.radius * sphere.radius;
  if (a == 0) return c <= 0 && tnear < tfar;
  const double discriminant = b * b - a * c;
  if (discriminant < 0) return false;
  // Stable roots: q = -(b + sign(b) sqrt(disc)), t = q / a and c / q.
  const double root = std::sqrt(discriminant);
  const double q = -(b + std::copysign(root, b));
  double t0 = q / a;
  double t1 = q != 0 ? c / q : t0;
  if (t0 > t1) std::swap(t0, t1);
  return t1 > tnear && t0 < tfar;
}

EmbreeDevice::EmbreeDevice() {
  device_ = rtcNewDevice(nullptr);
  // Out of memory is reported as such, so that callers name the step that ran out.
  if (!device_ && rtcGetDeviceError(nullptr) == RTC_ERROR_OUT_OF_MEMORY) throw std::bad_alloc();
  if (!device_) throw Error("Embree: cannot create a device (error " + std::to_string(rtcGetDeviceError(nullptr)) + ")");
  rtcSetDeviceErrorFunction(device_, record, &errors_);
}

EmbreeDevice::~EmbreeDevice() {
  if (device_) rtcReleaseDevice(device_);
}

void EmbreeDevice::record(void* user, RTCError code, const char* text) {
  auto* state = static_cast<ErrorState*>(user);
  std::lock_guard lock(state->mutex);
  if (state->message.empty()) {
    state->code = code;
    state->message = "Embree error " + std::to_string(static_cast<int>(code)) + ": " + (text ? text : "");
  }
}

void EmbreeDevice::throw_if_failed() {
  std::lock_guard lock(errors_.mutex);
  if (errors_.code == RTC_ERROR_OUT_OF_MEMORY) throw std::bad_alloc();
  if (!errors_.message.empty()) throw Error(errors_.message);
}

RTCScene EmbreeDevice::new_scene() {
  RTCScene scene = rtcNewScene(device_);
  throw_if_failed();
  rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
  rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
  return scene;
}

unsigned attach_triangles(EmbreeDevice& device, RTCScene scene, const TriangleMesh& mesh, unsigned mask) {
  RTCGeometry geometry = rtcNewGeometry(device.get(), RTC_GEOMETRY_TYPE_TRIANGLE);
  device.throw_if_failed();
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                               3 * sizeof(float), mesh.positions.size()));
  auto* indices = static_cast<std::uint32_t*>(rtcSetNewGeometryBuffer(
      geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(std::uint32_t), mesh.triangles.size()));
  if (!vertices || !indices) {
    rtcReleaseGeometry(geometry);
    device.throw_if_failed();
    throw Error("Embree: cannot allocate geometry buffers");
  }
  for (std::size_t i = 0; i < mesh.positions.size(); ++i)
    for (int axis = 0; axis < 3; ++axis) vertices[3 * i + axis] = static_cast<float>(mesh.positions[i][axis]);
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
    for (int corner = 0; corner < 3; ++corner) indices[3 * i + corner] = mesh.triangles[i][corner];
  rtcSetGeometryMask(geometry, mask);
  rtcCommitGeometry(geometry);
  const unsigned id = rtcAttachGeometry(scene, geometry);
  rtcReleaseGeometry(geometry);
  device.throw_if_failed();
  return id;
}

unsigned attach_spheres(EmbreeDevice& device, RTCScene scene, std::span<const Sphere> spheres, unsigned mask) {
  RTCGeometry geometry = rtcNewGeometry(device.get(), RTC_GEOMETRY_TYPE_USER);
  device.throw_if_failed();
  rtcSetGeometryUserPrimitiveCount(geometry, static_cast<unsigned>(spheres.size()));
  rtcSetGeometryUserData(geometry, const_cast<Sphere*>(spheres.data()));
  rtcSetGeometryBoundsFunction(geometry, sphere_bounds, nullptr);
  rtcSetGeometryIntersectFunction(geometry, sphere_intersect);
  rtcSetGeometryOccludedFunction(geometry, sphere_occluded);
  rtcSetGeometryMask(geometry, mask);
  rtcCommitGeometry(geometry);
  const unsigned id = rtcAttachGeometry(scene, geometry);
  rtcReleaseGeometry(geometry);
  device.throw_if_failed();
  return id;
}

RTCRay segment_ray(const Vertex& from, const Vertex& to) {
  RTCRay ray{};
  const Vertex direction = to - from;
  ray.org_x = static_cast<float>(from.x());
  ray.org_y = static_cast<float>(from.y());
  ray.org_z = static_cast<float>(from.z());
  ray.dir_x = static_cast<float>(direction.x());
  ray.dir_y = static_cast<float>(direction.y());
  ray.dir_z = static_cast<float>(direction.z());
  ray.tnear = 0.0f;
  ray.tfar = 1.0f;
  ray.mask = 0xFFFFFFFFu;
  ray.flags = 0;
  return ray;
}

}  // namespace visproxy
