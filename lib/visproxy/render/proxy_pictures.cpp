#include "visproxy/render/proxy_pictures.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

#include "visproxy/core/errors.h"
#include "visproxy/render/world/sampling.h"

namespace visproxy {
namespace {

// Linear RGB of the report's kind colours (#1f77b4, #2ca02c, #d62728 in sRGB).
Color kind_color(ProxyKind kind) {
  switch (kind) {
    case ProxyKind::outside:
      return {0.0137, 0.1845, 0.4560};
    case ProxyKind::inside:
      return {0.0232, 0.3763, 0.0232};
    case ProxyKind::general:
      return {0.6795, 0.0194, 0.0212};
  }
  return Color::Constant(0.5);
}

const Color kBackground = Color::Constant(0.92);
const Color kMissedColor(0.80, 0.03, 0.03);
const Color kExtraColor(0.03, 0.22, 0.85);

// What one camera subsample saw of one surface.
struct ViewSample {
  bool hit = false;
  float facing = 0;  // |cos| between the ray and the normal
  float depth = 0;   // along the ray
  Vertex normal = Vertex::Zero();
};

// Ground shading of a pixel that sees `light` of the light: white lit, dark grey in umbra.
Color ground_color(double light) { return Color::Constant(0.12 + 0.78 * light); }

}  // namespace

struct ProxyPictureStage::Impl {
  ProxyPictureOptions options;
  double diagonal = 0;
  Scene scene;                                           // the light and the thumbnail camera; meshes are set per world
  Scene mesh_scene;                                      // the same with the mesh as its one instance
  double ground_height = 0;                              // y of the ground plane
  double ground_x0 = 0, ground_z0 = 0, ground_side = 0;  // the pictured square
  std::vector<ViewSample> mesh_view;                     // (2 size)^2 camera subsamples
  std::vector<double> mesh_light;                        // size^2 fractions
  Image mesh_shadow;

  int sub() const { return 2 * options.size; }

  // The ground point at the centre of pixel (x, y): x to +x, rows to +z (seen from above
  // with +z down the image).
  Vertex ground_point(int x, int y) const {
    const double step = ground_side / options.size;
    return {ground_x0 + (x + 0.5) * step, ground_height, ground_z0 + (y + 0.5) * step};
  }

  std::vector<Vertex> light_points() const {
    // The square a b c e is the triangles (a, b, c) and (a, c, e): its sides are b - a and e - a.
    const auto& t = scene.lights.front().triangles;
    const Vertex corner = t[0][0], u = t[0][1] - t[0][0], v = t[1][2] - t[0][0];
    const int n = options.light_samples_per_side;
    std::vector<Vertex> points;
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) points.push_back(corner + (i + 0.5) / n * u + (j + 0.5) / n * v);
    return points;
  }

  // The fraction of the light each ground pixel sees in `world`, through `blocks`.
  template <class Blocks>
  std::vector<double> light_fractions(const RenderWorld& world, const Blocks& blocks) const {
    const std::vector<Vertex> on_light = light_points();
    const Vertex light_normal(0, -1, 0);
    const int size = options.size;
    std::vector<double> fractions(static_cast<std::size_t>(size) * static_cast<std::size_t>(size));
    tbb::parallel_for(tbb::blocked_range<int>(0, size), [&](const tbb::blocked_range<int>& rows) {
      std::vector<Vertex> ends(on_light.size());
      std::vector<std::uint8_t> blocked(on_light.size());
      for (int y = rows.begin(); y != rows.end(); ++y)
        for (int x = 0; x < size; ++x) {
          const Vertex from = ground_point(x, y);
          for (std::size_t k = 0; k < on_light.size(); ++k)
            ends[k] = segment_end(world, on_light[k], light_normal, from);
          blocks(from, ends, blocked);
          const auto lit = std::count(blocked.begin(), blocked.end(), std::uint8_t{0});
          fractions[static_cast<std::size_t>(y) * static_cast<std::size_t>(size) + static_cast<std::size_t>(x)] =
              static_cast<double>(lit) / static_cast<double>(on_light.size());
        }
    });
    return fractions;
  }

  std::vector<ViewSample> view(const RenderWorld& world) const {
    const int n = sub();
    Camera camera = scene.camera;
    camera.width = camera.height = n;
    const CameraRays rays(camera);
    std::vector<ViewSample> samples(static_cast<std::size_t>(n) * static_cast<std::size_t>(n));
    tbb::parallel_for(tbb::blocked_range<int>(0, n), [&](const tbb::blocked_range<int>& rows) {
      for (int y = rows.begin(); y != rows.end(); ++y)
        for (int x = 0; x < n; ++x) {
          const Vertex direction = rays.direction(x + 0.5, y + 0.5);
          const std::optional<SurfaceHit> hit = world.intersect(rays.origin(), direction);
          if (!hit || hit->instance < 0) continue;
          ViewSample& s =
              samples[static_cast<std::size_t>(y) * static_cast<std::size_t>(n) + static_cast<std::size_t>(x)];
          s.hit = true;
          s.facing = static_cast<float>(std::abs(hit->normal.dot(direction)));
          s.depth = static_cast<float>(hit->distance);
          s.normal = hit->normal;
        }
    });
    return samples;
  }

