// STL (stereolithography): binary (80-byte header, uint32 count, 50 bytes a triangle) or
// ASCII ("solid ... facet normal ... outer loop vertex x y z ... endsolid"). STL stores
// each triangle's corners separately; read_mesh welds them by default.

#include <cmath>
#include <cstring>
#include <string>

#include "visproxy/core/errors.h"
#include "visproxy/mesh/mesh_parsing.h"

namespace visproxy::parsing {
namespace {

constexpr std::size_t kBinaryHeader = 84;
constexpr std::size_t kBinaryTriangle = 50;

// The triangle count in a binary header (the caller has checked there are 84 bytes).
std::uint32_t binary_triangle_count(std::string_view bytes) {
  std::uint32_t count = 0;
  std::memcpy(&count, bytes.data() + 80, 4);  // little-endian on every platform we build for
  return count;
}

std::uint64_t binary_size(std::uint32_t count) { return kBinaryHeader + std::uint64_t{count} * kBinaryTriangle; }

TriangleMesh parse_binary_stl(std::string_view bytes, const std::filesystem::path& source) {
  const std::uint32_t count = binary_triangle_count(bytes);
  const std::uint64_t expected = binary_size(count);
  if (expected != bytes.size())
    throw InvalidInputError(source, "binary STL header claims " + std::to_string(count) + " triangles (" +
                                        std::to_string(expected) + " bytes) but the file has " +
                                        std::to_string(bytes.size()) + " bytes");
  if (count == 0) throw InvalidInputError(source, "contains no faces");
  MeshBuilder builder(source);
  builder.reserve(std::size_t{count} * 3, count);
  const char* record = bytes.data() + kBinaryHeader;
  for (std::uint32_t t = 0; t < count; ++t, record += kBinaryTriangle) {
    float corner[9];
    std::memcpy(corner, record + 12, sizeof corner);  // skip the facet normal
    for (const float value : corner)
      if (!std::isfinite(value))
        throw InvalidInputError(source, "triangle " + std::to_string(t) + " has a non-finite coordinate");
    const std::uint64_t first = builder.vertex_count();
    for (int k = 0; k < 3; ++k) builder.add_vertex(corner[3 * k], corner[3 * k + 1], corner[3 * k + 2]);
    const std::uint64_t corners[3] = {first, first + 1, first + 2};
    builder.add_polygon(corners);
  }
  return builder.finish();
}

TriangleMesh parse_ascii_stl(std::string_view bytes, const std::filesystem::path& source) {
  TextScanner scanner(bytes, source);
  MeshBuilder builder(source);
  auto expect = [&](std::string_view word) {
    const std::string_view found = scanner.token();
    if (found != word)
      scanner.fail("expected '" + std::string(word) + "', found " +
                   (found.empty() ? std::string("the end of the file") : quote_token(found)));
  };
  std::vector<std::uint64_t> corners;
  bool in_solid = false;
  for (std::string_view word = scanner.token(); !word.empty(); word = scanner.token()) {
    if (word == "solid" && !in_solid) {
      in_solid = true;
      scanner.skip_line();  // the solid's name
    } else if (word == "endsolid" && in_solid) {
      in_solid = false;
      scanner.skip_line();
    } else if (word == "facet" && in_solid) {
      expect("normal");
      for (int k = 0; k < 3; ++k) scanner.read_number("a normal component");
      expect("outer");
      expect("loop");
      corners.clear();
      for (word = scanner.token(); word == "vertex"; word = scanner.token()) {
        const double x = scanner.read_number("vertex x");
        const double y = scanner.read_number("vertex y");
        const double z = scanner.read_number("vertex z");
        corners.push_back(builder.vertex_count());
        builder.add_vertex(x, y, z);
      }
      if (word != "endloop") scanner.fail("expected 'vertex' or 'endloop'");
      if (corners.size() < 3) scanner.fail("facet with " + std::to_string(corners.size()) + " vertices; a facet needs 3");
      expect("endfacet");
      builder.add_polygon(corners);
    } else {
      scanner.fail("unexpected " + quote_token(word) + " in ASCII STL");
    }
  }
  if (in_solid) scanner.fail("truncated: no 'endsolid'");
  return builder.finish();
}

}  // namespace

TriangleMesh parse_stl(std::string_view bytes, const std::filesystem::path& source) {
  // Binary files may start with "solid" too: the size decides.
  if (bytes.size() >= kBinaryHeader && binary_size(binary_triangle_count(bytes)) == bytes.size())
    return parse_binary_stl(bytes, source);
  std::size_t start = 0;
  while (start < bytes.size() && std::isspace(static_cast<unsigned char>(bytes[start]))) ++start;
  if (bytes.substr(start).starts_with("solid")) return parse_ascii_stl(bytes, source);
  if (bytes.size() < kBinaryHeader) throw InvalidInputError(source, "too short for binary STL and not ASCII STL");
  return parse_binary_stl(bytes, source);
}

}  // namespace visproxy::parsing
