// The proof fuzzer: random small scenes made to break the shortcuts the renderer proves,
// and the checks that each shortcut gives the answer it claims to.
//
//   scene_proofs [--seed S] [--scenes N] [--first K] [--work DIR] [--verbose]
//
// Each scene (seeded by S and its index, so that one scene can be run again alone with
// --first K --scenes 1) holds meshes made to be hard: a box whose top face is a fan of sliver
// triangles, a bumpy closed blob, a torus, a thin slab and its nearly coplanar twin, a
// closed room seen from inside; instances rotated, mirrored, unevenly scaled or sheared,
// overlapping, up to 40 of them (past the 31 mask bits), far from the origin; area lights
// above the scene, a hair below a sliver face's plane, inside an outside proxy, inside a
// mesh, on a proxy's face. Its proxies come from the renderer's own path
// (prepare_scene_proxies: built, verified, cached). Then:
//  - exact:   `bounds` gives the bytes of `exact`, direct and with virtual point lights;
//  - cuts:    lightcuts at error 0 with visibility bounds lower, upper and both give the bytes
//             of no bounds, with no proof disagreeing with its traced light;
//  - disks:   occluder disks with clusters, lazily made or not, give the images of every
//             disk; and on the API, from random points (tiny balls far away included), the
//             clustered and flat tests agree for single segments and groups;
//  - unbiased: eq. 8 (equal and adaptive probabilities) and the control variate (equal and
//             learned) agree with exact within 4 standard errors of their paired difference
//             (same camera and light samples), confirmed by a second seed before it counts;
//  - folders: a proxy folder tampered with (kinds, claims and verdicts swapped, files
//             swapped or edited by hand, a verdict copied from another folder) is refused or
//             demoted with one line by the render path and the runtime, never trusted: a
//             proxy that keeps its claim is proved again from its files, and every file the
//             folder ships holds its geometry.
// Prints one line per failure and a summary; exits 1 when a check failed.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/core/random.h"
#include "visproxy/folder/proxy_folder.h"
#include "visproxy/render/scene_proxies.h"
#include "visproxy/folder/verdict.h"
#include "visproxy/mesh/mesh_topology.h"
#include "visproxy/mesh/read_mesh.h"
#include "visproxy/mesh/sphere_set.h"
#include "visproxy/mesh/write_mesh.h"
#include "visproxy/render/world/render_world.h"
#include "visproxy/render/renderer.h"
#include "visproxy/render/visibility/occluder_disks.h"
#include "visproxy/runtime/runtime.h"
#include "render/render_test_scenes.h"
#include "test_meshes.h"

namespace fs = std::filesystem;
using nlohmann::json;
using namespace visproxy;