  Scene scene_of(const TriangleMesh& mesh) const {
    Scene s = scene;
    s.meshes.push_back({"geometry", {}, mesh, {}});
    s.instances.push_back({"geometry", Eigen::Affine3d::Identity(), Color::Constant(0.5), {}});
    return s;
  }

  Image shadow_image(const std::vector<double>& light) const {
    Image image(options.size, options.size);
    for (std::size_t i = 0; i < light.size(); ++i) image.pixels[i] = ground_color(light[i]);
    return image;
  }
};

ProxyPictureStage::ProxyPictureStage(const TriangleMesh& mesh, const ProxyPictureOptions& options)
    : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.options = options;
  if (options.size < 8 || options.size > 4096) throw Error("proxy pictures: the size must be 8 to 4096 pixels");
  if (options.light_samples_per_side < 1 || options.light_samples_per_side > 64)
    throw Error("proxy pictures: 1 to 64 light samples a side");
  const BoundingBox box = bounding_box(mesh);
  s.diagonal = box.diagonal();
  if (!(s.diagonal > 0) || !std::isfinite(s.diagonal)) throw Error("proxy pictures: the mesh has no extent to picture");
  const double d = s.diagonal;
  const Vertex centre = 0.5 * (box.min + box.max);

  // The light: a square facing down, above and to one side of the mesh.
  s.ground_height = box.min.y() - 1e-3 * d;
  const double half = 0.125 * d;
  const Vertex light_centre(centre.x() + 0.35 * d, box.max.y() + 0.8 * d, centre.z() + 0.25 * d);
  const Vertex a = light_centre + Vertex(-half, 0, -half), b = light_centre + Vertex(half, 0, -half),
               c = light_centre + Vertex(half, 0, half), e = light_centre + Vertex(-half, 0, half);
  AreaLight light;
  light.triangles = {{a, b, c}, {a, c, e}};  // counter-clockwise seen from below: faces down
  light.radiance = Color::Ones();
  s.scene.lights.push_back(light);

  // The pictured ground: the footprint and the shadow of the box from every light corner.
  BoundingBox ground;
  for (int corner = 0; corner < 8; ++corner) {
    const Vertex p((corner & 1) ? box.max.x() : box.min.x(), (corner & 2) ? box.max.y() : box.min.y(),
                   (corner & 4) ? box.max.z() : box.min.z());
    ground.extend({p.x(), s.ground_height, p.z()});
    for (const Vertex& l : {a, b, c, e}) {
      const double t = (l.y() - s.ground_height) / (l.y() - p.y());
      const Vertex q = l + t * (p - l);
      ground.extend({q.x(), s.ground_height, q.z()});
    }
  }
  s.ground_side = 1.25 * std::max(ground.max.x() - ground.min.x(), ground.max.z() - ground.min.z());
  s.ground_x0 = 0.5 * (ground.min.x() + ground.max.x()) - 0.5 * s.ground_side;
  s.ground_z0 = 0.5 * (ground.min.z() + ground.max.z()) - 0.5 * s.ground_side;

  // The view: the bounding sphere filling a 30 degree field from the front, right and above.
  const double fov = 30;
  const double distance = 0.5 * d / std::sin(fov * std::numbers::pi / 360) * 1.04;
  s.scene.camera.at = centre;
  s.scene.camera.from = centre + distance * Vertex(0.55, 0.45, 1.0).normalized();
  s.scene.camera.up = Vertex(0, 1, 0);
  s.scene.camera.fov_degrees = fov;
  s.scene.camera.width = s.scene.camera.height = options.size;

  s.mesh_scene = s.scene_of(mesh);
  const RenderWorld world(s.mesh_scene, std::vector<MeshProxies>(1));
  s.mesh_view = s.view(world);
  s.mesh_light =
      s.light_fractions(world, [&](const Vertex& from, std::span<const Vertex> ends, std::span<std::uint8_t> blocked) {
        world.mesh_blocks(from, ends, blocked, {.skip = -1, .only = 0});
      });
  s.mesh_shadow = s.shadow_image(s.mesh_light);
}

ProxyPictureStage::~ProxyPictureStage() = default;

const Image& ProxyPictureStage::mesh_shadow() const { return impl_->mesh_shadow; }
const std::vector<double>& ProxyPictureStage::mesh_light_fractions() const { return impl_->mesh_light; }

nlohmann::json ProxyPictureStage::geometry() const {
  const auto& t = impl_->scene.lights.front().triangles;
  const auto point = [](const Vertex& p) { return nlohmann::json::array({p.x(), p.y(), p.z()}); };
  return {{"size", impl_->options.size},
          {"ground_height", impl_->ground_height},
          {"ground_x0", impl_->ground_x0},
          {"ground_z0", impl_->ground_z0},
          {"ground_side", impl_->ground_side},
          {"light_corner", point(t[0][0])},
          {"light_u", point(t[0][1] - t[0][0])},
          {"light_v", point(t[1][2] - t[0][0])},
          {"light_samples_per_side", impl_->options.light_samples_per_side}};
}

