#include "visproxy/mesh/write_mesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "visproxy/core/errors.h"
#include "visproxy/core/files.h"
#include "visproxy/mesh/read_mesh.h"
#include "test_meshes.h"
#include "test_support.h"

namespace visproxy {
namespace {

using WriteMesh = testing::ScratchFolder;

// Coordinates that no float holds and that need all 17 significant digits.
TriangleMesh awkward_mesh() {
  TriangleMesh mesh = testing::tetrahedron();
  mesh.positions[1] = {0.1, 1.0 / 3.0, -std::nextafter(2.0, 3.0)};
  mesh.positions[2] = {1e-300, -7.5e99, std::ldexp(1.0, -1070)};  // a subnormal too
  return mesh;
}

TEST_F(WriteMesh, PlyAndObjRoundTripExactly) {
  const TriangleMesh mesh = awkward_mesh();
  for (const char* name : {"mesh.ply", "mesh.obj"}) {
    const auto path = folder_ / name;
    write_mesh(path, mesh);
    EXPECT_EQ(read_mesh(path, {.weld = Weld::never, .on_warning = {}}), mesh) << name;
  }
}

TEST_F(WriteMesh, LeavesNoTemporaryFilesAndReplacesAtomically) {
  const auto path = folder_ / "mesh.ply";
  write_mesh(path, testing::unit_cube());
  write_mesh(path, testing::tetrahedron());
  EXPECT_EQ(read_mesh(path), testing::tetrahedron());
  EXPECT_EQ(entries(), 1u);
}

TEST_F(WriteMesh, RejectsUnknownExtensionAndMissingFolder) {
  EXPECT_THROW(write_mesh(folder_ / "mesh.off", testing::unit_cube()), InvalidInputError);
  EXPECT_THROW(write_mesh(folder_ / "missing" / "mesh.ply", testing::unit_cube()), IOError);
}

}  // namespace
}  // namespace visproxy
