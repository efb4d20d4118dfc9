#include "trace/ray_scene.h"

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

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

}  // namespace

struct RayScene::Impl {
  ErrorState errors;
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;

  void throw_if_failed() {
    std::lock_guard lock(errors.mutex);
    if (!errors.message.empty()) throw Error(errors.message);
  }
  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

RayScene::RayScene(const TriangleMesh& mesh) : impl_(std::make_unique<Impl>()) {
  impl_->device = rtcNewDevice(nullptr);
  if (!impl_->device) throw Error("Embree: cannot create a device (error " + std::to_string(rtcGetDeviceError(nullptr)) + ")");
  rtcSetDeviceErrorFunction(impl_->device, record_error, &impl_->errors);
  impl_->scene = rtcNewScene(impl_->device);
  rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_HIGH);
  impl_->throw_if_failed();

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
  rtcCommitScene(impl_->scene);
  impl_->throw_if_failed();
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