namespace {

// ---------------------------------------------------------------------------------------
// Tally

struct Tally {
  std::map<std::string, std::uint64_t> checks;  // by kind
  std::vector<std::string> failures;
  std::uint64_t scenes = 0;
  void pass(const std::string& kind) { ++checks[kind]; }
  void fail(const std::string& kind, std::uint64_t scene, const std::string& what) {
    ++checks[kind];
    failures.push_back("scene " + std::to_string(scene) + ": " + kind + ": " + what);
    std::printf("FAIL scene %llu: %s: %s\n", static_cast<unsigned long long>(scene), kind.c_str(), what.c_str());
    std::fflush(stdout);
  }
};

// ---------------------------------------------------------------------------------------
// Meshes, each closed (every edge used once each way).

// A box whose top face is a fan of `fan` sliver triangles (render_test_scenes.h).
TriangleMesh sliver_box(Random& random, int fan) {
  return visproxy::testing::sliver_fan_box(Vertex(0.6 + random.uniform(), 0.6 + random.uniform(), 0.2 + 0.6 * random.uniform()), fan);
}

TriangleMesh blob(Random& random) {
  TriangleMesh mesh = sphere_set_mesh({Sphere{Vertex::Zero(), 1.0}}, 2);
  const Vertex k1 = random.unit_vector() * (2 + 3 * random.uniform()), k2 = random.unit_vector() * (2 + 3 * random.uniform());
  const double amplitude = 0.25 * random.uniform();
  for (Vertex& p : mesh.positions) p *= 1 + amplitude * std::sin(k1.dot(p)) * std::cos(k2.dot(p));
  return mesh;  // radial moves keep the icosphere's outward winding
}

TriangleMesh torus(Random& random) {
  return visproxy::testing::torus(1.0, 0.15 + 0.3 * random.uniform(), 12 + static_cast<int>(random.below(12)), 6 + static_cast<int>(random.below(6)));
}

// Two thin slabs, one a hair above the other (nearly coplanar faces): one closed mesh of two parts.
TriangleMesh slab_pair(Random& random) {
  const double gap = std::pow(10.0, -3 - 3 * random.uniform());
  TriangleMesh mesh = visproxy::testing::box({0, 0, 0}, {1.5, 1, 0.05});
  append_mesh(mesh, visproxy::testing::box({0.2 * random.uniform(), 0.1, 0.05 + gap}, {1.3, 0.9, 0.1 + gap}));
  return mesh;
}

// A closed room: a box whose faces point inwards (its "solid", where the winding number
// is not 0, is its air), holding the camera and the lights.
TriangleMesh room(Random& random) {
  TriangleMesh mesh = visproxy::testing::box({0, 0, 0}, {4 + random.uniform(), 3 + random.uniform(), 2.5 + random.uniform()});
  for (Triangle& t : mesh.triangles) std::swap(t[1], t[2]);
  return mesh;
}

// ---------------------------------------------------------------------------------------
// Scenes

Eigen::Matrix3d random_rotation(Random& random) {
  Eigen::Quaterniond q(random.uniform() - 0.5, random.uniform() - 0.5, random.uniform() - 0.5, random.uniform() - 0.5);
  q.normalize();
  return q.toRotationMatrix();
}

struct Made {
  Scene scene;
  std::vector<std::string> kinds;  // per mesh: what it is
  // Sliver boxes: the frame their box [0, size] was turned into (their vertices are given
  // tilted, so that Embree's float normals of the slivers tilt off their plane).
  std::map<std::string, std::pair<Eigen::Affine3d, BoundingBox>> box_frames;
  bool tiny_balls = false;
  std::string summary;
};

AreaLight quad_light(const Vertex& corner, const Vertex& u, const Vertex& v, double radiance, bool two_sided) {
  AreaLight light;
  light.triangles.push_back({corner, corner + u, corner + u + v});
  light.triangles.push_back({corner, corner + u + v, corner + v});
  light.radiance = Color::Constant(radiance);
  light.two_sided = two_sided;
  return light;
}

Made make_scene(std::uint64_t scene_seed) {
  Random random(scene_seed);
  Made made;
  Scene& scene = made.scene;
  scene.file = "fuzz-scene-" + std::to_string(scene_seed) + ".json";
  // Far from the origin, sometimes very far.
  const double far = std::array<double, 5>{0, 0, 1e3, 1e5, 1e6}[random.below(5)];
  const Vertex offset = far * random.unit_vector();
  const bool with_room = random.below(5) == 0;
  const int shapes = 1 + static_cast<int>(random.below(3));
  const char* names[] = {"sliver_box", "blob", "torus", "slab_pair"};
  std::vector<std::string> shape_names;
  for (int s = 0; s < shapes; ++s) {
    // Sliver boxes most often: they carry the tangent-plane shortcut's hardest case.
    const std::size_t pick = random.below(10) < 4 ? 0 : random.below(4);
    SceneMesh mesh;
    mesh.name = std::string(names[pick]) + "-" + std::to_string(s);
    switch (pick) {
      case 0: {
        mesh.mesh = sliver_box(random, 40 + static_cast<int>(random.below(1400)));
        Eigen::Affine3d frame = Eigen::Affine3d::Identity();
        if (random.below(10) < 7) frame.linear() = random_rotation(random);
        const BoundingBox box = bounding_box(mesh.mesh);
        for (Vertex& p : mesh.mesh.positions) p = frame * p;
        made.box_frames[mesh.name] = {frame, box};
        break;
      }
      case 1: mesh.mesh = blob(random); break;
      case 2: mesh.mesh = torus(random); break;
      default: mesh.mesh = slab_pair(random); break;
    }
    made.kinds.push_back(names[pick]);
    shape_names.push_back(mesh.name);
    scene.meshes.push_back(std::move(mesh));
  }
  if (with_room) {
    scene.meshes.push_back({"room", {}, room(random), {}});
    made.kinds.push_back("room");
  }
  // Instances: a few, or many small ones (past the 31 mask bits).
  const bool many = random.below(6) == 0;
  const int count = many ? 25 + static_cast<int>(random.below(16)) : 1 + static_cast<int>(random.below(5));
  const double spread = many ? 6.0 : 2.5;
  const char* outside_specs[] = {"aabb", "obb", "hull", "hull:8"};
  for (int i = 0; i < count; ++i) {
    SceneInstance instance;
    instance.mesh = shape_names[random.below(shape_names.size())];
    Eigen::Matrix3d linear = random_rotation(random);
    double scale = many ? 0.2 + 0.3 * random.uniform() : 0.5 + random.uniform();
    Eigen::Vector3d scales = Eigen::Vector3d::Constant(scale);
    const bool uneven = random.below(4) == 0, mirrored = random.below(3) == 0, sheared = random.below(10) == 0;
    if (uneven) scales = scales.cwiseProduct(Eigen::Vector3d(0.5 + random.uniform(), 0.5 + random.uniform(), 0.5 + random.uniform()));
    if (mirrored) scales.x() = -scales.x();
    linear = linear * scales.asDiagonal();
    if (sheared) linear(0, 1) += 0.3 * (random.uniform() - 0.5) * scale;
    instance.transform.linear() = linear;
    instance.transform.translation() = offset + spread * Vertex(random.uniform() - 0.5, random.uniform() - 0.5, 0.5 * (random.uniform() - 0.5));
    instance.albedo = Color(0.3 + 0.6 * random.uniform(), 0.3 + 0.6 * random.uniform(), 0.3 + 0.6 * random.uniform());
    // Proxies: one or two outside, maybe inside spheres, maybe a sphere set as the
    // stochastic proxy and the occluder disks; in a random order (the first is stochastic).
    std::vector<std::string> specs{outside_specs[random.below(4)]};
    if (random.below(2) == 0) specs.push_back(outside_specs[random.below(4)]);
    if (random.below(2) == 0) specs.push_back("inside:6");
    if (random.below(2) == 0) specs.push_back("spheres:" + std::to_string(4 + random.below(12)));
    for (std::size_t k = specs.size(); k > 1; --k) std::swap(specs[k - 1], specs[random.below(k)]);
    specs.erase(std::unique(specs.begin(), specs.end()), specs.end());
    instance.proxies = specs;
    scene.instances.push_back(std::move(instance));
  }
  // Tiny sphere sets far away: small instances at 500-3000 units (occluder disks' edge).
  if (random.below(4) == 0) {
    made.tiny_balls = true;
    const int tiny = 3 + static_cast<int>(random.below(6));
    for (int i = 0; i < tiny; ++i) {
      SceneInstance instance;
      instance.mesh = shape_names[random.below(shape_names.size())];
      instance.transform.linear() = random_rotation(random) * (1e-3 + 0.01 * random.uniform());
      instance.transform.translation() = offset + (500 + 2500 * random.uniform()) * random.unit_vector();
      instance.proxies = {"spheres:" + std::to_string(4 + random.below(8))};
      scene.instances.push_back(std::move(instance));
    }
  }
  if (with_room) {
    SceneInstance instance;
    instance.mesh = "room";
    instance.transform = Eigen::Translation3d(offset - Vertex(2.5, 2, 1.2)) * Eigen::Affine3d::Identity();
    instance.proxies = {random.below(2) == 0 ? "aabb" : "hull"};
    if (random.below(2) == 0) instance.proxies.push_back("inside:6");
    scene.instances.push_back(std::move(instance));
  }

  // Lights.
  const Vertex up(0, 0, 1);
  scene.lights.push_back(quad_light(offset + Vertex(-1, -1, 3 + random.uniform()), {2, 0, 0}, {0, 2, 0}, 4 + 4 * random.uniform(),
                                    random.below(2) == 0));
  if (scene.lights.front().triangles.size() == 2 && !scene.lights.front().two_sided) {
    // Facing down: counter-clockwise seen from below.
    for (auto& t : scene.lights.front().triangles) std::swap(t[1], t[2]);
  }
  // A thin light a hair below the top face plane of a sliver box instance, beside it.
  for (std::size_t i = 0; i < scene.instances.size() && i < 6; ++i) {
    const SceneInstance& instance = scene.instances[i];
    if (!made.box_frames.contains(instance.mesh) || random.below(4) == 0) continue;
    const auto& [frame, box] = made.box_frames.at(instance.mesh);
    const double hair = std::pow(10.0, -4 - 3 * random.uniform()) * (box.max - box.min).norm();
    // In the box's frame: beside the box (x beyond its side), just below the top plane.
    const Vertex corner(box.max.x() * (1.05 + 0.5 * random.uniform()), box.max.y() * random.uniform(), box.max.z() - hair);
    const Vertex u(0.3 + random.uniform(), 0, 0), v(0, 0.01 + 0.05 * random.uniform(), 0);
    const Eigen::Affine3d t = instance.transform * frame;
    AreaLight light = quad_light(t * corner, t.linear() * u, t.linear() * v, 6, true);
    scene.lights.push_back(light);
    break;
  }
  // A light inside an instance's bounding box but outside its mesh, or inside its mesh.
  if (random.below(3) == 0) {
    const SceneInstance& instance = scene.instances[random.below(std::min<std::size_t>(scene.instances.size(), 6))];
    const BoundingBox box = bounding_box(scene.mesh(instance.mesh).mesh);
    const Vertex p = random.below(2) == 0 ? Vertex(box.min + 0.04 * (box.max - box.min)) : Vertex(0.5 * (box.min + box.max));
    const Eigen::Affine3d& t = instance.transform;
    scene.lights.push_back(quad_light(t * p, t.linear() * Vertex(0.02, 0, 0), t.linear() * Vertex(0, 0.02, 0), 8, true));
  }
  // A light on a face of an instance's bounding box (where an aabb proxy has its face).
  if (random.below(3) == 0) {
    const SceneInstance& instance = scene.instances[random.below(std::min<std::size_t>(scene.instances.size(), 6))];
    const BoundingBox box = bounding_box(scene.mesh(instance.mesh).mesh);
    const Eigen::Affine3d& t = instance.transform;
    const Vertex p(box.min.x() + 0.3 * (box.max.x() - box.min.x()), box.min.y() + 0.3 * (box.max.y() - box.min.y()), box.max.z());
    scene.lights.push_back(quad_light(t * p, t.linear() * Vertex(0.2, 0, 0), t.linear() * Vertex(0, 0.2, 0), 5, true));
  }
  if (with_room) {
    scene.lights.push_back(quad_light(offset + Vertex(-0.5, -0.5, 1.0), {1, 0, 0}, {0, 1, 0}, 5, true));
  }

  // Camera: at a sliver box's top face (when there is one), or at the scene's middle.
  scene.camera.width = 24;
  scene.camera.height = 18;
  scene.camera.fov_degrees = 35 + 30 * random.uniform();
  const SceneInstance& target = scene.instances[random.below(std::min<std::size_t>(scene.instances.size(), 6))];
  Eigen::Affine3d target_frame = Eigen::Affine3d::Identity();
  BoundingBox target_box = bounding_box(scene.mesh(target.mesh).mesh);
  if (made.box_frames.contains(target.mesh)) std::tie(target_frame, target_box) = made.box_frames.at(target.mesh);
  const Vertex target_top = target.transform * target_frame *
                            Vertex(0.5 * (target_box.min.x() + target_box.max.x()), 0.5 * (target_box.min.y() + target_box.max.y()),
                                   target_box.max.z());
  scene.camera.at = random.below(3) == 0 ? offset : target_top;
  Vertex from_direction = random.unit_vector();
  if (from_direction.z() < 0.2) from_direction.z() = 0.2 + 0.8 * random.uniform();
  if (made.box_frames.contains(target.mesh) && random.below(10) < 7) {
    // Above the sliver face, along its normal (give or take a little).
    from_direction = ((target.transform * target_frame).linear() * Vertex(0, 0, 1)).normalized() + 0.3 * random.unit_vector();
    scene.camera.at = target_top;
  }
  scene.camera.from = scene.camera.at + (with_room ? 1.0 : 2.5 + 3 * random.uniform()) * from_direction.normalized();
  if (with_room) scene.camera.from = offset + Vertex(0.3, 0.2, 0.1);
  scene.camera.up = std::abs(from_direction.normalized().z()) > 0.99 ? Vertex(0, 1, 0) : up;

  made.summary = std::to_string(scene.meshes.size()) + " meshes, " + std::to_string(scene.instances.size()) + " instances, " +
                 std::to_string(scene.lights.size()) + " lights, " + (far > 0 ? "offset " + std::to_string(far) : "at the origin");
  return made;
}

// ---------------------------------------------------------------------------------------
// Comparisons

bool same_bytes(const Image& a, const Image& b) {
  return a.width == b.width && a.height == b.height && a.pixels.size() == b.pixels.size() &&
         std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(Color)) == 0;
}