namespace {

// The mesh a proxy shows to camera rays: its triangles, or its balls as icospheres.
TriangleMesh view_mesh(const InstanceProxy& proxy) {
  return proxy.spheres.empty() ? proxy.mesh : sphere_set_mesh(proxy.spheres, 2);
}

}  // namespace

std::vector<double> ProxyPictureStage::proxy_light_fractions(const InstanceProxy& proxy) const {
  const Impl& s = *impl_;
  if (proxy.mesh.triangles.empty() && proxy.spheres.empty()) return std::vector<double>(s.mesh_light.size(), 1.0);
  // The proxy stands in for the mesh, as in a render: the world checks its claim's
  // conditions against the mesh and pads it for Embree's rounding.
  std::vector<MeshProxies> proxies(1);
  proxies[0].stochastic = proxy;
  const RenderWorld world(s.mesh_scene, proxies);
  return s.light_fractions(world,
                           [&](const Vertex& from, std::span<const Vertex> ends, std::span<std::uint8_t> blocked) {
                             for (std::size_t k = 0; k < ends.size(); ++k)
                               blocked[k] = world.proxy_blocks(from, ends[k], {.skip = -1, .only = 0});
                           });
}

ProxyPictures ProxyPictureStage::pictures(const InstanceProxy& proxy) const {
  const Impl& s = *impl_;
  ProxyPictures out;
  const int size = s.options.size, n = s.sub();

  // The overlay, from 2 x 2 subsamples a pixel.
  std::vector<ViewSample> proxy_view(s.mesh_view.size());
  const TriangleMesh shown = view_mesh(proxy);
  if (!shown.triangles.empty()) {
    const Scene scene = s.scene_of(shown);  // the world refers to it
    const RenderWorld world(scene, std::vector<MeshProxies>(1));
    proxy_view = s.view(world);
  }
  const Color tint = kind_color(proxy.kind);
  const double crease_cos = std::cos(25 * std::numbers::pi / 180), depth_jump = 0.03 * s.diagonal;
  auto at = [n](int x, int y) {
    return static_cast<std::size_t>(y) * static_cast<std::size_t>(n) + static_cast<std::size_t>(x);
  };
  // An edge of the proxy: a subsample whose neighbour sees a different surface of it, or none.
  auto edge = [&](int x, int y) {
    const ViewSample& p = proxy_view[at(x, y)];
    for (const auto& [dx, dy] : std::array<std::pair<int, int>, 4>{{{1, 0}, {-1, 0}, {0, 1}, {0, -1}}}) {
      const int qx = x + dx, qy = y + dy;
      if (qx < 0 || qy < 0 || qx >= n || qy >= n) continue;
      const ViewSample& q = proxy_view[at(qx, qy)];
      if (p.hit != q.hit) return p.hit;  // the silhouette, drawn on the proxy's side
      if (p.hit && (p.normal.dot(q.normal) < crease_cos || std::abs(p.depth - q.depth) > depth_jump)) return true;
    }
    return false;
  };
  out.overlay = Image(size, size);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      Color sum = Color::Zero();
      for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) {
          const int sx = 2 * x + i, sy = 2 * y + j;
          const ViewSample& m = s.mesh_view[at(sx, sy)];
          const ViewSample& p = proxy_view[at(sx, sy)];
          Color c = m.hit ? Color(Color::Constant(0.75 * (0.25 + 0.75 * m.facing))) : kBackground;
          if (p.hit) c = 0.55 * c + 0.45 * tint * (0.55 + 0.45 * p.facing);
          if (edge(sx, sy)) c = 0.15 * c + 0.85 * tint * 0.6;
          sum += c;
        }
      out.overlay.at(x, y) = 0.25 * sum;
    }

  // The shadows.
  const std::vector<double> light = proxy_light_fractions(proxy);
  out.shadow = s.shadow_image(light);
  out.difference = Image(size, size);
  double missed = 0, extra = 0, shadow = 0;
  for (std::size_t i = 0; i < light.size(); ++i) {
    const double mesh = s.mesh_light[i];
    const double miss = std::max(light[i] - mesh, 0.0), more = std::max(mesh - light[i], 0.0);
    missed += miss, extra += more, shadow += 1 - mesh;
    Color c = Color::Constant(0.55 + 0.4 * mesh);
    c = (1 - miss) * c + miss * kMissedColor;
    c = (1 - more) * c + more * kExtraColor;
    out.difference.pixels[i] = c;
  }
  const double none = std::numeric_limits<double>::quiet_NaN();
  out.missed_shadow = shadow > 0 ? missed / shadow : none;
  out.extra_shadow = shadow > 0 ? extra / shadow : none;
  return out;
}

}  // namespace visproxy
