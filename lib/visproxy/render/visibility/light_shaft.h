#pragma once
// The shaft from a shading point to every area light, for culling the instances a shadow
// segment to any light could meet.

#include <algorithm>
#include <cmath>
#include <vector>

#include "visproxy/mesh/sphere_set.h"
#include "visproxy/mesh/triangle_mesh.h"
#include "visproxy/scene/scene.h"

namespace visproxy {

// The shaft from a point to every light: the convex hull of the point and the lights'
// corners. meets() is conservative: false only when an instance is provably outside the
// shaft: its box separated along a coordinate axis, or its bounding sphere outside the
// circular cone around the shaft.
class LightShaft {
 public:
  explicit LightShaft(const Scene& scene) {
    for (const AreaLight& light : scene.lights)
      for (const auto& t : light.triangles)
        for (const Vertex& corner : t)
          if (std::find(corners_.begin(), corners_.end(), corner) == corners_.end()) corners_.push_back(corner);
  }

  /// The shaft from one apex: its bounds, and its cone once an instance needs it.
  struct From {
    Vertex apex, lo, hi, axis;
    bool has_cone = false;
    double cos_half = -1, sin_half = 0, reach = 0;
  };
  From from(const Vertex& apex) const {
    From shaft;
    shaft.apex = shaft.lo = shaft.hi = apex;
    for (const Vertex& c : corners_) shaft.lo = shaft.lo.cwiseMin(c), shaft.hi = shaft.hi.cwiseMax(c);
    return shaft;
  }

  bool meets(From& shaft, const BoundingBox& box, const Sphere& sphere) const {
    if (box.empty()) return false;
    // Separating coordinate axes: the shaft's extent is that of its points.
    if ((shaft.hi.array() < box.min.array()).any() || (shaft.lo.array() > box.max.array()).any()) return false;
    // The cone from the apex around the corners against the instance's bounding sphere.
    if (!shaft.has_cone) cone(shaft);
    if (shaft.cos_half <= 0) return true;  // wider than a half-space: no cone test
    const Vertex v = sphere.center - shaft.apex;
    const double distance = v.norm();
    if (distance <= sphere.radius) return true;
    if (distance - sphere.radius > shaft.reach) return false;
    // Within the cone grown by the sphere's angular radius beta: angle(axis, v) <= half + beta,
    // compared through cosines (half + beta < pi here since both are below pi / 2).
    const double sin_beta = sphere.radius / distance, cos_beta = std::sqrt(std::max(0.0, 1 - sin_beta * sin_beta));
    const double cos_limit = shaft.cos_half * cos_beta - shaft.sin_half * sin_beta;
    return shaft.axis.dot(v) / distance >= cos_limit - 1e-12;
  }

 private:
  void cone(From& shaft) const {
    shaft.has_cone = true;
    shaft.axis = Vertex::Zero();
    for (const Vertex& c : corners_) shaft.axis += (c - shaft.apex).normalized();
    shaft.cos_half = -1;
    if (shaft.axis.norm() == 0) return;
    shaft.axis.normalize();
    shaft.cos_half = 1, shaft.reach = 0;
    for (const Vertex& c : corners_) {
      shaft.cos_half = std::min(shaft.cos_half, shaft.axis.dot((c - shaft.apex).normalized()));
      shaft.reach = std::max(shaft.reach, (c - shaft.apex).norm());
    }
    shaft.sin_half = std::sqrt(std::max(0.0, 1 - shaft.cos_half * shaft.cos_half));
  }

  std::vector<Vertex> corners_;
};

}  // namespace visproxy