std::string difference_text(const Image& a, const Image& b) {
  std::size_t differing = 0;
  double largest = 0;
  for (std::size_t i = 0; i < a.pixels.size() && i < b.pixels.size(); ++i)
    if (std::memcmp(&a.pixels[i], &b.pixels[i], sizeof(Color)) != 0) {
      ++differing;
      largest = std::max(largest, (a.pixels[i] - b.pixels[i]).cwiseAbs().maxCoeff() / std::max(1e-300, a.pixels[i].cwiseAbs().maxCoeff()));
    }
  return std::to_string(differing) + " of " + std::to_string(a.pixels.size()) + " pixels differ (largest relative " +
         std::to_string(largest) + ")";
}

// The paired difference of a stochastic image and the exact one (same camera and light
// samples): its mean over pixels in standard errors (pixels are independent; under the
// hypothesis of no bias each pixel's difference has mean 0, so sum d^2 estimates the sum
// of their variances).
double paired_z(const Image& estimate, const Image& exact) {
  double sum = 0, squares = 0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < exact.pixels.size(); ++i) {
    const double d = estimate.pixels[i].sum() - exact.pixels[i].sum();
    sum += d, squares += d * d, ++n;
  }
  if (!(squares > 0)) return sum == 0 ? 0.0 : std::numeric_limits<double>::infinity();
  return sum / std::sqrt(squares);
}

