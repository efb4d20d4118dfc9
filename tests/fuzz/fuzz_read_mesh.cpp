// libFuzzer target for the mesh readers: visproxy::parse_mesh on arbitrary bytes.
//
// The first byte of an input selects the format (its value modulo 8: 0 OBJ, 1 PLY, 2 OFF,
// 3 STL, and through Assimp 4 glTF, 5 binary glTF, 6 FBX, 7 Collada); the rest is the
// file's content. A reader may reject its input only by throwing
// visproxy::Error; anything else escaping (another exception, a crash, a sanitizer report)
// is a bug, as is a mesh that breaks the invariants checked below.
//
//   cmake --preset fuzz && cmake --build --preset fuzz --target fuzz_read_mesh
//   build/fuzz/tests/fuzz/fuzz_read_mesh -max_len=4096 CORPUS_DIR tests/fuzz/corpus
// For the Assimp formats add -detect_leaks=0: Assimp 5.2 leaks on some malformed files.
// Assimp runs in a child process with a memory limit (read_assimp.cpp); under
// AddressSanitizer that limit ends the child with "allocator is out of memory" and an
// artifact instead of std::bad_alloc. Such an artifact is an Assimp memory bomb: check it
// with the release build's `visproxy info`, which must refuse it with one line.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>

#include "visproxy/core/errors.h"
#include "visproxy/mesh/read_mesh.h"

namespace {

[[noreturn]] void invariant_broken(const char* what, std::size_t where) {
  std::fprintf(stderr, "fuzz_read_mesh: parse_mesh returned a mesh with %s (at %zu)\n", what, where);
  std::abort();
}

struct FuzzedFormat {
  visproxy::MeshFormat format;
  const char* source;  // Assimp takes the format from the name's extension
};
constexpr FuzzedFormat kFormats[] = {{visproxy::MeshFormat::obj, "fuzz-input.obj"},  {visproxy::MeshFormat::ply, "fuzz-input.ply"},
                                     {visproxy::MeshFormat::off, "fuzz-input.off"},  {visproxy::MeshFormat::stl, "fuzz-input.stl"},
                                     {visproxy::MeshFormat::assimp, "fuzz-input.gltf"}, {visproxy::MeshFormat::assimp, "fuzz-input.glb"},
                                     {visproxy::MeshFormat::assimp, "fuzz-input.fbx"},  {visproxy::MeshFormat::assimp, "fuzz-input.dae"}};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const FuzzedFormat& format = kFormats[data[0] % 8];
  const std::string_view bytes(reinterpret_cast<const char*>(data) + 1, size - 1);

  visproxy::TriangleMesh mesh;
  try {
    mesh = visproxy::parse_mesh(bytes, format.format, format.source);
  } catch (const visproxy::Error&) {
    return 0;  // rejected input: the expected outcome for most of it
  }

  if (mesh.triangles.empty()) invariant_broken("no triangle", 0);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (const visproxy::VertexIndex index : mesh.triangles[t])
      if (index >= mesh.positions.size()) invariant_broken("a vertex index out of range in triangle", t);
  for (std::size_t v = 0; v < mesh.positions.size(); ++v)
    if (!mesh.positions[v].allFinite()) invariant_broken("a non-finite coordinate in vertex", v);
  return 0;
}
