#pragma once
// What every integrator samples: per-pixel random streams, points on the area lights by
// area, and the pinhole camera's rays.

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "visproxy/render/world/render_world.h"
#include "visproxy/scene/scene.h"

namespace visproxy {

/// splitmix64: a small, fast generator; one stream per (seed, pixel, pass).
class PixelRandom {
 public:
  PixelRandom(std::uint64_t seed, std::uint64_t pixel, std::uint64_t pass)
      : state_(seed * 0x9E3779B97F4A7C15ull ^ (pixel + 1) * 0xD1B54A32D192ED03ull ^ (pass + 1) * 0x8CB92BA72F3D8DD7ull) {
    next();
  }
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }

 private:
  std::uint64_t state_;
};

/// Seeds the stochastic estimators' stream apart from the camera and light stream, and the
/// virtual point lights' paths apart from both.
inline constexpr std::uint64_t kChoiceStream = 0x43484F4943455321ull;
inline constexpr std::uint64_t kLightPathStream = 0x4C49474854504154ull;

struct LightSample {
  Vertex position;
  Vertex normal;
  Color radiance;
  bool two_sided;
};

/// Every light triangle, chosen with probability proportional to its area: a point is then
/// uniform over the total emitting area, with density 1 / total_area.
class LightSampler {
 public:
  explicit LightSampler(const Scene& scene);
  double total_area() const { return total_; }
  bool empty() const { return triangles_.empty(); }
  LightSample sample(PixelRandom& random) const;

 private:
  struct Entry {
    std::array<Vertex, 3> corners;
    Vertex normal;
    const AreaLight* light;
  };
  std::vector<Entry> triangles_;
  std::vector<double> cumulative_;
  double total_ = 0;
};

/// The end of a shadow segment at a point `end` on a surface of normal `normal` (a light
/// sample, a virtual point light): moved off that plane, towards the side `from` is on, by
/// the world's rounding offset (RenderWorld::surface_offset with `distance`, the length of
/// the ray that found the point, 0 for points sampled on a surface), so that the surface
/// the end lies on cannot shadow it through float rounding.
Vertex segment_end(const RenderWorld& world, const Vertex& end, const Vertex& normal, const Vertex& from, double distance = 0);
inline Vertex light_end(const RenderWorld& world, const LightSample& y, const Vertex& x) {
  return segment_end(world, y.position, y.normal, x);
}

/// The geometry of a Lambertian point's segment to a light sample, as direct light weighs
/// it: the cosines at the point (of unit normal `normal`) and at the light, and the squared
/// distance. None when the light lies behind the point or the point behind a one-sided
/// light, or the two coincide: such a sample adds nothing and traces no segment.
struct LightGeometry {
  double cos_x = 0, cos_y = 0, distance2 = 0;
};
std::optional<LightGeometry> light_geometry(const Vertex& x, const Vertex& normal, const LightSample& y);

/// The pinhole camera's rays through jittered points of pixels.
class CameraRays {
 public:
  explicit CameraRays(const Camera& camera);
  /// The unit direction through image point (x, y), in pixels from the top left corner.
  Vertex direction(double x, double y) const;
  /// The unit direction through the image point at fractions (u, v) of its width and height.
  Vertex direction_at(double u, double v) const;
  const Vertex& origin() const { return origin_; }

 private:
  Vertex origin_, forward_, right_, up_;
  double tan_half_ = 0, aspect_ = 1;
  int width_ = 1, height_ = 1;
};

/// A unit direction around `normal` with density cos(theta) / pi, from two uniforms.
Vertex cosine_direction(const Vertex& normal, double u1, double u2);

}  // namespace visproxy