std::string one_line(const std::string& text) {
  return text.find('\n') == std::string::npos ? text : text.substr(0, text.find('\n')) + " [...more lines]";
}

// ---------------------------------------------------------------------------------------
// The renderer's checks.

struct SceneRun {
  std::uint64_t index = 0;
  const Scene* scene = nullptr;
  const std::vector<MeshProxies>* proxies = nullptr;
  const RenderWorld* world = nullptr;
  Random* random = nullptr;
  Tally* tally = nullptr;
  bool any_spheres = false;
};

RenderResult render_with(const SceneRun& run, RenderOptions options) {
  return render(*run.scene, *run.world, options);
}

void check_bounds(const SceneRun& run) {
  for (const IntegratorKind integrator : {IntegratorKind::direct, IntegratorKind::vpl}) {
    RenderOptions options;
    options.integrator = integrator;
    options.spp = integrator == IntegratorKind::direct ? 2 : 1;
    options.shadow_rays = 2;
    options.vpls = 12;
    options.seed = run.index * 7 + 1;
    options.visibility = VisibilityMode::exact;
    const RenderResult exact = render_with(run, options);
    options.visibility = VisibilityMode::bounds;
    const RenderResult bounds = render_with(run, options);
    const std::string kind = std::string("exact: bounds = exact (") + std::string(name_of(integrator)) + ")";
    if (same_bytes(exact.image, bounds.image)) run.tally->pass(kind);
    else run.tally->fail(kind, run.index, difference_text(exact.image, bounds.image));
  }
}

void check_lightcuts(const SceneRun& run) {
  RenderOptions options;
  options.integrator = IntegratorKind::lightcuts;
  options.visibility = VisibilityMode::exact;
  options.spp = 1;
  options.light_points = 6 + static_cast<int>(run.random->below(10));
  options.lightcut_vpls = run.random->below(2) == 0;
  options.vpls = 6;
  options.seed = run.index * 7 + 2;
  options.lightcut = {.error = 0, .max_cut = 1, .bounds = VisibilityBounds::none, .check_proofs = false};
  const RenderResult none = render_with(run, options);
  for (const VisibilityBounds bounds : {VisibilityBounds::lower, VisibilityBounds::upper, VisibilityBounds::both}) {
    options.lightcut = {.error = 0, .max_cut = 1, .bounds = bounds, .check_proofs = true};
    const RenderResult with = render_with(run, options);
    const std::string kind = std::string("cuts: error 0, bounds ") + std::string(name_of(bounds)) + " = none";
    const json& described = with.stats.integrator;
    const std::uint64_t disagreements = described.value("proof_disagreements", json(0)).is_number()
                                            ? described.at("proof_disagreements").get<std::uint64_t>()
                                            : 0;
    if (!same_bytes(none.image, with.image)) run.tally->fail(kind, run.index, difference_text(none.image, with.image));
    else if (disagreements != 0) run.tally->fail(kind, run.index, std::to_string(disagreements) + " proof disagreements");
    else run.tally->pass(kind);
  }
}

void check_disk_images(const SceneRun& run) {
  if (!run.any_spheres) return;
  for (const IntegratorKind integrator : {IntegratorKind::direct, IntegratorKind::vpl}) {
    RenderOptions options;
    options.integrator = integrator;
    options.visibility = VisibilityMode::spheres;
    options.spp = 1;
    options.shadow_rays = 2;
    options.vpls = 12;
    options.seed = run.index * 7 + 3;
    options.self_shadow = std::array<SelfShadow, 3>{SelfShadow::heuristic, SelfShadow::exact, SelfShadow::none}[run.random->below(3)];
    options.disk_clusters = false;
    options.disk_lazy_from = 1000000;
    const RenderResult every = render_with(run, options);
    const int variants = integrator == IntegratorKind::vpl ? 4 : 3;
    for (int variant = 0; variant < variants; ++variant) {
      options.disk_clusters = variant != 1;
      options.disk_lazy_from = variant == 0 || variant == 3 ? 1000000 : 1;
      options.group_connections = variant != 3;  // 3: clusters with single rays, against every disk in packets
      const RenderResult with = render_with(run, options);
      const char* names[] = {"clusters", "lazy", "lazy clusters", "clusters, single rays"};
      const std::string kind = std::string("disks: ") + names[variant] + " = every disk (" + std::string(name_of(integrator)) + ")";
      if (same_bytes(every.image, with.image)) run.tally->pass(kind);
      else run.tally->fail(kind, run.index, difference_text(every.image, with.image));
    }
  }
}

