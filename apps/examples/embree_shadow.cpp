// A minimal Embree renderer of your own that lets a visproxy proxy stand in for one mesh in
// its shadow rays: direct light from the scene's area lights on Lambertian surfaces, with
// the proxied instance's visibility estimated without bias (eq. 8 or the control variate).
//
//   visproxy-example-embree-shadow SCENE.json MESH_NAME PROXY_FOLDER PROXY_NAME OUT.pfm
//                                  [SPP] [SEED] [eq8|control-variate]
//
// The scene file only supplies geometry, lights and camera (visproxy::load_scene); the
// rendering is this file's. The proxy replaces the first instance of MESH_NAME, whose mesh
// must be the one PROXY_FOLDER was built from (`visproxy build MESH -o PROXY_FOLDER`). Its
// image estimates the same pixels as `visproxy render SCENE --visibility exact`.

#include <embree3/rtcore.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <visproxy/image/image.h>
#include <visproxy/runtime/runtime.h>
#include <visproxy/scene/scene.h>

using visproxy::Vertex;

namespace {

// Your geometry: triangles in world space, in float, one Embree scene per role.
unsigned add_triangles(RTCDevice device, RTCScene scene, const std::vector<Vertex>& points,
                       const std::vector<visproxy::Triangle>& triangles) {
  RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, points.size()));
  for (std::size_t i = 0; i < points.size(); ++i)
    for (int k = 0; k < 3; ++k) v[3 * i + static_cast<std::size_t>(k)] = static_cast<float>(points[i][k]);
  auto* t = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, triangles.size()));
  for (std::size_t i = 0; i < triangles.size(); ++i)
    for (std::size_t k = 0; k < 3; ++k) t[3 * i + k] = triangles[i][k];
  rtcCommitGeometry(g);
  const unsigned id = rtcAttachGeometry(scene, g);
  rtcReleaseGeometry(g);
  return id;
}

bool occluded(RTCScene scene, const Vertex& from, const Vertex& to) {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  const Vertex d = to - from;
  RTCRay ray{};
  ray.org_x = static_cast<float>(from.x()), ray.org_y = static_cast<float>(from.y()), ray.org_z = static_cast<float>(from.z());
  ray.dir_x = static_cast<float>(d.x()), ray.dir_y = static_cast<float>(d.y()), ray.dir_z = static_cast<float>(d.z());
  ray.tnear = 0, ray.tfar = 1, ray.mask = ~0u;
  rtcOccluded1(scene, &context, &ray);
  return ray.tfar < 0;
}

}  // namespace

