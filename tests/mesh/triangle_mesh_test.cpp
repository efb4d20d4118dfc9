// The coordinate range every module relies on: a non-finite or huge coordinate in any of
// the three axes is found, whichever axis and whichever vertex it is in.

#include "visproxy/mesh/triangle_mesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "visproxy/core/errors.h"

namespace visproxy {
namespace {

TriangleMesh tetrahedron() {
  TriangleMesh mesh;
  mesh.positions = {Vertex(0, 0, 0), Vertex(1, 0, 0), Vertex(0, 1, 0), Vertex(0, 0, 1)};
  mesh.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return mesh;
}

std::string error_of(const TriangleMesh& mesh) {
  try {
    require_coordinates_in_range(mesh, "m.obj");
  } catch (const InvalidInputError& error) {
    return error.what();
  }
  return "";
}

// NaN beside zeros is the case Eigen's maxCoeff steps over.
TEST(CoordinateRange, FindsANonFiniteCoordinateInEveryAxisOfEveryVertex) {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  const std::pair<double, const char*> bad[] = {{nan, "nan"}, {inf, "inf"}, {-inf, "-inf"}};
  for (std::size_t vertex = 0; vertex < 4; ++vertex)
    for (int axis = 0; axis < 3; ++axis)
      for (const auto& [value, name] : bad) {
        TriangleMesh mesh = tetrahedron();
        mesh.positions[vertex][axis] = value;
        ASSERT_EQ(first_vertex_out_of_range(mesh), vertex) << vertex << " " << axis << " " << name;
        EXPECT_FALSE(within_coordinate_range(mesh.positions[vertex]));
        EXPECT_EQ(error_of(mesh), "m.obj: vertex " + std::to_string(vertex) + ": " + std::string(1, "xyz"[axis]) +
                                      " is not finite (" + name + ")");
      }
}

TEST(CoordinateRange, RefusesMagnitudesBeyondTheLimitAndKeepsThoseAtIt) {
  TriangleMesh mesh = tetrahedron();
  mesh.positions[2].z() = -kMaxCoordinate;
  EXPECT_EQ(first_vertex_out_of_range(mesh), std::nullopt);
  EXPECT_EQ(error_of(mesh), "");
  mesh.positions[3].y() = std::nextafter(kMaxCoordinate, 2 * kMaxCoordinate);
  EXPECT_EQ(first_vertex_out_of_range(mesh), 3u);
  EXPECT_NE(error_of(mesh).find("m.obj: vertex 3 has a coordinate of magnitude 1e+100"), std::string::npos)
      << error_of(mesh);
}

}  // namespace
}  // namespace visproxy