// The occluder disks' API: flat and clustered answers from random points, with ends aimed
// within 2e-3 radians of the balls' centres and silhouettes.
void check_disk_api(const SceneRun& run) {
  const RenderWorld& world = *run.world;
  Random& random = *run.random;
  std::vector<std::size_t> with_balls;
  for (std::size_t i = 0; i < run.scene->instances.size(); ++i)
    if (!world.occluder_spheres(i).empty()) with_balls.push_back(i);
  if (with_balls.empty()) return;
  std::size_t mismatches = 0, segments = 0;
  for (int p = 0; p < 24; ++p) {
    const std::size_t i = with_balls[random.below(with_balls.size())];
    const std::vector<Sphere>& balls = world.occluder_spheres(i);
    const Sphere& aim = balls[random.below(balls.size())];
    // A point 1 to 3000 ball radii... or scene units away.
    const double distance = std::pow(10.0, 3.5 * random.uniform()) * std::max(aim.radius, 1e-3);
    const Vertex x = aim.center + distance * random.unit_vector();
    const Vertex n = random.unit_vector();
    const bool heuristic = random.below(2) == 0;
    OccluderDisks flat, clustered;
    flat.reset(x, n), clustered.reset(x, n);
    flat.add(balls, heuristic);
    clustered.add(balls, world.occluder_clusters(i), heuristic);
    const bool grid = random.below(2) == 0;
    flat.finish(grid), clustered.finish(grid);
    std::vector<Vertex> ends;
    std::vector<std::uint8_t> flat_answers;
    std::uint64_t tests = 0;
    for (int e = 0; e < 48; ++e) {
      const Sphere& ball = balls[random.below(balls.size())];
      const Vertex v = ball.center - x;
      const double t = v.norm();
      if (!(t > ball.radius)) continue;
      const Vertex u = v / t;
      Vertex side = random.unit_vector();
      side = (side - side.dot(u) * u).normalized();
      const double gamma = std::asin(ball.radius / t);
      const double angle = (e % 2 == 0 ? gamma : 0.0) + 2e-3 * (2 * random.uniform() - 1) * std::pow(10.0, -3 * random.uniform());
      const Vertex direction = std::cos(angle) * u + std::sin(angle) * side;
      ends.push_back(x + (t + ball.radius * (0.5 + 3 * random.uniform()) + 1e-3 * t) * direction);
      const bool answer = flat.occludes(ends.back(), tests);
      flat_answers.push_back(answer ? 1 : 0);
      ++segments;
      if (clustered.occludes(ends.back(), tests) != answer) ++mismatches;
    }
    std::vector<std::uint8_t> grouped(ends.size(), 0);
    clustered.occludes(ends, grouped, tests);
    for (std::size_t k = 0; k < ends.size(); ++k) mismatches += grouped[k] != flat_answers[k] ? 1 : 0;
  }
  const std::string kind = "disks: clustered = flat (API)";
  if (mismatches == 0) run.tally->pass(kind);
  else run.tally->fail(kind, run.index, std::to_string(mismatches) + " of " + std::to_string(2 * segments) + " answers differ");
}

void check_unbiased(const SceneRun& run) {
  struct Mode {
    const char* name;
    IntegratorKind integrator;
    StochasticEstimator estimator;
    ProbabilityMode probabilities;
  };
  const Mode modes[] = {{"eq. 8 equal", IntegratorKind::direct, StochasticEstimator::term_choice, ProbabilityMode::equal},
                        {"eq. 8 adaptive", IntegratorKind::direct, StochasticEstimator::term_choice, ProbabilityMode::adaptive},
                        {"control variate equal", IntegratorKind::direct, StochasticEstimator::control_variate, ProbabilityMode::equal},
                        {"control variate learned", IntegratorKind::direct, StochasticEstimator::control_variate, ProbabilityMode::learned},
                        {"control variate learned (vpl)", IntegratorKind::vpl, StochasticEstimator::control_variate, ProbabilityMode::learned}};
  const Mode& mode = modes[run.random->below(std::size(modes))];
  RenderOptions options;
  options.integrator = mode.integrator;
  options.spp = mode.integrator == IntegratorKind::direct ? 8 : 2;
  options.shadow_rays = 2;
  options.vpls = 8;
  options.probe_rays = 4;
  options.split = run.random->below(4) != 0;
  auto z_for = [&](std::uint64_t seed) {
    options.seed = seed;
    options.visibility = VisibilityMode::exact;
    const RenderResult exact = render_with(run, options);
    options.visibility = VisibilityMode::stochastic;
    options.estimator = mode.estimator;
    options.probabilities = mode.probabilities;
    const RenderResult estimate = render_with(run, options);
    return paired_z(estimate.image, exact.image);
  };
  const std::string kind = std::string("unbiased: ") + mode.name;
  const double z = z_for(run.index * 7 + 4);
  if (!(std::abs(z) > 4)) return run.tally->pass(kind);
  // A second seed confirms a bias (both beyond 4 standard errors, with one sign); a false
  // alarm at 4 standard errors (6e-5) rarely repeats.
  const double again = z_for(run.index * 7 + 5 + 1000003);
  if (std::abs(again) > 4 && (again > 0) == (z > 0))
    run.tally->fail(kind, run.index, "mean paired difference " + std::to_string(z) + " and " + std::to_string(again) + " standard errors");
  else
    run.tally->pass(kind);
}

