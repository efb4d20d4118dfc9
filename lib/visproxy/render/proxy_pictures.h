#pragma once
// Pictures of a proxy beside its mesh, for the report: the proxy drawn over the mesh, and
// the shadow each casts on a ground plane under a square area light, with the difference
// between the two shadows. Rendered through RenderWorld (Embree, with the proxies' proofs
// and rounding pads) and with no random choice: the same mesh and proxy give the same
// pixels whatever the number of threads.
//
// The stage is set from the mesh alone, so that every proxy of it is pictured the same way:
//  - the up axis is +y; the ground is the plane just below the mesh's lowest point
//    (a thousandth of the bounding-box diagonal below), seen from straight above, over a
//    square that holds the mesh's footprint and its shadow;
//  - the light is a square a quarter of the diagonal on a side, facing down, 0.8 diagonals
//    above the mesh's top and offset to one side so that the shadow falls beside it;
//  - every ground point is lit by the same regular grid of N x N points on the light, for
//    the mesh and for every proxy, so a difference between two shadows is the geometry's;
//  - the view of the proxy over the mesh looks at the mesh's bounding sphere from the
//    front, right and above, 2 x 2 rays a pixel.

#include <memory>
#include <nlohmann/json.hpp>
#include <vector>

#include "visproxy/image/image.h"
#include "visproxy/render/world/render_world.h"

namespace visproxy {

struct ProxyPictureOptions {
  int size = 192;                  ///< pixels on a side of every picture
  int light_samples_per_side = 6;  ///< N: N x N points on the light per ground point
};

struct ProxyPictures {
  /// The mesh in grey with the proxy over it, translucent in its kind's colour (outside
  /// blue, inside green, general red), its silhouette and creases drawn: an x-ray, so an
  /// inside proxy shows through the mesh.
  Image overlay;
  /// The ground lit by the light with the proxy's shadow (white lit, dark grey in umbra).
  Image shadow;
  /// The mesh's shadow faded, with missed shadow (the mesh blocks light the proxy lets
  /// through) in red and extra shadow (the proxy blocks light the mesh lets through) in blue.
  Image difference;
  /// Over the pictured ground, the sum of max(V_proxy - V_mesh, 0) (missed) and of
  /// max(V_mesh - V_proxy, 0) (extra), each over the sum of 1 - V_mesh (the mesh's shadow),
  /// where V is the fraction of the light's points a ground point sees. NaN when the mesh
  /// casts no shadow there.
  double missed_shadow = 0;
  double extra_shadow = 0;
};

/// The camera, ground and light of one mesh, its view and its shadow, made once and shared
/// by the pictures of all its proxies.
class ProxyPictureStage {
 public:
  /// Throws InvalidInputError when the mesh has no triangle with area.
  explicit ProxyPictureStage(const TriangleMesh& mesh, const ProxyPictureOptions& options = {});
  ~ProxyPictureStage();
  ProxyPictureStage(const ProxyPictureStage&) = delete;
  ProxyPictureStage& operator=(const ProxyPictureStage&) = delete;

  /// The ground with the mesh's shadow (the same shading as ProxyPictures::shadow).
  const Image& mesh_shadow() const;
  /// The fraction of the light each ground pixel sees past the mesh, row-major, top row first.
  const std::vector<double>& mesh_light_fractions() const;
  /// Where everything is, for rebuilding the stage in another renderer:
  /// {"size", "ground_height", "ground_x0", "ground_z0", "ground_side", "light_corner",
  ///  "light_u", "light_v", "light_samples_per_side"}: pixel (x, y) looks at the ground point
  /// (x0 + (x + 0.5) side / size, ground_height, z0 + (y + 0.5) side / size); the light is the
  /// square corner + s u + t v, s and t in [0, 1], facing -y.
  nlohmann::json geometry() const;

  /// The pictures of one proxy of the mesh (in the mesh's frame). A proxy marked proved is
  /// padded as RenderWorld pads it, so a proved outside proxy misses no shadow and a proved
  /// inside proxy adds none. An empty proxy blocks nothing.
  ProxyPictures pictures(const InstanceProxy& proxy) const;
  /// The fraction of the light each ground pixel sees past the proxy (same layout).
  std::vector<double> proxy_light_fractions(const InstanceProxy& proxy) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace visproxy