int main(int argc, char** argv) try {
  if (argc < 6) {
    std::fprintf(stderr, "usage: %s SCENE.json MESH_NAME PROXY_FOLDER PROXY_NAME OUT.pfm [SPP] [SEED] [eq8|control-variate]\n", argv[0]);
    return 2;
  }
  const visproxy::Scene scene = visproxy::load_scene(argv[1]);
  const std::string proxied_mesh = argv[2];
  const int spp = argc > 6 ? std::atoi(argv[6]) : 16;
  const unsigned long long seed = argc > 7 ? std::strtoull(argv[7], nullptr, 10) : 1;
  const bool control_variate = argc > 8 && std::string(argv[8]) == "control-variate";

  RTCDevice device = rtcNewDevice(nullptr);
  RTCScene camera_scene = rtcNewScene(device);  // everything, for camera rays
  RTCScene others = rtcNewScene(device);        // what is always traced exactly
  RTCScene exact = rtcNewScene(device);         // the proxied instance's mesh
  RTCScene proxy_scene = rtcNewScene(device);   // its proxy
  std::vector<int> instance_of;                 // camera_scene geometry ID -> instance, -1 for a light
  int proxied = -1;
  for (std::size_t i = 0; i < scene.instances.size(); ++i) {
    const visproxy::SceneMesh& mesh = scene.mesh(scene.instances[i].mesh);
    std::vector<Vertex> world;
    for (const Vertex& p : mesh.mesh.positions) world.push_back(scene.instances[i].transform * p);
    add_triangles(device, camera_scene, world, mesh.mesh.triangles);
    instance_of.push_back(static_cast<int>(i));
    const bool stands_in = proxied < 0 && scene.instances[i].mesh == proxied_mesh;
    if (stands_in) proxied = static_cast<int>(i);
    add_triangles(device, stands_in ? exact : others, world, mesh.mesh.triangles);
  }
  if (proxied < 0) throw visproxy::Error(std::string(argv[1]) + ": no instance of mesh '" + proxied_mesh + "'");
  struct LightTriangle { Vertex a, b, c, normal; double area; const visproxy::AreaLight* light; };
  std::vector<LightTriangle> light_triangles;
  double total_area = 0;
  for (const visproxy::AreaLight& light : scene.lights)
    for (const auto& t : light.triangles) {
      const Vertex n = (t[1] - t[0]).cross(t[2] - t[0]);
      light_triangles.push_back({t[0], t[1], t[2], n.normalized(), 0.5 * n.norm(), &light});
      total_area += 0.5 * n.norm();
      add_triangles(device, camera_scene, {t[0], t[1], t[2]}, {{0, 1, 2}});
      instance_of.push_back(-1);
    }

  // The proxy, loaded with its proof and placed where the instance is.
  const visproxy::SceneMesh& mesh = scene.mesh(proxied_mesh);
  const visproxy::RuntimeProxy proxy = visproxy::RuntimeProxy::load(argv[3], argv[4], mesh.file);
  const visproxy::PlacedProxy placed = proxy.place({.transform = scene.instances[static_cast<std::size_t>(proxied)].transform});
  placed.attach(device, proxy_scene);
  for (RTCScene s : {camera_scene, others, exact, proxy_scene}) rtcCommitScene(s);
  const visproxy::ShadowEstimator estimator(placed);
  std::uint64_t proxy_tests = 0, mesh_tests = 0;
  auto trace_proxy = [&](const Vertex& a, const Vertex& b) { ++proxy_tests; return occluded(proxy_scene, a, b); };
  auto trace_mesh = [&](const Vertex& a, const Vertex& b) { ++mesh_tests; return occluded(exact, a, b); };

  // The pinhole camera of the scene file.
  const visproxy::Camera& camera = scene.camera;
  const Vertex forward = (camera.at - camera.from).normalized(), right = forward.cross(camera.up).normalized();
  const Vertex up = right.cross(forward);
  const double tan_half = std::tan(camera.fov_degrees * std::numbers::pi / 360), aspect = double(camera.width) / camera.height;
  const double offset = 1e-5 * (camera.at - camera.from).norm();

  visproxy::Image image(camera.width, camera.height);
  for (int py = 0; py < camera.height; ++py)
    for (int px = 0; px < camera.width; ++px) {
      std::mt19937_64 random(seed * 0x9E3779B97F4A7C15ull + static_cast<unsigned long long>(py * camera.width + px));
      std::uniform_real_distribution<double> uniform(0, 1);
      visproxy::LearnedCorrections learned;  // the control variate learns per pixel
      visproxy::Color sum = visproxy::Color::Zero();
      for (int s = 0; s < spp; ++s) {
        const double sx = (2 * (px + uniform(random)) / camera.width - 1) * tan_half * aspect;
        const double sy = (1 - 2 * (py + uniform(random)) / camera.height) * tan_half;
        const Vertex dir = (forward + sx * right + sy * up).normalized();
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        RTCRayHit hit{};
        hit.ray.org_x = float(camera.from.x()), hit.ray.org_y = float(camera.from.y()), hit.ray.org_z = float(camera.from.z());
        hit.ray.dir_x = float(dir.x()), hit.ray.dir_y = float(dir.y()), hit.ray.dir_z = float(dir.z());
        hit.ray.tnear = 0, hit.ray.tfar = INFINITY, hit.ray.mask = ~0u;
        hit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(camera_scene, &context, &hit);
        if (hit.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
        Vertex normal = Vertex(hit.hit.Ng_x, hit.hit.Ng_y, hit.hit.Ng_z).normalized();
        const int instance = instance_of[hit.hit.geomID];
        if (instance < 0) {  // a light, seen from its front
          const LightTriangle& t = light_triangles[hit.hit.geomID - scene.instances.size()];
          if (t.normal.dot(dir) < 0 || t.light->two_sided) sum += t.light->radiance;
          continue;
        }
        if (normal.dot(dir) > 0) normal = -normal;
        const Vertex x = camera.from + double(hit.ray.tfar) * dir + offset * normal;
        // One light point by area, and its shadow segment through the estimator.
        double pick = uniform(random) * total_area;
        const LightTriangle* t = &light_triangles.back();
        for (const LightTriangle& candidate : light_triangles)
          if ((pick -= candidate.area) < 0) { t = &candidate; break; }
        double a = uniform(random), b = uniform(random);
        if (a + b > 1) a = 1 - a, b = 1 - b;
        const Vertex y = t->a + a * (t->b - t->a) + b * (t->c - t->a);
        const Vertex to_light = y - x;
        const double d2 = to_light.squaredNorm(), d = std::sqrt(d2);
        const double cos_x = normal.dot(to_light) / d;
        double cos_y = -t->normal.dot(to_light) / d;
        if (t->light->two_sided) cos_y = std::abs(cos_y);
        const double u = uniform(random);
        if (cos_x <= 0 || cos_y <= 0) continue;
        const Vertex end = y - offset * to_light / d;
        if (occluded(others, x, end)) continue;
        const double v = control_variate ? estimator.control_variate(x, end, u, learned, trace_proxy, trace_mesh)
                                         : estimator.eq8(x, end, u, trace_proxy, trace_mesh);
        const visproxy::Color albedo = scene.instances[static_cast<std::size_t>(instance)].albedo;
        sum += (v * cos_x * cos_y / d2 * total_area / std::numbers::pi) * albedo.cwiseProduct(t->light->radiance);
      }
      image.at(px, py) = sum / spp;
    }
  visproxy::write_pfm(argv[5], image);
  std::printf("%s: %dx%d, %d spp, seed %llu, %s with proxy %s (%s) for mesh '%s': %llu proxy tests, %llu mesh tests%s%s\n",
              argv[5], camera.width, camera.height, spp, seed, control_variate ? "control variate" : "eq. 8", argv[4],
              std::string(visproxy::kind_name(placed.kind())).c_str(), proxied_mesh.c_str(),
              static_cast<unsigned long long>(proxy_tests), static_cast<unsigned long long>(mesh_tests),
              placed.note().empty() ? "" : "; note: ", placed.note().c_str());
  for (RTCScene s : {camera_scene, others, exact, proxy_scene}) rtcReleaseScene(s);
  rtcReleaseDevice(device);
  return 0;
} catch (const visproxy::Error& error) {
  std::fprintf(stderr, "visproxy-example-embree-shadow: %s\n", error.what());
  return 2;
} catch (const std::exception& error) {
  std::fprintf(stderr, "visproxy-example-embree-shadow: internal error: %s\n", error.what());
  return 3;
}