// ---------------------------------------------------------------------------------------
// Tampered folders.

void copy_folder(const fs::path& from, const fs::path& to) {
  fs::remove_all(to);
  fs::create_directories(to);
  for (const auto& entry : fs::directory_iterator(from)) fs::copy_file(entry.path(), to / entry.path().filename());
}

json load_json(const fs::path& path) {
  std::ifstream in(path);
  return json::parse(in);
}
void save_json(const fs::path& path, const json& value) {
  std::ofstream out(path);
  out << value.dump(2) << "\n";
}

// Whether every file an entry lists holds the same triangles as its first (meshes only).
bool files_agree(const fs::path& folder, const json& entry) {
  if (entry.at("primitive_type") == "sphere" || !entry.contains("files")) return true;
  const TriangleMesh first = read_mesh(folder / entry.at("file").get<std::string>(), {.weld = Weld::never, .on_warning = {}});
  for (const json& name : entry.at("files")) {
    const TriangleMesh other = read_mesh(folder / name.get<std::string>(), {.weld = Weld::never, .on_warning = {}});
    if (other.positions != first.positions || other.triangles.size() != first.triangles.size()) return false;
    for (std::size_t t = 0; t < first.triangles.size(); ++t)
      if (other.triangles[t] != first.triangles[t]) return false;
  }
  return true;
}

// Whether `geometry` keeps `kind`'s claim for `mesh`, decided now from scratch.
bool claim_holds_now(const TriangleMesh& mesh, const json& manifest, ProxyKind kind, const std::vector<Sphere>& spheres,
                     const TriangleMesh& proxy_mesh) {
  if (kind == ProxyKind::general) return true;
  ProxyGeometry geometry;
  geometry.type = spheres.empty() ? PrimitiveType::triangle : PrimitiveType::sphere;
  geometry.mesh = proxy_mesh;
  geometry.spheres = spheres;
  const json entry = {{"name", "check"}, {"kind", std::string(kind_name(kind))}, {"file", "check"}};
  return verify_proxy(mesh, manifest, entry, geometry).at("holds").get<bool>();
}

void scale_mesh_file(const fs::path& path, double factor) {
  TriangleMesh mesh = read_mesh(path, {.weld = Weld::never, .on_warning = {}});
  const BoundingBox box = bounding_box(mesh);
  const Vertex centre = 0.5 * (box.min + box.max);
  for (Vertex& p : mesh.positions) p = centre + factor * (p - centre);
  write_mesh(path, mesh);
}

