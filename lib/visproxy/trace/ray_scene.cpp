#include "visproxy/trace/ray_scene.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <limits>

#include "visproxy/trace/embree_support.h"

namespace visproxy {

struct RayScene::Impl {
  EmbreeDevice device;
  RTCScene scene = nullptr;
  std::vector<Sphere> spheres;  // user geometry data: must outlive the scene
  Vertex origin = Vertex::Zero();

  ~Impl() {
    if (scene) rtcReleaseScene(scene);
  }
};

std::unique_ptr<RayScene::Impl> RayScene::make_impl() {
  auto impl = std::make_unique<RayScene::Impl>();
  impl->scene = impl->device.new_scene();
  return impl;
}

void RayScene::commit() {
  rtcCommitScene(impl_->scene);
  impl_->device.throw_if_failed();
}

RayScene::RayScene(std::span<const Sphere> spheres, const Vertex& origin) : impl_(make_impl()) {
  impl_->origin = origin;
  impl_->spheres.assign(spheres.begin(), spheres.end());
  for (Sphere& sphere : impl_->spheres) sphere.center -= origin;
  if (!spheres.empty()) attach_spheres(impl_->device, impl_->scene, impl_->spheres);
  commit();
}

RayScene::RayScene(const TriangleMesh& mesh, const Vertex& origin) : impl_(make_impl()) {
  impl_->origin = origin;
  if (!mesh.triangles.empty()) {
    if (origin == Vertex::Zero()) {
      attach_triangles(impl_->device, impl_->scene, mesh);
    } else {
      TriangleMesh local = mesh;
      for (Vertex& p : local.positions) p -= origin;
      attach_triangles(impl_->device, impl_->scene, local);
    }
  }
  commit();
}

RayScene::~RayScene() = default;

bool RayScene::segment_blocked(const Segment& segment) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay ray = segment_ray(segment.from - impl_->origin, segment.to - impl_->origin);
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
  impl_->device.throw_if_failed();
  return blocked;
}

}  // namespace visproxy
