#include "trace/ray_scene.h"

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <limits>
#include <mutex>
#include <string>

#include "core/errors.h"

namespace visproxy {
namespace {

// Embree reports errors through a C callback; throwing from it would unwind through
// Embree's frames, so the callback records the first error and the caller throws.
struct ErrorState {
  std::mutex mutex;
  std::string message;
};

void record_error(void* user, RTCError code, const char* text) {
  auto* state = static_cast<ErrorState*>(user);
  std::lock_guard lock(state->mutex);
  if (state->message.empty())
    state->message = "Embree error " + std::to_string(static_cast<int>(code)) + ": " + (text ? text : "");
}

float round_down(double value) {
  const auto rounded = static_cast<float>(value);
  return static_cast<double>(rounded) <= value ? rounded : std::nextafter(rounded, -std::numeric_limits<float>::infinity());
}

float round_up(double value) {
  const auto rounded = static_cast<float>(value);
  return static_cast<double>(rounded) >= value ? rounded : std::nextafter(rounded, std::numeric_limits<float>::infinity());
}

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

// Whether the ray's parameter interval (tnear, tfar) meets the closed ball: the roots of
// |o + t d - c|^2 = r^2, in double precision from the ray's float values.
bool ray_meets_ball(const Sphere& sphere, const Vertex& origin, const Vertex& direction, double tnear, double tfar) {
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

void sphere_occluded(const RTCOccludedFunctionNArguments* args) {
  const Sphere& sphere = static_cast<const Sphere*>(args->geometryUserPtr)[args->primID];
  for (unsigned lane = 0; lane < args->N; ++lane) {
    if (args->valid[lane] == 0) continue;
    RTCRayN* ray = args->ray;
    const unsigned n = args->N;
    const Vertex origin(RTCRayN_org_x(ray, n, lane), RTCRayN_org_y(ray, n, lane), RTCRayN_org_z(ray, n, lane));
    const Vertex direction(RTCRayN_dir_x(ray, n, lane), RTCRayN_dir_y(ray, n, lane), RTCRayN_dir_z(ray, n, lane));
    float& tfar = RTCRayN_tfar(ray, n, lane);
    if (ray_meets_ball(sphere, origin, direction, RTCRayN_tnear(ray, n, lane), tfar))
      tfar = -std::numeric_limits<float>::infinity();
  }
}

// Closest-hit queries are not offered by RayScene; the intersect callback only has to be
// valid. It reports nothing, so rtcIntersect on a sphere scene finds no hit.
void sphere_intersect(const RTCIntersectFunctionNArguments*) {}

}  // namespace

struct RayScene::Impl {
  ErrorState errors;
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  std::vector<Sphere> spheres;  // user geometry data: must outlive the scene

  void throw_if_failed() {
    std::lock_guard lock(errors.mutex);
    if (!errors.message.empty()) throw Error(errors.message);
  }
  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

std::unique_ptr<RayScene::Impl> RayScene::make_impl() {
  auto impl = std::make_unique<RayScene::Impl>();
  impl->device = rtcNewDevice(nullptr);
  if (!impl->device) throw Error("Embree: cannot create a device (error " + std::to_string(rtcGetDeviceError(nullptr)) + ")");
  rtcSetDeviceErrorFunction(impl->device, record_error, &impl->errors);
  impl->scene = rtcNewScene(impl->device);
  rtcSetSceneBuildQuality(impl->scene, RTC_BUILD_QUALITY_HIGH);
  rtcSetSceneFlags(impl->scene, RTC_SCENE_FLAG_ROBUST);
  impl->throw_if_failed();
  return impl;
}

void RayScene::commit() {
  rtcCommitScene(impl_->scene);
  impl_->throw_if_failed();
}

RayScene::RayScene(std::span<const Sphere> spheres) : impl_(make_impl()) {
  impl_->spheres.assign(spheres.begin(), spheres.end());
  if (!spheres.empty()) {
    RTCGeometry geometry = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_USER);
    impl_->throw_if_failed();
    rtcSetGeometryUserPrimitiveCount(geometry, static_cast<unsigned>(impl_->spheres.size()));
    rtcSetGeometryUserData(geometry, impl_->spheres.data());
    rtcSetGeometryBoundsFunction(geometry, sphere_bounds, nullptr);
    rtcSetGeometryIntersectFunction(geometry, sphere_intersect);
    rtcSetGeometryOccludedFunction(geometry, sphere_occluded);
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(impl_->scene, geometry);
    rtcReleaseGeometry(geometry);
  }
  commit();
}

RayScene::RayScene(const TriangleMesh& mesh) : impl_(make_impl()) {

  if (!mesh.triangles.empty()) {
    RTCGeometry geometry = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    impl_->throw_if_failed();
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                                 3 * sizeof(float), mesh.positions.size()));
    auto* indices = static_cast<std::uint32_t*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(std::uint32_t), mesh.triangles.size()));
    if (!vertices || !indices) {
      rtcReleaseGeometry(geometry);
      impl_->throw_if_failed();
      throw Error("Embree: cannot allocate geometry buffers");
    }
    for (std::size_t i = 0; i < mesh.positions.size(); ++i)
      for (int axis = 0; axis < 3; ++axis) vertices[3 * i + axis] = static_cast<float>(mesh.positions[i][axis]);
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
      for (int corner = 0; corner < 3; ++corner) indices[3 * i + corner] = mesh.triangles[i][corner];
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(impl_->scene, geometry);
    rtcReleaseGeometry(geometry);
  }
  commit();
}

RayScene::~RayScene() = default;

bool RayScene::segment_blocked(const Segment& segment) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay ray{};
  const Vertex direction = segment.to - segment.from;
  ray.org_x = static_cast<float>(segment.from.x());
  ray.org_y = static_cast<float>(segment.from.y());
  ray.org_z = static_cast<float>(segment.from.z());
  ray.dir_x = static_cast<float>(direction.x());
  ray.dir_y = static_cast<float>(direction.y());
  ray.dir_z = static_cast<float>(direction.z());
  ray.tnear = 0.0f;
  ray.tfar = 1.0f;
  ray.mask = 0xFFFFFFFFu;
  ray.flags = 0;
  rtcOccluded1(impl_->scene, &context, &ray);
  return ray.tfar == -std::numeric_limits<float>::infinity();
}

std::vector<std::uint8_t> RayScene::segments_blocked(std::span<const Segment> segments) const {
  std::vector<std::uint8_t> blocked(segments.size(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, segments.size(), 1024),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t i = range.begin(); i != range.end(); ++i)
                        blocked[i] = segment_blocked(segments[i]) ? 1 : 0;
                    });
  impl_->throw_if_failed();
  return blocked;
}

}  // namespace visproxy