void check_folders(const SceneRun& run, const fs::path& cache, const fs::path& work) {
  const Scene& scene = *run.scene;
  Random& random = *run.random;
  // A closed mesh with an outside and an inside proxy, built in its own folder.
  const SceneMesh* chosen = nullptr;
  for (const SceneMesh& mesh : scene.meshes)
    if (mesh.name != "room") chosen = chosen ? chosen : &mesh;
  if (!chosen) return;
  Scene single;
  single.file = scene.file;
  single.meshes = {*chosen};
  SceneInstance instance;
  instance.mesh = chosen->name;
  instance.proxies = {"hull", "obb", "inside:6", "spheres:6"};
  single.instances = {instance};
  single.lights = {quad_light(Vertex(-5, -5, 10), {10, 0, 0}, {0, 10, 0}, 1, true)};
  single.camera = scene.camera;
  const std::vector<MeshProxies> built = prepare_scene_proxies(single, {.cache = cache, .stochastic_spec = std::nullopt, .seed = 1});
  (void)built;
  fs::path original;
  for (const auto& entry : fs::directory_iterator(cache))
    if (entry.path().filename().string().rfind(chosen->name + "-", 0) == 0) original = entry.path();
  if (original.empty()) return;
  // The cache holds one folder per spec; gather them into one folder of four entries.
  const fs::path base = work / "folder";
  fs::remove_all(base);
  fs::create_directories(base);
  json manifest;
  for (const char* spec : {"hull", "obb", "inside-6", "spheres-6"}) {
    const fs::path folder = original / spec;
    const json part = load_json(folder / "manifest.json");
    if (manifest.is_null()) manifest = part, manifest["proxies"] = json::array();
    for (const json& entry : part.at("proxies")) {
      manifest["proxies"].push_back(entry);
      for (const json& file : entry.at("files")) fs::copy_file(folder / file.get<std::string>(), base / file.get<std::string>(),
                                                               fs::copy_options::overwrite_existing);
    }
  }
  save_json(base / "manifest.json", manifest);
  const fs::path mesh_path = work / "mesh.ply";
  write_mesh(mesh_path, chosen->mesh);
  manifest["mesh"]["path"] = mesh_path.string();
  save_json(base / "manifest.json", manifest);
  // A folder of another mesh, for verdicts copied from it.
  const fs::path other = work / "other";
  {
    fs::remove_all(other);
    fs::create_directories(other);
    Random r(run.index + 17);
    Scene second = single;
    second.meshes[0].name = "other";
    second.meshes[0].mesh = blob(r);
    second.instances[0].mesh = "other";
    second.instances[0].proxies = {"hull", "inside:6"};
    prepare_scene_proxies(second, {.cache = other, .stochastic_spec = std::nullopt, .seed = 1});
  }
  auto other_verdict = [&](const std::string& spec) -> json {
    for (const auto& entry : fs::recursive_directory_iterator(other))
      if (entry.path().filename() == "manifest.json" && entry.path().parent_path().filename() == spec)
        return load_json(entry.path()).at("proxies").at(0).at("verify");
    return json();
  };
  auto index_of = [&](const json& m, const std::string& name) {
    for (std::size_t k = 0; k < m.at("proxies").size(); ++k)
      if (m.at("proxies")[k].at("name") == name) return k;
    return m.at("proxies").size();
  };

  struct Tamper {
    const char* name;
    std::function<void(const fs::path& folder, json& m)> apply;
  };
  const std::vector<Tamper> tampers = {
      {"kinds swapped", [&](const fs::path&, json& m) {
         std::swap(m["proxies"][index_of(m, "hull")]["kind"], m["proxies"][index_of(m, "inside-6")]["kind"]);
       }},
      {"an inside proxy called outside", [&](const fs::path&, json& m) { m["proxies"][index_of(m, "inside-6")]["kind"] = "outside"; }},
      {"a general proxy called inside", [&](const fs::path&, json& m) { m["proxies"][index_of(m, "spheres-6")]["kind"] = "inside"; }},
      {"verdicts swapped", [&](const fs::path&, json& m) {
         std::swap(m["proxies"][index_of(m, "hull")]["verify"], m["proxies"][index_of(m, "obb")]["verify"]);
       }},
      {"claims swapped", [&](const fs::path&, json& m) {
         std::swap(m["proxies"][index_of(m, "hull")]["verify"]["claim"], m["proxies"][index_of(m, "inside-6")]["verify"]["claim"]);
         std::swap(m["proxies"][index_of(m, "hull")]["kind"], m["proxies"][index_of(m, "inside-6")]["kind"]);
       }},
      {"files swapped", [&](const fs::path& folder, json& m) {
         // hull's and obb's files swapped, the counts with them: only the verdicts disagree.
         json& a = m["proxies"][index_of(m, "hull")];
         json& b = m["proxies"][index_of(m, "obb")];
         for (const char* extension : {".ply", ".obj"}) {
           fs::rename(folder / ("hull" + std::string(extension)), folder / "swap.tmp");
           fs::rename(folder / ("obb" + std::string(extension)), folder / ("hull" + std::string(extension)));
           fs::rename(folder / "swap.tmp", folder / ("obb" + std::string(extension)));
         }
         for (const char* key : {"primitives", "vertices", "triangles"}) std::swap(a[key], b[key]);
       }},
      {"obj shrunk by hand", [&](const fs::path& folder, json&) { scale_mesh_file(folder / "hull.obj", 0.97); }},
      {"ply and obj shrunk by hand", [&](const fs::path& folder, json&) {
         scale_mesh_file(folder / "hull.ply", 0.97);
         scale_mesh_file(folder / "hull.obj", 0.97);
       }},
      {"verdict copied from another folder", [&](const fs::path&, json& m) {
         const json copied = other_verdict("hull");
         if (!copied.is_null()) m["proxies"][index_of(m, "hull")]["verify"] = copied;
         const json inside = other_verdict("inside-6");
         if (!inside.is_null()) m["proxies"][index_of(m, "inside-6")]["verify"] = inside;
       }},
      {"untouched", [&](const fs::path&, json&) {}},
  };
  const Tamper& tamper = tampers[random.below(tampers.size())];
  const fs::path folder = work / "tampered";
  copy_folder(base, folder);
  json tampered = load_json(folder / "manifest.json");
  tamper.apply(folder, tampered);
  save_json(folder / "manifest.json", tampered);
  const std::string kind = std::string("folders: ") + tamper.name;

  // 1. The render path: the scene names the folder; every proxy that keeps its claim must
  //    hold it now, from its files, and every file it ships must agree.
  Scene named = single;
  named.meshes[0].proxy_folder = folder;
  named.instances[0].proxies = {"hull", "obb", "inside:6", "spheres:6"};
  std::string problem;
  auto found = [&](const std::string& what) { problem += (problem.empty() ? "" : "; ") + what; };
  try {
    const std::vector<MeshProxies> proxies =
        prepare_scene_proxies(named, {.cache = work / "unused-cache", .stochastic_spec = std::nullopt, .seed = 1});
    for (const std::optional<InstanceProxy>* p : {&proxies[0].stochastic, &proxies[0].outside, &proxies[0].inside}) {
      if (!*p || !(*p)->proved) continue;
      const std::string name = (*p)->spec == "inside:6" ? "inside-6" : (*p)->spec == "spheres:6" ? "spheres-6" : (*p)->spec;
      const json& entry = tampered["proxies"][index_of(tampered, name)];
      if (!claim_holds_now(chosen->mesh, tampered, (*p)->kind, (*p)->spheres, (*p)->mesh))
        found("the render path trusts " + (*p)->spec + " as " + std::string(kind_name((*p)->kind)) + ", which does not hold");
      else if (!files_agree(folder, entry))
        found("the render path trusts " + (*p)->spec + " while its files disagree");
    }
    // Lightcuts with the folder's proofs (whatever they are) must neither crash nor disagree.
    {
      RenderWorld world(named, proxies, {.counting = false, .ray_masks = true, .keep_solids = true});
      named.camera.width = 12, named.camera.height = 9;
      named.camera.at = named.instances[0].transform * Vertex::Zero();
      RenderOptions options;
      options.integrator = IntegratorKind::lightcuts;
      options.spp = 1;
      options.light_points = 8;
      options.lightcut = {.error = 0, .max_cut = 1, .bounds = VisibilityBounds::none, .check_proofs = false};
      const RenderResult none = render(named, world, options);
      options.lightcut = {.error = 0, .max_cut = 1, .bounds = VisibilityBounds::both, .check_proofs = true};
      const RenderResult both = render(named, world, options);
      if (!same_bytes(none.image, both.image)) found("lightcuts with the folder's proofs: " + difference_text(none.image, both.image));
      for (const double error : {0.002, 0.02, 0.2}) {  // refinement with proofs: no crash, no negative light
        options.lightcut = {.error = error, .max_cut = 1000, .bounds = VisibilityBounds::both, .check_proofs = true};
        for (const Color& c : render(named, world, options).image.pixels)
          if (!c.allFinite() || (c.array() < 0).any()) {
            found("lightcuts at error " + std::to_string(error) + " gave a pixel that is negative or not finite");
            break;
          }
      }
    }
  } catch (const InvalidInputError& error) {
    if (std::string(error.what()).find('\n') != std::string::npos) found("refused with more than one line");
  }
  // 2. The runtime, with and without verifying now.
  for (const bool verify_now : {false, true}) {
    for (const char* name : {"hull", "obb", "inside-6", "spheres-6"}) {
      try {
        const RuntimeProxy proxy = RuntimeProxy::load(folder, name, mesh_path, {.require_proof = false, .verify_now = verify_now});
        if (proxy.kind() != ProxyKind::general) {
          if (!claim_holds_now(chosen->mesh, tampered, proxy.kind(), proxy.sphere_set(), proxy.mesh()))
            found(std::string("the runtime trusts ") + name + " as " + std::string(kind_name(proxy.kind())) + ", which does not hold");
          else if (!files_agree(folder, tampered["proxies"][index_of(tampered, name)]))
            found(std::string("the runtime trusts ") + name + " while its files disagree");
        } else if (proxy.note().find('\n') != std::string::npos) {
          found(std::string("the runtime demotes ") + name + " with more than one line");
        }
      } catch (const InvalidInputError& error) {
        if (std::string(error.what()).find('\n') != std::string::npos) found("the runtime refuses with more than one line");
      }
    }
  }
  if (problem.empty()) run.tally->pass(kind);
  else run.tally->fail(kind, run.index, problem);
}

