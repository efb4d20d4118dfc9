#include "visproxy/render/world/sampling.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace visproxy {

LightSampler::LightSampler(const Scene& scene) {
  for (const AreaLight& light : scene.lights)
    for (const auto& t : light.triangles) {
      const Vertex cross = (t[1] - t[0]).cross(t[2] - t[0]);
      const double area = 0.5 * cross.norm();
      if (area <= 0) continue;
      total_ += area;
      cumulative_.push_back(total_);
      triangles_.push_back({t, cross.normalized(), &light});
    }
}

LightSample LightSampler::sample(PixelRandom& random) const {
  const double pick = random.uniform() * total_;
  const auto it = std::upper_bound(cumulative_.begin(), cumulative_.end(), pick);
  const auto& t = triangles_[std::min<std::size_t>(static_cast<std::size_t>(it - cumulative_.begin()), triangles_.size() - 1)];
  double a = random.uniform(), b = random.uniform();
  if (a + b > 1) a = 1 - a, b = 1 - b;
  return {t.corners[0] + a * (t.corners[1] - t.corners[0]) + b * (t.corners[2] - t.corners[0]), t.normal, t.light->radiance,
          t.light->two_sided};
}

std::optional<LightGeometry> light_geometry(const Vertex& x, const Vertex& normal, const LightSample& y) {
  const Vertex to_light = y.position - x;
  const double distance2 = to_light.squaredNorm();
  const double distance = std::sqrt(distance2);
  const double cos_x = normal.dot(to_light) / distance;
  double cos_y = -y.normal.dot(to_light) / distance;
  if (y.two_sided) cos_y = std::abs(cos_y);
  if (cos_x <= 0 || cos_y <= 0 || distance2 == 0) return std::nullopt;
  return LightGeometry{cos_x, cos_y, distance2};
}

Vertex segment_end(const RenderWorld& world, const Vertex& end, const Vertex& normal, const Vertex& from, double distance) {
  const double side = normal.dot(from - end) >= 0 ? 1.0 : -1.0;
  return end + side * world.surface_offset(end, distance) * normal;
}

CameraRays::CameraRays(const Camera& camera)
    : origin_(camera.from),
      forward_((camera.at - camera.from).normalized()),
      tan_half_(std::tan(camera.fov_degrees * std::numbers::pi / 360.0)),
      aspect_(static_cast<double>(camera.width) / camera.height),
      width_(camera.width),
      height_(camera.height) {
  right_ = forward_.cross(camera.up).normalized();
  up_ = right_.cross(forward_);
}

Vertex CameraRays::direction(double x, double y) const {
  const double sx = (2 * x / width_ - 1) * tan_half_ * aspect_;
  const double sy = (1 - 2 * y / height_) * tan_half_;
  return (forward_ + sx * right_ + sy * up_).normalized();
}

Vertex CameraRays::direction_at(double u, double v) const {
  const double sx = (2 * u - 1) * tan_half_ * aspect_, sy = (1 - 2 * v) * tan_half_;
  return (forward_ + sx * right_ + sy * up_).normalized();
}

Vertex cosine_direction(const Vertex& normal, double u1, double u2) {
  // Malley's method: a uniform point on the unit disc, lifted to the hemisphere.
  const double r = std::sqrt(u1), phi = 2 * std::numbers::pi * u2;
  const double x = r * std::cos(phi), y = r * std::sin(phi), z = std::sqrt(std::max(0.0, 1 - u1));
  const Vertex helper = std::abs(normal.x()) > 0.9 ? Vertex(0, 1, 0) : Vertex(1, 0, 0);
  const Vertex t = normal.cross(helper).normalized(), b = normal.cross(t);
  return (x * t + y * b + z * normal).normalized();
}

}  // namespace visproxy
