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