// ---------------------------------------------------------------------------------------

std::uint64_t scene_seed(std::uint64_t seed, std::uint64_t index) {
  std::uint64_t z = seed * 0x9E3779B97F4A7C15ull + index * 0xD1B54A32D192ED03ull + 0x8CB92BA72F3D8DD7ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

int run_main(int argc, char** argv) {
  std::uint64_t seed = 1, first = 0, scenes = 40;
  fs::path work = fs::temp_directory_path() / "visproxy-scene-proofs";
  bool verbose = false;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw Error("scene_proofs: " + flag + " needs a value");
      return argv[++i];
    };
    if (flag == "--seed") seed = std::stoull(value());
    else if (flag == "--scenes") scenes = std::stoull(value());
    else if (flag == "--first") first = std::stoull(value());
    else if (flag == "--work") work = value();
    else if (flag == "--verbose") verbose = true;
    else if (flag == "--help" || flag == "-h") {
      std::printf("usage: scene_proofs [--seed S] [--scenes N] [--first K] [--work DIR] [--verbose]\n");
      return 0;
    } else throw Error("scene_proofs: unknown option " + flag);
  }
  fs::remove_all(work);
  fs::create_directories(work);
  Tally tally;
  const auto start = std::chrono::steady_clock::now();
  std::printf("scene_proofs: seed %llu, scenes %llu..%llu, work folder %s\n", static_cast<unsigned long long>(seed),
              static_cast<unsigned long long>(first), static_cast<unsigned long long>(first + scenes - 1), work.string().c_str());
  std::fflush(stdout);
  for (std::uint64_t index = first; index < first + scenes; ++index) {
    const std::uint64_t s = scene_seed(seed, index);
    Made made = make_scene(s);
    if (verbose) {
      std::printf("scene %llu: %s\n", static_cast<unsigned long long>(index), made.summary.c_str());
      std::fflush(stdout);
    }
    Random random(s ^ 0x5DEECE66Dull);
    const fs::path cache = work / ("cache-" + std::to_string(index));
    try {
      const std::vector<MeshProxies> proxies = prepare_scene_proxies(made.scene, {.cache = cache, .stochastic_spec = std::nullopt, .seed = 1});
      RenderWorld world(made.scene, proxies, {.counting = false, .ray_masks = true, .keep_solids = true});
      SceneRun run{index, &made.scene, &proxies, &world, &random, &tally, false};
      for (std::size_t i = 0; i < made.scene.instances.size(); ++i) run.any_spheres = run.any_spheres || !world.occluder_spheres(i).empty();
      check_bounds(run);
      check_lightcuts(run);
      check_disk_images(run);
      check_disk_api(run);
      check_unbiased(run);
      check_folders(run, cache, work);
    } catch (const std::exception& error) {
      tally.fail("scene set-up", index, one_line(error.what()));
    }
    fs::remove_all(cache);
    ++tally.scenes;
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::uint64_t total = 0;
  for (const auto& [kind, count] : tally.checks) total += count;
  std::printf("scene_proofs: %llu scenes, %llu checks, %zu failed, %.1f s (seed %llu)\n", static_cast<unsigned long long>(tally.scenes),
              static_cast<unsigned long long>(total), tally.failures.size(), seconds, static_cast<unsigned long long>(seed));
  for (const auto& [kind, count] : tally.checks) std::printf("  %6llu  %s\n", static_cast<unsigned long long>(count), kind.c_str());
  fs::remove_all(work);
  return tally.failures.empty() ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run_main(argc, argv);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "scene_proofs: %s\n", error.what());
    return 2;
  }
}
