// libFuzzer target for the readers of untrusted files other than meshes (those have
// fuzz_read_mesh): scene JSON, proxy-folder manifest, sphere set, PFM and OpenEXR images.
//
// The first byte of an input selects the reader (its value modulo 5: 0 scene, 1 manifest,
// 2 sphere set, 3 PFM, 4 OpenEXR); the rest is the file's content, parsed from memory.
// FUZZ_READERS_SELECTOR=N in the environment makes every input go to reader N instead, so
// that a run spends its time on one reader however its mutations change the first byte. A
// reader may reject its input only by throwing visproxy::InvalidInputError naming the
// file (or IOError: a scene's mesh files are opened, and there are none where they point);
// anything else escaping (another exception, a crash, a sanitizer report, a leak) is a
// bug, as is a result that breaks the invariants checked below or a manifest whose fields
// the commands cannot read.
//
//   cmake --preset fuzz && cmake --build --preset fuzz --target fuzz_readers
//   build/fuzz/tests/fuzz/fuzz_readers -max_len=4096 -dict=tests/fuzz/readers.dict CORPUS_DIR tests/fuzz/corpus
//   FUZZ_READERS_SELECTOR=4 build/fuzz/tests/fuzz/fuzz_readers -max_len=4096 CORPUS_DIR  # OpenEXR only

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <string_view>

#include "visproxy/core/errors.h"
#include "visproxy/folder/proxy_folder.h"
#include "visproxy/mesh/sphere_set.h"
#include "visproxy/image/image.h"
#include "visproxy/scene/scene.h"

namespace {

[[noreturn]] void broken(const char* reader, const std::string& what) {
  std::fprintf(stderr, "fuzz_readers: %s: %s\n", reader, what.c_str());
  std::abort();
}

// The reader FUZZ_READERS_SELECTOR pins, or -1.
int pinned_selector = -1;

// The file names the readers are given; every error must name its file.
const std::filesystem::path kScene = "/nonexistent/fuzz/scene.json";
const std::filesystem::path kManifest = "/nonexistent/fuzz/manifest.json";
const std::filesystem::path kSphereSet = "/nonexistent/fuzz/spheres.json";
const std::filesystem::path kPfm = "/nonexistent/fuzz/image.pfm";
const std::filesystem::path kExr = "/nonexistent/fuzz/image.exr";

void check_scene(const visproxy::Scene& scene) {
  if (scene.meshes.empty() || scene.instances.empty() || scene.lights.empty()) broken("scene", "an empty part");
  for (const visproxy::SceneMesh& mesh : scene.meshes) {
    if (mesh.mesh.triangles.empty()) broken("scene", "a mesh without triangles");
    for (const visproxy::Triangle& t : mesh.mesh.triangles)
      for (const visproxy::VertexIndex v : t)
        if (v >= mesh.mesh.positions.size()) broken("scene", "a vertex index out of range");
  }
  for (const visproxy::SceneInstance& instance : scene.instances) {
    if (std::none_of(scene.meshes.begin(), scene.meshes.end(),
                     [&](const visproxy::SceneMesh& mesh) { return mesh.name == instance.mesh; }))
      broken("scene", "an instance of no mesh");
    if (!instance.transform.matrix().allFinite()) broken("scene", "a transform that is not finite");
    if (!instance.albedo.allFinite() || (instance.albedo.array() < 0).any() || (instance.albedo.array() > 1).any())
      broken("scene", "an albedo outside [0, 1]");
  }
  for (const visproxy::AreaLight& light : scene.lights) {
    if (light.triangles.empty() || !light.radiance.allFinite() || (light.radiance.array() < 0).any())
      broken("scene", "a light without triangles or with a bad radiance");
    for (const auto& triangle : light.triangles)
      for (const visproxy::Vertex& corner : triangle)
        if (!corner.allFinite()) broken("scene", "a light corner that is not finite");
  }
  const visproxy::Camera& camera = scene.camera;
  if (!(camera.fov_degrees > 0 && camera.fov_degrees < 180) || camera.width < 1 || camera.height < 1)
    broken("scene", "a bad camera");
}

// Reads what read_manifest_mesh, read_proxy_geometry and the commands read from a manifest
// read_manifest accepted: none of it may throw.
void use_manifest(const nlohmann::json& manifest) {
  const nlohmann::json& mesh = manifest.at("mesh");
  mesh.value("weld", "auto");
  mesh.at("path").get<std::string>();
  mesh.at("vertices").get<std::size_t>();
  mesh.at("triangles").get<std::size_t>();
  for (const char* corner : {"min", "max"})
    for (std::size_t axis = 0; axis < 3; ++axis) mesh.at("bbox").at(corner).at(axis).get<double>();
  for (const nlohmann::json& entry : manifest.at("proxies")) {
    visproxy::entry_kind(entry);
    entry.at("name").get<std::string>();
    entry.at("file").get<std::string>();
    entry.at("primitive_type").get<std::string>();
    entry.at("primitives").get<std::size_t>();
    entry.value("triangles", std::size_t{0});
  }
}

void check_image(const char* reader, const visproxy::Image& image) {
  if (image.width < 1 || image.height < 1 ||
      image.pixels.size() != static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height))
    broken(reader, "an image whose size and pixels disagree");
  if (!visproxy::all_finite(image)) broken(reader, "a pixel that is not finite");
}

void read(std::uint8_t selector, std::string_view bytes) {
  switch (selector % 5) {
    case 0: check_scene(visproxy::parse_scene(std::string(bytes), kScene)); break;
    case 1: use_manifest(visproxy::parse_manifest(bytes, kManifest)); break;
    case 2:
      for (const visproxy::Sphere& sphere : visproxy::parse_sphere_set(bytes, kSphereSet))
        if (!sphere.center.allFinite() || !std::isfinite(sphere.radius) || sphere.radius < 0)
          broken("sphere set", "a sphere with a bad centre or radius");
      break;
    case 3: check_image("PFM", visproxy::parse_pfm(bytes, kPfm)); break;
    case 4: check_image("OpenEXR", visproxy::parse_exr(bytes, kExr)); break;
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  // `cgal-demo:NAME` mesh paths in scenes point nowhere, so every input is read the same
  // way wherever the fuzzer runs.
  setenv("VISPROXY_MESH_DIR", "/nonexistent/fuzz/meshes", 1);
  if (const char* selector = std::getenv("FUZZ_READERS_SELECTOR")) pinned_selector = std::atoi(selector) % 5;
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string_view bytes(reinterpret_cast<const char*>(data) + 1, size - 1);
  try {
    read(pinned_selector >= 0 ? static_cast<std::uint8_t>(pinned_selector) : data[0], bytes);
  } catch (const visproxy::InvalidInputError& error) {
    // Errors name a file: the input's, or a mesh file a scene refers to.
    if (error.file().empty() || std::string_view(error.what()).rfind(error.file().string(), 0) != 0)
      broken("error", std::string("a message that does not start with its file: ") + error.what());
  } catch (const visproxy::IOError&) {
    // A mesh file a scene refers to cannot be opened.
  }
  return 0;  // any other exception escapes, and libFuzzer reports it as a crash
}
