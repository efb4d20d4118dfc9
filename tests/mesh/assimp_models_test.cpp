// Debian's assimp-testmodels (unpacked by the build into VISPROXY_ASSIMP_MODEL_DIR):
// every model in the glTF 2.0, glTF 1, FBX, Collada and 3DS folders and in `invalid/`
// either loads as a mesh that keeps the reader's invariants or is refused with one line
// that names the file. A crash or another exception fails the test.

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <map>
#include <string>

#include "visproxy/core/errors.h"
#include "visproxy/mesh/read_mesh.h"

namespace visproxy {
namespace {

struct Tally {
  int loaded = 0, refused = 0;
};

TEST(AssimpTestModels, EveryModelLoadsOrIsRefusedWithOneLineNamingIt) {
  const std::filesystem::path root = VISPROXY_ASSIMP_MODEL_DIR;
  ASSERT_TRUE(std::filesystem::is_directory(root)) << root;
  std::map<std::string, Tally> tallies;
  for (const std::string folder : {"glTF2", "glTF", "FBX", "Collada", "3DS", "invalid"}) {
    Tally& tally = tallies[folder];
    for (const auto& item : std::filesystem::recursive_directory_iterator(root / folder)) {
      if (!item.is_regular_file() || !format_from_extension(item.path())) continue;  // textures, buffers, notes
      try {
        const TriangleMesh mesh = read_mesh(item.path());
        ++tally.loaded;
        ASSERT_FALSE(mesh.triangles.empty()) << item.path();
        for (const Triangle& t : mesh.triangles)
          for (const VertexIndex i : t) ASSERT_LT(i, mesh.positions.size()) << item.path();
        for (const Vertex& p : mesh.positions) ASSERT_TRUE(p.allFinite()) << item.path();
      } catch (const Error& error) {
        ++tally.refused;
        const std::string message = error.what();
        EXPECT_EQ(message.find('\n'), std::string::npos) << message;
        EXPECT_EQ(message.rfind(item.path().string() + ":", 0), 0u) << message;
      } catch (const std::exception& error) {
        ADD_FAILURE() << item.path() << ": " << error.what();
      }
    }
    std::printf("assimp-testmodels %-8s %3d loaded, %3d refused\n", folder.c_str(), tally.loaded, tally.refused);
  }
  // Assimp 5.2.5 on assimp-testmodels 5.2.5: glTF2 24 of 46 (the rest are the package's
  // deliberately broken files and point or line primitives), glTF 6 of 7, FBX 18 of 19,
  // Collada 25 of 29, 3DS 9 of 9, invalid 0 of 14.
  EXPECT_GE(tallies["glTF2"].loaded, 20);
  EXPECT_GE(tallies["FBX"].loaded, 15);
  EXPECT_GE(tallies["Collada"].loaded, 20);
  EXPECT_GE(tallies["3DS"].loaded, 5);
  EXPECT_EQ(tallies["invalid"].loaded, 0);
  EXPECT_GE(tallies["invalid"].refused, 10);
}

}  // namespace
}  // namespace visproxy

#include <stdlib.h>

#include <csignal>
#include <vector>

#include "visproxy/core/files.h"
#include "visproxy/mesh/mesh_parsing.h"

namespace visproxy {
namespace {

// Assimp runs in a child process: what it gives back, and what becomes of a crash, a
// memory bomb and a refusal there.
TEST(AssimpIsolated, GivesTheMeshBackAndTurnsCrashesAndMemoryBombsIntoOneLine) {
  TriangleMesh mesh;
  mesh.positions = {Vertex(0, 0, 0), Vertex(1, 0, 0), Vertex(0, 1e-300, 1e300)};
  mesh.triangles = {{0, 1, 2}, {2, 1, 0}};
  EXPECT_EQ(parsing::assimp_isolated("m.glb", 10, [&] { return mesh; }), mesh);  // bit for bit

  auto error_of = [](const std::function<TriangleMesh()>& read) {
    try {
      parsing::assimp_isolated("bad.glb", 1000, read);
      return std::string("read");
    } catch (const InvalidInputError& error) {
      return std::string(error.what());
    }
  };
  EXPECT_EQ(error_of([]() -> TriangleMesh { std::raise(SIGSEGV); return {}; }),
            "bad.glb: Assimp crashed reading it (Segmentation fault)");
  EXPECT_EQ(error_of([]() -> TriangleMesh { throw InvalidInputError("bad.glb", "Assimp cannot read it: no"); }),
            "bad.glb: Assimp cannot read it: no");
  ::setenv("VISPROXY_ASSIMP_SECONDS", "1", 1);
  const std::string hang = error_of([]() -> TriangleMesh {
    volatile unsigned long spin = 0;
    for (;;) spin = spin + 1;
  });
  ::unsetenv("VISPROXY_ASSIMP_SECONDS");
  EXPECT_EQ(hang, "bad.glb: Assimp took more than 1 s of processor time reading it (set VISPROXY_ASSIMP_SECONDS to allow more)");
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer aborts at the memory limit instead of throwing std::bad_alloc";
#endif
  const std::string bomb = error_of([]() -> TriangleMesh {
    std::vector<std::vector<char>> hoard;
    for (;;) hoard.emplace_back(std::size_t{64} << 20, 'x');  // until the limit stops it
  });
  EXPECT_EQ(bomb.rfind("bad.glb: Assimp needs more than 1024 MB of memory to read it", 0), 0u) << bomb;
}

// Found by fuzz_read_mesh: 5 KB of Collada that makes Assimp 5.2 allocate 17 GB.
TEST(AssimpIsolated, TheColladaMemoryBombIsRefusedWithinTheLimit) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer aborts at the memory limit instead of throwing std::bad_alloc";
#endif
  const std::string bytes = read_file(std::filesystem::path(VISPROXY_SOURCE_DIR) / "tests/fuzz/corpus/collada-memory-bomb");
  try {
    parse_mesh(std::string_view(bytes).substr(1), MeshFormat::assimp, "bomb.dae");  // the first byte picks the format
    ADD_FAILURE() << "read";
  } catch (const InvalidInputError& error) {
    EXPECT_NE(std::string(error.what()).find("bomb.dae: Assimp needs more than"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace visproxy


namespace visproxy {
namespace {

// Found by fuzz_read_mesh: a glTF file on which Assimp 5.2 dies of a segmentation fault.
// In the child process the crash is one line, and this process goes on.
TEST(AssimpIsolated, AGltfFileThatCrashesAssimpIsRefused) {
  const std::string bytes = read_file(std::filesystem::path(VISPROXY_SOURCE_DIR) / "tests/fuzz/corpus/gltf-assimp-segfault");
  try {
    parse_mesh(std::string_view(bytes).substr(1), MeshFormat::assimp, "crash.gltf");
    ADD_FAILURE() << "read";
  } catch (const InvalidInputError& error) {
    EXPECT_EQ(std::string(error.what()), "crash.gltf: Assimp crashed reading it (Segmentation fault)");
  }
}

}  // namespace
}  // namespace visproxy
