// The measuring loop of `visproxy measure` against a bare Embree loop on the same rays:
// rays per second per core for the exact mesh, and the ratio of the two (target: ours at
// least 0.8 of bare). Bare: the rays converted to RTCRay once, then rtcOccluded1 in a
// loop, with the same scene flags (robust, high quality). Ours: RayScene::segment_blocked
// per ray (one core) and measure_proxy's parallel tracing and counting (all cores).
//   visproxy-bench-measure [--rays N] [--repetitions R] [--subdivide L] [MESH]

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "visproxy/core/process.h"
#include "visproxy/measure/proxy_measurement.h"
#include "visproxy/measure/random_lines.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/mesh/subdivide.h"
#include "visproxy/trace/ray_scene.h"

namespace {

using namespace visproxy;

double best_seconds(int repetitions, const std::function<void()>& run) {
  run();  // warm-up
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < repetitions; ++i) {
    const auto start = std::chrono::steady_clock::now();
    run();
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return best;
}

struct BareScene {
  RTCDevice device = rtcNewDevice(nullptr);
  RTCScene scene = rtcNewScene(device);
  explicit BareScene(const TriangleMesh& mesh) {
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
    rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
    RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                          3 * sizeof(float), mesh.positions.size()));
    auto* t = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                             3 * sizeof(unsigned), mesh.triangles.size()));
    for (std::size_t i = 0; i < mesh.positions.size(); ++i)
      for (int a = 0; a < 3; ++a) v[3 * i + a] = static_cast<float>(mesh.positions[i][a]);
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
      for (int a = 0; a < 3; ++a) t[3 * i + a] = mesh.triangles[i][a];
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(scene, geometry);
    rtcReleaseGeometry(geometry);
    rtcCommitScene(scene);
  }
  ~BareScene() {
    rtcReleaseScene(scene);
    rtcReleaseDevice(device);
  }
  std::size_t occluded(const std::vector<RTCRay>& rays, std::size_t begin, std::size_t end) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    std::size_t blocked = 0;
    for (std::size_t i = begin; i < end; ++i) {
      RTCRay ray = rays[i];
      rtcOccluded1(scene, &context, &ray);
      blocked += ray.tfar < 0 ? 1 : 0;
    }
    return blocked;
  }
};

}  // namespace

int main(int argc, char** argv) {
  visproxy::disable_transparent_huge_pages();  // see visproxy/core/process.h
  std::size_t ray_count = 1'000'000;
  int repetitions = 5, subdivide = 0;
  std::string path = std::string(VISPROXY_MESH_DIR) + "/bunny00.off";
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--rays" && i + 1 < argc) ray_count = std::stoul(argv[++i]);
    else if (arg == "--repetitions" && i + 1 < argc) repetitions = std::stoi(argv[++i]);
    else if (arg == "--subdivide" && i + 1 < argc) subdivide = std::stoi(argv[++i]);
    else path = arg;
  }
  TriangleMesh mesh = read_mesh(path);
  if (subdivide > 0) mesh = subdivide_midpoint(mesh, subdivide);
  const std::vector<Segment> segments = isotropic_lines(bounding_sphere(mesh), ray_count, 1);
  std::vector<RTCRay> rays(segments.size());
  for (std::size_t i = 0; i < segments.size(); ++i) {
    RTCRay& r = rays[i];
    std::memset(&r, 0, sizeof r);
    const Vertex d = segments[i].to - segments[i].from;
    r.org_x = static_cast<float>(segments[i].from.x()), r.org_y = static_cast<float>(segments[i].from.y()),
    r.org_z = static_cast<float>(segments[i].from.z());
    r.dir_x = static_cast<float>(d.x()), r.dir_y = static_cast<float>(d.y()), r.dir_z = static_cast<float>(d.z());
    r.tnear = 0, r.tfar = 1, r.mask = 0xFFFFFFFFu;
  }
  const BareScene bare(mesh);
  const RayScene ours(mesh);
  const std::size_t cores = static_cast<std::size_t>(tbb::info::default_concurrency());

  std::size_t bare_blocked = 0, ours_blocked = 0;
  const double bare_one = best_seconds(repetitions, [&] { bare_blocked = bare.occluded(rays, 0, rays.size()); });
  const double ours_one = best_seconds(repetitions, [&] {
    ours_blocked = 0;
    for (const Segment& s : segments) ours_blocked += ours.segment_blocked(s) ? 1 : 0;
  });
  const double bare_all = best_seconds(repetitions, [&] {
    bare_blocked = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, rays.size(), 1024), std::size_t{0},
        [&](const tbb::blocked_range<std::size_t>& r, std::size_t sum) { return sum + bare.occluded(rays, r.begin(), r.end()); },
        std::plus<>());
  });
  // measure_proxy's own loop: the proxy traced in parallel and the ray types counted
  // (timing switched off by timing zero rays).
  ReferenceRays reference;
  reference.rays = segments;
  reference.mesh_blocked = ours.segments_blocked(segments);
  ProxyMeasurement measured;
  const double ours_all = best_seconds(repetitions, [&] { measured = measure_proxy(reference, ours, ProxyKind::general, {.rays = 0}); });

  const double n = static_cast<double>(rays.size());
  std::printf("visproxy-bench-measure: %s%s, %zu triangles, %zu isotropic lines (seed 1), best of %d, %zu cores\n",
              path.c_str(), subdivide > 0 ? (" subdivided " + std::to_string(subdivide) + "x").c_str() : "",
              mesh.triangles.size(), rays.size(), repetitions, cores);
  std::printf("%-46s %12s %14s %12s\n", "loop", "ns per ray", "M rays/s/core", "ours / bare");
  std::printf("%-46s %12.1f %14.2f %12s\n", "bare rtcOccluded1, one core", bare_one * 1e9 / n, n / bare_one / 1e6, "");
  std::printf("%-46s %12.1f %14.2f %12.3f\n", "RayScene::segment_blocked, one core", ours_one * 1e9 / n, n / ours_one / 1e6,
              bare_one / ours_one);
  std::printf("%-46s %12.1f %14.2f %12s\n", "bare rtcOccluded1, all cores (TBB)", bare_all * 1e9 / n,
              n / bare_all / 1e6 / static_cast<double>(cores), "");
  std::printf("%-46s %12.1f %14.2f %12.3f\n", "measure_proxy (trace + count), all cores", ours_all * 1e9 / n,
              n / ours_all / 1e6 / static_cast<double>(cores), bare_all / ours_all);
  std::printf("ours / bare: throughput of our loop as a fraction of the bare loop's (target >= 0.8). Blocked: bare %zu, "
              "ours %zu, types 1-4 %llu/%llu/%llu/%llu\n",
              bare_blocked, ours_blocked, static_cast<unsigned long long>(measured.counts.counts[0]),
              static_cast<unsigned long long>(measured.counts.counts[1]),
              static_cast<unsigned long long>(measured.counts.counts[2]),
              static_cast<unsigned long long>(measured.counts.counts[3]));
  return 0;
}
